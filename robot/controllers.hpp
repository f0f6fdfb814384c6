#pragma once
// The hierarchical null-space controller (thesis Sect. 2.3.2, Eq. 2.10-2.11) and the command
// limiter that keeps every joint command inside the software position limits, the velocity
// limits and the acceleration limits (second-order smoothing, Sect. 8.1).
//
// Task space: the tip position p_WT (M = 3) in the base frame W, metres. Joint space: radians.
// Both classes preallocate in their constructors; update() calls do not allocate, so they are
// safe in the 1 kHz control loop.
#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "robot/kinematics.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::robot {

/// The taught redundancy resolution q_c(x) (Sect. 2.3): a task-space position maps to a
/// preferred posture. The learning library's learners plug in here; FixedPosture stands in.
class RedundancyMap {
 public:
  virtual ~RedundancyMap() = default;
  /// Number of joints of the postures it predicts.
  virtual int dof() const = 0;
  /// q_c(p_W): writes dof() values into q_c (sized by the caller). Must not allocate.
  virtual void predict(const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) const = 0;
};

/// q_c(x) = q_fixed everywhere: the compliant-recording null-space target (Sect. 8.1) and the
/// default before anything is learned.
class FixedPosture final : public RedundancyMap {
 public:
  explicit FixedPosture(Eigen::VectorXd q_fixed) : q_fixed_(std::move(q_fixed)) {}
  int dof() const override { return static_cast<int>(q_fixed_.size()); }
  void predict(const Eigen::Vector3d&, Eigen::VectorXd& q_c) const override { q_c = q_fixed_; }
  void set(const Eigen::VectorXd& q_fixed) { q_fixed_ = q_fixed; }
  const Eigen::VectorXd& posture() const { return q_fixed_; }

 private:
  Eigen::VectorXd q_fixed_;
};

/// How often each limit changed a command. Every clamp is counted, never silently dropped.
struct LimitCounters {
  std::uint64_t position = 0;      ///< cycles where a joint target lay outside the soft limits
  std::uint64_t velocity = 0;      ///< cycles where a joint velocity was limited
  std::uint64_t acceleration = 0;  ///< cycles where a joint acceleration was limited
  std::uint64_t rejected = 0;      ///< non-finite or wrongly sized targets (held, not propagated)
  std::uint64_t total() const { return position + velocity + acceleration + rejected; }
  LimitCounters& operator+=(const LimitCounters& other) {
    position += other.position;
    velocity += other.velocity;
    acceleration += other.acceleration;
    rejected += other.rejected;
    return *this;
  }
};

/// Declared parameters of the command limiter ("limits.*").
std::span<const ParameterDeclaration> limiterParameters();

/// Second-order smoothing of joint targets (Sect. 8.1): the output q_cmd moves towards the
/// target with |q̇| <= v_max (URDF velocity limits times limits.velocity_scale) and
/// |q̈| <= limits.acceleration, braking in time so that it neither overshoots the target nor
/// leaves [softLowerLimits, softUpperLimits]. Whatever the input, the output is finite and
/// inside these bounds.
class CommandLimiter {
 public:
  CommandLimiter(const RobotModel& model, const ParameterSet& parameters, double cycle_time);

  /// Starts from posture q at rest. A posture outside the soft limits is clamped into them
  /// (counted as a position clamp); non-finite entries are replaced by the centre of the limits.
  void reset(const Eigen::VectorXd& q);
  /// One cycle: moves the output towards q_target. A target with a wrong size or a non-finite
  /// entry is rejected: the output brakes to a stop where it is (counted as rejected).
  const Eigen::VectorXd& update(const Eigen::VectorXd& q_target);
  /// One cycle driven by a desired joint velocity [rad/s] (the hierarchical controller's q̇):
  /// the same limits apply; a wrongly sized or non-finite request brakes to a stop (rejected).
  const Eigen::VectorXd& updateVelocity(const Eigen::VectorXd& qd_desired);

  const Eigen::VectorXd& command() const { return q_; }
  const Eigen::VectorXd& velocity() const { return qd_; }
  const Eigen::VectorXd& lower() const { return lower_; }
  const Eigen::VectorXd& upper() const { return upper_; }
  const Eigen::VectorXd& velocityLimit() const { return v_max_; }
  double accelerationLimit() const { return a_max_; }
  double cycleTime() const { return dt_; }
  const LimitCounters& counters() const { return counters_; }

 private:
  // Smooths joint i towards v_desired, keeps the limits, records which ones acted.
  void integrateJoint(Eigen::Index i, double v_desired, bool count_acceleration, bool& position_clamped,
                      bool& acceleration_clamped);

  double dt_;
  double a_max_;
  Eigen::VectorXd lower_, upper_, v_max_;
  Eigen::VectorXd q_, qd_;
  LimitCounters counters_;
};

/// Declared parameters of the hierarchical controller ("hierarchical.*").
std::span<const ParameterDeclaration> hierarchicalParameters();

/// Eq. 2.11: q̇ = κ_x J⁺ (x_des − x) + κ_q (I − J⁺J)(q_c(x_des) − q), with J the 3 × N
/// position Jacobian of the tip in W and J⁺ = Jᵀ(JJᵀ + μ²I)⁻¹ a damped pseudo-inverse whose
/// damping μ² = μ_max²(1 − (σ_min/σ_0)²) rises only when the smallest singular value σ_min
/// drops below σ_0 (Sect. 2.1; exact pseudo-inverse elsewhere, so the null-space term does not
/// move the tip). Joints resting on a soft limit that q̇ would push further out are taken out
/// of J and of the null-space projection, so the remaining joints still reach the target.
/// The joint velocity is scaled down as a whole (direction kept) to the velocity limits.
class HierarchicalController {
 public:
  HierarchicalController(const RobotModel& model, const ParameterSet& parameters);

  enum class Status { kOk, kRejectedTarget };

  /// Joint velocity for posture q (the integration base: the previous command, or the measured
  /// posture for closed-loop use), task target p_des [m, W] and null-space target q_c [rad].
  /// Non-finite or wrongly sized inputs give q̇ = 0 and kRejectedTarget.
  /// With a limiter, the null-space term is scaled down first so that q̇ keeps to the limiter's
  /// velocity and acceleration limits; the task term keeps priority (scaling both together, or
  /// clipping joints one by one, would turn q̇ out of the null space and move the tip).
  Status velocity(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des, const Eigen::VectorXd& q_c,
                  Eigen::VectorXd& qd, const CommandLimiter* limiter = nullptr);
  /// The same for a target moving at pd_des [m/s]: its velocity enters the task term as the
  /// feed-forward ẋ of Eq. 2.6, J⁺(ẋ_des + κ_x (x_des − x)), so that the tip follows a moving
  /// target without the steady lag |ẋ_des|/κ_x that Eq. 2.11's feedback alone leaves.
  Status velocity(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des, const Eigen::Vector3d& pd_des,
                  const Eigen::VectorXd& q_c, Eigen::VectorXd& qd, const CommandLimiter* limiter = nullptr);
  /// q_target = q + q̇·dt (Fig. 2.6), for a CommandLimiter to smooth and clamp.
  Status target(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des, const Eigen::VectorXd& q_c, double dt,
                Eigen::VectorXd& q_target);

  /// For kinematic searches (IK as target() iterated a fixed number of times), not motions:
  /// joints allowed less than kSearchVelocity (URDF limit times limits.velocity_scale) step as if
  /// allowed that much, so that the search covers a slow arm's joint range as well (the LWR IV's
  /// joints all allow more at the default scale of 1; a scene that slows them below 0.78 gets
  /// the LWR IV's own search steps back).
  void useForKinematicSearch() { v_max_ = v_max_.cwiseMax(kSearchVelocity); }
  static constexpr double kSearchVelocity = 1.5;  ///< [rad/s, m/s]

  /// Of the last velocity() call: the task error |x_des − x| [m], σ_min of J, and the damping μ².
  double taskError() const { return task_error_; }
  double smallestSingularValue() const { return sigma_min_; }
  double damping() const { return mu_squared_; }
  /// Cycles in which q̇ was scaled down to the velocity limits, or a target was rejected.
  const LimitCounters& counters() const { return counters_; }
  /// Cycles in which the null-space term was scaled down to keep to the limits (this shapes
  /// the secondary task only and is not a clamp of the command).
  std::uint64_t nullSpaceScaled() const { return null_space_scaled_; }
  double kappaX() const { return kappa_x_; }
  double kappaQ() const { return kappa_q_; }
  const Kinematics& kinematics() const { return kinematics_; }

 private:
  /// How many independent directions the tip can move in at all (3; 2 for a planar arm).
  int structuralTaskRank();

  const RobotModel* model_;
  Kinematics kinematics_;
  double kappa_x_, kappa_q_, sigma_0_, mu_max_squared_;
  int task_rank_ = 3;
  Eigen::VectorXd lower_, upper_, v_max_;
  Matrix3Xd J_full_, J_;
  Eigen::MatrixXd J_pinv_, N_;
  Eigen::VectorXd dq_null_, free_, qd_buffer_, qd_task_, qd_null_;
  LimitCounters counters_;
  std::uint64_t null_space_scaled_ = 0;
  double task_error_ = 0.0, sigma_min_ = 0.0, mu_squared_ = 0.0;
};

}  // namespace flexirob::robot
