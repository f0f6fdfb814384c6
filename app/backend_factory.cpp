#include "app/backend_factory.hpp"

#include <cstdio>
#include <utility>

#include "robot/errors.hpp"
#include "robot/fri_protocol.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {
namespace {

constexpr const char* kFriScheme = "fri://";

[[noreturn]] void refuse(const std::string& text, const std::string& reason) {
  throw InputError("backend '" + text + "': " + reason + " (expected 'sim' or 'fri://HOST:PORT')");
}

}  // namespace

BackendChoice parseBackendChoice(const std::string& text) {
  BackendChoice choice;
  choice.text = text;
  if (text == "sim") return choice;
  if (text.empty()) refuse(text, "empty");
  const std::string scheme(kFriScheme);
  if (text.rfind(scheme, 0) != 0) {
    const auto separator = text.find("://");
    refuse(text, separator == std::string::npos ? "unknown backend"
                                                : "unknown scheme '" + text.substr(0, separator) + "'");
  }
  const std::string authority = text.substr(scheme.size());
  if (authority.empty()) refuse(text, "no robot controller address");
  if (authority.find_first_of("/?#") != std::string::npos) refuse(text, "a path or query is not allowed");
  if (authority.find('@') != std::string::npos) refuse(text, "a user part is not allowed");
  const auto colon = authority.rfind(':');
  if (colon == std::string::npos) refuse(text, "no port (the KRC's FRI port, e.g. 49938)");
  if (colon == 0) refuse(text, "no host");
  // Host resolution and the port's range are UdpEndpoint's; its message names this choice.
  choice.kind = BackendKind::kFri;
  try {
    choice.fri.robot = robot::UdpEndpoint::parse(authority, 0, "backend '" + text + "'");
  } catch (const InputError& error) {
    throw InputError(std::string(error.what()) + " (expected 'sim' or 'fri://HOST:PORT')");
  }
  return choice;
}

std::string LinkStatus::summary() const {
  char cycle_text[32];
  std::snprintf(cycle_text, sizeof cycle_text, "%.1f ms", cycle * 1e3);
  if (kind == BackendKind::kSimulation) return backend + " " + link + ", " + cycle_text;
  std::string line = backend + " " + link;
  if (fault) line += " (" + fault_reason + "; confirm to reconnect)";
  if (!quality.empty()) line += ", quality " + quality;
  line += ", ";
  line += cycle_text;
  return line;
}

RobotConnection::RobotConnection(const BackendChoice& choice, const robot::RobotModel& model,
                                 const robot::Scene* scene, const robot::ParameterSet& parameters)
    : RobotConnection(choice, [&]() -> std::unique_ptr<robot::RobotBackend> {
        if (choice.kind == BackendKind::kFri) return std::make_unique<robot::FriBackend>(model, choice.fri);
        return std::make_unique<robot::Simulation>(model, scene, parameters);
      }()) {}

RobotConnection::RobotConnection(BackendChoice choice, std::unique_ptr<robot::RobotBackend> backend)
    : choice_(std::move(choice)), backend_(std::move(backend)) {
  if (!backend_) throw InputError("robot connection: no backend");
  fri_ = dynamic_cast<robot::FriBackend*>(backend_.get());
  choice_.kind = fri_ ? BackendKind::kFri : BackendKind::kSimulation;
  state_.resize(backend_->model().dof());
  publish();
}

RobotConnection::~RobotConnection() = default;

robot::CommandStatus RobotConnection::writeCommand(const robot::JointImpedanceCommand& command) {
  const robot::CommandStatus status = backend_->writeCommand(command);
  if (!fri_ && status == robot::CommandStatus::kRejected) ++sim_rejections_;
  return status;
}

void RobotConnection::step() {
  backend_->step();
  ++steps_;
  if (reconnect_requested_.exchange(false, std::memory_order_acq_rel)) {
    // Only the FRI backend has a watchdog; for the simulation a confirmation has nothing to do.
    if (fri_ && fri_->status().link == robot::FriLink::kFault) {
      ++(fri_->confirmReconnect() ? reconnects_ : reconnects_refused_);
    }
  }
  publish();
}

void RobotConnection::publish() {
  // Assignments into building_ reuse the strings' capacity after the first cycles, so a
  // steady control loop does not allocate here.
  LinkStatus& s = building_;
  s.kind = choice_.kind;
  s.backend = choice_.text;
  s.cycle = backend_->cycleTime();
  backend_->readState(state_);
  s.time = state_.time;
  s.reconnects = reconnects_;
  s.reconnects_refused = reconnects_refused_;
  if (!fri_) {
    s.link = "simulated";
    s.commanding = true;
    s.measurements = steps_;
    s.commands_rejected = sim_rejections_;
  } else {
    const robot::FriStatus& fri = fri_->status();
    const robot::FriCounters& c = fri.counters;
    s.link = robot::toString(fri.link);
    s.state = fri_->hasMeasurement() ? robot::fri::interfaceStateName(fri.state) : "";
    s.quality = fri_->hasMeasurement() ? robot::fri::qualityName(fri.quality) : "";
    s.control = fri_->hasMeasurement() ? robot::fri::controlModeName(fri.control) : "";
    s.commanding = fri.link == robot::FriLink::kCommanding;
    s.fault = fri.link == robot::FriLink::kFault;
    s.fault_reason = s.fault ? robot::toString(fri.fault) : "";
    s.last_rejection = fri.last_rejection == robot::FriRejection::kNone ? "" : robot::toString(fri.last_rejection);
    s.answer_rate = static_cast<double>(fri.statistics.answer_rate);
    s.latency = static_cast<double>(fri.statistics.latency);
    s.measurements = c.measurements_accepted;
    s.lost_measurements = c.lost_measurements;
    s.dropped_datagrams =
        c.foreign_dropped + c.short_dropped + c.oversized_dropped + c.malformed_dropped + c.out_of_order_dropped;
    s.commands_rejected = c.commands_rejected;
    s.watchdog_trips = c.watchdog_trips;
  }
  // Never wait on a reader: a reader holding the lock costs this cycle's publication only.
  std::unique_lock lock(status_mutex_, std::try_to_lock);
  if (lock.owns_lock()) published_ = building_;
}

LinkStatus RobotConnection::status() const {
  std::lock_guard lock(status_mutex_);
  return published_;
}

}  // namespace flexirob::app
