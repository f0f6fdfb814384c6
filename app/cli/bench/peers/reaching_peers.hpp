#pragma once
// Reaching task-space targets: our hierarchical controller (Eq. 2.11) run as an iterative
// position solver against KDL's joint-limited Newton-Raphson IK (ChainIkSolverPos_NR_JL) and
// KDL's Levenberg-Marquardt solver weighted to position only (ChainIkSolverPos_LMA), on the
// same URDF, from the same start posture, to the same targets (tip poses of seeded random
// postures inside the soft limits). KDL entries exist only when built with FLEXIROB_HAVE_KDL.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "robot/robot_model.hpp"

namespace flexirob::bench::peers {

struct ReachingOptions {
  int targets = 200;
  std::uint64_t seed = 1;
  double success_tolerance = 1e-3;  ///< [m] final tip position error counted as reached
  double eps = 1e-5;                ///< stopping threshold of every solver (KDL's default)
  int max_iterations = 100;         ///< KDL NR_JL's default; the same cap for ours
  int repetitions = 3;              ///< the timing is the median over repeated passes
};

struct ReachingMethodResult {
  std::string name;
  int targets = 0;
  int reached = 0;                  ///< within success_tolerance and inside the soft limits
  double success_rate = 0.0;
  double time_per_target_us = 0.0;  ///< median over repetitions of (pass time / targets)
  double mean_iterations = 0.0;     ///< solver iterations per target (0 if the solver does not say)
  double median_error_m = 0.0;      ///< final tip position error over all targets
};

/// Our controller as a solver: q ← clamp(q + q̇·Δt) with κ_x·Δt = 1 (a Newton step on the
/// task), κ_q·Δt = kappa_q_step towards the start posture (the null-space target q_c), q̇
/// scaled to the velocity limits (so one step moves a joint at most its limit times one
/// second), until |x_des − x| < eps.
struct ControllerSolveResult {
  Eigen::VectorXd q;
  int iterations = 0;
  double error_m = 0.0;
};
class ControllerPositionSolver {
 public:
  explicit ControllerPositionSolver(const robot::RobotModel& model, double eps = 1e-5, int max_iterations = 100,
                                    double kappa_q_step = 0.5);
  ~ControllerPositionSolver();
  ControllerSolveResult solve(const Eigen::VectorXd& q_start, const Eigen::Vector3d& p_des);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The start posture of every solve: each joint 30 % of the way from the middle of its soft
/// limits towards the upper limit (even joints) or the lower one (odd joints), so that the arm
/// starts bent, away from the stretched singularity the middle posture is for most arms.
Eigen::VectorXd bentStartPosture(const robot::RobotModel& model);

/// Runs every available method on the same targets. Progress on stderr.
std::vector<ReachingMethodResult> compareReaching(const robot::RobotModel& model, const ReachingOptions& options);

/// True when the KDL peers were compiled in.
bool kdlAvailable();

}  // namespace flexirob::bench::peers
