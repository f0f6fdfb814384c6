// ITM invariants checked after every single sample of random and hostile streams (jumps across
// the workspace, repeated and nearly repeated samples, joint-space jumps, pose streams):
// undirected, no self-edges or duplicates, edges only between live nodes, every edge the hybrid
// ITM creates respects the joint criterion D_theta < d_theta_max (Sect. 7.3.1), the insert
// report agrees with the change of the graph, and the statistics agree with the adjacency.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <set>
#include <utility>

#include "planning/itm.hpp"

namespace flexirob::planning {
namespace {

using Edge = std::pair<int, int>;

std::set<Edge> edgesOf(const Itm& itm) {
  std::set<Edge> edges;
  for (const int id : itm.nodeIds()) {
    for (const int other : itm.neighbors(id)) edges.insert({std::min(id, other), std::max(id, other)});
  }
  return edges;
}

/// Checks the structural invariants; returns the undirected edge set.
std::set<Edge> checkStructure(const Itm& itm) {
  int valence_sum = 0;
  for (const int id : itm.nodeIds()) {
    std::set<int> unique;
    EXPECT_TRUE(itm.prototype(id).allFinite());
    EXPECT_TRUE(itm.joints(id).allFinite());
    for (const int other : itm.neighbors(id)) {
      EXPECT_NE(other, id) << "self-edge at " << id;
      EXPECT_TRUE(itm.isNode(other)) << "edge to a deleted node";
      EXPECT_TRUE(itm.hasEdge(other, id)) << "directed edge " << id << " -> " << other;
      EXPECT_TRUE(unique.insert(other).second) << "duplicate edge";
    }
    valence_sum += static_cast<int>(itm.neighbors(id).size());
  }
  const auto edges = edgesOf(itm);
  EXPECT_EQ(2 * itm.edgeCount(), valence_sum);
  EXPECT_EQ(static_cast<int>(edges.size()), itm.edgeCount());
  EXPECT_EQ(static_cast<int>(itm.nodeIds().size()), itm.nodeCount());
  return edges;
}

/// A hostile stream: a random walk with, at random, teleports across the workspace, exact
/// repeats, sub-millimetre jitter and jumps of the joint configuration.
struct HostileStream {
  explicit HostileStream(std::uint32_t seed, int task_size) : rng(seed), task(task_size) {
    x = Eigen::VectorXd::Zero(task);
    x.head<3>() = Eigen::Vector3d(0.3, 0.0, 0.5);
    if (task == 7) x.tail<4>() = Eigen::Vector4d(1, 0, 0, 0);
    q = Eigen::VectorXd::Zero(7);
  }
  std::pair<Eigen::VectorXd, Eigen::VectorXd> next() {
    const int kind = std::uniform_int_distribution<int>(0, 19)(rng);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::uniform_real_distribution<double> anywhere(-1.2, 1.2);
    if (kind == 0) {  // teleport
      x.head<3>() = Eigen::Vector3d(anywhere(rng), anywhere(rng), anywhere(rng));
    } else if (kind == 1) {  // exact repeat
    } else if (kind == 2) {  // jitter far below any e_max
      for (int i = 0; i < 3; ++i) x[i] += 1e-9 * normal(rng);
    } else {  // walk, 1 cm steps
      for (int i = 0; i < 3; ++i) x[i] += 0.01 * normal(rng);
    }
    if (task == 7) {
      Eigen::Vector4d quaternion = x.tail<4>();
      for (int i = 0; i < 4; ++i) quaternion[i] += (kind == 0 ? 1.0 : 0.05) * normal(rng);
      x.tail<4>() = quaternion.normalized();
    }
    // The posture follows the position smoothly (a redundancy resolution), within one of a
    // few families; a jump switches to another family at the same place.
    if (kind == 3) family = std::uniform_int_distribution<int>(0, 3)(rng);
    for (int i = 0; i < 7; ++i) {
      q[i] = 0.8 * (family - 1.5) * (i % 2 == 0 ? 1.0 : -1.0) + 0.5 * x[i % 3] + 1e-3 * normal(rng);
    }
    return {x, q};
  }
  std::mt19937 rng;
  int task;
  int family = 0;
  Eigen::VectorXd x, q;
};

void runStream(const ItmParameters& p, std::uint32_t seed, int samples) {
  const int task_size = p.task_space == TaskSpace::kPose ? 7 : 3;
  Itm itm(p, 7);
  HostileStream stream(seed, task_size);
  auto before = checkStructure(itm);
  for (int k = 0; k < samples; ++k) {
    const int nodes_before = itm.nodeCount();
    const auto [x, q] = stream.next();
    const InsertReport report = itm.insert(x, q);
    const auto after = checkStructure(itm);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "invariant broken after sample " << k << " (seed " << seed << ")";
      return;
    }
    std::set<Edge> added, removed;
    for (const auto& e : after) {
      if (!before.count(e)) added.insert(e);
    }
    for (const auto& e : before) {
      if (!after.count(e)) removed.insert(e);
    }
    if (p.variant == ItmVariant::kHybrid) {
      // The hybrid ITM never removes anything, and every new edge joins postures closer than
      // d_theta_max in joint space.
      ASSERT_TRUE(removed.empty()) << "sample " << k;
      ASSERT_EQ(report.edges_removed, 0);
      ASSERT_EQ(report.nodes_removed, 0);
      for (const auto& [a, b] : added) {
        ASSERT_LT(itm.jointDistance(a, b), p.d_theta_max) << "edge " << a << "-" << b << " at sample " << k;
      }
      ASSERT_EQ(static_cast<int>(added.size()), report.edges_added) << "sample " << k;
      ASSERT_EQ(itm.nodeCount() - nodes_before, (report.created >= 0 ? 1 : 0) + report.bootstrap_nodes) << "sample " << k;
      if (report.created >= 0) {
        ASSERT_TRUE(itm.isNode(report.created));
      }
    }
    before = after;
  }
  // Statistics agree with the adjacency.
  const ItmStatistics stats = itm.statistics();
  int valence_sum = 0, max_valence = 0;
  for (const int id : itm.nodeIds()) {
    const int valence = static_cast<int>(itm.neighbors(id).size());
    valence_sum += valence;
    max_valence = std::max(max_valence, valence);
  }
  EXPECT_EQ(stats.nodes, itm.nodeCount());
  EXPECT_EQ(stats.edges, itm.edgeCount());
  EXPECT_EQ(2 * stats.edges, valence_sum);
  EXPECT_EQ(stats.max_valence, max_valence);
  if (stats.nodes > 0) {
    EXPECT_DOUBLE_EQ(stats.mean_valence, static_cast<double>(valence_sum) / stats.nodes);
  }
  EXPECT_EQ(stats.real_samples, samples);
  // The streams exercise the graph: it grew nodes and edges.
  EXPECT_GT(stats.nodes, 20);
  EXPECT_GT(stats.edges, 20);
  EXPECT_LE(stats.bootstrapped_nodes, stats.nodes);
}

TEST(ItmProperty, HybridInvariantsHoldAfterEverySampleOfHostileStreams) {
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    ItmParameters p;
    p.variant = ItmVariant::kHybrid;
    p.e_max = 0.05 + 0.05 * (seed % 2);
    p.delta = static_cast<int>(seed % 4);
    p.d_theta_max = 1.0 + 0.5 * seed;
    p.d_c_max = seed % 2 == 0 ? 0.25 : 0.0;
    runStream(p, seed, 1500);
    if (HasFailure()) return;
  }
}

TEST(ItmProperty, PlainInvariantsHoldAfterEverySampleOfHostileStreams) {
  for (std::uint32_t seed = 11; seed <= 13; ++seed) {
    ItmParameters p;
    p.variant = ItmVariant::kPlain;
    p.e_max = 0.08;
    p.eta = 0.05 * (seed - 10);
    p.delta = 0;
    p.d_c_max = 0.0;
    runStream(p, seed, 1500);
    if (HasFailure()) return;
  }
}

TEST(ItmProperty, PoseGraphInvariantsHoldAfterEverySampleOfHostileStreams) {
  ItmParameters p;
  p.variant = ItmVariant::kHybrid;
  p.task_space = TaskSpace::kPose;
  p.e_max = 0.1;
  p.delta = 2;
  p.d_theta_max = 2.0;
  runStream(p, 21, 1200);
}

}  // namespace
}  // namespace flexirob::planning
