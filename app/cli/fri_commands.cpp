// `fri probe` (DESIGN §6): listen to the real LWR IV, mirror it and hold its current posture;
// `fri simulate`: the robot controller's side over loopback, for demos and tests.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <utility>

#include "app/cli/cli_support.hpp"
#include "robot/errors.hpp"
#include "robot/fri_backend.hpp"
#include "robot/fri_simulated_controller.hpp"
#include "robot/parameters.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::cli {
namespace {

constexpr double kMaxSeconds = 86400.0;

struct ProbeOptions {
  int port = robot::fri::kDefaultPcPort;
  std::string robot;
  double seconds = 5.0;
  std::string bind = "0.0.0.0";
  int watchdog_cycles = 3;
  double stiffness = 300.0;
  double damping = 0.7;
};

struct SimulateOptions {
  int port = 0;
  std::string peer;
  double seconds = 5.0;
  double cycle_ms = 1.0;
  double loss = 0.0;
  double delay_ms = 0.0;
  double reorder = 0.0;
  std::uint64_t seed = 1;
  bool monitor_only = false;
  std::string q;  // initial posture, empty: the middle of the software limits
  std::string arm = "bullet";
};

robot::RobotModel loadLwr4() { return robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4")); }

void checkSeconds(double seconds) {
  if (!(seconds > 0.0 && seconds <= kMaxSeconds)) {
    throw InputError("--seconds: expected a duration in (0, 86400], got " + printableNumber(seconds));
  }
}

Json countersJson(const robot::FriCounters& c) {
  return {{"datagrams_received", c.datagrams_received},
          {"measurements_accepted", c.measurements_accepted},
          {"foreign_dropped", c.foreign_dropped},
          {"short_dropped", c.short_dropped},
          {"oversized_dropped", c.oversized_dropped},
          {"malformed_dropped", c.malformed_dropped},
          {"out_of_order_dropped", c.out_of_order_dropped},
          {"stale_skipped", c.stale_skipped},
          {"lost_measurements", c.lost_measurements},
          {"replies_sent", c.replies_sent},
          {"commands_sent", c.commands_sent},
          {"hold_replies", c.hold_replies},
          {"send_failures", c.send_failures},
          {"commands_rejected", c.commands_rejected},
          {"watchdog_trips", c.watchdog_trips},
          {"quality_holds", c.quality_holds},
          {"step_timeouts", c.step_timeouts}};
}

Json probe(const ProbeOptions& options) {
  checkSeconds(options.seconds);
  robot::FriBackendConfig config;
  config.local_address = options.bind;
  config.local_port = static_cast<std::uint16_t>(options.port);
  config.robot = robot::UdpEndpoint::parse(options.robot, 0, "--robot");
  config.watchdog_cycles = options.watchdog_cycles;
  config.hold_stiffness = options.stiffness;
  config.hold_damping = options.damping;
  robot::FriBackend backend(loadLwr4(), config);
  const int dof = backend.model().dof();

  // Hold: the posture latched when command mode begins, with the given impedance.
  robot::JointImpedanceCommand hold;
  hold.resize(dof);
  hold.stiffness.setConstant(options.stiffness);
  hold.damping.setConstant(options.damping);
  bool commanding = false;
  std::uint64_t accepted = 0;
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  while (std::chrono::duration<double>(Clock::now() - start).count() < options.seconds) {
    backend.step();
    const bool now_commanding = backend.status().link == robot::FriLink::kCommanding;
    if (now_commanding && !commanding) hold.q_cmd = backend.heldPosture();
    commanding = now_commanding;
    if (commanding && backend.writeCommand(hold) == robot::CommandStatus::kAccepted) ++accepted;
    reportProgress("fri probe", std::chrono::duration<double>(Clock::now() - start).count() / options.seconds);
  }

  const robot::FriStatus& status = backend.status();
  robot::RobotState state;
  state.resize(dof);
  backend.readState(state);
  const bool measured = backend.hasMeasurement();
  return {{"robot_address", config.robot.toString()},
          {"port", backend.localEndpoint().port},
          {"seconds", options.seconds},
          {"packets_received", status.counters.datagrams_received},
          {"measurements", status.counters.measurements_accepted},
          {"commands_sent", status.counters.commands_sent},
          {"commands_accepted", accepted},
          {"state", measured ? robot::fri::interfaceStateName(status.state) : "none"},
          {"quality", measured ? robot::fri::qualityName(status.quality) : "none"},
          {"control_mode", measured ? robot::fri::controlModeName(status.control) : "none"},
          {"link", robot::toString(status.link)},
          {"fault", robot::toString(status.fault)},
          {"last_rejection", robot::toString(status.last_rejection)},
          {"cycle_s", backend.cycleTime()},
          {"answer_rate", static_cast<double>(status.statistics.answer_rate)},
          {"latency_s", static_cast<double>(status.statistics.latency)},
          {"krc_miss_counter", status.statistics.miss_counter},
          {"q", measured ? toJson(state.q) : Json(nullptr)},
          {"q_cmd", measured ? toJson(state.q_cmd) : Json(nullptr)},
          {"tau_ext", measured ? toJson(state.tau_ext) : Json(nullptr)},
          {"position", measured ? toJson(state.p_WT()) : Json(nullptr)},
          {"counters", countersJson(status.counters)}};
}

Json simulate(const SimulateOptions& options) {
  checkSeconds(options.seconds);
  robot::FriSimulatedControllerConfig config;
  config.port = static_cast<std::uint16_t>(options.port);
  config.peer = robot::UdpEndpoint::parse(options.peer, 0, "--peer");
  if (config.peer.port == 0) throw InputError("--peer: expected ADDRESS:PORT, got '" + options.peer + "'");
  config.cycle = options.cycle_ms * 1e-3;
  config.loss = options.loss;
  config.delay = options.delay_ms * 1e-3;
  config.reorder = options.reorder;
  config.seed = options.seed;
  config.enter_command_mode = !options.monitor_only;
  robot::RobotModel model = loadLwr4();
  if (!options.q.empty()) config.q_initial = parseNumberList(options.q, "--q", model.dof());
  // The arm: the Bullet simulation (robot/sim/), or the controller's built-in joint model.
  // `model` must outlive the Bullet arm, which keeps a reference to it.
  std::unique_ptr<robot::FriSimulatedController> controller_owner;
  std::string arm_model;
  if (options.arm == "bullet") {
    const robot::ParameterSet parameters(robot::simulationParameters());
    auto simulation = std::make_unique<robot::Simulation>(model, nullptr, parameters);
    if (config.q_initial.size() > 0) simulation->reset(config.q_initial);
    controller_owner = std::make_unique<robot::FriSimulatedController>(model, config, std::move(simulation));
    arm_model = "bullet simulation (robot/sim), joint impedance with gravity compensation";
  } else if (options.arm == "impedance") {
    controller_owner = std::make_unique<robot::FriSimulatedController>(model, config);
    arm_model = "per-joint spring-damper (FRI joint impedance law), nominal inertia";
  } else {
    throw InputError("--arm: expected bullet or impedance, got '" + options.arm + "'");
  }
  robot::FriSimulatedController& controller = *controller_owner;
  std::cerr << "fri simulate: robot controller on " << controller.localEndpoint().toString() << ", PC at "
            << config.peer.toString() << std::endl;
  controller.runFor(options.seconds);
  const robot::FriSimulatedControllerStats s = controller.stats();
  return {{"address", controller.localEndpoint().toString()},
          {"peer", config.peer.toString()},
          {"seconds", options.seconds},
          {"cycle_s", config.cycle},
          {"arm_model", arm_model},
          {"cycles", s.cycles},
          {"measurements_sent", s.measurements_sent},
          {"measurements_lost", s.measurements_lost},
          {"measurements_reordered", s.measurements_reordered},
          {"commands_received", s.commands_received},
          {"commands_applied", s.commands_applied},
          {"commands_refused", s.commands_refused},
          {"commands_lost", s.commands_lost},
          {"commands_foreign", s.commands_foreign},
          {"commands_malformed", s.commands_malformed},
          {"answers_matched", s.answers_matched},
          {"answers_unmatched", s.answers_unmatched},
          {"command_mode_entries", s.command_mode_entries},
          {"command_mode_exits", s.command_mode_exits},
          {"state", robot::fri::toString(s.state)},
          {"quality", robot::fri::toString(s.quality)},
          {"answer_rate", s.answer_rate},
          {"q", toJson(s.q)},
          {"q_desired", toJson(s.q_desired)}};
}

}  // namespace

void registerFriCommands(CLI::App& app, CommandRunner& runner) {
  auto* fri = app.add_subcommand("fri", "the real LWR IV over FRI, and a simulated robot controller");
  fri->require_subcommand(1);
  {
    auto* command = fri->add_subcommand("probe", "listen to the robot controller, mirror the arm, hold its posture");
    auto options = std::make_shared<ProbeOptions>();
    command->add_option("--port", options->port, "local UDP port the robot controller sends to")
        ->check(finiteRange(1, 65535))
        ->capture_default_str();
    command->add_option("--robot", options->robot, "the robot controller's address host[:port]")->required();
    command->add_option("--seconds", options->seconds, "how long to listen [s]")->capture_default_str();
    command->add_option("--bind", options->bind, "local address to listen on")->capture_default_str();
    command->add_option("--watchdog-cycles", options->watchdog_cycles, "missed measurements before holding")
        ->check(finiteRange(1, 1000))
        ->capture_default_str();
    command->add_option("--stiffness", options->stiffness, "joint stiffness of the hold [Nm/rad]")
        ->check(finiteRange(0.0, 5000.0))
        ->capture_default_str();
    command->add_option("--damping", options->damping, "normalized joint damping of the hold")
        ->check(finiteRange(0.0, 1.0))
        ->capture_default_str();
    command->callback([&runner, options] { runner.select([options] { return probe(*options); }); });
  }
  {
    auto* command = fri->add_subcommand("simulate", "act as the robot controller over loopback");
    auto options = std::make_shared<SimulateOptions>();
    command->add_option("--port", options->port, "local UDP port of the simulated controller (0: any)")
        ->check(finiteRange(0, 65535))
        ->capture_default_str();
    command->add_option("--peer", options->peer, "the PC's address ADDRESS:PORT (loopback)")->required();
    command->add_option("--seconds", options->seconds, "how long to run [s]")->capture_default_str();
    command->add_option("--cycle-ms", options->cycle_ms, "measurement period [ms]")
        ->check(finiteRange(0.5, 100.0))
        ->capture_default_str();
    command->add_option("--loss", options->loss, "probability that a datagram is lost")
        ->check(finiteRange(0.0, 1.0))
        ->capture_default_str();
    command->add_option("--delay-ms", options->delay_ms, "extra latency of measurements [ms]")
        ->check(finiteRange(0.0, 1000.0))
        ->capture_default_str();
    command->add_option("--reorder", options->reorder, "probability that a measurement is overtaken")
        ->check(finiteRange(0.0, 1.0))
        ->capture_default_str();
    command->add_option("--seed", options->seed, "random seed of the fault injection")->check(seedValidator())->capture_default_str();
    command->add_option("--q", options->q, "initial joint posture q1,...,q7 [rad]");
    command->add_option("--arm", options->arm, "arm model: bullet (robot/sim) or impedance (built-in)")
        ->capture_default_str();
    command->add_flag("--monitor-only", options->monitor_only, "stay in monitor mode (never switch to command)");
    command->callback([&runner, options] { runner.select([options] { return simulate(*options); }); });
  }
}

}  // namespace flexirob::cli
