#pragma once
// One slider per joint, spanning the joint's hardware limits, with the zones beyond the
// software limits marked in red; the value in degrees (metres for prismatic joints) beside it.
// Moving a slider emits the whole posture; the panel itself computes no kinematics.
#include <QSlider>
#include <QWidget>
#include <vector>

#include <Eigen/Core>

#include "robot/robot_model.hpp"

class QLabel;
class QGridLayout;


namespace flexirob::ui {

/// A horizontal slider over [lower, upper] (radians or metres, in steps of 1e-3) that shades
/// the zones outside [soft_lower, soft_upper].
class LimitSlider : public QSlider {
  Q_OBJECT

 public:
  LimitSlider(const robot::JointLimits& limits, QWidget* parent = nullptr);
  double valueSi() const { return value() * kStep; }
  void setValueSi(double value);
  static constexpr double kStep = 1e-3;

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  int soft_lower_ = 0;
  int soft_upper_ = 0;
};

/// Distance of a joint to its nearest software limit as a bar (full: at mid range), green,
/// amber within twice the workflow's near-limit margin and red within it (Sect. 4.3.4: the
/// tutor is warned when a posture nears a joint limit; app::nearLimitMargin: 0.17 rad, or 2 cm
/// for a prismatic joint, at most a tenth of the joint's range).
class LimitDistanceBar : public QWidget {
  Q_OBJECT

 public:
  enum class Level { kOk, kAmber, kRed };

  explicit LimitDistanceBar(const robot::Joint& joint, QWidget* parent = nullptr);
  void setValue(double q);
  double distance() const { return distance_; }
  double redMargin() const { return red_margin_; }
  Level level() const;
  QSize sizeHint() const override { return {70, 14}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  double lower_, upper_, red_margin_, distance_ = 0.0;
};

class JointPanel : public QWidget {
  Q_OBJECT

 public:
  explicit JointPanel(QWidget* parent = nullptr);

  /// Rebuilds the rows for `model` and shows posture q (size model.dof()).
  void setRobot(const robot::RobotModel& model, const Eigen::VectorXd& q);
  /// Shows posture q.
  void setPosture(const Eigen::VectorXd& q);
  Eigen::VectorXd posture() const;
  int jointCount() const { return static_cast<int>(sliders_.size()); }
  LimitSlider* slider(int joint) const { return sliders_.at(static_cast<std::size_t>(joint)); }
  LimitDistanceBar* limitBar(int joint) const { return bars_.at(static_cast<std::size_t>(joint)); }
 private:
  void updateValueLabel(int joint);

  QGridLayout* grid_ = nullptr;
  std::vector<LimitSlider*> sliders_;
  std::vector<QLabel*> value_labels_;
  std::vector<LimitDistanceBar*> bars_;
  std::vector<bool> prismatic_;
};

}  // namespace flexirob::ui
