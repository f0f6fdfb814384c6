#include "planning/path_postures.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace flexirob::planning {

const char* toString(PlanPostures postures) {
  return postures == PlanPostures::kDemonstrated ? "demonstrated" : "learned";
}

PlanPostures planPosturesFromString(const std::string& name) {
  if (name == "demonstrated") return PlanPostures::kDemonstrated;
  if (name == "learned") return PlanPostures::kLearned;
  throw std::invalid_argument("postures: expected demonstrated or learned, got '" + name.substr(0, 64) + "'");
}

PathPostures::PathPostures(const Itm& graph, const PlannedPath& path, const Eigen::Vector3d& p_start,
                           const Eigen::VectorXd& q_start) {
  if (!path.found) throw std::invalid_argument("PathPostures: the path was not found");
  if (q_start.size() != graph.jointCount() || path.node_joints.cols() != static_cast<Eigen::Index>(path.nodes.size())) {
    throw std::invalid_argument("PathPostures: joint counts of the start posture, the graph and the path differ");
  }
  // Leading nodes the start lies beyond: its projection on the segment to the next node falls
  // inside that segment.
  std::size_t first = 0;
  while (first + 1 < path.nodes.size()) {
    const Eigen::Vector3d a = graph.prototype(path.nodes[first]).head<3>();
    const Eigen::Vector3d b = graph.prototype(path.nodes[first + 1]).head<3>();
    if ((p_start - a).dot(b - a) <= 0.0) break;
    ++first;
  }
  const auto count = static_cast<Eigen::Index>(path.nodes.size() - first) + 1;
  points_.resize(3, count);
  postures_.resize(q_start.size(), count);
  points_.col(0) = p_start;
  postures_.col(0) = q_start;
  for (Eigen::Index k = 1; k < count; ++k) {
    const std::size_t node = first + static_cast<std::size_t>(k - 1);
    points_.col(k) = graph.prototype(path.nodes[node]).head<3>();
    postures_.col(k) = path.node_joints.col(static_cast<Eigen::Index>(node));
  }
}

void PathPostures::at(const Eigen::Vector3d& p_W, Eigen::Ref<Eigen::VectorXd> q) const {
  if (points_.cols() == 1) {
    q = postures_.col(0);
    return;
  }
  double nearest = std::numeric_limits<double>::infinity();
  Eigen::Index segment_index = segment_;
  double along = 0.0;
  const Eigen::Index last = std::min(points_.cols() - 2, segment_ + kLookAhead);
  for (Eigen::Index k = segment_; k <= last; ++k) {
    const Eigen::Vector3d a = points_.col(k);
    const Eigen::Vector3d segment = points_.col(k + 1) - a;
    const double length2 = segment.squaredNorm();
    const double s = length2 > 1e-12 ? std::clamp((p_W - a).dot(segment) / length2, 0.0, 1.0) : 0.0;
    const double distance = (a + s * segment - p_W).squaredNorm();
    if (distance < nearest) {
      nearest = distance;
      segment_index = k;
      along = s;
    }
  }
  segment_ = segment_index;
  q = (1.0 - along) * postures_.col(segment_index) + along * postures_.col(segment_index + 1);
}

}  // namespace flexirob::planning
