#include "robot/fri_simulated_controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace {

constexpr std::size_t kAnswerWindow = 100;  // the KRC averages over its last 100 packets
constexpr int kQualityCyclesBeforeCommand = 10;
constexpr double kMaxSubstep = 0.5e-3;      // [s] integration step of the arm model
constexpr double kKrcMaxStiffness = 5000.0;  // [Nm/rad] what this stand-in accepts

void requireRange(double value, double low, double high, const std::string& what) {
  if (!(value >= low && value <= high)) {
    throw InputError("simulated controller: expected " + what + " in [" + printableNumber(low) + ", " +
                     printableNumber(high) + "], got " + printableNumber(value));
  }
}

// Quality from the answer rate (our thresholds; the KRC's own are configured on the KRC).
fri::Quality qualityFromAnswerRate(double rate) {
  if (rate >= 0.95) return fri::Quality::kPerfect;
  if (rate >= 0.8) return fri::Quality::kOk;
  if (rate >= 0.5) return fri::Quality::kBad;
  return fri::Quality::kUnacceptable;
}

}  // namespace

FriSimulatedController::FriSimulatedController(RobotModel model, FriSimulatedControllerConfig config)
    : model_(std::move(model)),
      config_(std::move(config)),
      socket_("127.0.0.1", config_.port),
      kinematics_(model_),
      random_(config_.seed) {
  if (model_.dof() != fri::kJoints) {
    throw InputError("simulated controller: expected a 7-joint robot (the LWR IV), got " +
                     std::to_string(model_.dof()) + " joints");
  }
  if (!config_.peer.isLoopback() || config_.peer.port == 0) {
    throw InputError("simulated controller: the peer must be a loopback address with a port, got " +
                     config_.peer.toString());
  }
  requireRange(config_.cycle, 5e-4, 0.1, "cycle [s]");
  requireRange(config_.loss, 0.0, 1.0, "loss probability");
  requireRange(config_.delay, 0.0, 1.0, "delay [s]");
  requireRange(config_.reorder, 0.0, 1.0, "reorder probability");
  requireRange(config_.joint_inertia, 1e-3, 100.0, "joint inertia [kg m^2]");
  requireRange(config_.viscous_damping, 0.0, 1e3, "viscous damping [Nm s/rad]");
  requireRange(config_.krl_stiffness, 0.0, kKrcMaxStiffness, "KRL stiffness [Nm/rad]");
  requireRange(config_.krl_damping, 0.0, 1.0, "KRL damping");
  requireRange(config_.lockstep_patience, 0.0, 3600.0, "lockstep patience [s]");
  const int dof = model_.dof();
  if (config_.q_initial.size() == 0) {
    q_ = model_.midPosture();
  } else {
    model_.checkPosture(config_.q_initial);
    q_ = config_.q_initial.cwiseMax(model_.lowerLimits()).cwiseMin(model_.upperLimits());
  }
  qd_.setZero(dof);
  q_desired_ = q_;
  krl_q_ = q_;
  stiffness_.setConstant(dof, config_.krl_stiffness);
  damping_.setConstant(dof, config_.krl_damping);
  tau_ext_.setZero(dof);
  external_torque_.setZero(dof);
  sent_.resize(128);
  stats_.q = q_;
  stats_.q_desired = q_desired_;
  stats_.stiffness = stiffness_;
}

FriSimulatedController::FriSimulatedController(RobotModel model, FriSimulatedControllerConfig config,
                                               std::unique_ptr<RobotBackend> arm)
    : FriSimulatedController(std::move(model), std::move(config)) {
  if (!arm || arm->model().dof() != model_.dof()) {
    throw InputError("simulated controller: the arm model must be a 7-joint robot backend");
  }
  const double ratio = config_.cycle / arm->cycleTime();
  arm_steps_per_cycle_ = static_cast<int>(std::lround(ratio));
  if (arm_steps_per_cycle_ < 1 || std::abs(ratio - arm_steps_per_cycle_) > 1e-6) {
    throw InputError("simulated controller: the cycle " + std::to_string(config_.cycle) +
                     " s is no whole multiple of the arm's cycle " + std::to_string(arm->cycleTime()) + " s");
  }
  arm_ = std::move(arm);
  arm_state_.resize(model_.dof());
  arm_command_.resize(model_.dof());
  arm_->readState(arm_state_);
  q_ = arm_state_.q;
  q_desired_ = q_;
  krl_q_ = q_;
  stats_.q = q_;
  stats_.q_desired = q_desired_;
}

FriSimulatedController::~FriSimulatedController() { stop(); }

void FriSimulatedController::start() {
  if (thread_.joinable()) return;
  stop_requested_ = false;
  thread_ = std::thread([this] { run(std::numeric_limits<double>::infinity()); });
}

void FriSimulatedController::stop() {
  stop_requested_ = true;
  if (thread_.joinable()) thread_.join();
}

void FriSimulatedController::runFor(double seconds) {
  stop_requested_ = false;
  run(seconds);
}

FriSimulatedControllerStats FriSimulatedController::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void FriSimulatedController::injectRaw(std::vector<std::uint8_t> bytes) {
  std::lock_guard lock(mutex_);
  injected_.push_back(std::move(bytes));
}

void FriSimulatedController::setExternalTorque(const Eigen::VectorXd& tau_ext) {
  if (tau_ext.size() != model_.dof() || !tau_ext.allFinite()) {
    throw InputError("simulated controller: expected 7 finite external torques");
  }
  std::lock_guard lock(mutex_);
  external_torque_ = tau_ext;
}

void FriSimulatedController::run(double seconds) {
  if (config_.lockstep) {
    runLockstep(seconds);
    return;
  }
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto elapsed = [&start] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  double next_cycle = 0.0;
  while (!stop_requested_) {
    double now = elapsed();
    if (now >= seconds) break;
    if (now >= next_cycle) {
      cycle(now);
      next_cycle += config_.cycle;
      // Fell behind (a loaded machine): skip, as a burst of catch-up packets helps nobody.
      if (next_cycle < now) next_cycle = now + config_.cycle;
    }
    sendDue(now);
    receiveCommands(now);
    // Sleep until the next cycle, the next delayed packet or a command, whichever comes first.
    double wake = std::min(next_cycle, seconds);
    for (const auto& packet : outgoing_) wake = std::min(wake, packet.due);
    now = elapsed();
    if (wake > now) socket_.waitReadable(wake - now);
  }
}

void FriSimulatedController::runLockstep(double seconds) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto elapsed = [&start] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  // A stop() must be seen within this wall-clock time while we wait for an answer.
  constexpr double kPoll = 0.01;  // [s]
  while (!stop_requested_ && elapsed() < seconds) {
    const double now = static_cast<double>(lockstep_cycles_++) * config_.cycle;  // simulated time
    cycle(now);
    const std::uint16_t awaited = send_seq_;
    sendDue(now + config_.delay);  // no wall-clock delay to wait out: the clock is simulated
    // Wait for the PC's answer to this measurement, however long the PC takes (a measurement
    // lost or held back gets none, and an answer the loss injection dropped never arrives: go on).
    answer_lost_ = false;
    const double wait_start = elapsed();
    const bool patient = config_.lockstep_patience <= 0.0;
    const auto answered = [&] { return last_reflected_seq_ == awaited || (answer_lost_ && lost_answer_seq_ == awaited); };
    while (measurement_left_ && !stop_requested_ && !answered()) {
      receiveCommands(now);
      if (answered()) break;
      const double waited = elapsed() - wait_start;
      if (!patient && waited >= config_.lockstep_patience) break;
      socket_.waitReadable(patient ? kPoll : std::min(kPoll, config_.lockstep_patience - waited));
    }
    receiveCommands(now);
  }
}

void FriSimulatedController::cycle(double now) {
  {
    std::lock_guard lock(mutex_);
    tau_ext_ = external_torque_;
  }
  integrate(config_.cycle);
  updateQuality();

  // The KRL script's part: enter command mode once the link is good, leave it when it is not.
  if (state_ == fri::InterfaceState::kMonitor) {
    good_quality_cycles_ = quality_ >= fri::Quality::kOk ? good_quality_cycles_ + 1 : 0;
    if (config_.enter_command_mode && good_quality_cycles_ >= kQualityCyclesBeforeCommand) {
      state_ = fri::InterfaceState::kCommand;
      q_desired_ = q_;
      krl_q_ = q_;
      std::lock_guard lock(mutex_);
      ++stats_.command_mode_entries;
    }
  } else if (state_ == fri::InterfaceState::kCommand && quality_ == fri::Quality::kUnacceptable) {
    state_ = fri::InterfaceState::kMonitor;
    good_quality_cycles_ = 0;
    q_desired_ = q_;
    krl_q_ = q_;
    stiffness_.setConstant(config_.krl_stiffness);
    damping_.setConstant(config_.krl_damping);
    std::lock_guard lock(mutex_);
    ++stats_.command_mode_exits;
  }

  // This cycle's measurement; the sequence counter advances even for lost ones.
  fri::MeasurementDatagram measurement;
  ++send_seq_;
  fillMeasurement(measurement, now);
  sent_[sent_next_] = SentRecord{send_seq_, now, false, true};
  sent_next_ = (sent_next_ + 1) % sent_.size();
  Outgoing packet;
  packet.due = now + config_.delay;
  fri::encode(measurement, packet.bytes);

  std::uint64_t lost = 0;
  std::uint64_t reordered = 0;
  measurement_left_ = false;
  if (drop_next_ > 0) {
    --drop_next_;
    lost = 1;
  } else if (config_.loss > 0.0 && uniform_(random_) < config_.loss) {
    lost = 1;
  } else if (held_back_) {
    // The held measurement is overtaken: it leaves right after this one.
    outgoing_.push_back(packet);
    held_back_->due = packet.due;
    outgoing_.push_back(*held_back_);
    held_back_.reset();
    reordered = 1;
    measurement_left_ = true;
  } else if (config_.reorder > 0.0 && uniform_(random_) < config_.reorder) {
    held_back_ = packet;
  } else {
    outgoing_.push_back(packet);
    measurement_left_ = true;
  }

  std::vector<std::vector<std::uint8_t>> injected;
  {
    std::lock_guard lock(mutex_);
    injected.swap(injected_);
    ++stats_.cycles;
    stats_.measurements_lost += lost;
    stats_.measurements_reordered += reordered;
    stats_.last_measurement_seq = send_seq_;
    stats_.state = state_;
    stats_.quality = quality_;
    stats_.q = q_;
    stats_.q_desired = q_desired_;
    stats_.stiffness = stiffness_;
  }
  for (const auto& bytes : injected) socket_.sendTo(bytes, config_.peer);
}

void FriSimulatedController::sendDue(double now) {
  // Keep the queue's order: a delayed packet never overtakes an earlier one by accident.
  std::size_t sent = 0;
  while (sent < outgoing_.size() && outgoing_[sent].due <= now) {
    socket_.sendTo(outgoing_[sent].bytes, config_.peer);
    ++sent;
  }
  if (sent == 0) return;
  outgoing_.erase(outgoing_.begin(), outgoing_.begin() + static_cast<std::ptrdiff_t>(sent));
  std::lock_guard lock(mutex_);
  stats_.measurements_sent += sent;
}

void FriSimulatedController::receiveCommands(double now) {
  fri::CommandDatagram command;
  while (auto received = socket_.receive(buffer_)) {
    if (!(received->from == config_.peer)) {
      std::lock_guard lock(mutex_);
      ++stats_.commands_foreign;
      continue;
    }
    const bool valid =
        !received->truncated &&
        fri::decode(std::span<const std::uint8_t>(buffer_.data(), received->size), command) == fri::DecodeStatus::kOk;
    if (config_.loss > 0.0 && uniform_(random_) < config_.loss) {
      // Lost in transit; lockstep must not wait for it.
      if (valid) {
        answer_lost_ = true;
        lost_answer_seq_ = command.header.refl_seq;
      }
      std::lock_guard lock(mutex_);
      ++stats_.commands_lost;
      continue;
    }
    if (!valid) {
      std::lock_guard lock(mutex_);
      ++stats_.commands_malformed;
      continue;
    }
    // Match the answer to the measurement it reflects.
    bool matched = false;
    for (auto& record : sent_) {
      if (record.valid && record.seq == command.header.refl_seq) {
        if (!record.answered) latency_sum_ += now - record.time;
        record.answered = true;
        matched = true;
        break;
      }
    }
    last_command_seq_ = command.header.send_seq;
    last_reflected_seq_ = command.header.refl_seq;
    {
      std::lock_guard lock(mutex_);
      ++stats_.commands_received;
      ++(matched ? stats_.answers_matched : stats_.answers_unmatched);
      stats_.last_command_seq = command.header.send_seq;
      stats_.last_reflected_seq = command.header.refl_seq;
    }
    applyCommand(command);
  }
}

void FriSimulatedController::applyCommand(const fri::CommandDatagram& command) {
  if (state_ != fri::InterfaceState::kCommand) return;  // monitor mode: commands are ignored
  const std::uint32_t flags = command.cmd.flags;
  const int dof = model_.dof();
  Eigen::VectorXd q_target = q_desired_;
  Eigen::VectorXd stiffness = stiffness_;
  Eigen::VectorXd damping = damping_;
  bool refused = false;
  for (int j = 0; j < dof; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const auto& limits = model_.joints()[i].limits;
    if ((flags & fri::command_flags::kJointPosition) != 0) {
      const double target = static_cast<double>(command.cmd.jnt_pos[i]);
      // A jump beyond the velocity limit over the cycle (with slack for float rounding and a
      // lost command in between) or outside the hardware limits is refused.
      const double max_step = limits.velocity * config_.cycle * 2.5;
      refused = refused || !std::isfinite(target) || target < limits.lower || target > limits.upper ||
                std::abs(target - q_desired_[j]) > max_step;
      q_target[j] = target;
    }
    if (config_.control == fri::ControlMode::kJointImpedance && (flags & fri::command_flags::kJointStiffness) != 0) {
      const double k = static_cast<double>(command.cmd.jnt_stiffness[i]);
      refused = refused || !(k >= 0.0 && k <= kKrcMaxStiffness);
      stiffness[j] = k;
    }
    if (config_.control == fri::ControlMode::kJointImpedance && (flags & fri::command_flags::kJointDamping) != 0) {
      const double d = static_cast<double>(command.cmd.jnt_damping[i]);
      refused = refused || !(d >= 0.0 && d <= 1.0);
      damping[j] = d;
    }
  }
  std::lock_guard lock(mutex_);
  if (refused) {
    ++stats_.commands_refused;
    return;
  }
  q_desired_ = q_target;
  stiffness_ = stiffness;
  damping_ = damping;
  ++stats_.commands_applied;
}

void FriSimulatedController::integrate(double dt) {
  if (arm_) {
    const std::lock_guard arm_lock(arm_mutex_);
    // The external arm runs its own joint impedance law around the command in force.
    arm_command_.q_cmd = q_desired_;
    arm_command_.stiffness = stiffness_;
    arm_command_.damping = damping_;
    arm_->writeCommand(arm_command_);
    for (int k = 0; k < arm_steps_per_cycle_; ++k) arm_->step();
    arm_->readState(arm_state_);
    q_ = arm_state_.q;
    qd_ = arm_state_.qd;
    tau_ext_ = arm_state_.tau_ext;
    return;
  }
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt / kMaxSubstep)));
  const double h = dt / substeps;
  const double m = config_.joint_inertia;
  const Eigen::VectorXd lower = model_.lowerLimits();
  const Eigen::VectorXd upper = model_.upperLimits();
  for (int s = 0; s < substeps; ++s) {
    for (Eigen::Index j = 0; j < q_.size(); ++j) {
      // FRI's joint impedance: spring to q_d, damping 2ζ sqrt(K m), plus the external torque.
      const double d = 2.0 * damping_[j] * std::sqrt(stiffness_[j] * m) + config_.viscous_damping;
      const double torque = stiffness_[j] * (q_desired_[j] - q_[j]) - d * qd_[j] + tau_ext_[j];
      qd_[j] += torque / m * h;  // semi-implicit Euler
      q_[j] += qd_[j] * h;
      if (q_[j] < lower[j] || q_[j] > upper[j]) {
        q_[j] = std::clamp(q_[j], lower[j], upper[j]);
        qd_[j] = 0.0;
      }
    }
  }
}

void FriSimulatedController::updateQuality() {
  // Answer rate over the last measurements whose answer is due by now.
  const double now_limit = sent_[(sent_next_ + sent_.size() - 1) % sent_.size()].time - config_.delay - config_.cycle;
  std::size_t due = 0;
  std::size_t answered = 0;
  for (std::size_t k = 1; k <= sent_.size() && due < kAnswerWindow; ++k) {
    const auto& record = sent_[(sent_next_ + sent_.size() - k) % sent_.size()];
    if (!record.valid) break;
    if (record.time > now_limit) continue;
    ++due;
    if (record.answered) ++answered;
  }
  const double rate = due == 0 ? 0.0 : static_cast<double>(answered) / static_cast<double>(due);
  quality_ = due < 10 ? fri::Quality::kUnacceptable : qualityFromAnswerRate(rate);
  std::lock_guard lock(mutex_);
  stats_.answer_rate = rate;
}

void FriSimulatedController::fillMeasurement(fri::MeasurementDatagram& m, double now) {
  m.header.send_seq = send_seq_;
  m.header.refl_seq = last_command_seq_;
  m.intf.timestamp = static_cast<float>(now);
  m.intf.state = static_cast<std::uint16_t>(state_);
  m.intf.quality = static_cast<std::uint16_t>(quality_);
  m.intf.desired_msr_sample_time = static_cast<float>(config_.cycle);
  m.intf.desired_cmd_sample_time = static_cast<float>(config_.cycle);
  {
    std::lock_guard lock(mutex_);
    m.intf.statistics.answer_rate = static_cast<float>(stats_.answer_rate);
    m.intf.statistics.miss_rate = static_cast<float>(1.0 - stats_.answer_rate);
    m.intf.statistics.latency =
        static_cast<float>(stats_.answers_matched == 0 ? 0.0 : latency_sum_ / static_cast<double>(stats_.answers_matched));
    const std::uint64_t generated = stats_.cycles;
    m.intf.statistics.miss_counter =
        static_cast<std::uint32_t>(generated > stats_.answers_matched ? generated - stats_.answers_matched : 0);
  }
  m.robot.power = 0x7F;  // all seven drives on
  m.robot.control = static_cast<std::uint16_t>(config_.control);
  kinematics_.update(q_);
  const Eigen::Isometry3d& X_WT = kinematics_.X_WT();
  Matrix6Xd J_WT;
  kinematics_.tipJacobian(J_WT);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      m.data.msr_cart_pos[static_cast<std::size_t>(4 * r + c)] = static_cast<float>(X_WT.matrix()(r, c));
    }
  }
  m.data.cmd_cart_pos = m.data.msr_cart_pos;
  const int row_order[6] = {0, 1, 2, 5, 4, 3};  // FRI rows: x y z rz ry rx
  for (int j = 0; j < fri::kJoints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    m.robot.temperature[i] = 30.0F;
    m.data.msr_jnt_pos[i] = static_cast<float>(q_[j]);
    m.data.cmd_jnt_pos[i] = static_cast<float>(krl_q_[j]);
    m.data.cmd_jnt_pos_fri_offset[i] = static_cast<float>(q_desired_[j] - krl_q_[j]);
    const double d = 2.0 * damping_[j] * std::sqrt(stiffness_[j] * config_.joint_inertia);
    m.data.msr_jnt_trq[i] = static_cast<float>(stiffness_[j] * (q_desired_[j] - q_[j]) - d * qd_[j]);
    m.data.est_ext_jnt_trq[i] = static_cast<float>(tau_ext_[j]);
    m.data.mass_matrix[static_cast<std::size_t>(j * fri::kJoints + j)] = static_cast<float>(config_.joint_inertia);
    for (int r = 0; r < 6; ++r) {
      m.data.jacobian[static_cast<std::size_t>(r * fri::kJoints + j)] = static_cast<float>(J_WT(row_order[r], j));
    }
  }
}

}  // namespace flexirob::robot
