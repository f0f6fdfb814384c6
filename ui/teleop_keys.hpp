#pragma once
// Keyboard tele-operation (thesis Sect. 8.1): (+/−) keys per task dimension and per joint, keys
// for the interaction triggers and for the four buttons, so that the whole teaching procedure
// runs from the keyboard. In the workflow's keyboard mode a held task key moves the task
// target Δx_des along that world axis at kTaskSpeed, a held joint key moves that joint's
// null-space target at kJointSpeed (the thesis' "commanded displacements" of Fig. 8.1); the
// interaction controller of the sub-stage turns them into motion.
//
// The map (US layout; the joint rows are the digit row and the letter row below it):
//   task:     ← → : −x / +x   ↑ ↓ : +y / −y   PgUp PgDn : +z / −z
//   joints:   1 … 9 : joint 1 … 9 in +     Q W E R T Y U I O : joint 1 … 9 in −
//   triggers: Space : on_affected   Enter : on_converged
//   buttons:  F5 start configuration   F6 finish configuration   F7 start programming
//             F8 finish programming   F9 replay the teach-in chosen in the panel (EXECUTION)
//   F1 or H : show or hide this map
#include <Qt>
#include <QString>
#include <optional>
#include <set>

#include <Eigen/Core>

#include "app/workflow.hpp"

namespace flexirob::ui {

struct TeleopAction {
  enum class Kind { kTask, kJoint, kTrigger, kButton, kToggleMap, kReplay };
  Kind kind = Kind::kTask;
  int index = 0;   ///< task axis (0..2) or joint (0-based)
  int sign = 1;    ///< +1 or −1 for task and joint keys
  app::Trigger trigger = app::Trigger::kOnAffected;
  app::Button button = app::Button::kStartConfiguration;
};

class TeleopKeys {
 public:
  static constexpr double kTaskSpeed = 0.08;   ///< [m/s] of the task target per held key
  static constexpr double kJointSpeed = 0.35;  ///< [rad/s] of a joint's null-space target

  /// The action of a key (Qt::Key), if any.
  static std::optional<TeleopAction> actionOf(int key);
  /// The key map as rich text for `dof` joints.
  static QString keyMapText(int dof);

  /// Tracks held keys (auto-repeat ignored by the caller). Returns true if the key is a held
  /// (task or joint) key.
  bool press(int key);
  bool release(int key);
  void clear() { held_.clear(); }
  bool anyHeld() const { return !held_.empty(); }

  /// The motion the held keys ask for: task-target velocity [m/s, W] and joint velocities
  /// [rad/s] (joints beyond `dof` ignored).
  Eigen::Vector3d taskVelocity() const;
  Eigen::VectorXd jointVelocities(int dof) const;

 private:
  std::set<int> held_;
};

}  // namespace flexirob::ui
