#include "app/cli/bench/peers/planning_peers.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "app/simulated_tutor.hpp"
#include "app/workflow.hpp"
#include "planning/path_planner.hpp"
#include "robot/collision.hpp"
#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

#ifdef FLEXIROB_HAVE_OMPL
#include "app/cli/bench/peers/ompl_planner.hpp"
#endif

namespace flexirob::bench::peers {

bool omplAvailable() {
#ifdef FLEXIROB_HAVE_OMPL
  return true;
#else
  return false;
#endif
}

namespace {

constexpr double kReachedTolerance = 0.01;  // [m], Sect. 8.3

struct Query {
  Eigen::VectorXd q_start;
  int goal_node = -1;
};

struct QueryOutcome {
  bool found = false;
  bool succeeded = false;
  double plan_ms = 0.0;
  double task_length_m = 0.0;
  double joint_length_rad = 0.0;
  double execution_ms = 0.0;
};

// Executes the planned spline as app::executeMotion does (1 kHz, controller + limiter + learned
// q_c, contacts checked every 10 ms, 2 s to settle) and also measures the path lengths, which
// executeMotion does not report.
QueryOutcome executeSpline(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                           const learning::Learner& map, robot::CollisionWorld& world, const Eigen::VectorXd& q_start,
                           const planning::CubicSplineTrajectory& spline, const Eigen::Vector3d& p_goal) {
  constexpr double kDt = 1e-3;
  constexpr double kSettle = 2.0;
  robot::HierarchicalController controller(model, parameters);
  robot::CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(q_start);
  robot::Kinematics kinematics(model);
  kinematics.update(q_start);
  Eigen::Vector3d p_previous = kinematics.p_WT();
  Eigen::VectorXd q_previous = q_start;
  Eigen::VectorXd qd(model.dof()), q_c(model.dof());
  QueryOutcome outcome;
  const double duration = spline.duration();
  const auto steps = static_cast<int>(std::ceil((duration + kSettle) / kDt));
  bool collided = false;
  for (int k = 1; k <= steps; ++k) {
    const Eigen::Vector3d target = spline.position(std::min(duration, k * kDt)).head<3>();
    map.predict(target, q_c);
    controller.velocity(limiter.command(), target, q_c, qd, &limiter);
    limiter.updateVelocity(qd);
    outcome.joint_length_rad += (limiter.command() - q_previous).norm();
    q_previous = limiter.command();
    kinematics.update(limiter.command());
    outcome.task_length_m += (kinematics.p_WT() - p_previous).norm();
    p_previous = kinematics.p_WT();
    if (k % 10 == 0) {
      world.update(limiter.command());
      if (!world.contacts().empty()) {
        collided = true;
        break;
      }
      if (k * kDt > duration && limiter.velocity().norm() < 1e-3 && controller.taskError() < 1e-4) break;
    }
  }
  outcome.succeeded = !collided && (kinematics.p_WT() - p_goal).norm() <= kReachedTolerance;
  return outcome;
}

PlanningMethodResult summarise(const std::string& name, const std::vector<QueryOutcome>& outcomes) {
  PlanningMethodResult result;
  result.name = name;
  result.queries = static_cast<int>(outcomes.size());
  std::vector<double> plan_ms;
  for (const auto& outcome : outcomes) {
    plan_ms.push_back(outcome.plan_ms);
    result.mean_plan_ms += outcome.plan_ms / static_cast<double>(outcomes.size());
    result.mean_execution_compute_ms += outcome.execution_ms / static_cast<double>(outcomes.size());
    if (outcome.found) ++result.found;
    if (!outcome.succeeded) continue;
    ++result.succeeded;
    result.mean_task_length_m += outcome.task_length_m;
    result.mean_joint_length_rad += outcome.joint_length_rad;
  }
  std::sort(plan_ms.begin(), plan_ms.end());
  if (!plan_ms.empty()) result.median_plan_ms = plan_ms[plan_ms.size() / 2];
  result.success_rate = result.queries > 0 ? static_cast<double>(result.succeeded) / result.queries : 0.0;
  if (result.succeeded > 0) {
    result.mean_task_length_m /= result.succeeded;
    result.mean_joint_length_rad /= result.succeeded;
  }
  return result;
}

}  // namespace

PlanningComparison comparePlanning(const PlanningOptions& options) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath(options.robot));
  const robot::Scene scene = robot::loadScene(options.scene);
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  parameters.applyOverrides(scene.parameters, robot::sceneOrigin(scene));
  const int n = model.dof();

  // The session: taught by the simulated tutor as `teach` does (ELM, same seed).
  PlanningComparison comparison;
  app::WorkflowOptions workflow_options;
  workflow_options.elm.seed = options.seed;
  workflow_options.llm.seed = options.seed;
  workflow_options.check_scene = &scene;
  robot::Simulation sim(model, &scene, parameters);
  if (scene.home_posture && scene.home_posture->size() == n) sim.reset(*scene.home_posture);
  app::Workflow workflow(sim, parameters, workflow_options);
  app::TutorOptions tutor_options;
  tutor_options.seed = options.seed;
  tutor_options.progress = [](const std::string& what, double fraction) {
    std::fprintf(stderr, "\r%s %3.0f %%", what.c_str(), 100.0 * fraction);
  };
  const auto teach_start = std::chrono::steady_clock::now();
  app::SimulatedTutor tutor(sim, workflow, scene, parameters, tutor_options);
  tutor.configure(options.areas);
  comparison.teach_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - teach_start).count();
  std::fprintf(stderr, "\n");
  const planning::Itm& graph = workflow.itm();
  comparison.itm_nodes = graph.nodeCount();
  learning::TrainingSet data;
  Eigen::Index samples = 0;
  for (const auto& area : workflow.areas()) samples += area.X.cols();
  data.X.resize(3, samples);
  data.Y.resize(n, samples);
  Eigen::Index column = 0;
  for (std::size_t k = 0; k < workflow.areas().size(); ++k) {
    const auto& area = workflow.areas()[k];
    data.X.middleCols(column, area.X.cols()) = area.X;
    data.Y.middleCols(column, area.Q.cols()) = area.Q;
    for (Eigen::Index l = 0; l < area.X.cols(); ++l) data.area.push_back(static_cast<int>(k));
    column += area.X.cols();
  }
  comparison.samples = static_cast<int>(samples);
  const std::vector<int> nodes = graph.nodeIds();
  if (workflow.areas().empty() || nodes.size() < 2) {
    throw InputError("bench --peers: the tutor taught no usable session on " + options.scene);
  }
  const std::unique_ptr<learning::Learner> map = app::makeLearner(workflow_options, n);
  map->fit(data);

  // The queries, identical for both planners.
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<std::size_t> pick(0, nodes.size() - 1);
  std::vector<Query> queries;
  Eigen::VectorXd q = workflow.areas().front().q_fixed;
  for (int g = 0; g < options.goals; ++g) {
    const int goal = nodes[pick(rng)];
    queries.push_back({q, goal});
    q = graph.joints(goal);
  }

  robot::CollisionWorld world(model, scene);
  std::vector<std::vector<QueryOutcome>> outcomes;
  std::vector<std::string> names;

  // Ours: A* + spline through the ITM graph (Sect. 8.2), executed with the learned q_c(x).
  names.push_back("flexirob_itm_astar");
  outcomes.emplace_back();
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const Eigen::Vector3d p_start = robot::tipPose(model, queries[k].q_start).translation();
    const Eigen::Vector3d p_goal = graph.prototype(queries[k].goal_node).head<3>();
    const auto t0 = std::chrono::steady_clock::now();
    const planning::PlannedPath path = planning::planPath(graph, p_start, p_goal);
    const double plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    QueryOutcome outcome;
    if (path.found && path.trajectory) {
      const auto t1 = std::chrono::steady_clock::now();
      outcome = executeSpline(model, parameters, *map, world, queries[k].q_start, *path.trajectory, p_goal);
      outcome.execution_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
      outcome.found = true;
    }
    outcome.plan_ms = plan_ms;
    outcomes.back().push_back(outcome);
    std::fprintf(stderr, "\rplanning ours %zu/%zu", k + 1, queries.size());
  }
  std::fprintf(stderr, "\n");

#ifdef FLEXIROB_HAVE_OMPL
  // OMPL RRTConnect between the same postures, with our collision world.
  OmplRrtConnect::seed(options.seed);
  OmplRrtConnect rrt(model, scene);
  names.push_back("ompl_rrtconnect");
  outcomes.emplace_back();
  robot::Kinematics kinematics(model);
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const Eigen::VectorXd q_goal = graph.joints(queries[k].goal_node);
    const JointSpacePath path = rrt.plan(queries[k].q_start, q_goal, options.time_limit_s);
    QueryOutcome outcome;
    outcome.plan_ms = path.plan_ms;
    outcome.found = path.solved;
    if (path.solved) {
      // Lengths and a dense re-check with the same collision world (0.01 rad steps).
      bool collided = false;
      kinematics.update(path.waypoints.front());
      Eigen::Vector3d p_previous = kinematics.p_WT();
      for (std::size_t w = 1; w < path.waypoints.size() && !collided; ++w) {
        const Eigen::VectorXd& a = path.waypoints[w - 1];
        const Eigen::VectorXd& b = path.waypoints[w];
        outcome.joint_length_rad += (b - a).norm();
        const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.01)));
        for (int s = 1; s <= steps; ++s) {
          const Eigen::VectorXd q_s = a + (b - a) * (static_cast<double>(s) / steps);
          kinematics.update(q_s);
          outcome.task_length_m += (kinematics.p_WT() - p_previous).norm();
          p_previous = kinematics.p_WT();
          if (!rrt.isValid(q_s)) {
            collided = true;
            break;
          }
        }
      }
      const Eigen::Vector3d p_goal = graph.prototype(queries[k].goal_node).head<3>();
      outcome.succeeded = !collided && (robot::tipPose(model, path.waypoints.back()).translation() - p_goal).norm() <= kReachedTolerance;
    }
    outcomes.back().push_back(outcome);
    std::fprintf(stderr, "\rplanning OMPL %zu/%zu", k + 1, queries.size());
  }
  std::fprintf(stderr, "\n");
#endif

  for (std::size_t m = 0; m < names.size(); ++m) comparison.methods.push_back(summarise(names[m], outcomes[m]));
  // Lengths over the queries every method solved.
  comparison.common_task_length_m.assign(names.size(), 0.0);
  comparison.common_joint_length_rad.assign(names.size(), 0.0);
  for (std::size_t k = 0; k < queries.size(); ++k) {
    bool all = true;
    for (const auto& method : outcomes) all = all && method[k].succeeded;
    if (!all) continue;
    ++comparison.common_successes;
    for (std::size_t m = 0; m < names.size(); ++m) {
      comparison.common_task_length_m[m] += outcomes[m][k].task_length_m;
      comparison.common_joint_length_rad[m] += outcomes[m][k].joint_length_rad;
    }
  }
  for (std::size_t m = 0; m < names.size() && comparison.common_successes > 0; ++m) {
    comparison.common_task_length_m[m] /= comparison.common_successes;
    comparison.common_joint_length_rad[m] /= comparison.common_successes;
  }
  return comparison;
}

}  // namespace flexirob::bench::peers
