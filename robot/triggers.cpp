#include "robot/triggers.hpp"

#include <array>

namespace flexirob::robot {
namespace {

constexpr std::array kTriggerParameters{
    ParameterDeclaration{"triggers.torque_threshold", 1.5, 0.0, 100.0, "Nm",
                         "on_affected: max |tau_ext| above this while the robot is still (App. A.3)"},
    ParameterDeclaration{"triggers.still_velocity", 0.05, 1e-6, 1.0, "rad/s",
                         "joint speed below which the robot counts as not moving (a hand pressing a "
                         "stiffly held arm deflects it slowly)"},
    ParameterDeclaration{"triggers.converged_time", 2.0, 0.0, 60.0, "s",
                         "on_converged: not moving for this long after on_affected (App. A.3)"},
    ParameterDeclaration{"triggers.onset_window", 0.1, 0.0, 1.0, "s",
                         "on_affected: the touch must begin within this time of the robot's last still "
                         "measurement (a compliant arm yields to the hand before tau_ext shows it)"},
};

// A touch begins where max |τ_ext| first exceeds this fraction of on_affected's threshold: a
// hand taking a held arm slowly deflects it, and the arm may move faster than still_velocity
// before the torque reaches the threshold; the touch still began on a still robot.
constexpr double kContactFraction = 1.0 / 3.0;
// [s] from such a beginning to the threshold at most: a hand's pull gets there within a second
// or two, while a standing offset of a measured τ_ext above the fraction (a real arm's
// estimate) would otherwise count as a touch begun still for as long as it stands.
constexpr double kMaxRiseTime = 2.0;

}  // namespace

std::span<const ParameterDeclaration> triggerParameters() { return kTriggerParameters; }

const char* toString(TriggerKind kind) {
  return kind == TriggerKind::kOnAffected ? "on_affected" : "on_converged";
}

InteractionTriggers::InteractionTriggers(const ParameterSet& parameters)
    : torque_threshold_(parameters.get("triggers.torque_threshold")),
      still_velocity_(parameters.get("triggers.still_velocity")),
      converged_time_(parameters.get("triggers.converged_time")),
      onset_window_(parameters.get("triggers.onset_window")) {}

void InteractionTriggers::reset() {
  affected_ = false;
  armed_ = true;
  in_contact_ = false;
  contact_began_still_ = false;
  contact_began_time_ = -1e9;
  last_moving_time_ = 0.0;
  last_still_time_ = -1e9;
}

void InteractionTriggers::markAffected(double time) {
  affected_ = true;
  armed_ = false;
  last_moving_time_ = time;
}

std::optional<TriggerEvent> InteractionTriggers::update(const RobotState& state) {
  const bool finite = state.qd.allFinite() && state.tau_ext.allFinite();
  const bool moving = !finite || (state.qd.size() > 0 && state.qd.cwiseAbs().maxCoeff() > still_velocity_);
  const double torque = finite && state.tau_ext.size() > 0 ? state.tau_ext.cwiseAbs().maxCoeff() : 0.0;
  const bool touched = torque > torque_threshold_;
  if (moving) {
    last_moving_time_ = state.time;
  } else {
    last_still_time_ = state.time;
  }
  if (!touched) armed_ = true;
  // App. A.3 asks for a touch on a robot that is not moving. Read causally: the touch began
  // while the robot was still. Under gravity compensation the arm yields to the hand within a
  // cycle, and τ_ext of a real (or FRI) measurement shows the push only after it has acted, so
  // "still at this very measurement" would never hold for a push on a compliant arm. A slow
  // pull on a held arm moves it before its torque crosses the threshold: the touch began where
  // the torque first showed it (kContactFraction).
  const bool still_lately = state.time - last_still_time_ <= onset_window_ + 1e-9;
  const bool contact = torque > kContactFraction * torque_threshold_;
  if (contact && !in_contact_) {
    contact_began_still_ = still_lately;
    contact_began_time_ = state.time;
  }
  in_contact_ = contact;
  if (!contact || state.time - contact_began_time_ > kMaxRiseTime + 1e-9) contact_began_still_ = false;
  const bool began_still = still_lately || contact_began_still_;
  if (touched && began_still && armed_ && !affected_) {
    affected_ = true;
    armed_ = false;
    contact_began_still_ = false;  // one beginning, one on_affected
    last_moving_time_ = state.time;  // stillness is counted from the touch on
    ++affected_count_;
    return TriggerEvent{TriggerKind::kOnAffected, state.time};
  }
  if (affected_ && !moving && state.time - last_moving_time_ >= converged_time_ - 1e-9) {
    affected_ = false;
    // A hand still on the arm now began no new touch: the next on_affected waits for it to let
    // go (a grip that loosened for a moment during the phase re-armed the trigger).
    armed_ = !touched;
    ++converged_count_;
    return TriggerEvent{TriggerKind::kOnConverged, state.time};
  }
  return std::nullopt;
}

}  // namespace flexirob::robot
