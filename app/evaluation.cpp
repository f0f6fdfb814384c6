#include "app/evaluation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <tuple>

#include "planning/path_planner.hpp"
#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::app {

MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const learning::Learner& map, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world) {
  constexpr double kDt = 1e-3;
  robot::HierarchicalController controller(model, parameters);
  robot::CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(q_start);
  robot::Kinematics kinematics(model);
  Eigen::VectorXd qd(model.dof()), q_c(model.dof());
  MotionOutcome outcome;
  const auto steps = static_cast<int>(std::ceil((duration + settle) / kDt));
  Eigen::Vector3d target = p_des(0.0);
  for (int k = 1; k <= steps; ++k) {
    target = p_des(std::min(duration, k * kDt));
    map.predict(target, q_c);
    controller.velocity(limiter.command(), target, q_c, qd, &limiter);
    limiter.updateVelocity(qd);
    if (k % 10 == 0) {
      if (world != nullptr) {
        world->update(limiter.command());
        if (!world->contacts().empty()) {
          outcome.collided = true;
          break;  // a collision ends the motion as on the real robot
        }
      }
      // Settled: at the end of the path, at rest and on target.
      if (k * kDt > duration && limiter.velocity().norm() < 1e-3 && controller.taskError() < 1e-4) break;
    }
  }
  kinematics.update(limiter.command());
  outcome.final_error_m = (kinematics.p_WT() - target).norm();
  outcome.q = limiter.command();
  return outcome;
}

namespace {

// Largest distance of the tip from joint 2's axis point over the stretched posture: the reach.
std::pair<Eigen::Vector3d, double> shoulderAndReach(const robot::RobotModel& model) {
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.dof())
                                .cwiseMax(model.softLowerLimits())
                                .cwiseMin(model.softUpperLimits());
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  const Eigen::Vector3d shoulder = kinematics.X_WB(std::min(2, model.dof())).translation();
  double reach = 0.0;
  for (int b = 2; b <= model.dof(); ++b) reach = std::max(reach, (kinematics.X_WB(b).translation() - shoulder).norm());
  reach = std::max(reach, (kinematics.p_WT() - shoulder).norm());
  return {shoulder, reach};
}

}  // namespace

ReachableResult evaluateReachable(const robot::RobotModel& model, const robot::Scene& scene,
                                  const robot::ParameterSet& parameters, const learning::Learner& map,
                                  const Eigen::VectorXd& q_start, const robot::EvaluationGrid& grid,
                                  const Eigen::MatrixXd& training_X, const ProgressCallback& progress) {
  model.checkPosture(q_start);
  robot::CollisionWorld world(model, scene);
  const auto [shoulder, reach] = shoulderAndReach(model);
  const std::vector<Eigen::Vector3d> points = grid.points();
  // Grid cells holding a training sample (explored space, Tab. 3.3).
  std::set<std::tuple<long, long, long>> explored_cells;
  for (Eigen::Index l = 0; l < training_X.cols(); ++l) {
    const Eigen::Vector3d cell = ((training_X.col(l) - grid.lower) / grid.spacing).array().round();
    explored_cells.insert({std::lround(cell.x()), std::lround(cell.y()), std::lround(cell.z())});
  }
  ReachableResult result;
  result.grid_points = static_cast<int>(points.size());
  std::vector<Eigen::Vector3d> targets;
  for (const auto& p : points) {
    if ((p - shoulder).norm() > reach - grid.tolerance) continue;
    bool inside = false;
    for (const auto& obstacle : scene.obstacles) inside = inside || robot::obstacleContains(obstacle, p);
    if (!inside) targets.push_back(p);
  }
  result.targets = static_cast<int>(targets.size());
  int explored = 0;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const Eigen::Vector3d& p = targets[i];
    const Eigen::Vector3d cell = ((p - grid.lower) / grid.spacing).array().round();
    if (explored_cells.count({std::lround(cell.x()), std::lround(cell.y()), std::lround(cell.z())}) != 0) ++explored;
    const MotionOutcome outcome = executeMotion(model, parameters, map, q_start, [&](double) { return p; }, 0.0, 3.0, &world);
    if (outcome.collided) ++result.collided;
    if (!outcome.collided && outcome.final_error_m <= grid.tolerance) ++result.reached;
    if (progress && i % 20 == 0) progress(static_cast<double>(i) / static_cast<double>(targets.size()));
  }
  if (progress) progress(1.0);
  if (result.targets > 0) {
    result.reachable_fraction = static_cast<double>(result.reached) / result.targets;
    result.explored_fraction = static_cast<double>(explored) / result.targets;
  }
  return result;
}

PlanningResult evaluatePlanning(const robot::RobotModel& model, const robot::Scene& scene,
                                const robot::ParameterSet& parameters, const learning::Learner& map,
                                const planning::Itm& graph, const Eigen::VectorXd& q_start, int goals,
                                std::uint64_t seed, const ProgressCallback& progress) {
  if (goals < 1) throw InputError("goals: expected at least 1");
  const std::vector<int> nodes = graph.nodeIds();
  if (nodes.size() < 2) throw InputError("plan: the session's ITM has fewer than two nodes");
  model.checkPosture(q_start);
  robot::CollisionWorld world(model, scene);
  learning::UniformRandom random(seed);
  PlanningResult result;
  result.goals = goals;
  Eigen::VectorXd q = q_start;
  double plan_ms = 0.0;
  for (int g = 0; g < goals; ++g) {
    const int goal = nodes[random.index(nodes.size())];
    const Eigen::Vector3d p_goal = graph.prototype(goal).head<3>();
    const Eigen::Vector3d p_start = robot::tipPose(model, q).translation();
    const auto t0 = std::chrono::steady_clock::now();
    const planning::PlannedPath path = planning::planPath(graph, p_start, p_goal);
    plan_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!path.found || !path.trajectory) continue;
    ++result.found;
    const planning::CubicSplineTrajectory& spline = *path.trajectory;
    const MotionOutcome outcome = executeMotion(
        model, parameters, map, q, [&](double t) { return Eigen::Vector3d(spline.position(t).head<3>()); },
        spline.duration(), 2.0, &world);
    if (!outcome.collided) ++result.collision_free;
    if (!outcome.collided && (robot::tipPose(model, outcome.q).translation() - p_goal).norm() <= 0.01) ++result.reached_1cm;
    q = outcome.q;
    if (progress) progress(static_cast<double>(g + 1) / goals);
  }
  result.mean_plan_ms = plan_ms / goals;
  return result;
}

}  // namespace flexirob::app
