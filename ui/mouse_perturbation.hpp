#pragma once
// Kinesthetic interaction with the mouse (issue #7 item 3; MuJoCo's and Gazebo's perturbation):
// a left-button press on a link of the arm grabs it at the point under the cursor; while the
// button is held, a spring from that point (fixed to the link) to the cursor pulls the link,
// F = k (p_cursor − p_grab), and the control worker applies it as the hand force of the
// simulation, so the workflow's triggers and controllers respond as under a person's hand. The
// cursor moves in the plane through the grab point facing the camera. A press elsewhere
// leaves the camera to orbit as before.
//
// ForceArrow draws the hand's force in the 3D view (from the snapshot, so the keyboard's
// pushes show as well): an arrow from the point of application, 5 mm per newton.
#include <osg/MatrixTransform>
#include <osg/ref_ptr>

#include <Eigen/Core>
#include <functional>

#include "app/evaluation.hpp"
#include "ui/osg_view.hpp"

namespace flexirob::render {
class World;
}
namespace flexirob::robot {
class Kinematics;
}

namespace flexirob::ui {

class LiveTeaching;

class ForceArrow {
 public:
  static constexpr double kMetresPerNewton = 0.005;
  ForceArrow();
  osg::Node* node() const { return transform_.get(); }
  /// Shows the force F_W [N] applied at p_W [m]; a force below 0.5 N (0.5 force() on an arm
  /// scaled against the LWR IV, setArmScale) hides the arrow. The force counts as F / force()
  /// and the length shrinks with the arm, so a pull looks alike on every arm.
  void show(const Eigen::Vector3d& p_W, const Eigen::Vector3d& F_W);
  void setArmScale(const app::ArmScale& scale) { scale_ = scale; }
  /// The arrow's length for F_W [m].
  double length(const Eigen::Vector3d& F_W) const;
  void hide();
  bool visible() const;

 private:
  osg::ref_ptr<osg::MatrixTransform> transform_;
  app::ArmScale scale_;
};

class MousePerturbation final : public ViewMouseGrabber {
 public:
  static constexpr double kStiffness = 250.0;  ///< [N/m] of the mouse spring on the LWR IV (times ArmScale::mass())

  /// live() and kinematics() give the current live robot and the GUI's mirror kinematics (at
  /// the snapshot's posture); either may return null (then nothing is grabbed).
  MousePerturbation(OsgView& view, render::World& world, std::function<LiveTeaching*()> live,
                    std::function<const robot::Kinematics*()> kinematics);

  bool press(const QPointF& position) override;
  void move(const QPointF& position) override;
  void release() override;

  bool grabbing() const { return body_ > 0; }
  int body() const { return body_; }
  const Eigen::Vector3d& target() const { return target_W_; }

 private:
  OsgView* view_;
  render::World* world_;
  std::function<LiveTeaching*()> live_;
  std::function<const robot::Kinematics*()> kinematics_;
  int body_ = -1;
  Eigen::Vector3d p_B_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_point_W_ = Eigen::Vector3d::Zero(), plane_normal_W_ = Eigen::Vector3d::UnitX();
  Eigen::Vector3d target_W_ = Eigen::Vector3d::Zero();
};

}  // namespace flexirob::ui
