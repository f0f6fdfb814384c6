#pragma once
// Paths through the ITM (Sect. 7.4): the nearest nodes to start and goal, A* between them, the
// node path shortened where a straight segment stays inside the space the ITM has mapped, and a
// smooth time-parametrized spline through the waypoints for the hierarchical controller.
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

  /// Shortcut ("string-pull") the A* node path: two waypoints of it are joined directly, skipping
  /// the nodes between them, only when (a) every point of the straight segment lies within
  /// shortcut_radius of some ITM node whose joint configuration is closer than d_theta_max to the
  /// joint configurations at both ends (so the segment stays in mapped space of one redundancy
  /// resolution), and (b) the two ends themselves are closer than d_theta_max in joint space
  /// (the ITM's edge criterion, Sect. 7.3.1). Consecutive waypoints of the node path are graph
  /// edges and always kept as they are. Off: the waypoints are the A* nodes, as in Sect. 7.4.
  bool shortcut = true;
  /// Radius of the mapped space around each node, as a fraction of e_max, in (0, 1]. The ITM
  /// creates a node whenever a sample lies farther than e_max from every node (its insertion
  /// threshold), so the space the tutor visited lies within about e_max of the nodes, and the
  /// graph's own edges already pass up to about e_max from every node (on the 9-DoF scene's map
  /// 10 % of the edges have a point farther than 0.094 m from every node). Nodes are at least
  /// e_max apart, so a radius below about 0.6 e_max would not even join a straight chain of them.
  double shortcut_radius = 1.0;
  /// (c) Every point of the segment also lies within shortcut_corridor e_max (translational
  /// distance) of an edge of the graph. The ITM joins the two nodes nearest to each sample, so its
  /// edges trace where the tutor moved, while the balls of (a) bulge up to e_max out of a thin
  /// sheet of visited space: on the 9-DoF scene a shortcut between two nodes of a helix drawn
  /// 7 cm above the bridge's slab, each within 0.09 m of a node, cut through the slab's edge.
  /// As in (a), points are accepted with a margin, within 0.9 shortcut_corridor e_max. In (0, 1].
  double shortcut_corridor = 0.5;
  /// Points the spline passes through along a shortcut are at most this fraction of e_max apart,
  /// so that the spline follows the straight segment as closely as it followed the node path
  /// (whose waypoints are about e_max apart) and does not swing wide at the corners. In (0, 1].
  double shortcut_waypoint_spacing = 0.5;

  /// Throws std::invalid_argument naming the first option out of range.
  void validate() const;
};

struct PlannedPath {
  bool found = false;
  int start_node = -1;
  int goal_node = -1;
  double start_gap = 0.0;   ///< translational distance start -> its nearest node [m]
  double goal_gap = 0.0;    ///< translational distance goal -> its nearest node [m]
  std::vector<int> nodes;   ///< graph nodes along the A* path (consecutive nodes share an edge)
  Eigen::MatrixXd waypoints;       ///< 3 x K positions [m] the spline passes through (shortened)
  Eigen::MatrixXd orientations;    ///< 4 x K quaternions [w,x,y,z] per waypoint (pose graphs)
  /// Per waypoint: the graph node it is, or -1 for the requested start / goal and for points
  /// inserted along a shortcut.
  std::vector<int> waypoint_nodes;
  /// 3 x L positions of the unshortened path: [start,] the prototypes of nodes [, goal] (for
  /// display). Equal to waypoints when shortcut is off.
  Eigen::MatrixXd raw_waypoints;
  Eigen::MatrixXd node_joints;     ///< N x nodes.size(): q of each node [rad]
  double length = 0.0;             ///< polyline length of the waypoints [m]
  double raw_length = 0.0;         ///< polyline length of raw_waypoints [m]
  int shortcuts = 0;               ///< straight segments that replaced two or more graph edges
  double graph_cost = 0.0;         ///< A* cost (sum of D_xi over the node path)
  double max_joint_step = 0.0;     ///< largest D_theta between consecutive nodes [rad]
  int expanded = 0;                ///< A* expansions
  std::optional<CubicSplineTrajectory> trajectory;  ///< spline over the waypoint positions
};

/// Plans from start to goal. start/goal have taskSize() numbers, or 3 (positions) on a pose
/// graph, in which case the nearest node is taken by position alone. found is false when the
/// graph is empty or start and goal nodes lie in different components. Throws
/// std::invalid_argument for points of the wrong size, non-finite points and bad options.
PlannedPath planPath(const Itm& graph, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PathOptions& options = {});

}  // namespace flexirob::planning
