#include "planning/path_planner.hpp"

#include <stdexcept>
#include <string>

namespace flexirob::planning {

PlannedPath planPath(const Itm& graph, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PathOptions& options) {
  options.limits.validate();
  const auto check = [&](const Eigen::VectorXd& point, const char* what) {
    if (point.size() != 3 && point.size() != graph.taskSize()) {
      throw std::invalid_argument(std::string("path: expected the ") + what + " as 3" +
                                  (graph.taskSize() == 7 ? " or 7" : "") + " numbers, got " + std::to_string(point.size()));
    }
    if (!point.allFinite()) throw std::invalid_argument(std::string("path: the ") + what + " must be finite");
  };
  check(start, "start");
  check(goal, "goal");

  PlannedPath path;
  if (graph.nodeCount() == 0) return path;
  const auto nearest = [&](const Eigen::VectorXd& point) {
    if (point.size() == graph.taskSize()) {
      Eigen::VectorXd normalized = point;
      if (point.size() == 7) {
        const double norm = point.tail<4>().norm();
        if (!(norm > 1e-9)) throw std::invalid_argument("path: quaternion of zero length");
        normalized.tail<4>() /= norm;
      }
      return graph.nearestNode(normalized);
    }
    return graph.nearestNode(point, true);
  };
  path.start_node = nearest(start);
  path.goal_node = nearest(goal);
  path.start_gap = (graph.prototype(path.start_node).head<3>() - start.head<3>()).norm();
  path.goal_gap = (graph.prototype(path.goal_node).head<3>() - goal.head<3>()).norm();

  const GraphPath route = shortestPath(graph, path.start_node, path.goal_node);
  path.expanded = route.expanded;
  if (!route.found) return path;
  path.found = true;
  path.nodes = route.nodes;
  path.graph_cost = route.cost;

  // Waypoints: [start,] node prototypes [, goal]; joint configurations from the nodes.
  const int count = static_cast<int>(route.nodes.size());
  const int extra_front = options.include_endpoints ? 1 : 0;
  const int total = count + 2 * extra_front;
  path.waypoints.resize(3, total);
  path.orientations.resize(4, graph.taskSize() == 7 ? total : 0);
  path.node_joints.resize(graph.jointCount(), count);
  for (int k = 0; k < count; ++k) {
    const auto omega = graph.prototype(route.nodes[static_cast<std::size_t>(k)]);
    path.waypoints.col(k + extra_front) = omega.head<3>();
    if (graph.taskSize() == 7) path.orientations.col(k + extra_front) = omega.tail<4>();
    path.node_joints.col(k) = graph.joints(route.nodes[static_cast<std::size_t>(k)]);
    if (k > 0) {
      path.max_joint_step = std::max(path.max_joint_step, graph.jointDistance(route.nodes[static_cast<std::size_t>(k - 1)],
                                                                              route.nodes[static_cast<std::size_t>(k)]));
    }
  }
  if (options.include_endpoints) {
    path.waypoints.col(0) = start.head<3>();
    path.waypoints.col(total - 1) = goal.head<3>();
    if (graph.taskSize() == 7) {
      // A position-only request keeps the orientation of the nearest node.
      path.orientations.col(0) = start.size() == 7 ? Eigen::Vector4d(start.tail<4>().normalized()) : Eigen::Vector4d(path.orientations.col(1));
      path.orientations.col(total - 1) =
          goal.size() == 7 ? Eigen::Vector4d(goal.tail<4>().normalized()) : Eigen::Vector4d(path.orientations.col(total - 2));
    }
  }
  for (int k = 1; k < total; ++k) path.length += (path.waypoints.col(k) - path.waypoints.col(k - 1)).norm();
  path.trajectory.emplace(path.waypoints, options.limits);
  return path;
}

}  // namespace flexirob::planning
