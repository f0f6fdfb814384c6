// A* against a brute-force Dijkstra on random graphs.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <random>

#include "planning/graph_search.hpp"

namespace flexirob::planning {
namespace {

// O(V^2) Dijkstra without a heap: the textbook algorithm, written independently of A*.
std::vector<double> dijkstraCosts(const Itm& graph, int start) {
  const int slots = graph.slotCount();
  std::vector<double> cost(static_cast<std::size_t>(slots), std::numeric_limits<double>::infinity());
  std::vector<bool> done(static_cast<std::size_t>(slots), false);
  cost[static_cast<std::size_t>(start)] = 0.0;
  for (;;) {
    int best = -1;
    for (int id = 0; id < slots; ++id) {
      if (graph.isNode(id) && !done[static_cast<std::size_t>(id)] &&
          (best < 0 || cost[static_cast<std::size_t>(id)] < cost[static_cast<std::size_t>(best)])) {
        best = id;
      }
    }
    if (best < 0 || std::isinf(cost[static_cast<std::size_t>(best)])) break;
    done[static_cast<std::size_t>(best)] = true;
    for (int c : graph.neighbors(best)) {
      cost[static_cast<std::size_t>(c)] =
          std::min(cost[static_cast<std::size_t>(c)], cost[static_cast<std::size_t>(best)] + graph.distance(best, c));
    }
  }
  return cost;
}

Itm randomGraph(std::mt19937& rng, TaskSpace space, int nodes, double connect_radius) {
  ItmParameters p;
  p.task_space = space;
  Itm graph(p, 3);
  std::uniform_real_distribution<double> coordinate(0.0, 1.0);
  std::normal_distribution<double> gaussian;
  for (int i = 0; i < nodes; ++i) {
    Eigen::VectorXd omega(storedSize(space));
    omega.head<3>() = Eigen::Vector3d(coordinate(rng), coordinate(rng), coordinate(rng));
    if (space == TaskSpace::kPose) {
      omega.tail<4>() = Eigen::Vector4d(gaussian(rng), gaussian(rng), gaussian(rng), gaussian(rng)).normalized();
    }
    graph.addNode(omega, Eigen::Vector3d::Zero());
  }
  std::bernoulli_distribution keep(0.6);
  for (int a = 0; a < nodes; ++a) {
    for (int b = a + 1; b < nodes; ++b) {
      if (graph.distance(a, b) < connect_radius && keep(rng)) graph.addEdge(a, b);
    }
  }
  return graph;
}

TEST(GraphSearch, AStarFindsTheSameShortestPathsAsDijkstra) {
  std::mt19937 rng(42);
  int found = 0, unreachable = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const TaskSpace space = trial % 2 == 0 ? TaskSpace::kPosition : TaskSpace::kPose;
    const Itm graph = randomGraph(rng, space, 60 + trial * 3, 0.28);
    AStarSearch search;
    std::uniform_int_distribution<int> pick(0, graph.slotCount() - 1);
    for (int query = 0; query < 10; ++query) {
      const int start = pick(rng), goal = pick(rng);
      const auto reference = dijkstraCosts(graph, start);
      const GraphPath path = search.run(graph, start, goal);
      const double expected = reference[static_cast<std::size_t>(goal)];
      ASSERT_EQ(path.found, std::isfinite(expected)) << "trial " << trial;
      if (!path.found) {
        EXPECT_TRUE(path.nodes.empty());
        ++unreachable;
        continue;
      }
      ++found;
      EXPECT_NEAR(path.cost, expected, 1e-12);
      ASSERT_FALSE(path.nodes.empty());
      EXPECT_EQ(path.nodes.front(), start);
      EXPECT_EQ(path.nodes.back(), goal);
      double sum = 0.0;
      for (std::size_t k = 1; k < path.nodes.size(); ++k) {
        ASSERT_TRUE(graph.hasEdge(path.nodes[k - 1], path.nodes[k]));
        sum += graph.distance(path.nodes[k - 1], path.nodes[k]);
      }
      EXPECT_NEAR(sum, path.cost, 1e-12);
    }
  }
  EXPECT_GT(found, 100);
  EXPECT_GT(unreachable, 5) << "the random graphs should include disconnected pairs";
}

TEST(GraphSearch, StartEqualsGoalGivesASingleNode) {
  std::mt19937 rng(1);
  const Itm graph = randomGraph(rng, TaskSpace::kPosition, 20, 0.5);
  const auto path = shortestPath(graph, 3, 3);
  EXPECT_TRUE(path.found);
  EXPECT_EQ(path.nodes, std::vector<int>{3});
  EXPECT_EQ(path.cost, 0.0);
  EXPECT_THROW(shortestPath(graph, 3, 99), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::planning
