#pragma once
// Shortest paths on the ITM graph: A* with the task-space metric as edge cost and as heuristic.
// D_xi is a metric (Euclidean, or Eq. 7.5: a positive combination of the Euclidean distance and
// the rotation angle, both metrics), so D_xi(node, goal) never overestimates the remaining cost
// and is consistent: A* returns a shortest path and expands each node at most once.
#include <cstdint>
#include <vector>

#include "planning/itm.hpp"

namespace flexirob::planning {

struct GraphPath {
  bool found = false;
  std::vector<int> nodes;  ///< start ... goal (node ids); empty when not found
  double cost = 0.0;       ///< sum of D_xi over the path's edges
  int expanded = 0;        ///< nodes taken from the open list
};

/// A* search with a workspace reused between queries (no allocation once warmed up).
class AStarSearch {
 public:
  /// Throws std::invalid_argument when start or goal is not a node of graph.
  GraphPath run(const Itm& graph, int start, int goal);

 private:
  struct Open {
    double f;
    int id;
    bool operator>(const Open& other) const { return f > other.f; }
  };
  std::vector<double> g_;
  std::vector<int> parent_;
  std::vector<std::uint32_t> seen_stamp_, closed_stamp_;
  std::uint32_t stamp_ = 0;
  std::vector<Open> open_;
};

/// One-off A* query.
GraphPath shortestPath(const Itm& graph, int start, int goal);

}  // namespace flexirob::planning
