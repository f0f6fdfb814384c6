#include "robot/kinematics.hpp"

#include "robot/errors.hpp"

#include <algorithm>
#include <cmath>

namespace flexirob::robot {

Kinematics::Kinematics(const RobotModel& model)
    : model_(&model),
      q_(Eigen::VectorXd::Zero(model.dof())),
      X_WB_(static_cast<std::size_t>(model.dof() + 1), Eigen::Isometry3d::Identity()) {
  update(q_);
}

void Kinematics::update(const Eigen::VectorXd& q) {
  const auto& joints = model_->joints();
  if (q.size() != static_cast<Eigen::Index>(joints.size())) {
    throw InputError("expected " + std::to_string(joints.size()) + " joint values, got " + std::to_string(q.size()));
  }
  q_ = q;
  X_WB_[0].setIdentity();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const Joint& joint = joints[j];
    const double value = q[static_cast<Eigen::Index>(j)];
    Eigen::Isometry3d X_JC = Eigen::Isometry3d::Identity();
    if (joint.type == JointType::kPrismatic) {
      X_JC.translation() = joint.axis_J * value;
    } else {
      X_JC.linear() = Eigen::AngleAxisd(value, joint.axis_J).toRotationMatrix();
    }
    X_WB_[j + 1] = X_WB_[j] * joint.X_PJ * X_JC;
  }
  X_WT_ = X_WB_.back() * model_->X_LastBodyTip();
}

Eigen::Vector3d Kinematics::axis_W(int joint) const {
  // The joint frame coincides with the child body frame, so the axis rotates with the child.
  return X_WB_[static_cast<std::size_t>(joint + 1)].linear() * model_->joints()[static_cast<std::size_t>(joint)].axis_J;
}

void Kinematics::pointJacobian(int body, const Eigen::Vector3d& p_W, Matrix3Xd& Jp) const {
  const int n = model_->dof();
  Jp.setZero(3, n);
  for (int j = 0; j < std::min(body, n); ++j) {
    const Eigen::Vector3d axis = axis_W(j);
    if (model_->joints()[static_cast<std::size_t>(j)].type == JointType::kPrismatic) {
      Jp.col(j) = axis;
    } else {
      const Eigen::Vector3d origin = X_WB_[static_cast<std::size_t>(j + 1)].translation();
      Jp.col(j) = axis.cross(p_W - origin);
    }
  }
}

void Kinematics::tipJacobian(Matrix6Xd& J_WT) const {
  const int n = model_->dof();
  J_WT.setZero(6, n);
  const Eigen::Vector3d p_tip = X_WT_.translation();
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d axis = axis_W(j);
    if (model_->joints()[static_cast<std::size_t>(j)].type == JointType::kPrismatic) {
      J_WT.block<3, 1>(0, j) = axis;
    } else {
      const Eigen::Vector3d origin = X_WB_[static_cast<std::size_t>(j + 1)].translation();
      J_WT.block<3, 1>(0, j) = axis.cross(p_tip - origin);
      J_WT.block<3, 1>(3, j) = axis;
    }
  }
}

void Kinematics::tipPositionJacobian(Matrix3Xd& Jp_WT) const {
  pointJacobian(model_->dof(), X_WT_.translation(), Jp_WT);
}

Eigen::Isometry3d tipPose(const RobotModel& model, const Eigen::VectorXd& q) {
  Kinematics kinematics(model);
  kinematics.update(q);
  return kinematics.X_WT();
}

Eigen::VectorXd jointInertiaDiagonal(const RobotModel& model, const Eigen::VectorXd& q) {
  const int dof = model.dof();
  Kinematics kinematics(model);
  kinematics.update(q);
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(dof);
  Matrix3Xd Jp(3, dof);
  for (int b = 1; b < static_cast<int>(model.bodies().size()); ++b) {
    const Body& body = model.bodies()[static_cast<std::size_t>(b)];
    if (!(body.mass > 0.0)) continue;
    const Eigen::Isometry3d& X_WB = kinematics.X_WB(b);
    kinematics.pointJacobian(b, X_WB * body.p_BCom, Jp);
    const Eigen::Matrix3d I_W = X_WB.linear() * body.I_BCom * X_WB.linear().transpose();
    for (int j = 0; j < dof; ++j) {
      diagonal[j] += body.mass * Jp.col(j).squaredNorm();
      // A turning joint spins every body after it about its axis as well.
      if (b > j && model.joints()[static_cast<std::size_t>(j)].type != JointType::kPrismatic) {
        const Eigen::Vector3d axis = kinematics.axis_W(j);
        diagonal[j] += axis.dot(I_W * axis);
      }
    }
  }
  return diagonal;
}

double inertiaScaleToLwr(const RobotModel& model) {
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.dof()).cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
  const Eigen::VectorXd inertia = jointInertiaDiagonal(model, q);
  double largest = 0.0;  // of the turning joints (a slide's is a mass)
  for (int j = 0; j < model.dof(); ++j) {
    if (model.joints()[static_cast<std::size_t>(j)].type != JointType::kPrismatic) largest = std::max(largest, inertia[j]);
  }
  if (!(largest > 0.0 && std::isfinite(largest))) return 1.0;
  const double ratio = largest / kLwrLargestJointInertia;
  return ratio < 1.0 ? ratio : std::max(1.0, ratio / kLwrClassInertiaRatio);
}

}  // namespace flexirob::robot
