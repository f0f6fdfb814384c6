#pragma once
// Evaluations of a taught session in simulation (kinematic, with the collision world):
// the reachable workspace of Sect. 3.3.2 (Tab. 3.3) and planned paths through the ITM graph of
// Sect. 8.3. The robot is driven by the hierarchical controller (Eq. 2.11) with the learned
// q_c(x) and the command limiter; the collision world only counts contacts (model-free
// control, Sect. A.4). Frames: W = robot base; metres, radians.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "learning/learner.hpp"
#include "planning/itm.hpp"
#include "robot/collision.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {

using ProgressCallback = std::function<void(double fraction)>;

/// One motion executed kinematically with the hierarchical controller.
struct MotionOutcome {
  double final_error_m = 0.0;
  bool collided = false;  ///< a contact with an obstacle or the robot itself at a checked sample
  Eigen::VectorXd q;      ///< final posture
};

/// Drives the command from q_start towards p_des(t) (t in [0, duration], held after) for
/// duration + settle seconds at 1 kHz; checks contacts every 10 ms. `world` may be null.
MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const learning::Learner& map, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world);

struct ReachableResult {
  int grid_points = 0;   ///< points of G
  int targets = 0;       ///< |T|: grid points within reach and outside the obstacles
  int reached = 0;       ///< reached within the tolerance without collision
  int collided = 0;
  double reachable_fraction = 0.0;  ///< reached / targets
  double explored_fraction = 0.0;   ///< targets whose grid cell holds a training sample
};

/// Sect. 3.3.2: each target of the grid is approached from `q_start` (settle time 3 s).
/// training_X: 3 x L training inputs (for the explored fraction).
ReachableResult evaluateReachable(const robot::RobotModel& model, const robot::Scene& scene,
                                  const robot::ParameterSet& parameters, const learning::Learner& map,
                                  const Eigen::VectorXd& q_start, const robot::EvaluationGrid& grid,
                                  const Eigen::MatrixXd& training_X, const ProgressCallback& progress = {});

struct PlanningResult {
  int goals = 0;
  int found = 0;          ///< paths the planner found
  int collision_free = 0; ///< executed without contact
  int reached_1cm = 0;    ///< ended within 1 cm of the goal node
  double mean_plan_ms = 0.0;
};

/// Sect. 8.3: `goals` random graph nodes (seeded) visited one after another from q_start; each
/// planned with A* + spline and executed with the hierarchical controller.
PlanningResult evaluatePlanning(const robot::RobotModel& model, const robot::Scene& scene,
                                const robot::ParameterSet& parameters, const learning::Learner& map,
                                const planning::Itm& graph, const Eigen::VectorXd& q_start, int goals,
                                std::uint64_t seed, const ProgressCallback& progress = {});

}  // namespace flexirob::app
