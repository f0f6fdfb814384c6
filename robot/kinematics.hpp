#pragma once
// Forward kinematics and geometric Jacobians of a RobotModel (Eq. 2.1-2.2).
//
// Kinematics owns its buffers: after construction, update() and the Jacobian queries do not
// allocate, so they are safe in the 1 kHz control loop.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "robot/robot_model.hpp"

namespace flexirob::robot {

using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Matrix3Xd = Eigen::Matrix<double, 3, Eigen::Dynamic>;

class Kinematics {
 public:
  explicit Kinematics(const RobotModel& model);
  /// The model is kept by reference: a temporary would be gone after the constructor.
  explicit Kinematics(const RobotModel&& model) = delete;

  /// Computes every body pose for posture q (size dof(), radians / metres).
  void update(const Eigen::VectorXd& q);

  const RobotModel& model() const { return *model_; }
  const Eigen::VectorXd& q() const { return q_; }
  /// Pose of body i (0 = base, i = child of joint i) in the base frame W.
  const Eigen::Isometry3d& X_WB(int body) const { return X_WB_[static_cast<std::size_t>(body)]; }
  /// Pose of the tip link in W.
  const Eigen::Isometry3d& X_WT() const { return X_WT_; }
  Eigen::Vector3d p_WT() const { return X_WT_.translation(); }
  /// Joint axis of joint j (0-based) in W, and a point on it.
  Eigen::Vector3d axis_W(int joint) const;

  /// 6 x N geometric Jacobian of the tip: rows 0-2 the linear velocity of the tip origin,
  /// rows 3-5 the angular velocity, both expressed in W.
  void tipJacobian(Matrix6Xd& J_WT) const;
  /// 3 x N position Jacobian of the tip origin in W.
  void tipPositionJacobian(Matrix3Xd& Jp_WT) const;
  /// 3 x N Jacobian of the velocity of a point p_W (in W) fixed to body `body`; joints after
  /// that body do not move it. Used for hand forces: tau = J^T F.
  void pointJacobian(int body, const Eigen::Vector3d& p_W, Matrix3Xd& Jp) const;

 private:
  const RobotModel* model_;
  Eigen::VectorXd q_;
  std::vector<Eigen::Isometry3d> X_WB_;
  Eigen::Isometry3d X_WT_ = Eigen::Isometry3d::Identity();
};

/// Convenience: tip pose for posture q.
Eigen::Isometry3d tipPose(const RobotModel& model, const Eigen::VectorXd& q);

/// The diagonal of the joint-space inertia matrix M(q) [kg m², kg for a slide] from the bodies'
/// masses and inertias (the kinetic energy of each joint moving alone at unit speed).
Eigen::VectorXd jointInertiaDiagonal(const RobotModel& model, const Eigen::VectorXd& q);

/// [kg m²] the LWR IV's largest joint inertia in the posture nearest zero (A2 under the upright
/// arm, 3.07 kg m²), a little less.
inline constexpr double kLwrLargestJointInertia = 3.0;
/// Arms up to this many times the LWR IV's joint inertia are driven with its gains.
inline constexpr double kLwrClassInertiaRatio = 4.0;

/// What the gains and dampings sized for the LWR IV are scaled by, from the ratio r of the
/// largest joint inertia of the turning joints in the posture nearest zero to the LWR IV's: r
/// on a lighter arm; 1 up to four times the LWR IV's (the LWR IV, arm9 at 3.1, arms of its
/// class are driven with its own gains); r / 4 beyond, continuous there (a 260 kg arm at 86
/// times could not be led by hands of the LWR IV's strength). 1 without a turning joint or a
/// mass. The workflow keeps the LWR IV's joint gains above 1 (docs/CONTROL.md).
double inertiaScaleToLwr(const RobotModel& model);

}  // namespace flexirob::robot
