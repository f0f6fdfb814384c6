#include "planning/graph_search.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>

namespace flexirob::planning {

GraphPath AStarSearch::run(const Itm& graph, int start, int goal) {
  if (!graph.isNode(start)) throw std::invalid_argument("A*: start " + std::to_string(start) + " is not a node");
  if (!graph.isNode(goal)) throw std::invalid_argument("A*: goal " + std::to_string(goal) + " is not a node");
  const auto slots = static_cast<std::size_t>(graph.slotCount());
  if (g_.size() < slots) {
    g_.resize(slots);
    parent_.resize(slots);
    seen_stamp_.resize(slots, 0);
    closed_stamp_.resize(slots, 0);
  }
  if (++stamp_ == 0) {
    std::fill(seen_stamp_.begin(), seen_stamp_.end(), 0);
    std::fill(closed_stamp_.begin(), closed_stamp_.end(), 0);
    stamp_ = 1;
  }
  const auto index = [](int id) { return static_cast<std::size_t>(id); };

  GraphPath path;
  open_.clear();
  g_[index(start)] = 0.0;
  parent_[index(start)] = -1;
  seen_stamp_[index(start)] = stamp_;
  open_.push_back({graph.distance(start, goal), start});
  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end(), std::greater<>());
    const Open current = open_.back();
    open_.pop_back();
    if (closed_stamp_[index(current.id)] == stamp_) continue;  // a stale, longer entry
    closed_stamp_[index(current.id)] = stamp_;
    ++path.expanded;
    if (current.id == goal) break;
    const double g_current = g_[index(current.id)];
    for (int next : graph.neighbors(current.id)) {
      if (closed_stamp_[index(next)] == stamp_) continue;
      const double g_next = g_current + graph.distance(current.id, next);
      if (seen_stamp_[index(next)] == stamp_ && g_next >= g_[index(next)]) continue;
      seen_stamp_[index(next)] = stamp_;
      g_[index(next)] = g_next;
      parent_[index(next)] = current.id;
      open_.push_back({g_next + graph.distance(next, goal), next});
      std::push_heap(open_.begin(), open_.end(), std::greater<>());
    }
  }
  if (closed_stamp_[index(goal)] != stamp_) return path;
  path.found = true;
  path.cost = g_[index(goal)];
  for (int id = goal; id >= 0; id = parent_[index(id)]) path.nodes.push_back(id);
  std::reverse(path.nodes.begin(), path.nodes.end());
  return path;
}

GraphPath shortestPath(const Itm& graph, int start, int goal) {
  AStarSearch search;
  return search.run(graph, start, goal);
}

}  // namespace flexirob::planning
