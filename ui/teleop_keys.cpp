#include "ui/teleop_keys.hpp"

#include <algorithm>
#include <array>

namespace flexirob::ui {
namespace {

constexpr std::array<int, 9> kJointPlusKeys = {Qt::Key_1, Qt::Key_2, Qt::Key_3, Qt::Key_4, Qt::Key_5,
                                               Qt::Key_6, Qt::Key_7, Qt::Key_8, Qt::Key_9};
constexpr std::array<int, 9> kJointMinusKeys = {Qt::Key_Q, Qt::Key_W, Qt::Key_E, Qt::Key_R, Qt::Key_T,
                                                Qt::Key_Y, Qt::Key_U, Qt::Key_I, Qt::Key_O};

TeleopAction task(int axis, int sign) {
  TeleopAction a;
  a.kind = TeleopAction::Kind::kTask;
  a.index = axis;
  a.sign = sign;
  return a;
}

}  // namespace

std::optional<TeleopAction> TeleopKeys::actionOf(int key) {
  switch (key) {
    case Qt::Key_Right:
      return task(0, +1);
    case Qt::Key_Left:
      return task(0, -1);
    case Qt::Key_Up:
      return task(1, +1);
    case Qt::Key_Down:
      return task(1, -1);
    case Qt::Key_PageUp:
      return task(2, +1);
    case Qt::Key_PageDown:
      return task(2, -1);
    case Qt::Key_Space: {
      TeleopAction a;
      a.kind = TeleopAction::Kind::kTrigger;
      a.trigger = app::Trigger::kOnAffected;
      return a;
    }
    case Qt::Key_Return:
    case Qt::Key_Enter: {
      TeleopAction a;
      a.kind = TeleopAction::Kind::kTrigger;
      a.trigger = app::Trigger::kOnConverged;
      return a;
    }
    case Qt::Key_F5:
    case Qt::Key_F6:
    case Qt::Key_F7:
    case Qt::Key_F8: {
      TeleopAction a;
      a.kind = TeleopAction::Kind::kButton;
      a.button = static_cast<app::Button>(key - Qt::Key_F5);
      return a;
    }
    case Qt::Key_F9: {
      TeleopAction a;
      a.kind = TeleopAction::Kind::kReplay;
      return a;
    }
    case Qt::Key_F1:
    case Qt::Key_H: {
      TeleopAction a;
      a.kind = TeleopAction::Kind::kToggleMap;
      return a;
    }
    default:
      break;
  }
  for (std::size_t j = 0; j < kJointPlusKeys.size(); ++j) {
    TeleopAction a;
    a.kind = TeleopAction::Kind::kJoint;
    a.index = static_cast<int>(j);
    if (key == kJointPlusKeys[j]) {
      a.sign = +1;
      return a;
    }
    if (key == kJointMinusKeys[j]) {
      a.sign = -1;
      return a;
    }
  }
  return std::nullopt;
}

QString TeleopKeys::keyMapText(int dof) {
  const int shown = std::min(dof, static_cast<int>(kJointPlusKeys.size()));
  QString plus;
  QString minus;
  for (int j = 0; j < shown; ++j) {
    plus += QChar(kJointPlusKeys[static_cast<std::size_t>(j)]);
    minus += QChar(kJointMinusKeys[static_cast<std::size_t>(j)]);
  }
  return QStringLiteral(
             "<b>Keyboard tele-operation</b> (hold a key to move)<br>"
             "<b>tip</b>: &larr;/&rarr; &minus;x/+x &nbsp; &uarr;/&darr; +y/&minus;y &nbsp; PgUp/PgDn +z/&minus;z<br>"
             "<b>joints 1&ndash;%1</b> (null space): %2 turn +, %3 turn &minus;<br>"
             "<b>triggers</b>: Space on_affected &nbsp; Enter on_converged<br>"
             "<b>buttons</b>: F5 start conf. &nbsp; F6 finish conf. &nbsp; F7 start prog. &nbsp; F8 finish prog. &nbsp; F9 replay<br>"
             "<b>mouse</b>: left-drag a link pulls it, elsewhere orbits; Ctrl+click a goal<br>"
             "<b>view</b>: Home resets the camera &nbsp; Ctrl+O opens a recording<br>"
             "<b>menus</b>: Alt+T Teaching (remove, re-teach, replay) &nbsp; Alt+F File<br>"
             "F1 / H: hide this map")
      .arg(shown)
      .arg(plus, minus);
}

bool TeleopKeys::press(int key) {
  const auto action = actionOf(key);
  if (!action || (action->kind != TeleopAction::Kind::kTask && action->kind != TeleopAction::Kind::kJoint)) return false;
  held_.insert(key);
  return true;
}

bool TeleopKeys::release(int key) { return held_.erase(key) > 0; }

Eigen::Vector3d TeleopKeys::taskVelocity() const {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  for (const int key : held_) {
    const auto action = actionOf(key);
    if (action && action->kind == TeleopAction::Kind::kTask) force[action->index] += action->sign * kTaskSpeed;
  }
  return force;
}

Eigen::VectorXd TeleopKeys::jointVelocities(int dof) const {
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(dof);
  for (const int key : held_) {
    const auto action = actionOf(key);
    if (action && action->kind == TeleopAction::Kind::kJoint && action->index < dof) {
      tau[action->index] += action->sign * kJointSpeed;
    }
  }
  return tau;
}

}  // namespace flexirob::ui
