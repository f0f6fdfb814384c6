// Planning through a learned map: nearest nodes, A*, spline, joint configurations.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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
  EXPECT_LE(path.length, path.raw_length + 1e-12);
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
  // The waypoints are graph nodes or shortcuts through mapped space, so the polyline stays inside
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


// --- Shortcuts through mapped space ------------------------------------------------------------

// An L-shaped corridor of nodes in the z = 0 plane on a 0.09 m lattice (just below the default
// e_max of 0.1 m, as the ITM spaces its nodes): the vertical arm x in {0, 0.09, 0.18}, y in
// [0, 0.9], and the horizontal arm y in {0, 0.09, 0.18}, x in [0, 0.9], lattice neighbours joined
// (4-connectivity). The square beyond x, y > 0.18 holds no node: it is the hole (an obstacle the
// tutor went around).
struct LCorridor {
  static constexpr double kSpacing = 0.09;
  static constexpr double kArm = 2 * kSpacing;  // the arms' inner edge
  static constexpr double kEnd = 10 * kSpacing;  // the arms' far ends
  Itm itm{ItmParameters{}, 2};
  std::vector<int> ids;
  LCorridor() {
    std::vector<std::vector<int>> at(11, std::vector<int>(11, -1));
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        if (i > 2 && j > 2) continue;
        at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
            itm.addNode(Eigen::Vector3d(kSpacing * i, kSpacing * j, 0.0), Eigen::Vector2d(0.1, -0.2));
        ids.push_back(at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)]);
      }
    }
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const int a = at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
        if (a < 0) continue;
        if (i < 10 && at[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(j)] >= 0) itm.addEdge(a, at[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(j)]);
        if (j < 10 && at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j + 1)] >= 0) itm.addEdge(a, at[static_cast<std::size_t>(i)][static_cast<std::size_t>(j + 1)]);
      }
    }
  }
  // Brute-force distance from p to the nearest node (independent of the ITM's spatial index).
  double nearestNodeDistance(const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const int id : ids) best = std::min(best, (Eigen::Vector3d(itm.prototype(id)) - p).norm());
    return best;
  }
  // Brute-force distance from p to the nearest edge.
  double nearestEdgeDistance(const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const int id : ids) {
      for (const int n : itm.neighbors(id)) {
        const Eigen::Vector3d a = itm.prototype(id), b = itm.prototype(n);
        const double s = std::clamp((b - a).dot(p - a) / (b - a).squaredNorm(), 0.0, 1.0);
        best = std::min(best, (a + s * (b - a) - p).norm());
      }
    }
    return best;
  }
};

// Does the segment a-b enter the open square x > lo, y > lo (the hole, extended beyond the
// lattice)? Slab test of the segment's parameter range against x > lo and y > lo.
bool segmentEntersQuadrant(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double lo) {
  double t0 = 0.0, t1 = 1.0;
  for (int axis = 0; axis < 2; ++axis) {
    const double da = a[axis] - lo, d = b[axis] - a[axis];
    // Points with a[axis] + t d > lo: t > -da / d when d > 0, t < -da / d when d < 0.
    if (d == 0.0) {
      if (da <= 0.0) return false;
    } else if (d > 0.0) {
      t0 = std::max(t0, -da / d);
    } else {
      t1 = std::min(t1, -da / d);
    }
  }
  return t0 < t1;
}

TEST(PathShortcut, LCorridorPathIsShorterAndNeverCrossesTheHole) {
  const LCorridor corridor;
  const Eigen::Vector3d start(LCorridor::kSpacing, LCorridor::kEnd, 0.0), goal(LCorridor::kEnd, LCorridor::kSpacing, 0.0);
  const PlannedPath path = planPath(corridor.itm, start, goal);
  ASSERT_TRUE(path.found);
  // Every lattice path from start to goal is monotone here: its length is the Manhattan distance.
  EXPECT_NEAR(path.raw_length, 2 * (LCorridor::kEnd - LCorridor::kSpacing), 1e-9);
  // Points within the shortcut radius of a node form the mapped space; beyond the arms' inner
  // edge + radius in both x and y no point is that close to a node (the corner node's disc ends
  // at kArm + radius / sqrt(2)). The shortest curve from start to goal that avoids this open
  // square bends at its corner: a lower bound that only a path through the hole could beat.
  const double radius = PathOptions{}.shortcut_radius * corridor.itm.parameters().e_max;
  const double hole = LCorridor::kArm + radius;
  const Eigen::Vector3d corner(hole, hole, 0.0);
  const double geodesic = (corner - start).norm() + (goal - corner).norm();
  EXPECT_GE(path.length, geodesic - 1e-9);
  EXPECT_LT(path.length, path.raw_length - 0.15) << "the zig-zag along the lattice is pulled straight";
  EXPECT_GE(path.shortcuts, 1);
  EXPECT_TRUE(path.waypoints.col(0).isApprox(start));
  EXPECT_TRUE(path.waypoints.rightCols(1).isApprox(goal));
  ASSERT_EQ(path.waypoint_nodes.size(), static_cast<std::size_t>(path.waypoints.cols()));
  // The raw node path is still there, edge by edge, for display.
  EXPECT_EQ(path.raw_waypoints.cols(), static_cast<Eigen::Index>(path.nodes.size()) + 2);
  for (std::size_t k = 1; k < path.nodes.size(); ++k) EXPECT_TRUE(corridor.itm.hasEdge(path.nodes[k - 1], path.nodes[k]));
  for (Eigen::Index k = 1; k < path.waypoints.cols(); ++k) {
    const Eigen::Vector3d a = path.waypoints.col(k - 1), b = path.waypoints.col(k);
    EXPECT_FALSE(segmentEntersQuadrant(a, b, hole)) << "segment " << k << " crosses the hole";
    // Every point of every segment lies within the shortcut radius of a node and within the
    // corridor of an edge.
    const double corridor_width = PathOptions{}.shortcut_corridor * corridor.itm.parameters().e_max;
    for (double s = 0.0; s <= 1.0; s += 1e-3) {
      ASSERT_LE(corridor.nearestNodeDistance(a + s * (b - a)), radius + 1e-9) << "segment " << k << " at " << s;
      ASSERT_LE(corridor.nearestEdgeDistance(a + s * (b - a)), corridor_width + 1e-9) << "segment " << k << " at " << s;
    }
  }
  // The executed spline follows the polyline: it stays out of the hole (within 1 cm of it).
  ASSERT_TRUE(path.trajectory.has_value());
  for (double t = 0.0; t <= path.trajectory->duration(); t += 0.01) {
    const Eigen::Vector3d p = path.trajectory->position(t);
    EXPECT_FALSE(p.x() > hole + 0.01 && p.y() > hole + 0.01) << "t = " << t << ": " << p.transpose();
  }
}

TEST(PathShortcut, OffKeepsTheNodePath) {
  const LCorridor corridor;
  const Eigen::Vector3d start(0.11, 0.88, 0.0), goal(0.87, 0.1, 0.0);
  const Eigen::Vector3d start_node(LCorridor::kSpacing, LCorridor::kEnd, 0.0), goal_node(LCorridor::kEnd, LCorridor::kSpacing, 0.0);
  PathOptions options;
  options.shortcut = false;
  const PlannedPath path = planPath(corridor.itm, start, goal, options);
  ASSERT_TRUE(path.found);
  EXPECT_EQ(path.shortcuts, 0);
  ASSERT_EQ(path.waypoints.cols(), static_cast<Eigen::Index>(path.nodes.size()) + 2);
  EXPECT_EQ(path.waypoints, path.raw_waypoints);
  EXPECT_EQ(path.waypoint_nodes.front(), -1);
  EXPECT_EQ(path.waypoint_nodes.back(), -1);
  for (std::size_t k = 0; k < path.nodes.size(); ++k) {
    EXPECT_EQ(path.waypoint_nodes[k + 1], path.nodes[k]);
    EXPECT_EQ(path.waypoints.col(static_cast<Eigen::Index>(k) + 1), corridor.itm.prototype(path.nodes[k]));
  }
  // Along a 4-connected lattice: Manhattan distance between the end nodes plus both gaps.
  EXPECT_EQ(path.nodes.front(), corridor.itm.nearestNode(start_node));
  EXPECT_EQ(path.nodes.back(), corridor.itm.nearestNode(goal_node));
  EXPECT_NEAR(path.length, 2 * (LCorridor::kEnd - LCorridor::kSpacing) + (start - start_node).norm() + (goal - goal_node).norm(), 1e-9);
  EXPECT_EQ(path.length, path.raw_length);
  // The same A* route with the shortcuts on, and a shorter polyline.
  const PlannedPath shortened = planPath(corridor.itm, start, goal);
  EXPECT_EQ(shortened.nodes, path.nodes);
  EXPECT_EQ(shortened.raw_waypoints, path.raw_waypoints);
  EXPECT_LT(shortened.length, path.length);
}

TEST(PathShortcut, StraightChainCollapsesToItsEnds) {
  // Nine nodes 0.08 m apart on a straight line, one redundancy resolution.
  Itm itm(ItmParameters{}, 3);
  const Eigen::Vector3d from(0.2, -0.1, 0.4), direction = Eigen::Vector3d(1.0, 2.0, -0.5).normalized();
  std::vector<int> chain;
  for (int k = 0; k < 9; ++k) {
    chain.push_back(itm.addNode(from + 0.08 * k * direction, Eigen::Vector3d(0.3, 0.3, 0.3)));
    if (k > 0) itm.addEdge(chain[static_cast<std::size_t>(k - 1)], chain.back());
  }
  PathOptions options;
  options.include_endpoints = false;
  const PlannedPath path = planPath(itm, itm.prototype(chain.front()), itm.prototype(chain.back()), options);
  ASSERT_TRUE(path.found);
  EXPECT_EQ(path.nodes, chain);
  EXPECT_EQ(path.shortcuts, 1);
  EXPECT_EQ(path.waypoint_nodes.front(), chain.front());
  EXPECT_EQ(path.waypoint_nodes.back(), chain.back());
  // Only points inserted along the shortcut in between, none of the chain's nodes.
  for (std::size_t k = 1; k + 1 < path.waypoint_nodes.size(); ++k) EXPECT_EQ(path.waypoint_nodes[k], -1);
  EXPECT_NEAR(path.length, 8 * 0.08, 1e-9);
  for (Eigen::Index k = 1; k < path.waypoints.cols(); ++k) {
    const Eigen::Vector3d step = path.waypoints.col(k) - path.waypoints.col(k - 1);
    EXPECT_LE(step.norm(), 0.5 * itm.parameters().e_max + 1e-9) << "waypoint spacing along a shortcut";
    EXPECT_NEAR(step.normalized().dot(direction), 1.0, 1e-9) << "inserted points lie on the line";
  }
}

TEST(PathShortcut, KeepsTheJointCriterionBetweenKeptNodes) {
  // A straight chain along which the arm turns: 0.5 rad per node, so the ends (4 rad apart)
  // must not be joined directly (d_theta_max = 2.5 rad) although the line is mapped space.
  Itm itm(ItmParameters{}, 1);
  std::vector<int> chain;
  for (int k = 0; k <= 8; ++k) {
    chain.push_back(itm.addNode(Eigen::Vector3d(0.08 * k, 0.0, 0.5), Eigen::VectorXd::Constant(1, 0.5 * k)));
    if (k > 0) itm.addEdge(chain[static_cast<std::size_t>(k - 1)], chain.back());
  }
  PathOptions options;
  options.include_endpoints = false;
  const PlannedPath path = planPath(itm, itm.prototype(chain.front()), itm.prototype(chain.back()), options);
  ASSERT_TRUE(path.found);
  std::vector<int> kept;
  for (const int node : path.waypoint_nodes) {
    if (node >= 0) kept.push_back(node);
  }
  ASSERT_GE(kept.size(), 3U) << "at least one node between the ends is kept";
  EXPECT_EQ(kept.front(), chain.front());
  EXPECT_EQ(kept.back(), chain.back());
  for (std::size_t k = 1; k < kept.size(); ++k) {
    EXPECT_LT(std::abs(itm.joints(kept[k])[0] - itm.joints(kept[k - 1])[0]), 2.5) << kept[k - 1] << " -> " << kept[k];
  }
  EXPECT_GE(path.shortcuts, 1) << "nodes within 2.5 rad of each other are still joined";
}

TEST(PathShortcut, PoseGraphShortcutsOnlyWhereTheOrientationsFollow) {
  ItmParameters p;
  p.task_space = TaskSpace::kPose;
  const auto pose = [](double x, double angle_z) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle_z, Eigen::Vector3d::UnitZ()));
    Eigen::VectorXd w(7);
    w << x, 0.0, 0.3, q.w(), q.x(), q.y(), q.z();
    return w;
  };
  // Three collinear nodes 0.1 m apart whose orientation turns evenly: the middle one lies on the
  // straight pose segment between the others, which collapses. When the middle node is turned
  // by half a turn instead, the segment's midpoint is far from every node in D_xi (from the
  // middle one alpha pi = 0.31, from the ends 0.9 * 0.1 + 0.1 * 0.2 = 0.11, both beyond the
  // radius 0.075) and the node stays.
  for (const bool turned : {false, true}) {
    Itm itm(p, 1);
    const int a = itm.addNode(pose(0.0, 0.0), Eigen::VectorXd::Zero(1));
    const int b = itm.addNode(pose(0.1, turned ? 0.2 + std::numbers::pi : 0.2), Eigen::VectorXd::Zero(1));
    const int c = itm.addNode(pose(0.2, 0.4), Eigen::VectorXd::Zero(1));
    itm.addEdge(a, b);
    itm.addEdge(b, c);
    PathOptions options;
    options.include_endpoints = false;
    options.shortcut_radius = 0.75;
    const PlannedPath path = planPath(itm, pose(0.0, 0.0), pose(0.2, 0.4), options);
    ASSERT_TRUE(path.found);
    EXPECT_EQ(path.nodes, (std::vector<int>{a, b, c}));
    const bool keeps_b = std::find(path.waypoint_nodes.begin(), path.waypoint_nodes.end(), b) != path.waypoint_nodes.end();
    EXPECT_EQ(keeps_b, turned);
    EXPECT_EQ(path.shortcuts, turned ? 0 : 1);
    // Inserted points carry unit quaternions between the ends' orientations.
    for (Eigen::Index k = 0; k < path.orientations.cols(); ++k) EXPECT_NEAR(path.orientations.col(k).norm(), 1.0, 1e-12);
  }
}

// A chain that bends around an obstacle, as the tutor's tip moved over a slab: A, the bend B
// 0.07 m off the chord, C. Every point of the chord A-C lies within 0.07 m of a node, inside the
// radius of (a), but its middle is 0.053 m from the edges the tutor moved along.
struct Bend {
  Bend() {
    node_a = itm.addNode(a, Eigen::VectorXd::Zero(1));
    node_b = itm.addNode(b, Eigen::VectorXd::Zero(1));
    node_c = itm.addNode(c, Eigen::VectorXd::Zero(1));
    itm.addEdge(node_a, node_b);
    itm.addEdge(node_b, node_c);
  }
  Itm itm{ItmParameters{}, 1};
  Eigen::Vector3d a{0.0, 0.0, 0.5}, b{0.08, 0.07, 0.5}, c{0.16, 0.0, 0.5};
  int node_a = -1, node_b = -1, node_c = -1;
};

TEST(PathShortcut, KeepsToTheEdgesWhereTheMapIsOneNodeWide) {
  Bend bend;
  auto& [itm, a, b, c, node_a, node_b, node_c] = bend;
  ASSERT_LT(((a + c) / 2 - b).norm(), 0.09) << "the chord lies in the balls of (a)";
  PathOptions options;
  options.include_endpoints = false;
  const PlannedPath path = planPath(itm, a, c, options);
  ASSERT_TRUE(path.found);
  EXPECT_EQ(path.waypoint_nodes, (std::vector<int>{node_a, node_b, node_c})) << "the bend is kept";
  EXPECT_EQ(path.shortcuts, 0);
  // A corridor wide enough for the chord's middle cuts the bend.
  options.shortcut_corridor = 0.6;
  const PlannedPath wide = planPath(itm, a, c, options);
  EXPECT_EQ(wide.shortcuts, 1);
  EXPECT_EQ(std::count(wide.waypoint_nodes.begin(), wide.waypoint_nodes.end(), node_b), 0);
}

TEST(PathShortcut, FindsAnEdgeNearTheSegmentThatIsNotTheNearestNodes) {
  // The bend of the test above, with a node D nearest to the chord's middle that has no edge of
  // its own and an edge E-F of another stroke 3 cm beside the chord: the chord keeps to the
  // corridor of E-F (though not to D's or the bend's edges), so the bend is cut; without E-F it
  // is kept.
  for (const bool with_edge : {true, false}) {
    Bend bend;
    auto& [itm, a, b, c, node_a, node_b, node_c] = bend;
    itm.addNode(Eigen::Vector3d(0.08, -0.01, 0.5), Eigen::VectorXd::Zero(1));  // D
    const int node_e = itm.addNode(Eigen::Vector3d(0.04, -0.03, 0.5), Eigen::VectorXd::Zero(1));
    const int node_f = itm.addNode(Eigen::Vector3d(0.12, -0.03, 0.5), Eigen::VectorXd::Zero(1));
    if (with_edge) itm.addEdge(node_e, node_f);
    PathOptions options;
    options.include_endpoints = false;
    const PlannedPath path = planPath(itm, a, c, options);
    ASSERT_TRUE(path.found);
    EXPECT_EQ(path.nodes, (std::vector<int>{node_a, node_b, node_c}));
    EXPECT_EQ(path.shortcuts, with_edge ? 1 : 0) << (with_edge ? "with" : "without") << " the edge E-F";
  }
}

TEST(PathShortcut, RefusesOptionsOutOfRange) {
  const LCorridor corridor;
  for (const double bad : {0.0, -0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    PathOptions radius;
    radius.shortcut_radius = bad;
    EXPECT_THROW(planPath(corridor.itm, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), radius), std::invalid_argument);
    PathOptions corridor_width;
    corridor_width.shortcut_corridor = bad;
    EXPECT_THROW(planPath(corridor.itm, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), corridor_width), std::invalid_argument);
    PathOptions spacing;
    spacing.shortcut_waypoint_spacing = bad;
    EXPECT_THROW(planPath(corridor.itm, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), spacing), std::invalid_argument);
  }
}

}  // namespace
}  // namespace flexirob::planning
