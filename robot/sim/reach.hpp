#pragma once
// Reaching a task-space target in simulation with the hierarchical controller (Eq. 2.11): the
// tip is driven to the target while the null space is pulled towards a posture. Used by
// `flexirob-cli reach` and by evaluations.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "robot/controllers.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {

/// Every parameter reach() reads: hierarchical.*, limits.* and sim.*.
std::vector<ParameterDeclaration> reachParameters();

struct ReachRequest {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< p_des [m, W]
  Eigen::VectorXd start;     ///< q at t = 0 [rad]; empty: the model's midPosture()
  Eigen::VectorXd posture;   ///< null-space target q_c [rad]; empty: the start posture
  double tolerance = 1e-4;   ///< [m] task error counted as reached
  double max_time = 30.0;    ///< [s] of simulated time
  /// [s] without progress after which the target counts as out of reach; for an arm whose
  /// slowest joint is allowed less than 1 rad/s, longer in proportion (progress is slower).
  double stall_time = 2.0;
};

struct ReachEvent {
  double time = 0.0;
  std::string link, other;
  bool self_collision = false;
};

struct ReachResult {
  /// "reached"; "unreachable" (the controller stalled farther than tolerance, e.g. outside the
  /// workspace or held by joint limits); "timeout" (still approaching at max_time).
  std::string status;
  double error_m = 0.0;        ///< final |x_des − x| of the simulated (measured) tip
  double best_error_m = 0.0;   ///< smallest measured error on the way
  std::uint64_t steps = 0;     ///< 1 ms control cycles
  double time_s = 0.0;
  Eigen::VectorXd q;           ///< final measured posture
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double posture_error_rad = 0.0;  ///< |q − q_c| at the end (what the null space could not satisfy)
  std::uint64_t collisions = 0;        ///< contact events (E_coll)
  std::uint64_t colliding_steps = 0;
  std::vector<ReachEvent> collision_events;  ///< the first few
  LimitCounters clamps;                      ///< controller and limiter together
  std::uint64_t null_space_scaled = 0;
  std::uint64_t torque_saturations = 0;
  int max_substeps = 0;                 ///< the most physics steps one control cycle took
  std::uint64_t rejected_commands = 0;  ///< commands the simulated robot refused (should be 0)
  /// Where the joints cannot hold the arm against gravity at the start or the final posture
  /// (Simulation::gravityLoad above 1): which, and how much; empty otherwise.
  std::string gravity_overload;
  /// Joints commanded onto a soft limit at the end: where the controller stalled on them,
  /// another start may reach the target.
  std::vector<std::string> joints_at_limits;
};

/// Runs the simulation until the target is reached (error below tolerance and the command at
/// rest), stalls or max_time passes. Throws InputError for wrongly sized or out-of-limit
/// postures and non-finite targets.
ReachResult reach(const RobotModel& model, const Scene* scene, const ParameterSet& parameters,
                  const ReachRequest& request);

}  // namespace flexirob::robot
