#pragma once
// The Bullet simulation backend: the arm as an articulated multibody (Featherstone) with the
// URDF's masses, inertias and hardware position limits, driven by an emulation of the LWR IV's
// joint impedance controller (thesis App. A.3):
//   τ = g(q) + K (q_cmd − q) − D q̇ − d_drift q̇,   D_jj = 2 ζ_j sqrt(K_jj M_jj(q)),
// where g(q) compensates gravity as the robot's own controller does, ζ is the command's
// normalized damping, M_jj the joint-space inertia and d_drift an added viscous damping so that
// the arm does not drift once released (DESIGN §3; on very light links at most 4000 s⁻¹ M_jj).
// The torque is clipped to the URDF's effort limits. A *hand* applies an external force at a
// point on any link (the GUI's mouse, the simulated tutor); τ_ext is reported as the robot would
// estimate it: J_pᵀ F at the contact.
//
// Stepping is deterministic: every step() advances exactly cycleTime() (1 ms) in equal physics
// steps, with the impedance law re-evaluated in each (the LWR's inner loop runs faster than
// FRI's cycle). Their number is `sim.substeps` or, where the arm is too light for that, as
// many as the explicitly applied impedance needs to stay stable (stableSubsteps()). Headless
// it runs faster than real time.
//
// With a scene, a collision world reports contacts of links with obstacles and with each
// other after every step (E_coll). The links pass through obstacles (no contact forces): what
// matters for evaluations is that no contact goes unnoticed.
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "robot/backend.hpp"
#include "robot/collision.hpp"
#include "robot/kinematics.hpp"
#include "robot/parameters.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {

/// Declared parameters of the simulation ("sim.*").
std::span<const ParameterDeclaration> simulationParameters();

class Simulation final : public RobotBackend {
 public:
  /// The model must outlive the simulation. `scene` may be null (an empty scene: the table top
  /// z = 0 and self-collision are checked, nothing else). Starts at rest at the model's
  /// midPosture().
  Simulation(const RobotModel& model, const Scene* scene, const ParameterSet& parameters);
  ~Simulation() override;
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  const RobotModel& model() const override { return *model_; }
  double cycleTime() const override { return cycle_time_; }
  void readState(RobotState& state) const override;
  CommandStatus writeCommand(const JointImpedanceCommand& command) override;
  void step() override;

  /// Puts the arm at rest at q (inside the hardware limits, else InputError); the command
  /// becomes q with the current gains; time and collision counts restart.
  void reset(const Eigen::VectorXd& q);

  /// The hand: force F_W [N, in W] at point p_W [m, in W, taken at the current posture] on
  /// body `body` (1..dof; the base cannot be pushed). The point stays fixed to the body.
  /// Throws InputError for a bad body index or non-finite values.
  void setHandForce(int body, const Eigen::Vector3d& p_W, const Eigen::Vector3d& F_W);
  void clearHandForce();

  /// Contacts after the last step, and the collision counts since reset() (E_coll).
  const std::vector<Contact>& contacts() const { return contacts_; }
  const CollisionMonitor& collisions() const { return monitor_; }
  /// Null without a scene. For the simulated tutor and evaluations only.
  CollisionWorld* collisionWorld() { return collision_.get(); }

  double time() const { return time_; }
  std::uint64_t steps() const { return steps_; }
  /// Substeps in which a joint torque hit its effort limit.
  std::uint64_t torqueSaturations() const { return torque_saturations_; }
  /// Physics steps the next step() takes (what the last one took, or what reset() planned),
  /// and the most any step() took since reset().
  int lastSubsteps() const { return last_substeps_; }
  int maxSubsteps() const { return max_substeps_; }
  /// Whether a step since reset() needed more than kSubstepCap physics steps (and took the cap):
  /// the arm may have shaken in the simulation.
  bool substepCapReached() const { return substep_cap_reached_; }
  /// The physics steps per cycle the current posture and command need: `sim.substeps`, or
  /// more where the impedance law, applied explicitly, would make the arm oscillate or diverge
  /// (light links under a stiff command); kSubstepCap + 1 where more than kSubstepCap are needed
  /// or the inertia cannot be judged. For the thread that steps the simulation (shared scratch).
  int stableSubsteps();
  static constexpr int kSubstepCap = 1024;
  /// M(q) at the posture stableSubsteps() last judged [kg m², kg m, kg] (both triangles).
  const Eigen::MatrixXd& jointSpaceInertia() const;
  /// Joint-space inertia diagonal M_jj(q) [kg m²] at the current posture.
  const Eigen::VectorXd& inertiaDiagonal() const { return inertia_diagonal_; }
  /// Gravity compensation torque g(q) [Nm] at the current posture.
  const Eigen::VectorXd& gravityTorque() const { return gravity_torque_; }

  /// The joint gravity loads most against its effort limit at a posture: |g_j(q)| / effort_j
  /// largest (a URDF effort of 0 counts as unlimited). Above 1 the joint cannot hold the arm
  /// there and it sags, whatever it is commanded. Allocates: not for the control cycle.
  struct GravityLoad {
    int joint = -1;          ///< -1: every joint is unlimited
    double torque = 0.0;     ///< |g_j(q)| [Nm or N]
    double effort = 0.0;     ///< the joint's effort limit [Nm or N]
    double ratio = 0.0;      ///< torque / effort
  };
  GravityLoad gravityLoad(const Eigen::VectorXd& q) const;
  /// "joint 'j2' to hold 850 Nm against gravity, 850 % of its effort limit of 100 Nm" (N for a
  /// prismatic joint).
  std::string describe(const GravityLoad& load) const;

 private:
  struct Impl;
  void readJoints();
  void computeModelTerms();  // kinematics, g(q), M_jj(q) at q_
  // g(q) and, when given, M_jj(q) at the posture `kinematics` was updated to.
  void modelTerms(const Kinematics& kinematics, Eigen::VectorXd& gravity_torque, Eigen::VectorXd* inertia_diagonal) const;
  double driftDamping(double joint_inertia) const;  // sim.drift_damping, bounded for light links
  bool isPrismatic(int joint) const { return model_->joints()[static_cast<std::size_t>(joint)].type == JointType::kPrismatic; }

  const RobotModel* model_;
  double cycle_time_;
  int substeps_;
  double gravity_;
  double drift_damping_;
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<CollisionWorld> collision_;
  CollisionMonitor monitor_;
  std::vector<Contact> contacts_;
  Kinematics kinematics_;
  mutable Matrix3Xd jacobian_;  // scratch for readState()
  Eigen::VectorXd q_, qd_, tau_, tau_ext_, gravity_torque_, inertia_diagonal_, effort_;
  JointImpedanceCommand command_;
  std::vector<double> masses_;                 // as given to Bullet, per body
  std::vector<Eigen::Vector3d> coms_;          // p_BCom per body
  std::vector<Eigen::Matrix3d> inertias_;      // I_BCom per body (as given to Bullet)
  static constexpr std::uint64_t kSubstepCheckCycles = 10;
  Eigen::VectorXd checked_stiffness_, checked_damping_;  // the gains stableSubsteps() last saw
  int last_substeps_ = 0;
  bool substep_cap_reached_ = false;
  int max_substeps_ = 0;
  int hand_body_ = -1;
  Eigen::Vector3d hand_p_B_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_F_W_ = Eigen::Vector3d::Zero();
  double time_ = 0.0;
  std::uint64_t steps_ = 0;
  std::uint64_t torque_saturations_ = 0;
};

}  // namespace flexirob::robot
