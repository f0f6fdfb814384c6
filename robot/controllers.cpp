#include "robot/controllers.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace flexirob::robot {
namespace {

constexpr std::array kLimiterParameters{
    ParameterDeclaration{"limits.velocity_scale", 1.0, 0.01, 1.0, "",
                         "fraction of the URDF velocity limits the commands may use"},
    ParameterDeclaration{"limits.acceleration", 5.0, 0.1, 1000.0, "rad/s^2",
                         "joint acceleration limit of the second-order command smoothing (Sect. 8.1)"},
};

constexpr std::array kHierarchicalParameters{
    ParameterDeclaration{"hierarchical.kappa_x", 10.0, 0.0, 500.0, "1/s",
                         "task-space gain kappa_x of Eq. 2.11"},
    ParameterDeclaration{"hierarchical.kappa_q", 2.0, 0.0, 100.0, "1/s",
                         "null-space gain kappa_q of Eq. 2.11"},
    ParameterDeclaration{"hierarchical.sigma_threshold", 0.05, 1e-6, 1.0, "m/rad",
                         "smallest singular value of J below which the pseudo-inverse is damped"},
    ParameterDeclaration{"hierarchical.damping_max", 0.05, 0.0, 1.0, "m/rad",
                         "damping mu_max of the pseudo-inverse at a singularity"},
};

// Largest speed from which the joint stops exactly within `distance` when it decelerates by
// a·dt per cycle: k full deceleration steps plus an even share of the remainder
// (v, v − a·dt, ..., δ covers a·dt²·k(k+1)/2 + (k+1)·δ·dt).
double brakingSpeed(double distance, double a, double dt) {
  if (!(distance > 0.0)) return 0.0;
  const double adt2 = a * dt * dt;
  const double k = std::floor(std::sqrt(0.25 + 2.0 * distance / adt2) - 0.5);
  const double remainder = std::max(0.0, distance - adt2 * k * (k + 1.0) / 2.0);
  return a * dt * k + remainder / ((k + 1.0) * dt);
}

}  // namespace

std::span<const ParameterDeclaration> limiterParameters() { return kLimiterParameters; }
std::span<const ParameterDeclaration> hierarchicalParameters() { return kHierarchicalParameters; }

// ---------------------------------------------------------------------------------------------
CommandLimiter::CommandLimiter(const RobotModel& model, const ParameterSet& parameters, double cycle_time)
    : dt_(cycle_time),
      a_max_(parameters.get("limits.acceleration")),
      lower_(model.softLowerLimits()),
      upper_(model.softUpperLimits()),
      v_max_(model.velocityLimits() * parameters.get("limits.velocity_scale")),
      q_(model.midPosture()),
      qd_(Eigen::VectorXd::Zero(model.dof())) {}

void CommandLimiter::reset(const Eigen::VectorXd& q) {
  qd_.setZero();
  if (q.size() != q_.size()) {
    ++counters_.rejected;
    return;
  }
  bool clamped = false;
  for (Eigen::Index i = 0; i < q_.size(); ++i) {
    double value = q[i];
    if (!std::isfinite(value)) {
      value = std::isfinite(lower_[i]) && std::isfinite(upper_[i]) ? 0.5 * (lower_[i] + upper_[i]) : 0.0;
      clamped = true;
    }
    if (value < lower_[i] || value > upper_[i]) clamped = true;
    q_[i] = std::clamp(value, lower_[i], upper_[i]);
  }
  if (clamped) ++counters_.position;
}

void CommandLimiter::integrateJoint(Eigen::Index i, double v_desired, bool count_acceleration,
                                    bool& position_clamped, bool& acceleration_clamped) {
  // Second-order smoothing: the velocity changes by at most a_max·dt per cycle.
  const double dv = a_max_ * dt_;
  double v = v_desired;
  if (v > qd_[i] + dv || v < qd_[i] - dv) {
    v = std::clamp(v, qd_[i] - dv, qd_[i] + dv);
    if (count_acceleration) acceleration_clamped = true;
  }
  // Never faster than the joint can still stop before a soft limit.
  const double v_up = brakingSpeed(upper_[i] - q_[i], a_max_, dt_);
  const double v_down = brakingSpeed(q_[i] - lower_[i], a_max_, dt_);
  if (v > v_up || v < -v_down) {
    v = std::clamp(v, -v_down, v_up);
    position_clamped = true;
  }
  v = std::clamp(v, -v_max_[i], v_max_[i]);
  double next = q_[i] + v * dt_;
  if (next < lower_[i] || next > upper_[i]) {
    position_clamped = true;
    next = std::clamp(next, lower_[i], upper_[i]);
  }
  qd_[i] = (next - q_[i]) / dt_;
  q_[i] = next;
}

const Eigen::VectorXd& CommandLimiter::update(const Eigen::VectorXd& q_target) {
  const bool valid = q_target.size() == q_.size() && q_target.allFinite();
  if (!valid) ++counters_.rejected;
  bool position_clamped = false;
  bool velocity_clamped = false;
  bool acceleration_clamped = false;
  for (Eigen::Index i = 0; i < q_.size(); ++i) {
    // Towards the (clamped) target, no faster than the velocity limit and slow enough to stop
    // on the target; an invalid target means stop here (braking is smoothing, not a clamp).
    double v_desired = 0.0;
    if (valid) {
      double target = q_target[i];
      if (target < lower_[i] || target > upper_[i]) {
        position_clamped = true;
        target = std::clamp(target, lower_[i], upper_[i]);
      }
      const double error = target - q_[i];
      const double speed = std::min(std::abs(error) / dt_, brakingSpeed(std::abs(error), a_max_, dt_));
      if (speed > v_max_[i]) velocity_clamped = true;
      v_desired = std::copysign(std::min(speed, v_max_[i]), error);
    }
    integrateJoint(i, v_desired, valid, position_clamped, acceleration_clamped);
  }
  if (position_clamped) ++counters_.position;
  if (velocity_clamped) ++counters_.velocity;
  if (acceleration_clamped) ++counters_.acceleration;
  return q_;
}

const Eigen::VectorXd& CommandLimiter::updateVelocity(const Eigen::VectorXd& qd_desired) {
  const bool valid = qd_desired.size() == q_.size() && qd_desired.allFinite();
  if (!valid) ++counters_.rejected;
  bool position_clamped = false;
  bool velocity_clamped = false;
  bool acceleration_clamped = false;
  // Velocity and acceleration limits scale the request as a whole, so that a null-space
  // velocity stays one (per-joint clipping would turn it and move the tip).
  double velocity_scale = 1.0;
  double acceleration_scale = 1.0;
  if (valid) {
    for (Eigen::Index i = 0; i < q_.size(); ++i) {
      if (std::abs(qd_desired[i]) > v_max_[i]) velocity_scale = std::min(velocity_scale, v_max_[i] / std::abs(qd_desired[i]));
    }
    for (Eigen::Index i = 0; i < q_.size(); ++i) {
      const double change = std::abs(velocity_scale * qd_desired[i] - qd_[i]);
      if (change > a_max_ * dt_) acceleration_scale = std::min(acceleration_scale, a_max_ * dt_ / change);
    }
    velocity_clamped = velocity_scale < 1.0;
    acceleration_clamped = acceleration_scale < 1.0;
  }
  for (Eigen::Index i = 0; i < q_.size(); ++i) {
    const double v_desired =
        valid ? qd_[i] + acceleration_scale * (velocity_scale * qd_desired[i] - qd_[i]) : 0.0;
    bool unused = false;
    integrateJoint(i, v_desired, valid, position_clamped, unused);
  }
  if (position_clamped) ++counters_.position;
  if (velocity_clamped) ++counters_.velocity;
  if (acceleration_clamped) ++counters_.acceleration;
  return q_;
}

// ---------------------------------------------------------------------------------------------
HierarchicalController::HierarchicalController(const RobotModel& model, const ParameterSet& parameters)
    : model_(&model),
      kinematics_(model),
      kappa_x_(parameters.get("hierarchical.kappa_x")),
      kappa_q_(parameters.get("hierarchical.kappa_q")),
      sigma_0_(parameters.get("hierarchical.sigma_threshold")),
      mu_max_squared_(std::pow(parameters.get("hierarchical.damping_max"), 2)),
      lower_(model.softLowerLimits()),
      upper_(model.softUpperLimits()),
      v_max_(model.velocityLimits()),
      J_full_(3, model.dof()),
      J_(3, model.dof()),
      J_pinv_(model.dof(), 3),
      N_(model.dof(), model.dof()),
      dq_null_(model.dof()),
      free_(model.dof()),
      qd_buffer_(model.dof()),
      qd_task_(model.dof()),
      qd_null_(model.dof()) {
  const double scale = parameters.has("limits.velocity_scale") ? parameters.get("limits.velocity_scale") : 1.0;
  v_max_ *= scale;
  task_rank_ = structuralTaskRank();
}

int HierarchicalController::structuralTaskRank() {
  // A planar arm (every axis parallel) moves its tip in a plane whatever its posture: J has a
  // zero singular value everywhere. Damping meant for singularities would then act all the
  // time and hold the tip short of targets in its plane; that direction is left out instead.
  // Looked at in a few postures spread over the ranges (a singular one may be among them).
  const int n = model_->dof();
  const Eigen::VectorXd lower = model_->sampleLowerLimits(), upper = model_->sampleUpperLimits();
  int rank = 0;
  for (int sample = 0; sample < 5; ++sample) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) {
      const double fraction = std::fmod(0.5 + 0.618034 * sample + 0.414214 * j * sample, 1.0);
      q[j] = lower[j] + fraction * (upper[j] - lower[j]);
    }
    kinematics_.update(q);
    kinematics_.tipPositionJacobian(J_full_);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(J_full_ * J_full_.transpose(), Eigen::EigenvaluesOnly);
    const double largest = eigen.eigenvalues()[2];
    int independent = 0;
    for (int k = 0; k < 3; ++k) independent += eigen.eigenvalues()[k] > std::max(1e-9 * largest, 1e-14) ? 1 : 0;
    rank = std::max(rank, independent);
  }
  return rank == 0 ? 3 : rank;
}

HierarchicalController::Status HierarchicalController::velocity(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des,
                                                                const Eigen::VectorXd& q_c, Eigen::VectorXd& qd,
                                                                const CommandLimiter* limiter) {
  return velocity(q, p_des, Eigen::Vector3d::Zero(), q_c, qd, limiter);
}

HierarchicalController::Status HierarchicalController::velocity(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des,
                                                                const Eigen::Vector3d& pd_des,
                                                                const Eigen::VectorXd& q_c, Eigen::VectorXd& qd,
                                                                const CommandLimiter* limiter) {
  const int n = model_->dof();
  if (qd.size() != n) qd.setZero(n);  // allocates only on a caller's first, unsized call
  if (q.size() != n || q_c.size() != n || !q.allFinite() || !q_c.allFinite() || !p_des.allFinite() ||
      !pd_des.allFinite()) {
    qd.setZero();
    ++counters_.rejected;
    return Status::kRejectedTarget;
  }
  kinematics_.update(q);
  kinematics_.tipPositionJacobian(J_full_);
  const Eigen::Vector3d error = p_des - kinematics_.p_WT();
  task_error_ = error.norm();

  // The null-space target as the shortest way round for continuous joints.
  model_->postureDifference(q_c, q, dq_null_);

  free_.setOnes();
  for (int pass = 0; pass <= n; ++pass) {
    // J of the joints still free to move.
    J_ = J_full_ * free_.asDiagonal();
    const Eigen::Matrix3d JJt = J_ * J_.transpose();
    Eigen::Matrix3d A = JJt;
    if (task_rank_ == 3) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(JJt, Eigen::EigenvaluesOnly);
      sigma_min_ = std::sqrt(std::max(0.0, eigen.eigenvalues()[0]));
    } else {
      // The directions the tip never moves in: J⁺ has nothing to map them to (Jᵀv = 0), and
      // the one added to A only keeps it invertible; σ_min is that of the directions it has.
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(JJt);
      const int missing = 3 - task_rank_;
      sigma_min_ = std::sqrt(std::max(0.0, eigen.eigenvalues()[missing]));
      for (int k = 0; k < missing; ++k) A += eigen.eigenvectors().col(k) * eigen.eigenvectors().col(k).transpose();
    }
    // Damped least squares only near singularities (Sect. 2.1).
    mu_squared_ = sigma_min_ < sigma_0_ ? mu_max_squared_ * (1.0 - std::pow(sigma_min_ / sigma_0_, 2)) : 0.0;
    A += Eigen::Matrix3d::Identity() * std::max(mu_squared_, 1e-12);
    J_pinv_.noalias() = J_.transpose() * A.inverse();
    // Null-space projector I − J⁺J, restricted to the free joints.
    N_.noalias() = -J_pinv_ * J_;
    N_.diagonal().array() += 1.0;
    N_ = free_.asDiagonal() * N_ * free_.asDiagonal();
    // Eq. 2.11, with the target's own velocity fed forward as in Eq. 2.6.
    qd_task_.noalias() = J_pinv_ * (pd_des + kappa_x_ * error);
    qd_null_.noalias() = kappa_q_ * N_ * dq_null_;
    qd = qd_task_ + qd_null_;
    // Joints on a soft limit that would be pushed out leave the task for this cycle.
    bool locked_more = false;
    for (int i = 0; i < n; ++i) {
      if (free_[i] == 0.0) continue;
      constexpr double kOnLimit = 1e-6;
      if ((q[i] >= upper_[i] - kOnLimit && qd[i] > 0.0) || (q[i] <= lower_[i] + kOnLimit && qd[i] < 0.0)) {
        free_[i] = 0.0;
        locked_more = true;
      }
    }
    if (!locked_more) break;
  }
  // Keep to the limits: first the null-space term gives way (largest s in [0, 1] with
  // q̇ = q̇_task + s·q̇_null inside the velocity window and, with a limiter, inside the
  // acceleration window around its current velocity); then the whole q̇ is scaled.
  // Intersection over the joints of the s-intervals where lo <= t + s·m <= hi.
  auto largestFeasible = [&](bool with_acceleration) {
    double s_lo = 0.0;
    double s_hi = 1.0;
    for (int i = 0; i < n; ++i) {
      double lo = -v_max_[i];
      double hi = v_max_[i];
      if (with_acceleration) {
        const double dv = limiter->accelerationLimit() * limiter->cycleTime();
        lo = std::max(lo, limiter->velocity()[i] - dv);
        hi = std::min(hi, limiter->velocity()[i] + dv);
      }
      const double t = qd_task_[i];
      const double m = qd_null_[i];
      if (std::abs(m) < 1e-15) {
        if (t < lo || t > hi) return -1.0;
        continue;
      }
      const double a = (lo - t) / m;
      const double b = (hi - t) / m;
      s_lo = std::max(s_lo, std::min(a, b));
      s_hi = std::min(s_hi, std::max(a, b));
    }
    return s_lo <= s_hi ? s_hi : -1.0;
  };
  double s = -1.0;
  if (limiter != nullptr && limiter->velocity().size() == n) s = largestFeasible(true);
  if (s < 0.0) s = largestFeasible(false);
  s = std::max(s, 0.0);
  qd = qd_task_ + s * qd_null_;
  if (s < 1.0) ++null_space_scaled_;
  double scale = 1.0;
  for (int i = 0; i < n; ++i) {
    if (std::abs(qd[i]) > v_max_[i]) scale = std::min(scale, v_max_[i] / std::abs(qd[i]));
  }
  if (scale < 1.0) {
    qd *= scale;
    ++counters_.velocity;
  }
  return Status::kOk;
}

HierarchicalController::Status HierarchicalController::target(const Eigen::VectorXd& q, const Eigen::Vector3d& p_des,
                                                              const Eigen::VectorXd& q_c, double dt,
                                                              Eigen::VectorXd& q_target) {
  const Status status = velocity(q, p_des, q_c, qd_buffer_);
  if (status != Status::kOk) {
    // Hold the base posture if it is usable; the limiter rejects it otherwise.
    q_target = q;
    return status;
  }
  q_target = q + qd_buffer_ * dt;
  return status;
}

}  // namespace flexirob::robot
