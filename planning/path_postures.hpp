#pragma once
// The postures the configuration stage showed along a planned path. Each node of the hybrid
// ITM keeps the joint values q_i the robot had when it was there (Sect. 7.3); where the path
// leaves the training areas, the learned map q_c(x) extrapolates between taught postures and
// may lead the arm into an obstacle the tutor steered around, while the q_i along the path
// were all taken without a contact. PathPostures gives, for a desired tip position, the q_i of
// the path interpolated in joint space, as the execution's null-space posture.
#include <Eigen/Core>
#include <string>

#include "planning/itm.hpp"
#include "planning/path_planner.hpp"

namespace flexirob::planning {

/// Where a planned motion's null-space posture comes from: the q_i the configuration stage
/// showed along the path (PathPostures), or the learned map q_c(x) alone (the thesis' Sect. 7.4
/// and 8.3 execution).
enum class PlanPostures { kDemonstrated, kLearned };
const char* toString(PlanPostures postures);
/// "demonstrated" or "learned"; throws std::invalid_argument naming both otherwise.
PlanPostures planPosturesFromString(const std::string& name);

class PathPostures {
 public:
  /// The polyline start -> prototypes of path.nodes carrying q_start, then each node's q_i
  /// (path.node_joints). The start node is the node nearest to the start, so the start may lie
  /// beyond it, on the way to the next: such leading nodes are left out, or the polyline would
  /// double back over them. Throws std::invalid_argument if the path was not found or q_start
  /// does not have the graph's joint count.
  PathPostures(const Itm& graph, const PlannedPath& path, const Eigen::Vector3d& p_start, const Eigen::VectorXd& q_start);

  /// The posture at the point of the polyline nearest to p_W: the joint values of the two
  /// ends of that segment, linearly interpolated. Calls follow one motion along the path: the
  /// search starts at the segment the last call found and looks kLookAhead segments ahead,
  /// never back, so that a path passing near one of its own earlier legs keeps to its order.
  /// No allocation (q must have the joint count).
  void at(const Eigen::Vector3d& p_W, Eigen::Ref<Eigen::VectorXd> q) const;

  Eigen::Index points() const { return points_.cols(); }

  static constexpr Eigen::Index kLookAhead = 3;

 private:
  Eigen::Matrix3Xd points_;   ///< 3 x K positions [m, W]
  Eigen::MatrixXd postures_;  ///< N x K joint values [rad or m]
  mutable Eigen::Index segment_ = 0;  ///< where the last call was
};

}  // namespace flexirob::planning
