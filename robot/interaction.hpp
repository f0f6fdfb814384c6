#pragma once
// Interaction controllers of the teaching workflow (thesis Sect. 4.1, 5.1, 6.1, 8.1, App. A.3):
// each turns the measured robot state into a joint impedance command once per 1 ms cycle.
//
//   gravity compensation π_q        the commanded posture follows the arm where the tutor
//                                   pushes it (joint-space admittance: virtual inertia and
//                                   damping driven by the spring's deflection torque), so the
//                                   arm moves freely and stops when released (Sect. 4.1);
//   compliant recording π_rec       q_cmd = q_fixed: the arm springs back (Sect. 4.1);
//   hierarchical control            q_cmd from Eq. 2.11 towards x_des with q_c(x_des);
//   assisted gravity compensation   the tip target x_des follows the tip (task-space admittance,
//                                   Cartesian damping), the null space follows q_c(x_des) (5.1);
//   assistance blending             q_des (an admittance driven by τ_ext) blended with
//                                   q_c(x_des) by α = C(x_des), Eq. 6.2, x_des = K_fwd(q_des),
//                                   fed to the hierarchical controller (Sect. 6.1);
//   keyboard tele-operation         Δx_des and Δq_des steps fused by the hierarchical
//                                   controller, as π_q, π_rec or assisted (Sect. 8.1).
// Stiffness, damping and inertia per mode: Tab. A.1. All commands pass the CommandLimiter.
// Allocation-free after construction.
#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "robot/backend.hpp"
#include "robot/controllers.hpp"
#include "robot/parameters.hpp"

namespace flexirob::robot {

enum class InteractionMode {
  kGravityCompensation,
  kCompliantRecording,
  kHierarchicalControl,
  kAssistedGravityCompensation,
  kAssistanceBlending,
};

const char* toString(InteractionMode mode);

/// Tab. A.1: joint stiffness [Nm/rad], normalized damping, and the virtual inertia of the
/// mode's admittance (joint space [kg m²] or task space [kg]; 0 where the mode has none).
struct ModeGains {
  double stiffness;
  double damping;
  double inertia;
};
ModeGains modeGains(InteractionMode mode);

/// The robot's confidence in its learned map, C(x) ∈ [0, 1] (Eq. 6.1). Must not allocate.
class ConfidenceMap {
 public:
  virtual ~ConfidenceMap() = default;
  virtual double confidence(const Eigen::Vector3d& p_W) const = 0;
};

/// C(x) = c everywhere (c = 0 before anything is learned, Sect. 6.1).
class ConstantConfidence final : public ConfidenceMap {
 public:
  explicit ConstantConfidence(double c) : c_(c) {}
  double confidence(const Eigen::Vector3d&) const override { return c_; }

 private:
  double c_;
};

/// Declared parameters of the interaction controllers ("interaction.*"), to be combined with
/// hierarchicalParameters() and limiterParameters().
std::span<const ParameterDeclaration> interactionParameters();

/// Everything the interaction controllers read: interaction.*, hierarchical.*, limits.*.
std::vector<ParameterDeclaration> interactionControllerParameters();

class InteractionController {
 public:
  /// parameters must declare interactionControllerParameters(). The map (and confidence) must
  /// outlive the controller; confidence may be null (C ≡ 0).
  InteractionController(const RobotModel& model, const ParameterSet& parameters, double cycle_time);

  /// Switches mode and starts it from the measured state (no jump: the command starts at q).
  void start(InteractionMode mode, const RobotState& state);
  InteractionMode mode() const { return mode_; }

  void setRedundancyMap(const RedundancyMap* map) { map_ = map; }
  void setConfidence(const ConfidenceMap* confidence) { confidence_ = confidence; }
  /// π_rec's posture (and the null-space target of hierarchical control without a map).
  void setFixedPosture(const Eigen::VectorXd& q_fixed);
  /// Target of hierarchical control [m, W], and the velocity it moves at [m/s] in the next
  /// cycle (fed forward; it holds for that cycle only, so a caller that stops moving the target
  /// leaves no drift behind). A non-finite velocity counts as zero.
  void setTaskTarget(const Eigen::Vector3d& p_des, const Eigen::Vector3d& pd_des = Eigen::Vector3d::Zero()) {
    p_des_ = p_des;
    pd_target_ = pd_des.allFinite() ? pd_des : Eigen::Vector3d::Zero();
  }

  /// Keyboard tele-operation (Sect. 8.1): moves the task target by Δx [m] and, in
  /// gravity compensation, the null-space target by Δq [rad]. Non-finite steps are ignored.
  void nudgeTask(const Eigen::Vector3d& dx);
  void nudgeJoints(const Eigen::VectorXd& dq);
  /// Keyboard mode: the tutor commands x_des and q_c by steps instead of pushing the arm
  /// (the simulated 9-DoF arm of Sect. 8.1 has no hand to feel).
  void setKeyboardMode(bool keyboard) { keyboard_ = keyboard; }
  /// Assisted gravity compensation holds x_des where it is instead of letting it follow the
  /// tip: PROGRAMMING's POSED keeps the start position the tutor chose (Sect. 2.3.3), so that a
  /// hand taking the arm again shows as external torque (on_affected) before the arm gives way.
  /// The keyboard's steps still move x_des.
  void setTaskHeld(bool held) { task_held_ = held; }
  /// Tab. A.1's gains and the admittances' damping are the LWR IV's. An arm lighter or much
  /// heavier than it gets its joint stiffness, joint-space virtual inertia and damping times
  /// `inertia` (robot::inertiaScaleToLwr), the Cartesian ones times `mass`, so that it moves as
  /// an LWR IV of its size would (a light arm under the LWR IV's gains rings faster than the
  /// control cycle samples it; a 260 kg arm crept). Both positive and finite (others are
  /// ignored); 1 is the LWR IV. Takes effect at once.
  void setArmScale(double inertia, double mass);

  /// One cycle: writes q_cmd, stiffness and damping for the current mode.
  void update(const RobotState& state, JointImpedanceCommand& command);

  const Eigen::Vector3d& taskTarget() const { return p_des_; }
  /// Whether the mode in force steers the tip to x_des. π_q and π_rec under the hand hold a
  /// posture instead; their x_des stays where the tip was when they began (Sect. 4.1).
  bool tracksTaskTarget() const {
    return keyboard_ || (mode_ != InteractionMode::kGravityCompensation && mode_ != InteractionMode::kCompliantRecording);
  }
  const Eigen::VectorXd& nullSpaceTarget() const { return q_c_; }
  /// The redundancy map's posture at x_des in the last cycle that asked it (hierarchical
  /// control and the assisted modes) [rad].
  const Eigen::VectorXd& mapPosture() const { return q_map_; }
  /// α of the last assistance-blending cycle.
  double alpha() const { return alpha_; }
  const CommandLimiter& limiter() const { return limiter_; }
  const HierarchicalController& hierarchical() const { return controller_; }

 private:
  const RobotModel* model_;
  double dt_;
  double joint_damping_;     // admittance damping [Nms/rad]
  double cartesian_stiffness_, cartesian_damping_;
  double blending_anchor_rate_;  // [1/s] times α: how fast q_des returns to the held arm (Sect. 6.1)
  HierarchicalController controller_;
  CommandLimiter limiter_;
  Kinematics kinematics_;
  const RedundancyMap* map_ = nullptr;
  const ConfidenceMap* confidence_ = nullptr;
  InteractionMode mode_ = InteractionMode::kHierarchicalControl;
  ModeGains gains_{};
  double inertia_scale_ = 1.0, mass_scale_ = 1.0;  // setArmScale()
  bool keyboard_ = false;
  bool task_held_ = false;  // setTaskHeld()
  Eigen::VectorXd q_fixed_, q_c_, q_des_, qd_des_, qd_, q_map_;
  Matrix3Xd J_des_;                 // tip position Jacobian at q_des (assistance blending)
  Eigen::VectorXd q_des_to_held_;   // q_held − q_des, then its null-space part
  Eigen::Vector3d p_des_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d pd_des_ = Eigen::Vector3d::Zero();     // the task-space admittance's velocity
  Eigen::Vector3d pd_target_ = Eigen::Vector3d::Zero();  // fed forward in hierarchical control
  double alpha_ = 0.0;
};

}  // namespace flexirob::robot
