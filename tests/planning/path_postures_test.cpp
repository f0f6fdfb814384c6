// The postures shown along a planned path, as the execution's null-space posture.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <stdexcept>

#include "planning/itm.hpp"
#include "planning/path_planner.hpp"
#include "planning/path_postures.hpp"

namespace flexirob::planning {
namespace {

Eigen::VectorXd joints(double a, double b) { return (Eigen::VectorXd(2) << a, b).finished(); }

// An L through three nodes, (0,0,0) -> (1,0,0) -> (1,1,0), each with its own posture.
struct LPath {
  LPath() : graph(ItmParameters{}, 2) {
    graph.addNode(Eigen::Vector3d(0, 0, 0), joints(0.0, 0.0));
    graph.addNode(Eigen::Vector3d(1, 0, 0), joints(1.0, -1.0));
    graph.addNode(Eigen::Vector3d(1, 1, 0), joints(3.0, 1.0));
    path.found = true;
    path.nodes = graph.nodeIds();
    path.node_joints.resize(2, 3);
    for (int k = 0; k < 3; ++k) path.node_joints.col(k) = graph.joints(path.nodes[static_cast<std::size_t>(k)]);
  }
  Itm graph;
  PlannedPath path;
};

Eigen::VectorXd postureAt(const PathPostures& postures, const Eigen::Vector3d& p) {
  Eigen::VectorXd q(2);
  postures.at(p, q);
  return q;
}

TEST(PathPostures, InterpolatesThePosturesOfTheNearestSegmentFromTheStartToTheGoal) {
  const LPath l;
  const auto fresh = [&l] { return PathPostures(l.graph, l.path, Eigen::Vector3d(-1, 0, 0), joints(-1.0, 5.0)); };
  EXPECT_EQ(fresh().points(), 4);
  // Before the start: the start's posture.
  EXPECT_TRUE(postureAt(fresh(), Eigen::Vector3d(-3, 0, 0)).isApprox(joints(-1.0, 5.0)));
  // One motion from the start to past the goal.
  const PathPostures postures = fresh();
  // Half way along the start's segment, and beside it: the mean of its two ends.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(-0.5, 0.05, 0)).isApprox(joints(-0.5, 2.5)));
  // A quarter along the first node's segment.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.25, -0.1, 0.1)).isApprox(joints(0.25, -0.25)));
  // Half way up the last segment.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(1.1, 0.5, 0)).isApprox(joints(2.0, 0.0)));
  // Past the goal: the goal node's posture.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(1, 4, 0)).isApprox(joints(3.0, 1.0)));
}

TEST(PathPostures, AStartBeyondTheFirstNodeDoesNotDoubleBackOverIt) {
  const LPath l;
  // The start lies half way from node 0 to node 1: the polyline goes start -> node 1 -> node 2.
  const PathPostures postures(l.graph, l.path, Eigen::Vector3d(0.5, 0, 0), joints(7.0, 7.0));
  EXPECT_EQ(postures.points(), 3);
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.5, 0, 0)).isApprox(joints(7.0, 7.0))) << "no jump at the start";
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.75, 0, 0)).isApprox(joints(4.0, 3.0)));
}

TEST(PathPostures, APathPassingNearItsOwnEarlierLegKeepsToItsOrder) {
  // A U: out along y = 0, over, and back along y = 0.2, each leg with its own postures.
  Itm graph(ItmParameters{}, 2);
  graph.addNode(Eigen::Vector3d(0, 0, 0), joints(0.0, 0.0));
  graph.addNode(Eigen::Vector3d(1, 0, 0), joints(1.0, 0.0));
  graph.addNode(Eigen::Vector3d(1, 0.2, 0), joints(1.0, 1.0));
  graph.addNode(Eigen::Vector3d(0, 0.2, 0), joints(0.0, 1.0));
  PlannedPath path;
  path.found = true;
  path.nodes = graph.nodeIds();
  path.node_joints.resize(2, 4);
  for (int k = 0; k < 4; ++k) path.node_joints.col(k) = graph.joints(path.nodes[static_cast<std::size_t>(k)]);
  const PathPostures postures(graph, path, Eigen::Vector3d(0, 0, 0), joints(0.0, 0.0));
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.5, 0, 0)).isApprox(joints(0.5, 0.0)));
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(1, 0.1, 0)).isApprox(joints(1.0, 0.5)));
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.5, 0.2, 0)).isApprox(joints(0.5, 1.0)));
  // On the way back, a point a little nearer the outward leg still takes the leg being driven.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0.4, 0.09, 0)).isApprox(joints(0.4, 1.0)));
}

TEST(PathPostures, AStartOnTheGoalNodeHoldsTheStartPosture) {
  LPath l;
  l.path.nodes.resize(1);
  l.path.node_joints.conservativeResize(2, 1);
  const PathPostures postures(l.graph, l.path, Eigen::Vector3d(0, 0, 0), joints(0.5, 0.5));
  // Start and node coincide: the segment has no length, the start's posture holds at it.
  EXPECT_TRUE(postureAt(postures, Eigen::Vector3d(0, 0, 0)).isApprox(joints(0.5, 0.5)));
}

TEST(PathPostures, RefusesAPathNotFoundOrPosturesOfAnotherJointCount) {
  LPath l;
  EXPECT_THROW(PathPostures(l.graph, l.path, Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(3)), std::invalid_argument);
  l.path.found = false;
  EXPECT_THROW(PathPostures(l.graph, l.path, Eigen::Vector3d::Zero(), joints(0, 0)), std::invalid_argument);
}

TEST(PathPostures, NamesItsModesAndRefusesOthers) {
  for (const PlanPostures mode : {PlanPostures::kDemonstrated, PlanPostures::kLearned}) {
    EXPECT_EQ(planPosturesFromString(toString(mode)), mode);
  }
  EXPECT_THROW(planPosturesFromString("guessed"), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::planning
