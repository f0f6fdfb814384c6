// The FRI backend against the simulated robot controller, over loopback only, on ephemeral
// ports: mirroring, command replies and sequence reflection, software limits, the watchdog,
// hostile datagrams.
#include "robot/fri_backend.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "robot/fri_simulated_controller.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/parameters.hpp"
#include "robot/resources.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::robot {
namespace {

const RobotModel& lwr4() {
  static const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

const UdpEndpoint kLoopback{0x7F000001, 0};

Eigen::VectorXd testPosture() {
  Eigen::VectorXd q(7);
  q << 0.3, 0.5, -0.2, -1.1, 0.4, 0.6, -0.7;
  return q;
}

// A backend and a simulated controller wired to each other on ephemeral loopback ports.
struct Link {
  std::unique_ptr<FriSimulatedController> controller;
  std::unique_ptr<FriBackend> backend;

  explicit Link(FriSimulatedControllerConfig sim = {}, FriBackendConfig config = {},
                std::unique_ptr<RobotBackend> arm = nullptr) {
    UdpSocket socket("127.0.0.1", 0);
    sim.peer = socket.localEndpoint();
    if (sim.q_initial.size() == 0) sim.q_initial = testPosture();
    controller = arm ? std::make_unique<FriSimulatedController>(lwr4(), sim, std::move(arm))
                     : std::make_unique<FriSimulatedController>(lwr4(), sim);
    config.robot = controller->localEndpoint();
    backend = std::make_unique<FriBackend>(lwr4(), config, std::move(socket));
    controller->start();
  }
  ~Link() { controller->stop(); }

  // Steps until `done` holds; fails the test after max_steps.
  bool stepUntil(const std::function<bool()>& done, int max_steps) {
    for (int i = 0; i < max_steps; ++i) {
      backend->step();
      if (done()) return true;
    }
    return false;
  }
  void steps(int n) {
    for (int i = 0; i < n; ++i) backend->step();
  }
};

FriSimulatedControllerConfig simConfig(double cycle, bool command_mode) {
  FriSimulatedControllerConfig sim;
  sim.cycle = cycle;
  sim.enter_command_mode = command_mode;
  return sim;
}

FriBackendConfig backendConfig(int watchdog_cycles, FriVelocityPolicy velocity = FriVelocityPolicy::kReject) {
  FriBackendConfig config;
  config.watchdog_cycles = watchdog_cycles;
  config.velocity_policy = velocity;
  return config;
}

JointImpedanceCommand impedance(const Eigen::VectorXd& q_cmd, double stiffness = 300.0, double damping = 0.7) {
  JointImpedanceCommand command;
  command.q_cmd = q_cmd;
  command.stiffness.setConstant(q_cmd.size(), stiffness);
  command.damping.setConstant(q_cmd.size(), damping);
  return command;
}

// Valid measurement bytes as a foreign sender would forge them.
fri::MeasurementBytes forgedMeasurement(std::uint16_t seq, float q_value) {
  fri::MeasurementDatagram m;
  m.header.send_seq = seq;
  m.intf.state = static_cast<std::uint16_t>(fri::InterfaceState::kCommand);
  m.intf.quality = static_cast<std::uint16_t>(fri::Quality::kPerfect);
  m.robot.control = static_cast<std::uint16_t>(fri::ControlMode::kJointImpedance);
  m.data.msr_jnt_pos.fill(q_value);
  return fri::encode(m);
}

TEST(FriBackend, MirrorsTheArmInMonitorMode) {
  Link link(simConfig(5e-3, false), backendConfig(50));
  Eigen::VectorXd tau(7);
  tau << 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().counters.measurements_accepted >= 10; }, 200));
  const FriStatus& status = link.backend->status();
  EXPECT_EQ(status.link, FriLink::kMonitoring);
  EXPECT_EQ(status.state, static_cast<std::uint16_t>(fri::InterfaceState::kMonitor));
  EXPECT_NEAR(link.backend->cycleTime(), 5e-3, 1e-9);  // taken from the KRC's sample time

  RobotState state;
  state.resize(7);
  link.backend->readState(state);
  // The simulated arm rests at its initial posture (the KRL impedance holds it there).
  EXPECT_LT((state.q - testPosture()).cwiseAbs().maxCoeff(), 1e-6);
  // x from our own kinematics of the mirrored q, checked against an independent evaluation.
  const Eigen::Isometry3d X_WT = tipPose(lwr4(), state.q);
  EXPECT_LT((state.X_WT.matrix() - X_WT.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(state.time, 0.0);

  // τ_ext mirrors estExtJntTrq; the arm yields to it in the simulation.
  tau << 2.0, -1.5, 0.5, 3.0, -0.25, 0.125, -1.0;
  link.controller->setExternalTorque(tau);
  ASSERT_TRUE(link.stepUntil(
      [&] {
        link.backend->readState(state);
        return (state.tau_ext - tau).cwiseAbs().maxCoeff() < 1e-6;
      },
      100));
  link.steps(20);
  link.backend->readState(state);
  EXPECT_GT(state.q[3], testPosture()[3]);  // pushed in the direction of the torque
  EXPECT_EQ(link.backend->status().counters.commands_sent, 0U);  // monitor mode: nothing commanded
}

TEST(FriBackend, AnswersEveryMeasurementAndReflectsSequenceNumbers) {
  Link link(simConfig(5e-3, false), backendConfig(50));
  link.steps(60);
  const FriStatus& status = link.backend->status();
  const FriSimulatedControllerStats stats = link.controller->stats();
  EXPECT_GE(status.counters.measurements_accepted, 50U);
  // Every answer names a measurement the controller really sent; the controller saw them.
  EXPECT_GE(stats.commands_received, 50U);
  EXPECT_EQ(stats.answers_unmatched, 0U);
  EXPECT_EQ(stats.commands_malformed, 0U);
  EXPECT_EQ(stats.commands_foreign, 0U);
  // The controller reflects our counter: it is one of our recent answers.
  const int behind = fri::sequenceDistance(status.last_reply_seq, status.last_reflected_seq);
  EXPECT_GE(behind, 0);
  EXPECT_LE(behind, 3);
  EXPECT_GT(status.statistics.answer_rate, 0.8F);
  EXPECT_EQ(status.counters.replies_sent, status.counters.hold_replies + status.counters.commands_sent);
}

TEST(FriBackend, CommandsMoveTheArmOnlyInCommandMode) {
  Link link(simConfig(5e-3, true), backendConfig(50));
  const Eigen::VectorXd q0 = testPosture();
  // Before the controller switches to CMD, commands are refused.
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->hasMeasurement(); }, 200));
  if (link.backend->status().link == FriLink::kMonitoring) {
    EXPECT_EQ(link.backend->writeCommand(impedance(q0)), CommandStatus::kRejected);
    EXPECT_EQ(link.backend->status().last_rejection, FriRejection::kNotPermitted);
  }
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 400));
  // The held posture at the switch is where the arm is: no jump.
  EXPECT_LT((link.backend->heldPosture() - q0).cwiseAbs().maxCoeff(), 1e-5);

  // A ramp on joint 1 at half its velocity limit, then hold the end point.
  const double dt = link.backend->cycleTime();
  const double speed = 0.5 * lwr4().velocityLimits()[0];
  Eigen::VectorXd q_cmd = link.backend->heldPosture();
  for (int i = 0; i < 40; ++i) {
    q_cmd[0] += speed * dt;
    ASSERT_EQ(link.backend->writeCommand(impedance(q_cmd, 500.0, 0.9)), CommandStatus::kAccepted) << i;
    link.backend->step();
  }
  for (int i = 0; i < 60; ++i) {
    ASSERT_EQ(link.backend->writeCommand(impedance(q_cmd, 500.0, 0.9)), CommandStatus::kAccepted);
    link.backend->step();
  }
  const FriSimulatedControllerStats stats = link.controller->stats();
  EXPECT_EQ(stats.commands_refused, 0U);  // nothing we sent broke the KRC's own checks
  EXPECT_GT(stats.commands_applied, 90U);
  EXPECT_NEAR(stats.q_desired[0], q_cmd[0], 1e-6);
  EXPECT_NEAR(stats.stiffness[0], 500.0, 1e-3);
  RobotState state;
  state.resize(7);
  link.backend->readState(state);
  EXPECT_NEAR(state.q_cmd[0], q_cmd[0], 1e-5);  // cmdJntPos + FRI offset mirrors our command
  EXPECT_NEAR(state.q[0], q_cmd[0], 0.02);      // the arm followed the ramp
  EXPECT_GT(state.q[0], q0[0] + 0.5 * speed * dt * 40);
  EXPECT_GE(link.backend->status().counters.commands_sent, 90U);
}

TEST(FriBackend, CommandsTheBulletSimulatedArmThroughTheControllerStandIn) {
  const ParameterSet parameters(simulationParameters());
  auto simulation = std::make_unique<Simulation>(lwr4(), nullptr, parameters);
  simulation->reset(testPosture());
  // Lockstep on both sides: what is checked here is the command path to the Bullet arm, which a
  // loaded machine must not turn into lost cycles (the real-time watchdog has its own tests).
  FriSimulatedControllerConfig sim = simConfig(2e-3, true);
  sim.lockstep = true;
  FriBackendConfig config = backendConfig(3);
  config.lockstep = true;
  Link link(sim, config, std::move(simulation));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 400));
  RobotState state;
  state.resize(7);
  link.backend->readState(state);
  EXPECT_LT((state.q - testPosture()).cwiseAbs().maxCoeff(), 1e-3);  // at rest where it was put

  // Move joint 4 by 0.1 rad at a quarter of its velocity limit, then hold.
  const double dt = link.backend->cycleTime();
  Eigen::VectorXd q_cmd = link.backend->heldPosture();
  const double target = q_cmd[3] + 0.1;
  const double step = 0.25 * lwr4().velocityLimits()[3] * dt;
  for (int i = 0; i < 400; ++i) {
    q_cmd[3] = std::min(target, q_cmd[3] + step);
    ASSERT_EQ(link.backend->writeCommand(impedance(q_cmd, 300.0, 0.95)), CommandStatus::kAccepted);
    link.backend->step();
  }
  link.backend->readState(state);
  EXPECT_NEAR(state.q[3], target, 0.01);
  EXPECT_EQ(link.controller->stats().commands_refused, 0U);
}

TEST(FriBackend, RejectsCommandsOutsideTheSoftwareLimits) {
  Link link(simConfig(5e-3, true), backendConfig(50));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 400));
  const RobotModel& model = lwr4();
  const Eigen::VectorXd held = link.backend->heldPosture();
  const double dt = link.backend->cycleTime();
  const std::uint64_t rejected_before = link.backend->status().counters.commands_rejected;

  // Position: beyond the soft limit (but inside the hardware limit) of joint 6.
  Eigen::VectorXd q = held;
  q[5] = 0.5 * (model.softUpperLimits()[5] + model.upperLimits()[5]);
  EXPECT_EQ(link.backend->writeCommand(impedance(q)), CommandStatus::kRejected);
  EXPECT_EQ(link.backend->status().last_rejection, FriRejection::kPositionLimit);

  // Velocity: every joint just below and just above v_max·T from the held posture.
  for (int j = 0; j < 7; ++j) {
    const double step = model.velocityLimits()[j] * dt;
    q = held;
    q[j] += 1.001 * step;
    EXPECT_EQ(link.backend->writeCommand(impedance(q)), CommandStatus::kRejected) << "joint " << j;
    EXPECT_EQ(link.backend->status().last_rejection, FriRejection::kVelocityLimit);
  }

  // Malformed: NaN, wrong size, negative stiffness, damping above 1.
  q = held;
  q[2] = std::nan("");
  EXPECT_EQ(link.backend->writeCommand(impedance(q)), CommandStatus::kRejected);
  EXPECT_EQ(link.backend->status().last_rejection, FriRejection::kInvalid);
  EXPECT_EQ(link.backend->writeCommand(impedance(Eigen::VectorXd::Zero(6))), CommandStatus::kRejected);
  EXPECT_EQ(link.backend->writeCommand(impedance(held, -1.0)), CommandStatus::kRejected);
  EXPECT_EQ(link.backend->writeCommand(impedance(held, 300.0, 1.5)), CommandStatus::kRejected);
  EXPECT_EQ(link.backend->status().counters.commands_rejected - rejected_before, 12U);

  // Just below the velocity limit is fine, and what leaves is exactly that.
  q = held;
  for (int j = 0; j < 7; ++j) q[j] += 0.999 * model.velocityLimits()[j] * dt * (j % 2 == 0 ? 1 : -1);
  EXPECT_EQ(link.backend->writeCommand(impedance(q)), CommandStatus::kAccepted);
  link.steps(5);
  EXPECT_EQ(link.controller->stats().commands_refused, 0U);
  EXPECT_LT((link.controller->stats().q_desired - q).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(FriBackend, RateLimitsAJumpingCommandTowardsItsTarget) {
  Link link(simConfig(5e-3, true), backendConfig(50, FriVelocityPolicy::kRateLimit));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 400));
  const RobotModel& model = lwr4();
  const double dt = link.backend->cycleTime();
  const Eigen::VectorXd held = link.backend->heldPosture();
  // A jump of 4.5 velocity-limit steps on joint 3 at low stiffness (a controller switching to
  // gravity compensation at where the arm was pushed to): it leaves in five steps of at most
  // v_max·T, the last one landing on the target.
  Eigen::VectorXd target = held;
  const double v_step = model.velocityLimits()[2] * dt;
  target[2] += 4.5 * v_step;
  std::vector<double> sent{held[2]};
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(link.backend->writeCommand(impedance(target, 20.0, 0.7)), CommandStatus::kAccepted);
    sent.push_back(link.backend->heldPosture()[2]);
    link.backend->step();
  }
  for (std::size_t i = 1; i < sent.size(); ++i) EXPECT_LE(std::abs(sent[i] - sent[i - 1]), v_step * (1.0 + 1e-9)) << i;
  EXPECT_NEAR(sent[4], held[2] + 4.0 * v_step, 1e-12);
  EXPECT_DOUBLE_EQ(sent[5], target[2]);
  EXPECT_EQ(link.backend->status().counters.commands_rate_limited, 4U);
  EXPECT_EQ(link.backend->status().counters.commands_rejected, 0U);
  link.steps(3);
  EXPECT_EQ(link.controller->stats().commands_refused, 0U);
  EXPECT_NEAR(link.controller->stats().q_desired[2], target[2], 1e-6);
  // Position limits still refuse.
  Eigen::VectorXd outside = target;
  outside[5] = 0.5 * (model.softUpperLimits()[5] + model.upperLimits()[5]);
  EXPECT_EQ(link.backend->writeCommand(impedance(outside)), CommandStatus::kRejected);
}

TEST(FriBackend, EveryAcceptedCommandKeepsTheLimitsForRandomInput) {
  Link link(simConfig(5e-3, true), backendConfig(50));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 400));
  const RobotModel& model = lwr4();
  const double dt = link.backend->cycleTime();
  Eigen::VectorXd last_sent = link.backend->heldPosture();
  std::mt19937 random(42);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int accepted = 0;
  for (int i = 0; i < 200; ++i) {
    // Steps of up to twice the velocity limit, stiffness and damping partly out of range.
    Eigen::VectorXd q = last_sent;
    for (int j = 0; j < 7; ++j) q[j] += 0.8 * noise(random) * model.velocityLimits()[j] * dt;
    const double stiffness = unit(random) < 0.1 ? -10.0 : 2000.0 * unit(random);
    const double damping = unit(random) < 0.1 ? 1.2 : unit(random);
    if (link.backend->writeCommand(impedance(q, stiffness, damping)) == CommandStatus::kAccepted) {
      ++accepted;
      // Checked independently: inside the soft limits, no joint faster than its limit.
      for (int j = 0; j < 7; ++j) {
        EXPECT_GE(q[j], model.softLowerLimits()[j]);
        EXPECT_LE(q[j], model.softUpperLimits()[j]);
        EXPECT_LE(std::abs(q[j] - last_sent[j]), model.velocityLimits()[j] * dt * (1.0 + 1e-6));
      }
      EXPECT_GE(stiffness, 0.0);
      EXPECT_LE(damping, 1.0);
      last_sent = q;
    }
    link.backend->step();
  }
  EXPECT_GT(accepted, 20);
  EXPECT_LT(accepted, 200);
  link.steps(3);
  EXPECT_EQ(link.controller->stats().commands_refused, 0U);
  EXPECT_LT((link.controller->stats().q_desired - last_sent).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(FriBackend, KeepsOnlyTheNewestMeasurementUnderLossDelayAndReordering) {
  FriSimulatedControllerConfig sim = simConfig(5e-3, false);
  sim.loss = 0.05;
  sim.reorder = 0.2;
  sim.delay = 2e-3;
  sim.seed = 11;
  Link link(sim, backendConfig(50));
  std::uint16_t last = 0;
  bool first = true;
  int backwards = 0;
  for (int i = 0; i < 150; ++i) {
    link.backend->step();
    if (!link.backend->hasMeasurement()) continue;
    const std::uint16_t seq = link.backend->status().last_measurement_seq;
    if (!first && fri::sequenceDistance(seq, last) < 0) ++backwards;
    first = false;
    last = seq;
  }
  const FriSimulatedControllerStats stats = link.controller->stats();
  const FriStatus& status = link.backend->status();
  EXPECT_GT(stats.measurements_lost, 0U);
  EXPECT_GT(stats.measurements_reordered, 0U);
  EXPECT_EQ(backwards, 0);  // the mirror never steps back in time
  // Every overtaken measurement arrives after its successor and is dropped (the last pair may
  // still be in flight).
  EXPECT_LE(status.counters.out_of_order_dropped, stats.measurements_reordered);
  EXPECT_GE(status.counters.out_of_order_dropped + 1, stats.measurements_reordered);
  EXPECT_GE(status.counters.lost_measurements, 1U);
  EXPECT_GE(status.statistics.latency, 2e-3F);  // the injected delay shows in the KRC's statistics
  EXPECT_EQ(status.link, FriLink::kMonitoring);
}

TEST(FriBackend, WatchdogStopsCommandingAfterThreeLostMeasurementsUntilConfirmed) {
  Link link(simConfig(10e-3, true), backendConfig(3));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 300));
  Eigen::VectorXd q_cmd = link.backend->heldPosture();
  const double step = 0.2 * lwr4().velocityLimits()[1] * link.backend->cycleTime();
  for (int i = 0; i < 5; ++i) {
    q_cmd[1] += step;
    ASSERT_EQ(link.backend->writeCommand(impedance(q_cmd)), CommandStatus::kAccepted);
    link.backend->step();
  }
  ASSERT_EQ(link.backend->status().link, FriLink::kCommanding);

  link.controller->dropNextMeasurements(3);
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kFault; }, 20));
  const FriStatus& status = link.backend->status();
  EXPECT_EQ(status.counters.watchdog_trips, 1U);
  EXPECT_TRUE(status.fault == FriFault::kMeasurementsLost || status.fault == FriFault::kMeasurementTimeout);

  // While in fault: commands are refused and the answers hold the last posture sent.
  const std::uint64_t commands_sent = status.counters.commands_sent;
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(link.backend->writeCommand(impedance(q_cmd)), CommandStatus::kRejected);
    EXPECT_EQ(link.backend->status().last_rejection, FriRejection::kNotPermitted);
    link.backend->step();
  }
  EXPECT_EQ(link.backend->status().link, FriLink::kFault);  // no automatic recovery
  EXPECT_EQ(link.backend->status().counters.commands_sent, commands_sent);
  EXPECT_GT(link.backend->status().counters.hold_replies, 0U);
  EXPECT_LT((link.backend->heldPosture() - q_cmd).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(link.controller->stats().q_desired[1], q_cmd[1], 1e-6);

  // The operator confirms: commanding resumes from the held posture.
  ASSERT_TRUE(link.backend->confirmReconnect());
  EXPECT_EQ(link.backend->status().link, FriLink::kCommanding);
  q_cmd[1] += step;
  EXPECT_EQ(link.backend->writeCommand(impedance(q_cmd)), CommandStatus::kAccepted);
  link.steps(3);
  EXPECT_EQ(link.controller->stats().commands_refused, 0U);
}

TEST(FriBackend, ToleratesFewerLostMeasurementsThanTheLimit) {
  Link link(simConfig(10e-3, false), backendConfig(3));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().counters.measurements_accepted >= 5; }, 100));
  link.controller->dropNextMeasurements(1);
  link.steps(10);
  EXPECT_EQ(link.backend->status().counters.lost_measurements, 1U);
  EXPECT_EQ(link.backend->status().counters.watchdog_trips, 0U);
  EXPECT_EQ(link.backend->status().link, FriLink::kMonitoring);
}

TEST(FriBackend, CountsRandomLossAsTheControllerDropsIt) {
  FriSimulatedControllerConfig sim = simConfig(2e-3, false);
  sim.loss = 0.2;
  sim.seed = 5;
  Link link(sim, backendConfig(50));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->hasMeasurement(); }, 100));
  const std::uint64_t lost_before = link.controller->stats().measurements_lost;
  link.steps(150);
  link.controller->stop();
  link.steps(1);  // take in what is still in flight (the step times out after that)
  const FriSimulatedControllerStats stats = link.controller->stats();
  const FriStatus& status = link.backend->status();
  // Every measurement the controller dropped after the first one we saw is a gap in its
  // sequence counter. Slack of a few: losses after the last measurement received show no gap
  // yet, and the controller's count was read a moment after our first measurement.
  const std::uint64_t lost = stats.measurements_lost - lost_before;
  EXPECT_GT(lost, 5U);
  EXPECT_LE(status.counters.lost_measurements, lost + 3);
  EXPECT_GE(status.counters.lost_measurements + 3, lost);
  EXPECT_EQ(status.counters.watchdog_trips, 1U);  // only the silence after stop()
  EXPECT_EQ(status.fault, FriFault::kMeasurementTimeout);
}

TEST(FriBackend, WatchdogTripsUnderHeavyRandomLoss) {
  // Half of all datagrams lost at random: three measurements in a row go missing within a few
  // hundred cycles (no such run in 400 cycles has a probability of about e^-25).
  FriSimulatedControllerConfig sim = simConfig(5e-3, false);
  sim.loss = 0.5;
  sim.seed = 9;
  Link link(sim, backendConfig(3));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->hasMeasurement(); }, 100));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kFault; }, 400));
  const FriStatus& status = link.backend->status();
  EXPECT_EQ(status.counters.watchdog_trips, 1U);
  EXPECT_TRUE(status.fault == FriFault::kMeasurementsLost || status.fault == FriFault::kMeasurementTimeout);
  EXPECT_GT(status.counters.lost_measurements, 0U);
  // It stays in fault while the lossy link goes on: only the operator clears it.
  link.steps(50);
  EXPECT_EQ(link.backend->status().link, FriLink::kFault);
  EXPECT_EQ(link.backend->status().counters.watchdog_trips, 1U);
}

TEST(FriBackend, TimeoutTripsWatchdogAndReconnectNeedsFreshMeasurements) {
  Link link(simConfig(5e-3, false), backendConfig(3));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->hasMeasurement(); }, 100));
  link.controller->stop();  // the controller falls silent
  const auto start = std::chrono::steady_clock::now();
  link.steps(2);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(link.backend->status().link, FriLink::kFault);
  EXPECT_EQ(link.backend->status().fault, FriFault::kMeasurementTimeout);
  EXPECT_GE(link.backend->status().counters.step_timeouts, 1U);
  EXPECT_LT(waited, 1.0);  // step() never blocks beyond the watchdog timeout
  EXPECT_FALSE(link.backend->confirmReconnect());  // nothing fresh to reconnect to

  link.controller->start();  // back again
  ASSERT_TRUE(link.stepUntil(
      [&] { return link.backend->status().counters.measurements_accepted > 0 && link.backend->confirmReconnect(); },
      100));
  EXPECT_EQ(link.backend->status().link, FriLink::kMonitoring);
}

// Lockstep (tests of whole runs): the stand-in waits for every answer, so a slow PC side is no
// lost cycle: the watchdog counts measurements by the KRC's sequence counter, trips on a burst
// really lost, and never on the wall clock.
TEST(FriBackend, LockstepWatchdogTripsOnLostMeasurementsButNotOnASlowLoop) {
  FriSimulatedControllerConfig sim = simConfig(1e-3, true);
  sim.lockstep = true;
  FriBackendConfig config = backendConfig(3);
  config.lockstep = true;
  Link link(sim, config);
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kCommanding; }, 300));
  const Eigen::VectorXd q_cmd = link.backend->heldPosture();
  // Our loop stalls for 30 ms, thirty cycles and far beyond the 3.5-cycle timeout of a real
  // link, between taking a measurement in and answering it: the stand-in waits, nothing trips.
  for (int i = 0; i < 3; ++i) {
    const std::uint64_t cycles = link.controller->stats().cycles;
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    EXPECT_EQ(link.controller->stats().cycles, cycles);  // no cycle passes without our answer
    ASSERT_EQ(link.backend->writeCommand(impedance(q_cmd)), CommandStatus::kAccepted);
    link.backend->step();
  }
  EXPECT_EQ(link.backend->status().link, FriLink::kCommanding);
  EXPECT_EQ(link.backend->status().counters.watchdog_trips, 0U);
  EXPECT_EQ(link.backend->status().counters.step_timeouts, 0U);

  // Three measurements lost in a row: the sequence gap trips the watchdog as on a real link.
  link.controller->dropNextMeasurements(3);
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().link == FriLink::kFault; }, 20));
  EXPECT_EQ(link.backend->status().fault, FriFault::kMeasurementsLost);
  EXPECT_EQ(link.backend->status().counters.lost_measurements, 3U);
  EXPECT_EQ(link.backend->status().counters.watchdog_trips, 1U);
  ASSERT_TRUE(link.backend->confirmReconnect());
  EXPECT_EQ(link.backend->status().link, FriLink::kCommanding);
}

// A lockstep stand-in whose answers the loss injection drops goes on instead of waiting for
// them; the run continues and the losses are counted on both sides.
TEST(FriBackend, LockstepGoesOnWhenAnswersAreLost) {
  FriSimulatedControllerConfig sim = simConfig(1e-3, false);
  sim.lockstep = true;
  sim.loss = 0.1;
  sim.seed = 4;
  FriBackendConfig config = backendConfig(50);
  config.lockstep = true;
  Link link(sim, config);
  link.steps(500);
  const FriSimulatedControllerStats stats = link.controller->stats();
  EXPECT_GT(stats.commands_lost, 10U);
  EXPECT_GT(stats.measurements_lost, 10U);
  // Every step took exactly one measurement in: the stand-in never waited for a lost answer.
  EXPECT_EQ(link.backend->status().counters.measurements_accepted, 500U);
  EXPECT_EQ(link.backend->status().counters.step_timeouts, 0U);
}

TEST(FriBackend, IgnoresDatagramsFromForeignEndpoints) {
  Link link(simConfig(5e-3, false), backendConfig(50));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->hasMeasurement(); }, 100));
  // Another address on the loopback net and another port on the robot's address.
  UdpSocket other_address("127.0.0.2", 0);
  UdpSocket other_port("127.0.0.1", 0);
  const UdpEndpoint backend = UdpEndpoint{0x7F000001, link.backend->localEndpoint().port};
  const std::uint64_t before = link.backend->status().counters.foreign_dropped;
  for (int i = 0; i < 20; ++i) {
    const auto seq = static_cast<std::uint16_t>(link.backend->status().last_measurement_seq + 1 + i);
    ASSERT_TRUE(other_address.sendTo(forgedMeasurement(seq, 1.0F), backend));
    ASSERT_TRUE(other_port.sendTo(forgedMeasurement(seq, -1.0F), backend));
    link.backend->step();
  }
  link.steps(5);
  EXPECT_EQ(link.backend->status().counters.foreign_dropped - before, 40U);
  RobotState state;
  state.resize(7);
  link.backend->readState(state);
  EXPECT_LT((state.q - testPosture()).cwiseAbs().maxCoeff(), 1e-6);  // still the real arm
  EXPECT_EQ(link.backend->status().state, static_cast<std::uint16_t>(fri::InterfaceState::kMonitor));
}

TEST(FriBackend, DropsMalformedShortOversizedAndStaleDatagramsWithoutHarm) {
  Link link(simConfig(5e-3, false), backendConfig(50));
  ASSERT_TRUE(link.stepUntil([&] { return link.backend->status().counters.measurements_accepted >= 3; }, 100));
  const FriCounters before = link.backend->status().counters;
  const fri::MeasurementBytes valid = forgedMeasurement(1, 0.0F);

  // From the robot's own endpoint: short, empty, oversized (one byte more, and beyond the
  // receive buffer), wrong id, wrong packetSize, NaN joint values, an old sequence number.
  link.controller->injectRaw(std::vector<std::uint8_t>(valid.begin(), valid.begin() + 100));
  link.controller->injectRaw({});
  std::vector<std::uint8_t> one_more(valid.begin(), valid.end());
  one_more.push_back(0);
  link.controller->injectRaw(one_more);
  link.controller->injectRaw(std::vector<std::uint8_t>(4000, 0xAB));
  std::vector<std::uint8_t> wrong_id(valid.begin(), valid.end());
  wrong_id[6] = 0x05;
  wrong_id[7] = 0x10;  // a command datagram's id
  link.controller->injectRaw(wrong_id);
  std::vector<std::uint8_t> wrong_size(valid.begin(), valid.end());
  wrong_size[4] = 0x00;
  link.controller->injectRaw(wrong_size);
  fri::MeasurementDatagram nan_measurement;
  nan_measurement.header.send_seq = 60000;
  nan_measurement.data.msr_jnt_pos[3] = std::nanf("");
  const auto nan_bytes = fri::encode(nan_measurement);
  link.controller->injectRaw(std::vector<std::uint8_t>(nan_bytes.begin(), nan_bytes.end()));
  const auto old_seq = static_cast<std::uint16_t>(link.backend->status().last_measurement_seq - 2);
  const auto old_bytes = forgedMeasurement(old_seq, 2.0F);
  link.controller->injectRaw(std::vector<std::uint8_t>(old_bytes.begin(), old_bytes.end()));

  // Random garbage of random length, fixed seed: none of it may disturb the mirror.
  std::mt19937 random(7);
  std::uniform_int_distribution<int> length(0, 1500);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 50; ++i) {
    std::vector<std::uint8_t> garbage(static_cast<std::size_t>(length(random)));
    for (auto& b : garbage) b = static_cast<std::uint8_t>(byte(random));
    link.controller->injectRaw(garbage);
  }

  const auto dropped = [&] {
    const FriCounters& c = link.backend->status().counters;
    return (c.short_dropped - before.short_dropped) + (c.oversized_dropped - before.oversized_dropped) +
           (c.malformed_dropped - before.malformed_dropped) + (c.out_of_order_dropped - before.out_of_order_dropped);
  };
  ASSERT_TRUE(link.stepUntil([&] { return dropped() >= 58U; }, 200));
  const FriCounters& after = link.backend->status().counters;
  EXPECT_GE(after.short_dropped - before.short_dropped, 2U);
  EXPECT_GE(after.oversized_dropped - before.oversized_dropped, 2U);
  EXPECT_GE(after.malformed_dropped - before.malformed_dropped, 3U);
  EXPECT_EQ(after.out_of_order_dropped - before.out_of_order_dropped, 1U);
  EXPECT_EQ(dropped(), 58U);
  EXPECT_EQ(after.foreign_dropped, before.foreign_dropped);

  link.steps(5);
  RobotState state;
  state.resize(7);
  link.backend->readState(state);
  EXPECT_TRUE(state.q.allFinite());
  EXPECT_LT((state.q - testPosture()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(link.backend->status().link, FriLink::kMonitoring);
}

TEST(FriBackend, RefusesModelsWithoutSevenJointsAndMissingRobotAddress) {
  FriBackendConfig config;
  config.local_address = "127.0.0.1";
  config.local_port = 0;
  const auto make = [&config](const RobotModel& model) { FriBackend backend(model, config); };
  EXPECT_THROW(make(lwr4()), InputError);  // no robot address
  config.robot = UdpEndpoint{0x7F000001, 0};
  config.watchdog_cycles = 0;
  EXPECT_THROW(make(lwr4()), InputError);
  config.watchdog_cycles = 3;
  EXPECT_NO_THROW(make(lwr4()));
  const RobotModel arm9 = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  EXPECT_THROW(make(arm9), InputError);
}

TEST(FriBackend, ReadsTheBackendChoiceUri) {
  const FriBackendConfig config = friConfigFromUri("fri://127.0.0.1:49939");
  EXPECT_EQ(config.robot, (UdpEndpoint{0x7F000001, 49939}));
  EXPECT_EQ(config.local_port, fri::kDefaultPcPort);
  EXPECT_EQ(friConfigFromUri("fri://127.0.0.1").robot.port, 0);
  EXPECT_THROW(friConfigFromUri("sim"), InputError);
  EXPECT_THROW(friConfigFromUri("fri://"), InputError);
  EXPECT_THROW(friConfigFromUri("udp://127.0.0.1:5"), InputError);
}

TEST(FriBackend, ParsesRobotAddresses) {
  const UdpEndpoint a = UdpEndpoint::parse("127.0.0.1:49939", 0, "robot");
  EXPECT_EQ(a.address, 0x7F000001U);
  EXPECT_EQ(a.port, 49939);
  EXPECT_EQ(UdpEndpoint::parse("127.0.0.5", 49938, "robot").port, 49938);
  EXPECT_EQ(a.toString(), "127.0.0.1:49939");
  EXPECT_THROW(UdpEndpoint::parse("127.0.0.1:70000", 0, "robot"), InputError);
  EXPECT_THROW(UdpEndpoint::parse("127.0.0.1:", 0, "robot"), InputError);
  EXPECT_THROW(UdpEndpoint::parse(":5", 0, "robot"), InputError);
  EXPECT_THROW(UdpEndpoint::parse("", 0, "robot"), InputError);
  EXPECT_THROW(UdpEndpoint::parse("127.0.0.1:12x", 0, "robot"), InputError);
}

}  // namespace
}  // namespace flexirob::robot
