#include "app/cli/bench/peers/reaching_peers.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <random>

#include "robot/controllers.hpp"
#include "robot/kinematics.hpp"
#include "robot/sim/reach.hpp"

#ifdef FLEXIROB_HAVE_KDL
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>

#include "app/cli/bench/peers/kdl_chain.hpp"
#endif

namespace flexirob::bench::peers {

struct ControllerPositionSolver::Impl {
  Impl(const robot::RobotModel& model_in, double eps_in, int max_iterations_in, double kappa_q_step)
      : model(&model_in),
        declarations(robot::reachParameters()),
        parameters(makeParameters(declarations, kappa_q_step)),
        controller(model_in, parameters),
        lower(model_in.softLowerLimits()),
        upper(model_in.softUpperLimits()),
        qd(model_in.dof()),
        eps(eps_in),
        max_iterations(max_iterations_in) {}

  static robot::ParameterSet makeParameters(const std::vector<robot::ParameterDeclaration>& declarations,
                                           double kappa_q_step) {
    robot::ParameterSet set(declarations);
    // With Δt = 1 s: κ_x·Δt = 1 is the Newton step on the task error.
    set.set("hierarchical.kappa_x", 1.0);
    set.set("hierarchical.kappa_q", kappa_q_step);
    return set;
  }

  const robot::RobotModel* model;
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
  robot::HierarchicalController controller;
  Eigen::VectorXd lower, upper, qd;
  double eps;
  int max_iterations;
};

ControllerPositionSolver::ControllerPositionSolver(const robot::RobotModel& model, double eps, int max_iterations,
                                                   double kappa_q_step)
    : impl_(std::make_unique<Impl>(model, eps, max_iterations, kappa_q_step)) {}
ControllerPositionSolver::~ControllerPositionSolver() = default;

ControllerSolveResult ControllerPositionSolver::solve(const Eigen::VectorXd& q_start, const Eigen::Vector3d& p_des) {
  constexpr double kStep = 1.0;  // Δt [s]
  ControllerSolveResult result;
  result.q = q_start;
  Impl& s = *impl_;
  // Stalled (held by joint limits or at a local minimum of the error): no 0.1 % progress of
  // the best error in 20 iterations ends the solve, as KDL's LMA stops on vanishing steps.
  constexpr int kStallIterations = 20;
  double best_error = std::numeric_limits<double>::infinity();
  int best_iteration = 0;
  for (result.iterations = 0; result.iterations <= s.max_iterations; ++result.iterations) {
    s.controller.velocity(result.q, p_des, q_start, s.qd);
    result.error_m = s.controller.taskError();
    if (result.error_m < s.eps || result.iterations == s.max_iterations) break;
    if (result.error_m < (1.0 - 1e-3) * best_error) {
      best_error = result.error_m;
      best_iteration = result.iterations;
    } else if (result.iterations - best_iteration >= kStallIterations) {
      break;
    }
    result.q = (result.q + kStep * s.qd).cwiseMax(s.lower).cwiseMin(s.upper);
  }
  return result;
}

bool kdlAvailable() {
#ifdef FLEXIROB_HAVE_KDL
  return true;
#else
  return false;
#endif
}

Eigen::VectorXd bentStartPosture(const robot::RobotModel& model) {
  const Eigen::VectorXd lower = model.softLowerLimits(), upper = model.softUpperLimits();
  const Eigen::VectorXd middle = 0.5 * (lower + upper);
  Eigen::VectorXd q = middle;
  for (Eigen::Index j = 0; j < q.size(); ++j) q[j] += 0.3 * ((j % 2 == 0 ? upper[j] : lower[j]) - middle[j]);
  return q;
}

namespace {

// One solve: final posture and iterations (-1 if unknown).
using Solve = std::function<std::pair<Eigen::VectorXd, int>(std::size_t target)>;

ReachingMethodResult measure(const std::string& name, const robot::RobotModel& model,
                             const std::vector<Eigen::Vector3d>& targets, const ReachingOptions& options,
                             const Solve& solve) {
  ReachingMethodResult result;
  result.name = name;
  result.targets = static_cast<int>(targets.size());
  const Eigen::VectorXd lower = model.softLowerLimits(), upper = model.softUpperLimits();
  std::vector<double> pass_us;
  std::vector<double> errors;
  double iterations = 0.0;
  for (int pass = 0; pass < options.repetitions; ++pass) {
    std::vector<std::pair<Eigen::VectorXd, int>> solutions(targets.size());
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t k = 0; k < targets.size(); ++k) solutions[k] = solve(k);
    pass_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
                      static_cast<double>(targets.size()));
    if (pass > 0) continue;
    // Success is judged on the first pass (all passes compute the same) by our forward
    // kinematics, the same for every method.
    for (std::size_t k = 0; k < targets.size(); ++k) {
      const Eigen::VectorXd& q = solutions[k].first;
      const double error = (robot::tipPose(model, q).translation() - targets[k]).norm();
      errors.push_back(error);
      const bool inside = ((q - lower).array() >= -1e-9).all() && ((upper - q).array() >= -1e-9).all();
      if (error <= options.success_tolerance && inside) ++result.reached;
      iterations += std::max(solutions[k].second, 0);
    }
  }
  std::sort(pass_us.begin(), pass_us.end());
  std::sort(errors.begin(), errors.end());
  result.time_per_target_us = pass_us[pass_us.size() / 2];
  result.success_rate = static_cast<double>(result.reached) / result.targets;
  result.mean_iterations = iterations / result.targets;
  result.median_error_m = errors[errors.size() / 2];
  std::fprintf(stderr, "reaching %s: %d/%d reached, %.1f us per target\n", name.c_str(), result.reached,
               result.targets, result.time_per_target_us);
  return result;
}

}  // namespace

std::vector<ReachingMethodResult> compareReaching(const robot::RobotModel& model, const ReachingOptions& options) {
  const int n = model.dof();
  const Eigen::VectorXd lower = model.softLowerLimits(), upper = model.softUpperLimits();
  const Eigen::VectorXd q_start = bentStartPosture(model);
  // Targets: tip poses of seeded random postures inside the soft limits (every one reachable).
  std::mt19937_64 rng(options.seed);
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector3d> targets;
  for (int k = 0; k < options.targets; ++k) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) q[j] = std::uniform_real_distribution<double>(lower[j], upper[j])(rng);
    poses.push_back(robot::tipPose(model, q));
    targets.push_back(poses.back().translation());
  }
  std::vector<ReachingMethodResult> results;

  // Ours twice: the task alone (κ_q = 0, the problem KDL's LMA solves) and with the
  // null-space pull towards the start posture (the redundancy resolution the product uses; the
  // pull moves the tip at second order, so convergence to eps takes more iterations).
  ControllerPositionSolver task_only(model, options.eps, options.max_iterations, 0.0);
  results.push_back(measure("flexirob_task_only", model, targets, options, [&](std::size_t k) {
    const ControllerSolveResult solved = task_only.solve(q_start, targets[k]);
    return std::make_pair(solved.q, solved.iterations);
  }));
  ControllerPositionSolver hierarchical(model, options.eps, options.max_iterations, 0.5);
  results.push_back(measure("flexirob_hierarchical", model, targets, options, [&](std::size_t k) {
    const ControllerSolveResult solved = hierarchical.solve(q_start, targets[k]);
    return std::make_pair(solved.q, solved.iterations);
  }));

#ifdef FLEXIROB_HAVE_KDL
  const KDL::Chain chain = kdlChainFromModel(model);
  const KDL::JntArray q_min = toKdl(lower), q_max = toKdl(upper), q_init = toKdl(q_start);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainIkSolverVel_pinv ik_velocity(chain);
  KDL::ChainIkSolverPos_NR_JL nr_jl(chain, q_min, q_max, fk, ik_velocity, static_cast<unsigned int>(options.max_iterations),
                                    options.eps);
  std::vector<KDL::Frame> frames;
  for (const auto& pose : poses) frames.push_back(toKdl(pose));
  KDL::JntArray q_out(static_cast<unsigned int>(n));
  // NR_JL solves the full pose (it has no position-only mode): it gets the target postures'
  // whole tip frames, so every target has an exact solution inside the limits.
  results.push_back(measure("kdl_nr_jl_pose", model, targets, options, [&](std::size_t k) {
    nr_jl.CartToJnt(q_init, frames[k], q_out);
    return std::make_pair(fromKdl(q_out), -1);
  }));
  // LMA with the orientation weighted out solves the same position-only problem as ours, but
  // ignores joint limits (a solution outside them counts as a failure).
  Eigen::Matrix<double, 6, 1> weights;
  weights << 1.0, 1.0, 1.0, 0.0, 0.0, 0.0;
  KDL::ChainIkSolverPos_LMA lma(chain, weights, options.eps, options.max_iterations);
  results.push_back(measure("kdl_lma_position", model, targets, options, [&](std::size_t k) {
    lma.CartToJnt(q_init, frames[k], q_out);
    return std::make_pair(fromKdl(q_out), lma.lastNrOfIter);
  }));
#endif
  return results;
}

}  // namespace flexirob::bench::peers
