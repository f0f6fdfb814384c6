#pragma once
// Planning on the 9-DoF scene (Sect. 8.3): our ITM graph + A* + spline, executed by the
// hierarchical controller with the learned q_c(x), against OMPL's RRTConnect in joint space
// with our collision world as its validity checker (only with FLEXIROB_HAVE_OMPL). The session
// is taught in-process by the simulated tutor (same seed every run); the queries are the same
// for both: from the posture of the previous goal node (the first area's q_fixed at first) to
// a seeded random graph node.
#include <cstdint>
#include <string>
#include <vector>

namespace flexirob::bench::peers {

struct PlanningOptions {
  std::string robot = "arm9";
  std::string scene = "arm9_areas";
  int areas = 3;
  int goals = 20;
  std::uint64_t seed = 1;
  double time_limit_s = 5.0;  ///< per OMPL query
};

struct PlanningMethodResult {
  std::string name;
  int queries = 0;
  int found = 0;              ///< the planner returned a path
  int succeeded = 0;          ///< collision-free (every 10 ms of execution / every 0.01 rad) and within 1 cm of the goal
  double success_rate = 0.0;
  double median_plan_ms = 0.0;
  double mean_plan_ms = 0.0;
  double mean_task_length_m = 0.0;     ///< tip path length over the successful queries
  double mean_joint_length_rad = 0.0;  ///< Euclidean joint-space path length over the successful queries
  double mean_execution_compute_ms = 0.0;  ///< ours: computing the 1 kHz execution (0 for OMPL)
};

struct PlanningComparison {
  int itm_nodes = 0;
  int samples = 0;
  double teach_wall_s = 0.0;
  std::vector<PlanningMethodResult> methods;
  /// Queries both methods solved: mean lengths over this common set, so the ratios compare
  /// the same motions.
  int common_successes = 0;
  std::vector<double> common_task_length_m;    ///< per method, same order as methods
  std::vector<double> common_joint_length_rad;
};

PlanningComparison comparePlanning(const PlanningOptions& options);

bool omplAvailable();

}  // namespace flexirob::bench::peers
