#include "robot/fri_backend.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace {

template <std::size_t N>
bool allFinite(const std::array<float, N>& values) {
  return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

// The KRC's sample time is trusted only within FRI's range (1-10 ms, with margin).
bool plausibleCycle(double cycle) { return std::isfinite(cycle) && cycle >= 1e-4 && cycle <= 0.1; }

}  // namespace

const char* toString(FriLink link) {
  switch (link) {
    case FriLink::kWaiting: return "waiting";
    case FriLink::kMonitoring: return "monitoring";
    case FriLink::kCommanding: return "commanding";
    case FriLink::kFault: return "fault";
  }
  return "unknown";
}

const char* toString(FriFault fault) {
  switch (fault) {
    case FriFault::kNone: return "none";
    case FriFault::kMeasurementTimeout: return "measurement timeout";
    case FriFault::kMeasurementsLost: return "measurements lost";
    case FriFault::kControlLoopLate: return "control loop late";
  }
  return "unknown";
}

const char* toString(FriRejection rejection) {
  switch (rejection) {
    case FriRejection::kNone: return "none";
    case FriRejection::kInvalid: return "invalid command";
    case FriRejection::kPositionLimit: return "outside the software position limits";
    case FriRejection::kVelocityLimit: return "exceeds the velocity limits";
    case FriRejection::kNotPermitted: return "commanding not permitted";
  }
  return "unknown";
}

FriBackendConfig friConfigFromUri(const std::string& uri) {
  const std::string scheme = "fri://";
  if (uri.rfind(scheme, 0) != 0 || uri.size() == scheme.size()) {
    throw InputError("backend: expected fri://HOST[:PORT], got '" + uri + "'");
  }
  FriBackendConfig config;
  config.robot = UdpEndpoint::parse(uri.substr(scheme.size()), 0, "backend " + uri);
  return config;
}

FriBackend::FriBackend(RobotModel model, FriBackendConfig config)
    : FriBackend(std::move(model), config, UdpSocket(config.local_address, config.local_port)) {}

FriBackend::FriBackend(RobotModel model, FriBackendConfig config, UdpSocket socket)
    : model_(std::move(model)),
      config_(std::move(config)),
      socket_(std::move(socket)),
      kinematics_(model_),
      cycle_(config_.nominal_cycle) {
  if (model_.dof() != fri::kJoints) {
    throw InputError("FRI backend: expected a robot with " + std::to_string(fri::kJoints) +
                     " joints (the LWR IV), got " + std::to_string(model_.dof()));
  }
  if (config_.robot.address == 0) throw InputError("FRI backend: the robot controller's address is required");
  if (config_.watchdog_cycles < 1 || config_.watchdog_cycles > 1000) {
    throw InputError("FRI backend: expected watchdog cycles in [1, 1000], got " +
                     std::to_string(config_.watchdog_cycles));
  }
  if (config_.lockstep && !(config_.lockstep_timeout >= 1e-3 && config_.lockstep_timeout <= 3600.0)) {
    throw InputError("FRI backend: expected a lockstep timeout in [0.001, 3600] s, got " +
                     std::to_string(config_.lockstep_timeout));
  }
  if (!plausibleCycle(config_.nominal_cycle)) {
    throw InputError("FRI backend: expected a nominal cycle in [1e-4, 0.1] s, got " +
                     std::to_string(config_.nominal_cycle));
  }
  if (!(config_.max_stiffness >= 0.0) || !(config_.hold_stiffness >= 0.0) ||
      config_.hold_stiffness > config_.max_stiffness || !(config_.hold_damping >= 0.0) ||
      config_.hold_damping > 1.0 || !(config_.velocity_tolerance >= 0.0)) {
    throw InputError("FRI backend: hold stiffness must lie in [0, max_stiffness] and hold damping in [0, 1]");
  }
  const int dof = model_.dof();
  state_.resize(dof);
  previous_q_.setZero(dof);
  reference_q_.setZero(dof);
  reference_stiffness_.setConstant(dof, config_.hold_stiffness);
  reference_damping_.setConstant(dof, config_.hold_damping);
  limited_q_.setZero(dof);
  status_.cycle = cycle_;
}

void FriBackend::readState(RobotState& state) const {
  state.time = state_.time;
  state.q = state_.q;
  state.qd = state_.qd;
  state.q_cmd = state_.q_cmd;
  state.tau_ext = state_.tau_ext;
  state.X_WT = state_.X_WT;
  state.in_contact = false;
}

bool FriBackend::commandingPermitted() const {
  return has_measurement_ && !fault_ &&
         measurement_.intf.state == static_cast<std::uint16_t>(fri::InterfaceState::kCommand) &&
         measurement_.intf.quality >= static_cast<std::uint16_t>(config_.min_quality) &&
         measurement_.intf.quality <= static_cast<std::uint16_t>(fri::Quality::kPerfect) &&
         measurement_.robot.control == static_cast<std::uint16_t>(fri::ControlMode::kJointImpedance);
}

void FriBackend::updateLink() {
  if (!has_measurement_) {
    status_.link = FriLink::kWaiting;
  } else if (fault_) {
    status_.link = FriLink::kFault;
  } else if (commandingPermitted()) {
    status_.link = FriLink::kCommanding;
  } else {
    status_.link = FriLink::kMonitoring;
  }
}

void FriBackend::tripWatchdog(FriFault fault) {
  // Stop forwarding; the answers from now on carry the held posture.
  if (!fault_) ++status_.counters.watchdog_trips;
  fault_ = true;
  command_active_ = false;
  status_.fault = fault;
  updateLink();
}

CommandStatus FriBackend::writeCommand(const JointImpedanceCommand& command) {
  const auto reject = [this](FriRejection reason) {
    ++status_.counters.commands_rejected;
    status_.last_rejection = reason;
    return CommandStatus::kRejected;
  };
  const int dof = model_.dof();
  // 1. Well-formed: sizes, finite values, stiffness and (normalized) damping in range.
  if (command.q_cmd.size() != dof || command.stiffness.size() != dof || command.damping.size() != dof ||
      !command.q_cmd.allFinite() || !command.stiffness.allFinite() || !command.damping.allFinite() ||
      (command.stiffness.array() < 0.0).any() || (command.stiffness.array() > config_.max_stiffness).any() ||
      (command.damping.array() < 0.0).any() || (command.damping.array() > 1.0).any()) {
    return reject(FriRejection::kInvalid);
  }
  // 2. Inside the software position limits (the URDF's safety controller).
  for (int j = 0; j < dof; ++j) {
    const auto& limits = model_.joints()[static_cast<std::size_t>(j)].limits;
    if (command.q_cmd[j] < limits.soft_lower || command.q_cmd[j] > limits.soft_upper) {
      return reject(FriRejection::kPositionLimit);
    }
  }
  // 3. The robot is in a state where commands act: CMD, joint impedance, quality, no fault.
  if (!commandingPermitted()) return reject(FriRejection::kNotPermitted);
  // 4. No joint faster than its velocity limit over one cycle, from what was sent last. A
  // faster command is refused, or (kRateLimit) the posture that leaves moves towards it at the
  // velocity limit, so that a mode switch of the controller (a new posture at low stiffness)
  // never makes the arm jump and the reference catches up within a few cycles.
  bool limited = false;
  limited_q_ = command.q_cmd;
  for (int j = 0; j < dof; ++j) {
    const double v_max = model_.joints()[static_cast<std::size_t>(j)].limits.velocity;
    const double step_max = v_max * cycle_ * (1.0 + config_.velocity_tolerance);
    const double step = command.q_cmd[j] - reference_q_[j];
    if (std::abs(step) <= step_max) continue;
    if (config_.velocity_policy == FriVelocityPolicy::kReject) return reject(FriRejection::kVelocityLimit);
    limited_q_[j] = reference_q_[j] + std::copysign(v_max * cycle_, step);
    limited = true;
  }
  if (limited) {
    ++status_.counters.commands_rate_limited;
    status_.last_rejection = FriRejection::kVelocityLimit;
  }
  reference_q_ = limited_q_;
  reference_stiffness_ = command.stiffness;
  reference_damping_ = command.damping;
  command_active_ = true;
  if (reply_pending_) sendReply();
  return CommandStatus::kAccepted;
}

void FriBackend::sendReply() {
  reply_pending_ = false;
  if (!has_measurement_) return;
  reply_.header.send_seq = ++reply_sequence_;
  reply_.header.refl_seq = measurement_.header.send_seq;
  reply_.header.packet_size = static_cast<std::uint16_t>(fri::kCommandSize);
  reply_.header.datagram_id = fri::kCommandDatagramId;
  // Flags follow the KRC's controller: joint impedance sets posture, stiffness and damping;
  // position control only the posture; other controllers get no joint command from us.
  const bool command_state = measurement_.intf.state == static_cast<std::uint16_t>(fri::InterfaceState::kCommand);
  switch (static_cast<fri::ControlMode>(measurement_.robot.control)) {
    case fri::ControlMode::kJointImpedance: reply_.cmd.flags = fri::command_flags::kJointImpedance; break;
    case fri::ControlMode::kPosition: reply_.cmd.flags = fri::command_flags::kJointPosition; break;
    default: reply_.cmd.flags = 0; break;
  }
  for (int j = 0; j < fri::kJoints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    reply_.cmd.jnt_pos[i] = static_cast<float>(reference_q_[j]);
    reply_.cmd.jnt_stiffness[i] = static_cast<float>(reference_stiffness_[j]);
    reply_.cmd.jnt_damping[i] = static_cast<float>(reference_damping_[j]);
  }
  fri::encode(reply_, reply_bytes_);
  if (socket_.sendTo(reply_bytes_, reply_to_)) {
    ++status_.counters.replies_sent;
    if (command_state && command_active_ && commandingPermitted()) {
      ++status_.counters.commands_sent;
    } else {
      ++status_.counters.hold_replies;
    }
  } else {
    ++status_.counters.send_failures;
  }
  unanswered_ = 0;
  last_reply_time_ = Clock::now();
  status_.last_reply_seq = reply_sequence_;
}

bool FriBackend::accept(const fri::MeasurementDatagram& measurement, int gap) {
  const bool was_command_state =
      has_measurement_ && measurement_.intf.state == static_cast<std::uint16_t>(fri::InterfaceState::kCommand);
  measurement_ = measurement;
  const auto previous_time = last_measurement_time_;
  const auto now = Clock::now();
  has_measurement_ = true;
  last_measurement_time_ = now;

  const double krc_cycle = static_cast<double>(measurement.intf.desired_msr_sample_time);
  if (plausibleCycle(krc_cycle)) cycle_ = krc_cycle;

  // Mirror: q, q̇ by the difference over the cycles elapsed, q_cmd, τ_ext, X_WT.
  for (int j = 0; j < fri::kJoints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    state_.q[j] = static_cast<double>(measurement.data.msr_jnt_pos[i]);
    state_.q_cmd[j] = static_cast<double>(measurement.data.cmd_jnt_pos[i]) +
                      static_cast<double>(measurement.data.cmd_jnt_pos_fri_offset[i]);
    state_.tau_ext[j] = static_cast<double>(measurement.data.est_ext_jnt_trq[i]);
  }
  if (gap > 0) {
    state_.qd = (state_.q - previous_q_) / (gap * cycle_);
    cycles_since_start_ += static_cast<std::uint64_t>(gap);
  } else {
    // No sequence to go by: no velocity estimate; the clock advances by the wall-clock gap
    // (by one cycle in lockstep, where the wall clock says nothing about the KRC's cycles).
    state_.qd.setZero();
    if (status_.counters.measurements_accepted > 0) {
      const double silence = std::chrono::duration<double>(now - previous_time).count();
      cycles_since_start_ +=
          config_.lockstep ? 1U : static_cast<std::uint64_t>(std::max(1.0, std::round(silence / cycle_)));
    }
  }
  previous_q_ = state_.q;
  state_.time = static_cast<double>(cycles_since_start_) * cycle_;
  kinematics_.update(state_.q);
  state_.X_WT = kinematics_.X_WT();
  ++status_.counters.measurements_accepted;

  // The posture to hold: outside command state it follows the arm, so that the switch to CMD
  // starts from where the arm is (no jump); on entering CMD it is latched there.
  const bool command_state = measurement.intf.state == static_cast<std::uint16_t>(fri::InterfaceState::kCommand);
  if (!command_state || !was_command_state) {
    reference_q_ = state_.q;
    command_active_ = false;
  }
  if (command_state && measurement.intf.quality < static_cast<std::uint16_t>(config_.min_quality)) {
    ++status_.counters.quality_holds;
  }

  status_.state = measurement.intf.state;
  status_.quality = measurement.intf.quality;
  status_.control = measurement.robot.control;
  status_.power = measurement.robot.power;
  status_.error = measurement.robot.error;
  status_.warning = measurement.robot.warning;
  status_.statistics = measurement.intf.statistics;
  status_.cycle = cycle_;
  status_.last_measurement_seq = measurement.header.send_seq;
  status_.last_reflected_seq = measurement.header.refl_seq;
  reply_pending_ = true;
  ++unanswered_;
  return true;
}

bool FriBackend::drainSocket() {
  auto& counters = status_.counters;
  std::optional<fri::MeasurementDatagram> newest;
  UdpEndpoint newest_from;
  int newest_gap = 0;
  bool resync = false;  // a measurement without a sequence to go by was among them
  int valid_count = 0;
  fri::MeasurementDatagram candidate;
  while (auto received = socket_.receive(receive_buffer_)) {
    ++counters.datagrams_received;
    // Only the configured robot: its address, and its port if one was given.
    if (received->from.address != config_.robot.address ||
        (config_.robot.port != 0 && received->from.port != config_.robot.port)) {
      ++counters.foreign_dropped;
      continue;
    }
    if (received->truncated || received->size > fri::kMeasurementSize) {
      ++counters.oversized_dropped;
      continue;
    }
    if (received->size < fri::kMeasurementSize) {
      ++counters.short_dropped;
      continue;
    }
    const std::span<const std::uint8_t> bytes(receive_buffer_.data(), received->size);
    if (fri::decode(bytes, candidate) != fri::DecodeStatus::kOk || !allFinite(candidate.data.msr_jnt_pos) ||
        !allFinite(candidate.data.cmd_jnt_pos) || !allFinite(candidate.data.cmd_jnt_pos_fri_offset) ||
        !allFinite(candidate.data.est_ext_jnt_trq)) {
      ++counters.malformed_dropped;
      continue;
    }
    // Sequence: repeated or older datagrams (reordering, duplicates) are dropped; gaps are losses.
    // gap 0: unknown (first measurement, or a resync after a silence).
    int gap = 0;
    if (has_sequence_) {
      gap = fri::sequenceDistance(candidate.header.send_seq, last_sequence_);
      if (gap <= 0) {
        ++counters.out_of_order_dropped;
        continue;
      }
      counters.lost_measurements += static_cast<std::uint64_t>(gap - 1);
      if (gap - 1 >= config_.watchdog_cycles && has_measurement_) tripWatchdog(FriFault::kMeasurementsLost);
    }
    has_sequence_ = true;
    last_sequence_ = candidate.header.send_seq;
    newest_gap += gap;
    resync = resync || gap == 0;
    ++valid_count;
    newest = candidate;
    newest_from = received->from;
  }
  if (!newest) return false;
  // Measurements we never answered because our loop came late count as missed cycles too.
  const int skipped = valid_count - 1 + unanswered_;
  counters.stale_skipped += static_cast<std::uint64_t>(valid_count - 1);
  if (skipped >= config_.watchdog_cycles && has_measurement_) tripWatchdog(FriFault::kControlLoopLate);
  reply_to_ = newest_from;  // answer where the measurement came from (the checked robot)
  return accept(*newest, resync ? 0 : newest_gap);
}

void FriBackend::step() {
  // Answer the measurement of the previous cycle if the caller wrote no command for it.
  if (reply_pending_) sendReply();
  const auto timeout = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(watchdogTimeout()));
  const auto start = Clock::now();
  // Wait for the measurement that is due; once it is overdue, wait at most one more timeout so
  // that a silent link neither spins nor blocks.
  // The timeout runs from the last measurement or from our answer to it, whichever came later:
  // a measurement is not late for an answer we had not sent yet. (If our loop was late while the
  // KRC kept sending, the measurements that piled up trip the watchdog in drainSocket().)
  const auto since = std::max(last_measurement_time_, last_reply_time_);
  auto deadline = has_measurement_ ? since + timeout : start + timeout;
  if (deadline <= start) deadline = start + timeout;
  for (;;) {
    if (drainSocket()) {
      updateLink();
      return;
    }
    const auto now = Clock::now();
    if (has_measurement_ && !fault_ && now - since >= timeout) {
      tripWatchdog(FriFault::kMeasurementTimeout);
      // After a silence the KRC may have restarted its counter: take the next one as it comes.
      has_sequence_ = false;
    }
    if (now >= deadline) break;
    socket_.waitReadable(std::chrono::duration<double>(deadline - now).count());
  }
  ++status_.counters.step_timeouts;
  updateLink();
}

bool FriBackend::confirmReconnect() {
  if (!fault_) return true;
  const auto timeout = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(watchdogTimeout()));
  if (!has_measurement_ || Clock::now() - last_measurement_time_ > timeout) return false;
  fault_ = false;
  command_active_ = false;
  updateLink();
  return true;
}

}  // namespace flexirob::robot
