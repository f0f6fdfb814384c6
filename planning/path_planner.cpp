#include "planning/path_planner.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace flexirob::planning {

void PathOptions::validate() const {
  limits.validate();
  if (!(shortcut_radius > 0.0 && shortcut_radius <= 1.0)) {
    throw std::invalid_argument("path: expected a shortcut radius in (0, 1] (fraction of e_max), got " + std::to_string(shortcut_radius));
  }
  if (!(shortcut_corridor > 0.0 && shortcut_corridor <= 1.0)) {
    throw std::invalid_argument("path: expected a shortcut corridor in (0, 1] (fraction of e_max), got " + std::to_string(shortcut_corridor));
  }
  if (!(shortcut_waypoint_spacing > 0.0 && shortcut_waypoint_spacing <= 1.0)) {
    throw std::invalid_argument("path: expected a shortcut waypoint spacing in (0, 1] (fraction of e_max), got " +
                                std::to_string(shortcut_waypoint_spacing));
  }
}

namespace {

// The point at fraction t of the way from a to b in task space: positions linearly, orientations
// (pose graphs) along the shorter great arc (slerp). Along this curve D_xi grows linearly in t:
// D_xi(p(t1), p(t2)) = |t2 - t1| D_xi(a, b), for the translational part trivially and for the
// rotational part because slerp turns at a constant rate about one axis, so that the rotation
// angle of Eq. 7.6 between p(t1) and p(t2) is |t2 - t1| times the whole angle.
Eigen::VectorXd interpolate(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double t) {
  Eigen::VectorXd p(a.size());
  p.head<3>() = a.head<3>() + t * (b.head<3>() - a.head<3>());
  if (a.size() == 7) {
    const Eigen::Quaterniond qa(a[3], a[4], a[5], a[6]), qb(b[3], b[4], b[5], b[6]);
    const Eigen::Quaterniond q = qa.slerp(t, qb);  // Eigen's slerp takes the shorter arc
    p.tail<4>() << q.w(), q.x(), q.y(), q.z();
  }
  return p;
}

// String-pulling of the path points against the mapped space of the ITM (see PathOptions).
class Shortcutter {
 public:
  Shortcutter(const Itm& graph, const PathOptions& options)
      : graph_(graph),
        radius_(options.shortcut_radius * graph.parameters().e_max),
        // Samples are accepted only with a margin below the radius, which bounds the number of
        // nearest-node queries per segment by its length / (0.1 radius).
        margin_(0.1 * radius_),
        corridor_(options.shortcut_corridor * graph.parameters().e_max),
        reach_(corridor_ + graph.parameters().e_max),
        d_theta_max_(graph.parameters().d_theta_max) {}

  // True when the straight segment from point a to point b stays inside the mapped space of
  // one redundancy resolution; joints_a / joints_b are the nodes whose q the ends carry.
  bool admissible(const Eigen::VectorXd& a, int joints_a, const Eigen::VectorXd& b, int joints_b) const {
    // The ITM's edge criterion between the two ends (Sect. 7.3.1).
    if (!(graph_.jointDistance(joints_a, joints_b) < d_theta_max_)) return false;
    const double total = graph_.metric().distance(a.data(), b.data());
    if (total <= 0.0) return true;
    // Walk along the segment: when the nearest node c of p(t) has D_xi(p(t), c) = d, every
    // p(t') with |t' - t| total <= radius - d lies within radius of c (triangle inequality and
    // the linear growth of D_xi along the segment), so the next point to examine is that far on.
    // Accepting only d <= radius - margin makes each step at least margin long; the whole
    // continuous segment is then proven to lie within radius of compatible nodes.
    double t = 0.0;
    for (;;) {
      const Eigen::VectorXd p = interpolate(a, b, t);
      const int c = graph_.nearestNode(p);
      const double d = graph_.distanceTo(c, p);
      if (!(d <= radius_ - margin_)) return false;  // NaN fails too
      if (!(graph_.jointDistance(c, joints_a) < d_theta_max_ && graph_.jointDistance(c, joints_b) < d_theta_max_)) return false;
      if (t >= 1.0) break;
      t = std::min(1.0, t + (radius_ - d) / total);
    }
    return withinCorridor(a.head<3>(), b.head<3>());
  }

 private:
  // True when every point of the segment a-b lies within corridor_ of a graph edge. The distance
  // of a point to the edges changes by at most the distance it moves, so as in admissible() the
  // walk's steps are (corridor_ - d) long and a point is accepted only with a margin.
  bool withinCorridor(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    const double length = (b - a).norm();
    const double margin = 0.1 * corridor_;
    for (double t = 0.0;;) {
      const Eigen::Vector3d p = a + t * (b - a);
      // The edges of the nearest node usually pass close enough; their distance bounds the
      // nearest edge's from above, which only shortens the step.
      double d = distanceToEdgesOf(graph_.nearestNode(p, true), p);
      if (!(d <= corridor_ - margin)) d = distanceToEdges(p);
      if (!(d <= corridor_ - margin)) return false;
      if (t >= 1.0 || length <= 0.0) return true;
      t = std::min(1.0, t + (corridor_ - d) / length);
    }
  }

  // Translational distance from p to the nearest edge with an end within reach_ of p (infinity if
  // none). An edge of up to 2 e_max that passes within corridor_ of p has an end that near; a
  // longer one is found only from its own nodes (the nearest node's edges above), and one left
  // out only makes the test stricter. Searching out to half the longest edge instead cost five
  // times the planning time on a 9 620-node map (docs/PLANNING.md).
  double distanceToEdges(const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const int c : graph_.nodesWithin(p, reach_, true)) best = std::min(best, distanceToEdgesOf(c, p));
    return best;
  }

  // Translational distance from p to the nearest edge of node c (infinity if it has none).
  double distanceToEdgesOf(int c, const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d from = graph_.prototype(c).head<3>();
    for (const int n : graph_.neighbors(c)) {
      const Eigen::Vector3d edge = graph_.prototype(n).head<3>() - from;
      const double s = std::clamp(edge.dot(p - from) / std::max(edge.squaredNorm(), 1e-18), 0.0, 1.0);
      best = std::min(best, (from + s * edge - p).norm());
    }
    return best;
  }

  const Itm& graph_;
  double radius_;
  double margin_;
  double corridor_;
  double reach_;
  double d_theta_max_;
};

// After this many consecutive rejected candidates the search for a farther end stops: a path
// that has left the mapped space of a shortcut seldom comes back to it within a few nodes, and
// the cost per waypoint stays bounded.
constexpr int kMaxRejectedInARow = 3;

}  // namespace

PlannedPath planPath(const Itm& graph, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PathOptions& options) {
  options.validate();
  const auto check = [&](const Eigen::VectorXd& point, const char* what) {
    if (point.size() != 3 && point.size() != graph.taskSize()) {
      throw std::invalid_argument(std::string("path: expected the ") + what + " as 3" +
                                  (graph.taskSize() == 7 ? " or 7" : "") + " numbers, got " + std::to_string(point.size()));
    }
    if (!point.allFinite()) throw std::invalid_argument(std::string("path: the ") + what + " must be finite");
    if (point.size() == 7 && !(point.tail<4>().norm() > 1e-9)) throw std::invalid_argument("path: quaternion of zero length");
  };
  check(start, "start");
  check(goal, "goal");

  PlannedPath path;
  if (graph.nodeCount() == 0) return path;
  const bool pose = graph.taskSize() == 7;
  const auto nearest = [&](const Eigen::VectorXd& point) {
    if (point.size() == graph.taskSize()) {
      Eigen::VectorXd normalized = point;
      if (pose) normalized.tail<4>().normalize();
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

  const int count = static_cast<int>(route.nodes.size());
  path.node_joints.resize(graph.jointCount(), count);
  for (int k = 0; k < count; ++k) {
    const int node = route.nodes[static_cast<std::size_t>(k)];
    path.node_joints.col(k) = graph.joints(node);
    if (k > 0) path.max_joint_step = std::max(path.max_joint_step, graph.jointDistance(route.nodes[static_cast<std::size_t>(k - 1)], node));
  }

  // The raw path: [start,] node prototypes [, goal] as full task-space points, each with the
  // node whose joint configuration it carries (the requested start and goal carry their nearest
  // node's) and its node id (-1 for the requested start and goal).
  struct Point {
    Eigen::VectorXd xi;
    int joints;
    int node;
  };
  std::vector<Point> raw;
  raw.reserve(static_cast<std::size_t>(count + 2));
  const auto endpoint = [&](const Eigen::VectorXd& requested, int node) {
    Eigen::VectorXd xi = graph.prototype(node);
    xi.head<3>() = requested.head<3>();
    // A position-only request on a pose graph keeps the orientation of the nearest node.
    if (pose && requested.size() == 7) xi.tail<4>() = requested.tail<4>().normalized();
    return Point{xi, node, -1};
  };
  if (options.include_endpoints) raw.push_back(endpoint(start, path.start_node));
  for (const int node : route.nodes) raw.push_back(Point{graph.prototype(node), node, node});
  if (options.include_endpoints) raw.push_back(endpoint(goal, path.goal_node));

  const auto polylineLength = [](const Eigen::MatrixXd& points) {
    double length = 0.0;
    for (Eigen::Index k = 1; k < points.cols(); ++k) length += (points.col(k) - points.col(k - 1)).norm();
    return length;
  };
  path.raw_waypoints.resize(3, static_cast<Eigen::Index>(raw.size()));
  for (std::size_t k = 0; k < raw.size(); ++k) path.raw_waypoints.col(static_cast<Eigen::Index>(k)) = raw[k].xi.head<3>();
  path.raw_length = polylineLength(path.raw_waypoints);

  // Kept points: greedily the farthest point reachable by an admissible straight segment, the
  // next raw point (a graph edge, or the connection of a requested end) otherwise.
  std::vector<Point> kept{raw.front()};
  std::vector<bool> shortcut_before{false};  // kept[k] is reached from kept[k - 1] by a shortcut
  const Shortcutter shortcutter(graph, options);
  for (std::size_t i = 0; i + 1 < raw.size();) {
    std::size_t next = i + 1;
    if (options.shortcut) {
      int rejected = 0;
      for (std::size_t j = i + 2; j < raw.size() && rejected < kMaxRejectedInARow; ++j) {
        if (shortcutter.admissible(raw[i].xi, raw[i].joints, raw[j].xi, raw[j].joints)) {
          next = j;
          rejected = 0;
        } else {
          ++rejected;
        }
      }
    }
    kept.push_back(raw[next]);
    shortcut_before.push_back(next > i + 1);
    if (next > i + 1) ++path.shortcuts;
    i = next;
  }

  // Waypoints: the kept points, with points every shortcut_waypoint_spacing e_max (translational
  // distance) inserted along the shortcuts.
  const double spacing = options.shortcut_waypoint_spacing * graph.parameters().e_max;
  std::vector<Point> waypoints{kept.front()};
  for (std::size_t k = 1; k < kept.size(); ++k) {
    if (shortcut_before[k]) {
      const double length = (kept[k].xi.head<3>() - kept[k - 1].xi.head<3>()).norm();
      const int pieces = static_cast<int>(std::ceil(length / spacing));
      for (int s = 1; s < pieces; ++s) {
        waypoints.push_back(Point{interpolate(kept[k - 1].xi, kept[k].xi, static_cast<double>(s) / pieces), -1, -1});
      }
    }
    waypoints.push_back(kept[k]);
  }
  const auto total = static_cast<Eigen::Index>(waypoints.size());
  path.waypoints.resize(3, total);
  path.orientations.resize(4, pose ? total : 0);
  path.waypoint_nodes.resize(waypoints.size());
  for (Eigen::Index k = 0; k < total; ++k) {
    const Point& point = waypoints[static_cast<std::size_t>(k)];
    path.waypoints.col(k) = point.xi.head<3>();
    if (pose) path.orientations.col(k) = point.xi.tail<4>();
    path.waypoint_nodes[static_cast<std::size_t>(k)] = point.node;
  }
  path.length = polylineLength(path.waypoints);
  path.trajectory.emplace(path.waypoints, options.limits);
  return path;
}

}  // namespace flexirob::planning
