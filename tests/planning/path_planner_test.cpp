// Planning through a learned map: nearest nodes, A*, spline, joint configurations.
#include <gtest/gtest.h>

#include "planning/path_planner.hpp"
#include "test_streams.hpp"

namespace flexirob::planning {
namespace {

using testing::Sample;

// A U-shaped corridor: down the left arm, along the bottom, up the right arm. The two arm tips
// are 0.6 m apart but only connected around the U.
Itm uShapedMap() {
  std::vector<Sample> stream;
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.2);
  Eigen::VectorXd q_right = q;
  q_right[0] = 1.2;  // the arm turns as it goes round
  testing::appendLine(stream, Eigen::Vector3d(-0.3, 0.8, 0.5), Eigen::Vector3d(-0.3, 0.0, 0.5), q, q, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(-0.3, 0.0, 0.5), Eigen::Vector3d(0.3, 0.0, 0.5), q, q_right, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(0.3, 0.0, 0.5), Eigen::Vector3d(0.3, 0.8, 0.5), q_right, q_right, 0.004);
  ItmParameters p;
  p.d_c_max = 0.0;  // no shortcuts across the U's gap (it is an obstacle)
  Itm itm(p, 7);
  testing::feed(itm, stream);
  return itm;
}

TEST(PathPlanner, GoesAroundTheUAndStartsAndEndsWhereAsked) {
  const Itm itm = uShapedMap();
  const Eigen::Vector3d start(-0.31, 0.79, 0.5), goal(0.29, 0.8, 0.52);
  const PlannedPath path = planPath(itm, start, goal);
  ASSERT_TRUE(path.found);
  EXPECT_GT(path.length, 2.0) << "down, across and up again (direct distance 0.6 m)";
  EXPECT_LT(path.length, 2.4);
  EXPECT_TRUE(path.waypoints.col(0).isApprox(start));
  EXPECT_TRUE(path.waypoints.rightCols(1).isApprox(goal));
  EXPECT_EQ(path.nodes.front(), path.start_node);
  EXPECT_EQ(path.nodes.back(), path.goal_node);
  EXPECT_EQ(path.start_node, itm.nearestNode(start));
  EXPECT_NEAR(path.start_gap, (itm.prototype(path.start_node) - start).norm(), 1e-12);
  for (std::size_t k = 1; k < path.nodes.size(); ++k) EXPECT_TRUE(itm.hasEdge(path.nodes[k - 1], path.nodes[k]));
  ASSERT_EQ(path.node_joints.cols(), static_cast<Eigen::Index>(path.nodes.size()));
  for (std::size_t k = 0; k < path.nodes.size(); ++k) {
    EXPECT_EQ(path.node_joints.col(static_cast<Eigen::Index>(k)), itm.joints(path.nodes[k]));
  }
  EXPECT_NEAR(path.node_joints(0, 0), 0.2, 1e-9);
  EXPECT_NEAR(path.node_joints(0, path.node_joints.cols() - 1), 1.2, 1e-9);
  EXPECT_LT(path.max_joint_step, 2.5);
  ASSERT_TRUE(path.trajectory.has_value());
  EXPECT_LE(path.trajectory->maxSpeed(), PathOptions{}.limits.max_speed * (1 + 1e-9));
  EXPECT_LT((path.trajectory->position(path.trajectory->duration()) - goal).norm(), 1e-12);
  // Every waypoint pair except the end connections is a graph edge, so the polyline stays inside
  // the corridor: no point of the spline comes near the U's gap.
  for (double t = 0; t <= path.trajectory->duration(); t += 0.05) {
    const Eigen::Vector3d p = path.trajectory->position(t);
    EXPECT_FALSE(std::abs(p.x()) < 0.2 && p.y() > 0.15) << "the spline cut through the gap at t = " << t;
  }
}

TEST(PathPlanner, ReportsNoPathBetweenDisconnectedParts) {
  ItmParameters p;
  Itm itm(p, 2);
  const int a = itm.addNode(Eigen::Vector3d(0, 0, 0), Eigen::Vector2d(0, 0));
  const int b = itm.addNode(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector2d(0, 0));
  const int c = itm.addNode(Eigen::Vector3d(1, 0, 0), Eigen::Vector2d(3, 3));
  itm.addEdge(a, b);
  const PlannedPath path = planPath(itm, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0));
  EXPECT_FALSE(path.found);
  EXPECT_EQ(path.goal_node, c);
  EXPECT_FALSE(path.trajectory.has_value());
  const PlannedPath empty = planPath(Itm(p, 2), Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0));
  EXPECT_FALSE(empty.found);
  EXPECT_THROW(planPath(itm, Eigen::Vector2d(0, 0), Eigen::Vector3d(1, 0, 0)), std::invalid_argument);
}

TEST(PathPlanner, PoseGraphAcceptsPositionOnlyQueries) {
  ItmParameters p;
  p.task_space = TaskSpace::kPose;
  Itm itm(p, 1);
  Eigen::VectorXd w(7);
  w << 0, 0, 0, 1, 0, 0, 0;
  const int a = itm.addNode(w, Eigen::VectorXd::Zero(1));
  w << 0.5, 0, 0, 0, 0, 0, 1;
  const int b = itm.addNode(w, Eigen::VectorXd::Zero(1));
  itm.addEdge(a, b);
  const PlannedPath path = planPath(itm, Eigen::Vector3d(0.01, 0, 0), Eigen::Vector3d(0.49, 0, 0));
  ASSERT_TRUE(path.found);
  EXPECT_EQ(path.nodes, (std::vector<int>{a, b}));
  ASSERT_EQ(path.orientations.cols(), 4);
  EXPECT_EQ(path.orientations.col(3), Eigen::Vector4d(0, 0, 0, 1));
}

TEST(PathPlanner, PlansBetweenAnyTwoSamplesWhileTheMapGrows) {
  // Any-time use: after every 200 samples of a random walk, a path from the first sample's place
  // to the latest one exists and follows edges that respect the joint criterion.
  const auto stream = testing::randomWalk(Eigen::Vector3d(-0.6, -0.6, 0.1), Eigen::Vector3d(0.6, 0.6, 0.9), 4000, 0.005, 7, 21);
  Itm itm(ItmParameters{}, 7);
  int plans = 0;
  for (std::size_t k = 0; k < stream.size(); ++k) {
    itm.insert(stream[k].x, stream[k].q);
    if (k % 200 != 199) continue;
    const PlannedPath path = planPath(itm, stream.front().x, stream[k].x);
    ASSERT_TRUE(path.found) << "after " << k + 1 << " samples";
    ++plans;
    for (std::size_t i = 1; i < path.nodes.size(); ++i) {
      ASSERT_TRUE(itm.hasEdge(path.nodes[i - 1], path.nodes[i]));
      EXPECT_LT(itm.jointDistance(path.nodes[i - 1], path.nodes[i]), 2.5);
    }
  }
  EXPECT_EQ(plans, 20);
}

}  // namespace
}  // namespace flexirob::planning
