#pragma once
// Paths through the ITM (Sect. 7.4): the nearest nodes to start and goal, A* between them, and
// a smooth time-parametrized spline through the waypoints for the hierarchical controller.
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "planning/graph_search.hpp"
#include "planning/itm.hpp"
#include "planning/spline.hpp"

namespace flexirob::planning {

struct PathOptions {
  TrajectoryLimits limits;
  /// Begin the waypoints at the requested start and end them at the requested goal (the robot is
  /// at the start and should reach the goal); otherwise they are the graph nodes only.
  bool include_endpoints = true;
};

struct PlannedPath {
  bool found = false;
  int start_node = -1;
  int goal_node = -1;
  double start_gap = 0.0;   ///< translational distance start -> its nearest node [m]
  double goal_gap = 0.0;    ///< translational distance goal -> its nearest node [m]
  std::vector<int> nodes;   ///< graph nodes along the path
  Eigen::MatrixXd waypoints;       ///< 3 x K positions [m] the spline passes through
  Eigen::MatrixXd orientations;    ///< 4 x K quaternions [w,x,y,z] per waypoint (pose graphs)
  Eigen::MatrixXd node_joints;     ///< N x nodes.size(): q of each node [rad]
  double length = 0.0;             ///< polyline length of the waypoints [m]
  double graph_cost = 0.0;         ///< A* cost (sum of D_xi over the node path)
  double max_joint_step = 0.0;     ///< largest D_theta between consecutive nodes [rad]
  int expanded = 0;                ///< A* expansions
  std::optional<CubicSplineTrajectory> trajectory;  ///< spline over the waypoint positions
};

/// Plans from start to goal. start/goal have taskSize() numbers, or 3 (positions) on a pose
/// graph, in which case the nearest node is taken by position alone. found is false when the
/// graph is empty or start and goal nodes lie in different components.
PlannedPath planPath(const Itm& graph, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PathOptions& options = {});

}  // namespace flexirob::planning
