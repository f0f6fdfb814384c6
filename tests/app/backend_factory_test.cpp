// The backend choice (sim / fri://HOST:PORT), the robot connection's link status, operator
// reconnect, and the connection driving the Bullet arm through the FRI controller stand-in in
// lockstep over loopback.
#include "app/backend_factory.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <thread>

#include "robot/errors.hpp"
#include "robot/fri_simulated_controller.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {
namespace {

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

TEST(BackendChoice, ReadsSimAndFriUris) {
  EXPECT_EQ(parseBackendChoice("sim").kind, BackendKind::kSimulation);
  const BackendChoice fri = parseBackendChoice("fri://127.0.0.1:49938");
  EXPECT_EQ(fri.kind, BackendKind::kFri);
  EXPECT_EQ(fri.fri.robot, (robot::UdpEndpoint{0x7F000001, 49938}));
  EXPECT_EQ(fri.text, "fri://127.0.0.1:49938");
  EXPECT_EQ(parseBackendChoice("fri://localhost:5").fri.robot, (robot::UdpEndpoint{0x7F000001, 5}));
}

TEST(BackendChoice, RefusesMalformedChoicesWithOneLineReasons) {
  const auto reason = [](const std::string& text) -> std::string {
    try {
      parseBackendChoice(text);
    } catch (const InputError& error) {
      return error.what();
    }
    return "accepted";
  };
  EXPECT_NE(reason("").find("empty"), std::string::npos);
  EXPECT_NE(reason("simulation").find("unknown backend"), std::string::npos);
  EXPECT_NE(reason("udp://127.0.0.1:5").find("unknown scheme 'udp'"), std::string::npos);
  EXPECT_NE(reason("fri://").find("no robot controller address"), std::string::npos);
  EXPECT_NE(reason("fri://127.0.0.1").find("no port"), std::string::npos);
  EXPECT_NE(reason("fri://:49938").find("no host"), std::string::npos);
  EXPECT_NE(reason("fri://127.0.0.1:49938/x").find("path"), std::string::npos);
  EXPECT_NE(reason("fri://me@127.0.0.1:49938").find("user"), std::string::npos);
  EXPECT_NE(reason("fri://127.0.0.1:0").find("port"), std::string::npos);
  EXPECT_NE(reason("fri://127.0.0.1:65536").find("port"), std::string::npos);
  EXPECT_NE(reason("fri://127.0.0.1:12a").find("port"), std::string::npos);
  EXPECT_NE(reason("fri://no-such-host.invalid:49938"), "accepted");
  for (const std::string text : {"", "fri://", "fri://127.0.0.1", "udp://x:1", "fri://127.0.0.1:70000"}) {
    const std::string line = reason(text);
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
    EXPECT_NE(line.find("fri://HOST:PORT"), std::string::npos) << line;
  }
}

TEST(RobotConnection, SimulationReportsItselfAndCountsSteps) {
  const robot::ParameterSet parameters(robot::reachParameters());
  RobotConnection connection(parseBackendChoice("sim"), lwr4(), nullptr, parameters);
  EXPECT_EQ(connection.fri(), nullptr);
  for (int i = 0; i < 5; ++i) connection.step();
  const LinkStatus status = connection.status();
  EXPECT_EQ(status.link, "simulated");
  EXPECT_TRUE(status.commanding);
  EXPECT_FALSE(status.fault);
  EXPECT_EQ(status.measurements, 5U);
  EXPECT_NEAR(status.time, 5 * connection.cycleTime(), 1e-9);
  EXPECT_EQ(status.summary(), "sim simulated, 1.0 ms");
}

TEST(RobotConnection, RefusesTheFriBackendForANineJointArm) {
  const robot::RobotModel arm9 = robot::RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  const robot::ParameterSet parameters(robot::reachParameters());
  EXPECT_THROW(RobotConnection(parseBackendChoice("fri://127.0.0.1:49938"), arm9, nullptr, parameters), InputError);
}

// A backend on an ephemeral loopback port, wrapped in a connection, and the controller stand-in.
struct FriLink {
  std::unique_ptr<robot::FriSimulatedController> controller;
  std::unique_ptr<RobotConnection> connection;
  robot::Simulation* arm = nullptr;  // owned by the controller

  FriLink(robot::FriSimulatedControllerConfig sim, int watchdog_cycles, std::unique_ptr<robot::Simulation> bullet) {
    robot::UdpSocket socket("127.0.0.1", 0);
    sim.peer = socket.localEndpoint();
    arm = bullet.get();
    controller = bullet ? std::make_unique<robot::FriSimulatedController>(lwr4(), sim, std::move(bullet))
                        : std::make_unique<robot::FriSimulatedController>(lwr4(), sim);
    BackendChoice choice;
    choice.kind = BackendKind::kFri;
    choice.fri.robot = controller->localEndpoint();
    choice.fri.watchdog_cycles = watchdog_cycles;
    choice.fri.lockstep = sim.lockstep;  // a lockstep stand-in: the watchdog counts by sequence number
    choice.text = "fri://" + choice.fri.robot.toString();
    connection = std::make_unique<RobotConnection>(
        choice, std::make_unique<robot::FriBackend>(lwr4(), choice.fri, std::move(socket)));
    controller->start();
  }
  ~FriLink() { controller->stop(); }

  bool stepUntil(const std::function<bool(const LinkStatus&)>& done, int max_steps) {
    for (int i = 0; i < max_steps; ++i) {
      connection->step();
      if (done(connection->status())) return true;
    }
    return false;
  }
};

TEST(RobotConnection, PublishesTheFriLinkAndReconnectsOnlyWhenTheOperatorConfirms) {
  robot::FriSimulatedControllerConfig sim;
  sim.cycle = 5e-3;
  FriLink link(sim, 3, nullptr);
  ASSERT_TRUE(link.stepUntil([](const LinkStatus& s) { return s.link == "commanding"; }, 400));
  LinkStatus status = link.connection->status();
  EXPECT_EQ(status.kind, BackendKind::kFri);
  EXPECT_EQ(status.state, "command");
  EXPECT_TRUE(status.commanding);
  EXPECT_NEAR(status.cycle, 5e-3, 1e-9);
  EXPECT_NE(status.summary().find("commanding"), std::string::npos);

  // A burst of lost measurements trips the watchdog; the status shows it, and stays so.
  link.controller->dropNextMeasurements(4);
  ASSERT_TRUE(link.stepUntil([](const LinkStatus& s) { return s.fault; }, 40));
  for (int i = 0; i < 20; ++i) link.connection->step();
  status = link.connection->status();
  EXPECT_TRUE(status.fault);
  EXPECT_FALSE(status.commanding);
  EXPECT_EQ(status.watchdog_trips, 1U);
  EXPECT_FALSE(status.fault_reason.empty());
  EXPECT_NE(status.summary().find("confirm to reconnect"), std::string::npos);

  // The operator's confirmation, from another thread (the GUI), takes effect on the next step.
  std::thread gui([&link] { link.connection->requestReconnect(); });
  gui.join();
  link.connection->step();
  status = link.connection->status();
  EXPECT_FALSE(status.fault);
  EXPECT_EQ(status.reconnects, 1U);
  EXPECT_EQ(status.link, "commanding");
}

TEST(RobotConnection, StatusCanBePolledWhileTheControlThreadSteps) {
  robot::FriSimulatedControllerConfig sim;
  sim.cycle = 2e-3;
  sim.enter_command_mode = false;
  FriLink link(sim, 50, nullptr);
  std::atomic<bool> running{true};
  std::thread control([&] {
    while (running.load()) link.connection->step();
  });
  std::uint64_t last = 0;
  bool monotonic = true;
  // Polled until the link has counted a few measurements, however slow the machine (a fixed
  // 150 ms window saw a single one under ThreadSanitizer on a loaded machine); the bound only
  // keeps a broken link from hanging the suite.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (last <= 10U && std::chrono::steady_clock::now() < until) {
    const LinkStatus status = link.connection->status();
    monotonic = monotonic && status.measurements >= last;
    last = status.measurements;
  }
  running = false;
  control.join();
  EXPECT_TRUE(monotonic);
  EXPECT_GT(last, 10U);
  EXPECT_EQ(link.connection->status().link, "monitoring");
}

// The controller stand-in in lockstep (faster than real time, for whole runs in tests): every
// measurement waits for our answer, the clock counts simulated cycles, and a ramp commanded
// through the connection reaches the Bullet arm behind the stand-in.
TEST(RobotConnection, DrivesTheBulletArmThroughTheLockstepControllerStandIn) {
  const robot::Scene scene = robot::loadScene("setup_A");
  robot::ParameterSet parameters(robot::reachParameters());
  auto bullet = std::make_unique<robot::Simulation>(lwr4(), &scene, parameters);
  bullet->reset(*scene.home_posture);
  robot::FriSimulatedControllerConfig sim;
  sim.cycle = bullet->cycleTime();
  sim.lockstep = true;
  // The default watchdog (3 cycles): in lockstep it counts missing measurements by the KRC's
  // sequence counter, so however slow either side runs (a sanitizer build, a loaded machine),
  // it trips only on measurements really lost.
  FriLink link(sim, 3, std::move(bullet));
  ASSERT_TRUE(link.stepUntil([](const LinkStatus& s) { return s.commanding; }, 500));
  robot::RobotState state;
  state.resize(7);
  link.connection->readState(state);
  const double t0 = state.time;
  Eigen::VectorXd q_cmd = link.connection->fri()->heldPosture();
  const double target = q_cmd[0] + 0.1;
  const double step = 0.5 * lwr4().velocityLimits()[0] * sim.cycle;
  robot::JointImpedanceCommand command;
  command.resize(7);
  command.stiffness.setConstant(800.0);
  command.damping.setConstant(0.9);
  constexpr int kSteps = 1000;
  for (int i = 0; i < kSteps; ++i) {
    q_cmd[0] = std::min(target, q_cmd[0] + step);
    command.q_cmd = q_cmd;
    ASSERT_EQ(link.connection->writeCommand(command), robot::CommandStatus::kAccepted);
    link.connection->step();
  }
  link.connection->readState(state);
  // One simulated cycle per step, whatever the wall clock did.
  EXPECT_NEAR(state.time - t0, kSteps * sim.cycle, 1e-6);  // the cycle travels as a float
  EXPECT_NEAR(state.q[0], target, 0.01);
  {
    std::lock_guard arm_lock(link.controller->armMutex());  // the stand-in's thread steps the arm
    EXPECT_NEAR(link.arm->time() - t0, kSteps * sim.cycle, 2 * sim.cycle);
  }
  const LinkStatus status = link.connection->status();
  const robot::FriSimulatedControllerStats controller = link.controller->stats();
  EXPECT_EQ(status.watchdog_trips, 0U);
  EXPECT_EQ(status.lost_measurements, 0U);
  EXPECT_EQ(controller.commands_refused, 0U);
  EXPECT_EQ(controller.answers_unmatched, 0U);
  EXPECT_EQ(controller.quality, robot::fri::Quality::kPerfect);
}

}  // namespace
}  // namespace flexirob::app
