// The ITM's learning rules (Alg. 7.1, Alg. 7.2) on hand-placed nodes and synthetic streams.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <queue>
#include <set>

#include "planning/itm.hpp"
#include "test_streams.hpp"

namespace flexirob::planning {
namespace {

using testing::feed;
using testing::Sample;

Eigen::VectorXd joints(double value, int n = 7) { return Eigen::VectorXd::Constant(n, value); }
Eigen::VectorXd point(double x, double y, double z) { return Eigen::Vector3d(x, y, z); }

ItmParameters plainParameters(double e_max = 0.1) {
  ItmParameters p;
  p.variant = ItmVariant::kPlain;
  p.e_max = e_max;
  return p;
}

ItmParameters hybridWithoutBootstrapping() {
  ItmParameters p;
  p.delta = 0;
  p.d_c_max = 0.0;
  return p;
}

// Connected components by breadth-first search (independent of the map's own statistics).
int countComponents(const Itm& itm) {
  std::set<int> unvisited;
  for (int id : itm.nodeIds()) unvisited.insert(id);
  int components = 0;
  while (!unvisited.empty()) {
    ++components;
    std::queue<int> queue;
    queue.push(*unvisited.begin());
    unvisited.erase(unvisited.begin());
    while (!queue.empty()) {
      const int id = queue.front();
      queue.pop();
      for (int c : itm.neighbors(id)) {
        if (unvisited.erase(c) > 0) queue.push(c);
      }
    }
  }
  return components;
}

TEST(Itm, FirstTwoStimuliFarerThanEmaxGiveTwoConnectedNodes) {
  for (const auto variant : {ItmVariant::kPlain, ItmVariant::kHybrid}) {
    ItmParameters p;
    p.variant = variant;
    Itm itm(p, 7);
    itm.insert(point(0, 0, 0), joints(0));
    itm.insert(point(0.05, 0, 0), joints(0));  // within e_max of the first: no node
    EXPECT_EQ(itm.nodeCount(), 1);
    itm.insert(point(1, 0, 0), joints(0));
    EXPECT_EQ(itm.nodeCount(), 2);
    EXPECT_EQ(itm.edgeCount(), 1);
  }
}

TEST(Itm, CreatesNodeOnlyOutsideTheThalesSphereAndBeyondEmax) {
  for (const auto variant : {ItmVariant::kPlain, ItmVariant::kHybrid}) {
    ItmParameters p = variant == ItmVariant::kPlain ? plainParameters() : hybridWithoutBootstrapping();
    Itm itm(p, 7);
    const int a = itm.addNode(point(0, 0, 0), joints(0));
    const int b = itm.addNode(point(1, 0, 0), joints(0));
    itm.addEdge(a, b);
    // (a - x).(b - x) = -0.25 + 0.16 < 0: inside the sphere with diameter ab.
    EXPECT_EQ(itm.insert(point(0.5, 0.4, 0), joints(0)).created, -1);
    EXPECT_EQ(itm.nodeCount(), 2);
    // Outside the Thales sphere but within e_max of the winner.
    EXPECT_EQ(itm.insert(point(-0.05, 0.0, 0), joints(0)).created, -1);
    // (a - x).(b - x) = -0.25 + 0.36 > 0 and farther than e_max: a new node joined to the winner.
    const auto report = itm.insert(point(0.5, 0.6, 0), joints(0));
    ASSERT_GE(report.created, 0);
    EXPECT_EQ(itm.nodeCount(), 3);
    EXPECT_TRUE(itm.hasEdge(report.created, report.winner));
    EXPECT_TRUE(itm.prototype(report.created).isApprox(point(0.5, 0.6, 0)));
  }
}

TEST(Itm, PlainItmRemovesTheEdgeWhoseThalesSphereHoldsTheSecondWinner) {
  Itm itm(plainParameters(), 7);
  const int n = itm.addNode(point(0, 0, 0), joints(0));
  const int c = itm.addNode(point(1, 0, 0), joints(0));
  const int s = itm.addNode(point(0.5, 0.1, 0), joints(0));  // inside the sphere over n, c
  const int d = itm.addNode(point(-0.5, 0.5, 0), joints(0));  // s outside the sphere over n, d
  itm.addEdge(n, c);
  itm.addEdge(c, s);
  itm.addEdge(n, d);
  const auto report = itm.insert(point(-0.02, 0, 0), joints(0));
  EXPECT_EQ(report.winner, n);
  EXPECT_EQ(report.second, s);
  EXPECT_TRUE(itm.hasEdge(n, s)) << "winners get connected";
  EXPECT_FALSE(itm.hasEdge(n, c)) << "s lies inside the Thales sphere over n and c";
  EXPECT_TRUE(itm.hasEdge(n, d)) << "s lies outside the Thales sphere over n and d";
  EXPECT_TRUE(itm.isNode(c)) << "c keeps its edge to s";
}

TEST(Itm, PlainItmDeletesNodesLeftWithoutEdges) {
  Itm itm(plainParameters(), 7);
  const int n = itm.addNode(point(0, 0, 0), joints(0));
  const int c = itm.addNode(point(1, 0, 0), joints(0));
  const int s = itm.addNode(point(0.5, 0.1, 0), joints(0));
  itm.addEdge(n, c);
  itm.insert(point(-0.02, 0, 0), joints(0));
  EXPECT_FALSE(itm.isNode(c));
  EXPECT_EQ(itm.nodeCount(), 2);
  EXPECT_TRUE(itm.hasEdge(n, s));
}

TEST(Itm, HybridItmNeverRemovesEdges) {
  Itm itm(hybridWithoutBootstrapping(), 7);
  const int n = itm.addNode(point(0, 0, 0), joints(0));
  const int c = itm.addNode(point(1, 0, 0), joints(0));
  const int s = itm.addNode(point(0.5, 0.1, 0), joints(0));
  itm.addEdge(n, c);
  itm.insert(point(-0.02, 0, 0), joints(0));
  EXPECT_TRUE(itm.hasEdge(n, c));
  EXPECT_TRUE(itm.hasEdge(n, s));
  EXPECT_EQ(itm.nodeCount(), 3);
}

TEST(Itm, PlainItmAdaptsTheWinnerByEta) {
  ItmParameters p = plainParameters();
  p.eta = 0.25;
  Itm itm(p, 7);
  const int n = itm.addNode(point(0, 0, 0), joints(0));
  const int s = itm.addNode(point(1, 0, 0), joints(0));
  itm.addEdge(n, s);
  itm.insert(point(0.08, 0.04, 0), joints(0));
  EXPECT_TRUE(itm.prototype(n).isApprox(point(0.02, 0.01, 0), 1e-12));
  // The index follows the move: a query at the new place finds n.
  EXPECT_EQ(itm.nearestNode(point(0.02, 0.01, 0)), n);
}

TEST(Itm, PlainItmRemovesASecondWinnerCloserThanHalfEmax) {
  Itm itm(plainParameters(), 7);
  const int n = itm.addNode(point(0, 0, 0), joints(0));
  const int s = itm.addNode(point(0.04, 0, 0), joints(0));
  const int far = itm.addNode(point(0, 0.5, 0), joints(0));
  itm.addEdge(n, s);
  itm.addEdge(n, far);
  itm.insert(point(-0.01, 0, 0), joints(0));
  EXPECT_FALSE(itm.isNode(s));
  EXPECT_TRUE(itm.isNode(n));
  EXPECT_TRUE(itm.hasEdge(n, far));
}

TEST(Itm, HybridItmNeverJoinsNodesFarApartInJointSpace) {
  Itm itm(hybridWithoutBootstrapping(), 7);
  const int a = itm.addNode(point(0, 0, 0), joints(0.0));
  const int b = itm.addNode(point(0.2, 0, 0), joints(1.0));  // D_theta = sqrt(7) > 2.5
  for (double x = 0.0; x <= 0.2; x += 0.01) itm.insert(point(x, 0.01, 0), joints(0.5));
  EXPECT_FALSE(itm.hasEdge(a, b));
  // The same pair at D_theta = sqrt(7) * 0.9 < 2.5 gets its edge.
  Itm close(hybridWithoutBootstrapping(), 7);
  const int c = close.addNode(point(0, 0, 0), joints(0.0));
  const int d = close.addNode(point(0.2, 0, 0), joints(0.9));
  close.insert(point(0.1, 0.01, 0), joints(0.5));
  EXPECT_TRUE(close.hasEdge(c, d));
}

// One area visited twice with opposite postures, side by side: the plain ITM joins the two
// visits, the hybrid ITM (with its bootstrapping) never does.
TEST(Itm, TwoVisitsWithOppositePosturesStayApartInTheHybridItm) {
  std::vector<Sample> stream;
  const Eigen::VectorXd elbow_up = joints(0.6), elbow_down = joints(-0.6);  // D_theta = 3.17 rad
  for (int pass = 0; pass < 3; ++pass) {
    testing::appendLine(stream, Eigen::Vector3d(-0.4, 0.0, 0.5), Eigen::Vector3d(0.4, 0.0, 0.5), elbow_up, elbow_up, 0.004);
    testing::appendLine(stream, Eigen::Vector3d(0.4, 0.0, 0.5), Eigen::Vector3d(-0.4, 0.0, 0.5), elbow_up, elbow_up, 0.004);
  }
  for (int pass = 0; pass < 3; ++pass) {
    testing::appendLine(stream, Eigen::Vector3d(-0.4, 0.13, 0.5), Eigen::Vector3d(0.4, 0.13, 0.5), elbow_down, elbow_down, 0.004);
    testing::appendLine(stream, Eigen::Vector3d(0.4, 0.13, 0.5), Eigen::Vector3d(-0.4, 0.13, 0.5), elbow_down, elbow_down, 0.004);
  }
  Itm hybrid(ItmParameters{}, 7);
  feed(hybrid, stream);
  ASSERT_GT(hybrid.nodeCount(), 10);
  for (int id : hybrid.nodeIds()) {
    for (int c : hybrid.neighbors(id)) {
      EXPECT_LT(hybrid.jointDistance(id, c), 2.5);
    }
  }
  int upper_row = 0, lower_row = 0;
  for (int id : hybrid.nodeIds()) (hybrid.joints(id)[0] > 0 ? upper_row : lower_row)++;
  EXPECT_GT(upper_row, 4);
  EXPECT_GT(lower_row, 4);
  EXPECT_EQ(countComponents(hybrid), 2);

  Itm plain(plainParameters(), 7);
  feed(plain, stream);
  int crossing = 0;
  for (int id : plain.nodeIds()) {
    for (int c : plain.neighbors(id)) crossing += plain.jointDistance(id, c) > 2.5 ? 1 : 0;
  }
  EXPECT_GT(crossing, 0) << "the plain ITM ignores joint space (the test would not catch a missing criterion)";
}

// Lifts node angles around the ring's centre along the graph; an edge that closes a lift with a
// different winding proves a cycle around the centre.
bool hasCycleAroundOrigin(const Itm& itm) {
  std::map<int, double> lifted;
  for (int root : itm.nodeIds()) {
    if (lifted.count(root)) continue;
    const auto angle = [&](int id) { return std::atan2(itm.prototype(id)[1], itm.prototype(id)[0]); };
    lifted[root] = angle(root);
    std::queue<int> queue;
    queue.push(root);
    while (!queue.empty()) {
      const int id = queue.front();
      queue.pop();
      for (int c : itm.neighbors(id)) {
        const double step = std::remainder(angle(c) - angle(id), 2.0 * std::numbers::pi);
        const double expected = lifted[id] + step;
        const auto it = lifted.find(c);
        if (it == lifted.end()) {
          lifted[c] = expected;
          queue.push(c);
        } else if (std::abs(it->second - expected) > 1.0) {
          return true;
        }
      }
    }
  }
  return false;
}

TEST(Itm, RingStreamGivesARingNotADisc) {
  const auto stream = testing::ringStream(0.5, 0.004, 3, joints(0.2));
  // Plain ITM and hybrid ITM without bootstrapping: exactly one cycle, every node of valence 2.
  for (const auto& p : {plainParameters(), hybridWithoutBootstrapping()}) {
    Itm itm(p, 7);
    feed(itm, stream);
    ASSERT_GT(itm.nodeCount(), 15);
    EXPECT_EQ(itm.edgeCount(), itm.nodeCount()) << "one cycle: E - V + C = 1";
    EXPECT_EQ(countComponents(itm), 1);
    for (int id : itm.nodeIds()) EXPECT_EQ(itm.neighbors(id).size(), 2U);
    EXPECT_TRUE(hasCycleAroundOrigin(itm));
  }
  // With the default bootstrapping the ring gains chords but still surrounds an empty centre.
  Itm itm(ItmParameters{}, 7);
  feed(itm, stream);
  EXPECT_EQ(countComponents(itm), 1);
  EXPECT_TRUE(hasCycleAroundOrigin(itm));
  for (int id : itm.nodeIds()) {
    EXPECT_GT(itm.prototype(id).head<2>().norm(), 0.4);
    for (int c : itm.neighbors(id)) {
      // Distance from the centre to the edge's segment.
      const Eigen::Vector2d a = itm.prototype(id).head<2>(), b = itm.prototype(c).head<2>();
      const double t = std::clamp(-a.dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      EXPECT_GT((a + t * (b - a)).norm(), 0.35) << "an edge across the ring's hole";
    }
  }
}

ItmStatistics sessionStatistics(int delta, double d_c_max) {
  const auto stream = testing::recordingSession(
      {Eigen::Vector3d(-0.5, -0.3, 0.4), Eigen::Vector3d(-0.5, 0.35, 0.5), Eigen::Vector3d(-0.2, 0.0, 0.7)}, joints(0.3), 7);
  ItmParameters p;
  p.delta = delta;
  p.d_c_max = d_c_max;
  Itm itm(p, 7);
  feed(itm, stream);
  return itm.statistics();
}

TEST(Itm, MoreDeltaGivesMoreEdgesAsInTable71) {
  const auto none = sessionStatistics(0, 0.0);
  const auto d2 = sessionStatistics(2, 0.0);
  const auto d3 = sessionStatistics(3, 0.0);
  const auto d5 = sessionStatistics(5, 0.0);
  EXPECT_LT(none.edges, d3.edges);
  EXPECT_LE(d2.edges, d3.edges);
  EXPECT_LT(d3.edges, d5.edges);
  EXPECT_LT(none.mean_valence, d3.mean_valence);
  EXPECT_LT(d3.mean_valence, d5.mean_valence);
  EXPECT_LE(none.nodes, d5.nodes);
  EXPECT_TRUE(std::isnan(none.bootstrap_error_max));
  EXPECT_EQ(none.bootstrapped_nodes, 0);
  EXPECT_GE(d5.bootstrap_samples, d3.bootstrap_samples);
}

TEST(Itm, GlobalBootstrappingConnectsNeighbouringAreas) {
  // Two parallel strokes 0.24 m apart, visited one after the other and joined only at one end by
  // a long detour: global bootstrapping (d_Cmax = 0.25) trains midpoints between them, whose
  // winners are one node of each stroke, so shortcuts appear between the strokes.
  std::vector<Sample> stream;
  const Eigen::VectorXd q = joints(0.1);
  testing::appendLine(stream, Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(1, 0, 0.5), q, q, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(1, 0, 0.5), Eigen::Vector3d(1, 0.6, 0.5), q, q, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(1, 0.6, 0.5), Eigen::Vector3d(0, 0.6, 0.5), q, q, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(0, 0.6, 0.5), Eigen::Vector3d(0, 0.24, 0.5), q, q, 0.004);
  testing::appendLine(stream, Eigen::Vector3d(0, 0.24, 0.5), Eigen::Vector3d(0.9, 0.24, 0.5), q, q, 0.004);
  const auto crossEdges = [&](double d_c_max) {
    ItmParameters p;
    p.delta = 2;
    p.d_c_max = d_c_max;
    Itm itm(p, 7);
    feed(itm, stream);
    int count = 0;
    for (int id : itm.nodeIds()) {
      for (int c : itm.neighbors(id)) {
        const Eigen::VectorXd a = itm.prototype(id), b = itm.prototype(c);
        if (a[1] < 0.05 && b[1] > 0.19 && a[0] > 0.15 && a[0] < 0.85) ++count;
      }
    }
    return count;
  };
  const int without = crossEdges(0.0);
  const int with = crossEdges(0.25);
  EXPECT_EQ(without, 0);
  EXPECT_GT(with, 3);
}

TEST(Itm, InvariantsHoldAfterRandomStreams) {
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    for (const auto variant : {ItmVariant::kPlain, ItmVariant::kHybrid}) {
      ItmParameters p;
      p.variant = variant;
      p.eta = variant == ItmVariant::kPlain ? 0.05 * (seed % 3) : 0.0;
      p.delta = static_cast<int>(seed % 5);
      p.d_theta_max = 1.0;
      const auto stream = testing::randomWalk(Eigen::Vector3d(-0.6, -0.6, 0.0), Eigen::Vector3d(0.6, 0.6, 0.9), 6000, 0.006, 7, seed);
      Itm itm(p, 7);
      feed(itm, stream);
      const auto stats = itm.statistics();
      int valence_sum = 0, max_valence = 0;
      for (int id : itm.nodeIds()) {
        std::set<int> unique;
        for (int c : itm.neighbors(id)) {
          EXPECT_NE(c, id) << "self-edge";
          EXPECT_TRUE(itm.isNode(c));
          EXPECT_TRUE(itm.hasEdge(c, id)) << "edges are undirected";
          EXPECT_TRUE(unique.insert(c).second) << "duplicate edge";
          if (variant == ItmVariant::kHybrid) {
            EXPECT_LT(itm.jointDistance(id, c), p.d_theta_max);
          }
        }
        valence_sum += static_cast<int>(itm.neighbors(id).size());
        max_valence = std::max(max_valence, static_cast<int>(itm.neighbors(id).size()));
        if (variant == ItmVariant::kPlain) {
          EXPECT_FALSE(itm.neighbors(id).empty()) << "the plain ITM deletes unconnected nodes";
        }
      }
      EXPECT_EQ(stats.nodes, static_cast<int>(itm.nodeIds().size()));
      EXPECT_EQ(2 * stats.edges, valence_sum);
      EXPECT_EQ(stats.max_valence, max_valence);
      EXPECT_DOUBLE_EQ(stats.mean_valence, static_cast<double>(valence_sum) / stats.nodes);
      EXPECT_EQ(stats.components, countComponents(itm));
      EXPECT_EQ(stats.real_samples, 6000);

      // The spatial index answers like a brute-force scan.
      std::mt19937 rng(seed);
      std::uniform_real_distribution<double> coordinate(-1.5, 1.5);
      const auto ids = itm.nodeIds();
      for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3d x(coordinate(rng), coordinate(rng), coordinate(rng));
        double best = 1e300;
        for (int id : ids) best = std::min(best, itm.distanceTo(id, x));
        EXPECT_DOUBLE_EQ(itm.distanceTo(itm.nearestNode(x), x), best);
        const double radius = 0.3 * (k % 4);
        std::set<int> expected;
        for (int id : ids) {
          if (itm.distanceTo(id, x) < radius) expected.insert(id);
        }
        const auto within = itm.nodesWithin(x, radius);
        EXPECT_EQ(std::set<int>(within.begin(), within.end()), expected);
      }
    }
  }
}

TEST(Itm, BootstrapErrorIsTheDistanceToTheNearestRealSample) {
  const auto stream = testing::recordingSession({Eigen::Vector3d(-0.4, 0.0, 0.5), Eigen::Vector3d(-0.4, 0.5, 0.5)}, joints(0.0), 3);
  ItmParameters p;
  p.delta = 4;
  Itm itm(p, 7);
  feed(itm, stream);
  const auto stats = itm.statistics();
  ASSERT_GT(stats.bootstrapped_nodes, 0);
  double max_error = 0.0, sum = 0.0;
  int count = 0;
  for (int id : itm.nodeIds()) {
    if (!itm.isBootstrapped(id)) continue;
    double best = 1e300;
    for (const auto& s : stream) best = std::min(best, (s.x - itm.prototype(id)).norm());
    max_error = std::max(max_error, best);
    sum += best;
    ++count;
  }
  EXPECT_EQ(count, stats.bootstrapped_nodes);
  EXPECT_NEAR(stats.bootstrap_error_max, max_error, Itm::sampleResolution());
  EXPECT_NEAR(stats.bootstrap_error_mean, sum / count, Itm::sampleResolution());
  EXPECT_GT(stats.bootstrap_error_max, 0.0);
}

TEST(Itm, PoseMetricCombinesTranslationAndRotationAngle) {
  const TaskMetric metric(TaskSpace::kPose, 0.1);
  const double angle = 0.8;
  const Eigen::Quaterniond rotated(Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()));
  Eigen::VectorXd a(7), b(7);
  a << 0, 0, 0, 1, 0, 0, 0;
  b << 0.3, 0.4, 0, rotated.w(), rotated.x(), rotated.y(), rotated.z();
  EXPECT_NEAR(metric.distance(a.data(), b.data()), 0.9 * 0.5 + 0.1 * angle, 1e-12);  // Eq. 7.5
  // q and -q are the same rotation (Eq. 7.6 squares the inner product).
  Eigen::VectorXd c = b;
  c.tail<4>() *= -1.0;
  EXPECT_NEAR(metric.distance(b.data(), c.data()), 0.0, 1e-6);
  // Bootstrapping midpoint: halfway position and the rotation by angle / 2.
  Eigen::VectorXd mid(7);
  metric.midpoint(a.data(), c.data(), mid.data());
  EXPECT_TRUE(mid.head<3>().isApprox(Eigen::Vector3d(0.15, 0.2, 0)));
  EXPECT_NEAR(quaternionAngle(a.data() + 3, mid.data() + 3), angle / 2, 1e-9);
  EXPECT_NEAR(quaternionAngle(mid.data() + 3, b.data() + 3), angle / 2, 1e-9);
}

TEST(Itm, PoseItmSeparatesOrientationsAtOnePlace) {
  // Turning the hand by 3 rad at a fixed position: D = 0.1 * angle passes e_max every 1 rad.
  ItmParameters p;
  p.task_space = TaskSpace::kPose;
  Itm itm(p, 7);
  for (int k = 0; k <= 300; ++k) {
    const Eigen::Quaterniond quaternion(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()));
    Eigen::VectorXd xi(7);
    xi << -0.5, 0.2, 0.4, quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z();
    itm.insert(xi, joints(0.001 * k));
  }
  EXPECT_GE(itm.nodeCount(), 2);
  EXPECT_LE(itm.nodeCount(), 4);
  EXPECT_EQ(countComponents(itm), 1);
  for (int id : itm.nodeIds()) EXPECT_TRUE(itm.prototype(id).head<3>().isApprox(Eigen::Vector3d(-0.5, 0.2, 0.4)));
}

TEST(Itm, PositionOnlyNeighbourhoodOfAPoseGraphIsTranslational) {
  // Nodes at one place and turned by 0.5 rad each (D_xi 0.05 apart), and nodes farther along x.
  ItmParameters p;
  p.task_space = TaskSpace::kPose;
  Itm itm(p, 1);
  const auto pose = [](double x, double angle) {
    const Eigen::Quaterniond quaternion(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
    Eigen::VectorXd xi(7);
    xi << x, 0.0, 0.5, quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z();
    return xi;
  };
  std::set<int> here, near;
  for (int k = 0; k < 6; ++k) here.insert(itm.addNode(pose(0.0, 0.5 * k), Eigen::VectorXd::Zero(1)));
  near.insert(itm.addNode(pose(0.07, 2.0), Eigen::VectorXd::Zero(1)));
  itm.addNode(pose(0.2, 0.0), Eigen::VectorXd::Zero(1));
  const auto within = [&](const Eigen::VectorXd& xi, double radius, bool position_only) {
    const auto ids = itm.nodesWithin(xi, radius, position_only);
    return std::set<int>(ids.begin(), ids.end());
  };
  // Translationally the turned nodes are all at the query point, the one at 0.07 m inside 0.1 m.
  std::set<int> expected = here;
  expected.insert(near.begin(), near.end());
  EXPECT_EQ(within(Eigen::Vector3d(0.0, 0.0, 0.5), 0.1, true), expected);
  EXPECT_EQ(within(pose(0.0, 0.0), 0.1, true), expected) << "the orientation of the query is ignored";
  EXPECT_EQ(within(Eigen::Vector3d(0.0, 0.0, 0.5), 0.05, true), here);
  // In D_xi (Eq. 7.5) the turned nodes count their angles.
  EXPECT_EQ(within(pose(0.0, 0.0), 0.075, false).size(), 2U);
  EXPECT_THROW(itm.nodesWithin(Eigen::Vector3d(0.0, 0.0, 0.5), 0.1, false), std::invalid_argument);
  EXPECT_THROW(itm.nodesWithin(Eigen::Vector2d(0.0, 0.0), 0.1, true), std::invalid_argument);
}

TEST(Itm, RefusesMalformedSamplesAndParameters) {
  Itm itm(ItmParameters{}, 7);
  EXPECT_THROW(itm.insert(Eigen::VectorXd::Zero(2), joints(0)), std::invalid_argument);
  EXPECT_THROW(itm.insert(point(0, 0, 0), joints(0, 6)), std::invalid_argument);
  EXPECT_THROW(itm.insert(point(std::nan(""), 0, 0), joints(0)), std::invalid_argument);
  EXPECT_THROW(itm.insert(point(1e9, 0, 0), joints(0)), std::invalid_argument);
  EXPECT_EQ(itm.nodeCount(), 0);
  ItmParameters bad;
  bad.e_max = 0.0;
  EXPECT_THROW(Itm(bad, 7), std::invalid_argument);
  bad = ItmParameters{};
  bad.delta = -1;
  EXPECT_THROW(Itm(bad, 7), std::invalid_argument);
  bad = ItmParameters{};
  bad.eta = 0.5;  // the hybrid ITM does not adapt
  EXPECT_THROW(Itm(bad, 7), std::invalid_argument);
  EXPECT_THROW(Itm(ItmParameters{}, 0), std::invalid_argument);
  ItmParameters pose;
  pose.task_space = TaskSpace::kPose;
  Itm pose_itm(pose, 7);
  Eigen::VectorXd zero_quaternion = Eigen::VectorXd::Zero(7);
  EXPECT_THROW(pose_itm.insert(zero_quaternion, joints(0)), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::planning
