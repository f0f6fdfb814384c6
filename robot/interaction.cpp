#include "robot/interaction.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace flexirob::robot {
namespace {

constexpr std::array kInteractionParameters{
    ParameterDeclaration{"interaction.joint_damping", 5.0, 0.01, 1000.0, "Nms/rad",
                         "damping of the joint-space admittance of gravity compensation (stops drift)"},
    ParameterDeclaration{"interaction.cartesian_stiffness", 500.0, 1.0, 1e5, "N/m",
                         "spring between the tip and x_des in assisted gravity compensation"},
    ParameterDeclaration{"interaction.cartesian_damping", 60.0, 0.01, 1e4, "Ns/m",
                         "Cartesian damping of assisted gravity compensation (stops drift)"},
    ParameterDeclaration{"interaction.blending_anchor_rate", 5.0, 0.0, 1000.0, "1/s",
                         "assistance blending: rate, times the confidence, at which q_des returns to the held arm"},
};

}  // namespace

const char* toString(InteractionMode mode) {
  switch (mode) {
    case InteractionMode::kGravityCompensation: return "gravity_compensation";
    case InteractionMode::kCompliantRecording: return "compliant_recording";
    case InteractionMode::kHierarchicalControl: return "hierarchical_control";
    case InteractionMode::kAssistedGravityCompensation: return "assisted_gravity_compensation";
    case InteractionMode::kAssistanceBlending: return "assistance_blending";
  }
  return "unknown";
}

ModeGains modeGains(InteractionMode mode) {
  // Tab. A.1
  switch (mode) {
    case InteractionMode::kGravityCompensation: return {20.0, 0.7, 0.1};
    case InteractionMode::kCompliantRecording: return {80.0, 0.7, 0.0};
    case InteractionMode::kHierarchicalControl: return {300.0, 0.95, 0.0};
    case InteractionMode::kAssistedGravityCompensation: return {50.0, 0.7, 0.5};
    case InteractionMode::kAssistanceBlending: return {50.0, 0.7, 0.1};
  }
  return {300.0, 0.95, 0.0};
}

std::span<const ParameterDeclaration> interactionParameters() { return kInteractionParameters; }

std::vector<ParameterDeclaration> interactionControllerParameters() {
  std::vector<ParameterDeclaration> all;
  for (auto declarations : {interactionParameters(), hierarchicalParameters(), limiterParameters()}) {
    all.insert(all.end(), declarations.begin(), declarations.end());
  }
  return all;
}

InteractionController::InteractionController(const RobotModel& model, const ParameterSet& parameters, double cycle_time)
    : model_(&model),
      dt_(cycle_time),
      joint_damping_(parameters.get("interaction.joint_damping")),
      cartesian_stiffness_(parameters.get("interaction.cartesian_stiffness")),
      cartesian_damping_(parameters.get("interaction.cartesian_damping")),
      blending_anchor_rate_(parameters.get("interaction.blending_anchor_rate")),
      controller_(model, parameters),
      limiter_(model, parameters, cycle_time),
      kinematics_(model),
      q_fixed_(model.midPosture()),
      q_c_(model.midPosture()),
      q_des_(model.midPosture()),
      qd_des_(Eigen::VectorXd::Zero(model.dof())),
      qd_(Eigen::VectorXd::Zero(model.dof())),
      q_map_(model.midPosture()),
      J_des_(3, model.dof()),
      q_des_to_held_(model.dof()) {
  gains_ = modeGains(mode_);
}

namespace {

// Tab. A.1 for an arm `inertia` and `mass` times the LWR IV's: the stiffness in Nm/rad scales
// with the joints' inertia (the same natural frequency), the admittance's virtual inertia with
// the joints' in the joint-space modes and with the mass in the task-space one.
ModeGains scaledGains(InteractionMode mode, double inertia, double mass) {
  ModeGains gains = modeGains(mode);
  gains.stiffness *= inertia;
  gains.inertia *= mode == InteractionMode::kAssistedGravityCompensation ? mass : inertia;
  return gains;
}

}  // namespace

void InteractionController::setArmScale(double inertia, double mass) {
  if (inertia > 0.0 && std::isfinite(inertia)) inertia_scale_ = inertia;
  if (mass > 0.0 && std::isfinite(mass)) mass_scale_ = mass;
  gains_ = scaledGains(mode_, inertia_scale_, mass_scale_);
}

void InteractionController::start(InteractionMode mode, const RobotState& state) {
  mode_ = mode;
  gains_ = scaledGains(mode, inertia_scale_, mass_scale_);
  limiter_.reset(state.q);
  q_des_ = limiter_.command();
  qd_des_.setZero();
  q_c_ = limiter_.command();
  kinematics_.update(limiter_.command());
  p_des_ = kinematics_.p_WT();
  pd_des_.setZero();
  pd_target_.setZero();
  alpha_ = 0.0;
}

void InteractionController::setFixedPosture(const Eigen::VectorXd& q_fixed) {
  if (q_fixed.size() == q_fixed_.size() && q_fixed.allFinite()) q_fixed_ = q_fixed;
}

void InteractionController::nudgeTask(const Eigen::Vector3d& dx) {
  if (dx.allFinite()) p_des_ += dx;
}

void InteractionController::nudgeJoints(const Eigen::VectorXd& dq) {
  if (dq.size() != q_c_.size() || !dq.allFinite()) return;
  q_c_ += dq;
  q_c_ = q_c_.cwiseMax(limiter_.lower()).cwiseMin(limiter_.upper());
}

void InteractionController::update(const RobotState& state, JointImpedanceCommand& command) {
  const int n = model_->dof();
  if (command.q_cmd.size() != n) command.resize(n);
  command.stiffness.setConstant(gains_.stiffness);
  command.damping.setConstant(gains_.damping);
  const double k = gains_.stiffness;
  switch (mode_) {
    case InteractionMode::kGravityCompensation:
      if (keyboard_) {
        // Fig. 8.1(a): x_des and the redundancy resolution by keys, fused by Eq. 2.11.
        controller_.velocity(limiter_.command(), p_des_, q_c_, qd_, &limiter_);
        limiter_.updateVelocity(qd_);
      } else {
        // The tutor deflects the arm from q_cmd; the deflection torque K (q − q_cmd) drives a
        // virtual inertia with damping: q_cmd follows the arm and stops with it (Sect. 4.1).
        const double inertia = gains_.inertia;
        for (int j = 0; j < n; ++j) {
          const double push = k * (state.q[j] - limiter_.command()[j]);
          qd_[j] = (limiter_.velocity()[j] + dt_ * push / inertia) / (1.0 + dt_ * joint_damping_ * inertia_scale_ / inertia);
        }
        limiter_.updateVelocity(qd_);
      }
      break;
    case InteractionMode::kCompliantRecording:
      if (keyboard_) {
        // Fig. 8.1(b): the tip moves by keys, the null space holds q_fixed.
        controller_.velocity(limiter_.command(), p_des_, q_fixed_, qd_, &limiter_);
        limiter_.updateVelocity(qd_);
      } else {
        limiter_.update(q_fixed_);  // spring back to q_fixed (Sect. 4.1)
      }
      break;
    case InteractionMode::kHierarchicalControl:
      if (map_ != nullptr) {
        map_->predict(p_des_, q_map_);
      } else {
        q_map_ = q_fixed_;
      }
      controller_.velocity(limiter_.command(), p_des_, pd_target_, q_map_, qd_, &limiter_);
      limiter_.updateVelocity(qd_);
      pd_target_.setZero();
      break;
    case InteractionMode::kAssistedGravityCompensation: {
      if (!keyboard_ && !task_held_ && state.X_WT.matrix().allFinite()) {
        // π_x: x_des follows the tip the tutor pulls, with virtual mass and Cartesian damping (Sect. 5.1).
        const Eigen::Vector3d pull = cartesian_stiffness_ * mass_scale_ * (state.p_WT() - p_des_);
        const double mass = gains_.inertia;
        pd_des_ = (pd_des_ + dt_ * pull / mass) / (1.0 + dt_ * cartesian_damping_ * mass_scale_ / mass);
        p_des_ += pd_des_ * dt_;
      }
      if (map_ != nullptr) {
        map_->predict(p_des_, q_map_);
      } else {
        q_map_ = q_fixed_;
      }
      controller_.velocity(limiter_.command(), p_des_, q_map_, qd_, &limiter_);
      limiter_.updateVelocity(qd_);
      break;
    }
    case InteractionMode::kAssistanceBlending: {
      // q_des: where the tutor pushes the arm: π_q's admittance, driven here by the estimated
      // external torque (the deflection the tutor causes, without the lag of the arm behind
      // its own null-space motion, which would otherwise feed back into x_des).
      const double inertia = gains_.inertia;
      for (int j = 0; j < n; ++j) {
        const double push = state.tau_ext.size() == n && std::isfinite(state.tau_ext[j]) ? state.tau_ext[j] : 0.0;
        qd_des_[j] = (qd_des_[j] + dt_ * push / inertia) / (1.0 + dt_ * joint_damping_ * inertia_scale_ / inertia);
        q_des_[j] = std::clamp(q_des_[j] + qd_des_[j] * dt_, limiter_.lower()[j], limiter_.upper()[j]);
      }
      kinematics_.update(q_des_);
      p_des_ = kinematics_.p_WT();
      const double c = confidence_ != nullptr ? confidence_->confidence(p_des_) : 0.0;
      alpha_ = std::isfinite(c) ? std::clamp(c, 0.0, 1.0) : 0.0;
      if (map_ != nullptr) {
        map_->predict(p_des_, q_map_);
      } else {
        q_map_ = q_des_;
      }
      q_map_ = alpha_ * q_map_ + (1.0 - alpha_) * q_des_;  // Eq. 6.2
      // Where the robot is confident it holds the arm's null space against the hand, and a push
      // there would pile up in q_des without moving the arm; leaving the confident region (α
      // falling) would then swing the arm by itself to a posture far beyond where the hand had
      // it. So the null-space part of q_des returns to the held arm (the command) at α times the
      // anchor rate: the thesis' q_des "relates to the damped current position" (Sect. 6.1).
      // Only the null-space part, so that x_des = K_fwd(q_des) stays where the hand put it
      // instead of following the arm's own lag; at α = 0 π_q follows the hand as before. It acts
      // from the next cycle on, with this cycle's kinematics of q_des.
      const double anchor = std::clamp(dt_ * alpha_ * blending_anchor_rate_, 0.0, 1.0);
      if (anchor > 0.0) {
        kinematics_.tipPositionJacobian(J_des_);  // still at q_des (x_des above)
        q_des_to_held_ = limiter_.command() - q_des_;
        // N = I − Jᵀ(JJᵀ + λ²I)⁻¹J, damped so that a stretched arm does not blow it up.
        const Eigen::Matrix3d JJt = J_des_ * J_des_.transpose() + 1e-4 * Eigen::Matrix3d::Identity();
        const Eigen::Vector3d task_part = JJt.ldlt().solve(J_des_ * q_des_to_held_);
        q_des_to_held_.noalias() -= J_des_.transpose() * task_part;
        q_des_ = (q_des_ + anchor * q_des_to_held_).cwiseMax(limiter_.lower()).cwiseMin(limiter_.upper());
      }
      controller_.velocity(limiter_.command(), p_des_, q_map_, qd_, &limiter_);
      limiter_.updateVelocity(qd_);
      break;
    }
  }
  command.q_cmd = limiter_.command();
}

}  // namespace flexirob::robot
