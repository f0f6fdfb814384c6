#pragma once
// The physical interaction triggers of App. A.3: `on_affected` fires when max |τ_ext| exceeds
// 1.5 Nm on a robot that was not moving when the touch began (within triggers.onset_window of a
// still measurement); `on_converged` fires when, after `on_affected`, the robot has not moved for
// 2 s. Events carry the robot's time stamps. Allocation-free.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>

#include "robot/backend.hpp"
#include "robot/parameters.hpp"

namespace flexirob::robot {

/// "triggers.*": torque threshold, still velocity, convergence time.
std::span<const ParameterDeclaration> triggerParameters();

enum class TriggerKind { kOnAffected, kOnConverged };
const char* toString(TriggerKind kind);

struct TriggerEvent {
  TriggerKind kind = TriggerKind::kOnAffected;
  double time = 0.0;  ///< [s] of the state that fired it
};

class InteractionTriggers {
 public:
  explicit InteractionTriggers(const ParameterSet& parameters);

  /// Feeds one measurement; returns the event it fires, if any. "Moving" means some joint
  /// faster than triggers.still_velocity. After on_affected, the torque must fall below the
  /// threshold again before on_affected can fire anew (one touch, one event).
  std::optional<TriggerEvent> update(const RobotState& state);
  void reset();
  /// A touch reported by another input (a keyboard trigger, Sect. 8.1) at `time`: the robot
  /// counts as affected from then on, so on_converged follows once it has been still for
  /// triggers.converged_time; the touch must end before on_affected can fire again.
  void markAffected(double time);

  bool affected() const { return affected_; }
  std::uint64_t count(TriggerKind kind) const { return kind == TriggerKind::kOnAffected ? affected_count_ : converged_count_; }

 private:
  double torque_threshold_, still_velocity_, converged_time_, onset_window_;
  bool affected_ = false;
  bool armed_ = true;  // torque has been below the threshold since the last on_affected
  // The touch under way (max |τ_ext| above kContactFraction of the threshold since it began at
  // contact_began_time_) began while the robot was still, at most kMaxRiseTime ago, and has not
  // yet fired on_affected.
  bool in_contact_ = false;
  bool contact_began_still_ = false;
  double contact_began_time_ = -1e9;
  double last_moving_time_ = 0.0;
  double last_still_time_ = -1e9;  // of the last measurement in which the robot was not moving
  std::uint64_t affected_count_ = 0;
  std::uint64_t converged_count_ = 0;
};

}  // namespace flexirob::robot
