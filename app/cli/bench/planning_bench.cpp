// Benchmarks of the planning library: ITM insertion per sample on maps of growing size (thesis
// Sect. 7.4: < 1 ms per sample with 300+ nodes and delta = 4) and A* / full path queries.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "app/cli/bench/benchmarks.hpp"
#include "planning/graph_search.hpp"
#include "planning/itm.hpp"
#include "planning/path_planner.hpp"

namespace flexirob::bench {
namespace {

using planning::Itm;

struct Sample {
  Eigen::Vector3d x;
  Eigen::VectorXd q;
};

// A tutor-like stream: a smooth random walk bounded by a box, joints a smooth function of the
// position (one redundancy resolution everywhere, so the joint criterion never splits the map).
class Walk {
 public:
  Walk(const Eigen::Vector3d& size, double step, std::uint32_t seed) : size_(size), step_(step), rng_(seed) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    p_ = Eigen::Vector3d(unit(rng_) * size.x(), unit(rng_) * size.y(), unit(rng_) * size.z());
    heading_ = Eigen::Vector3d(turn_(rng_), turn_(rng_), turn_(rng_)).normalized();
  }
  Sample next() {
    heading_ = (heading_ + Eigen::Vector3d(turn_(rng_), turn_(rng_), turn_(rng_))).normalized();
    p_ += step_ * heading_;
    for (int i = 0; i < 3; ++i) {
      if (p_[i] < 0.0 || p_[i] > size_[i]) {
        heading_[i] = -heading_[i];
        p_[i] = std::clamp(p_[i], 0.0, size_[i]);
      }
    }
    Eigen::VectorXd q(7);
    for (int j = 0; j < 7; ++j) q[j] = 0.3 * std::sin(0.8 * p_[j % 3] + 0.5 * j);
    return {p_, q};
  }

 private:
  Eigen::Vector3d size_;
  double step_;
  std::mt19937 rng_;
  std::normal_distribution<double> turn_{0.0, 0.1};
  Eigen::Vector3d p_, heading_;
};

// A map learned with delta = 4 (other parameters at their defaults) in a box whose volume holds
// about `nodes` nodes, followed by a stream that keeps moving through the mapped region.
struct MapFixture {
  std::unique_ptr<Itm> itm;
  std::vector<Sample> stream;
  std::size_t next = 0;
  std::vector<std::pair<int, int>> queries;
};

MapFixture& mapWithNodes(int nodes) {
  static std::map<int, std::unique_ptr<MapFixture>> cache;
  auto& entry = cache[nodes];
  if (entry) return *entry;
  entry = std::make_unique<MapFixture>();
  planning::ItmParameters parameters;
  parameters.delta = 4;
  entry->itm = std::make_unique<Itm>(parameters, 7);
  // About 700 nodes per cubic metre for a saturated walk at these parameters (measured).
  const double volume = nodes / 700.0;
  const double side = std::cbrt(2.0 * volume);
  const Eigen::Vector3d size(side, side, 0.5 * side);
  Walk exploration(size, 0.03, 1);
  for (std::int64_t k = 0; k < 150 * static_cast<std::int64_t>(nodes) && entry->itm->nodeCount() < nodes; ++k) {
    const Sample sample = exploration.next();
    entry->itm->insert(sample.x, sample.q);
  }
  Walk continuation(size, 0.005, 2);
  entry->stream.reserve(100000);
  for (int k = 0; k < 100000; ++k) entry->stream.push_back(continuation.next());
  std::mt19937 rng(3);
  const auto ids = entry->itm->nodeIds();
  std::uniform_int_distribution<std::size_t> pick(0, ids.size() - 1);
  for (int k = 0; k < 256; ++k) entry->queries.emplace_back(ids[pick(rng)], ids[pick(rng)]);
  return *entry;
}

void itmInsertPerSample(benchmark::State& state, int nodes) {
  MapFixture& fixture = mapWithNodes(nodes);
  for (auto _ : state) {
    const Sample& sample = fixture.stream[fixture.next];
    fixture.next = (fixture.next + 1) % fixture.stream.size();
    benchmark::DoNotOptimize(fixture.itm->insert(sample.x, sample.q));
  }
  state.counters["nodes"] = fixture.itm->nodeCount();
  state.counters["edges"] = fixture.itm->edgeCount();
}

void astarQuery(benchmark::State& state, int nodes) {
  MapFixture& fixture = mapWithNodes(nodes);
  planning::AStarSearch search;
  std::size_t k = 0;
  std::int64_t expanded = 0;
  for (auto _ : state) {
    const auto& [start, goal] = fixture.queries[k++ % fixture.queries.size()];
    const auto path = search.run(*fixture.itm, start, goal);
    expanded += path.expanded;
    benchmark::DoNotOptimize(path.cost);
  }
  state.counters["nodes"] = fixture.itm->nodeCount();
  state.counters["expanded"] = benchmark::Counter(static_cast<double>(expanded), benchmark::Counter::kAvgIterations);
}

void planPathQuery(benchmark::State& state, int nodes) {
  MapFixture& fixture = mapWithNodes(nodes);
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& [start, goal] = fixture.queries[k++ % fixture.queries.size()];
    const Eigen::VectorXd from = fixture.itm->prototype(start) + Eigen::Vector3d(0.01, -0.01, 0.01);
    const Eigen::VectorXd to = fixture.itm->prototype(goal) + Eigen::Vector3d(-0.01, 0.01, 0.0);
    const auto path = planning::planPath(*fixture.itm, from, to);
    benchmark::DoNotOptimize(path.length);
  }
}

}  // namespace

void registerPlanningBenchmarks() {
  for (int nodes : {300, 3000, 30000}) {
    benchmark::RegisterBenchmark(("planning/itm_insert_delta4/" + std::to_string(nodes)).c_str(), itmInsertPerSample, nodes);
  }
  benchmark::RegisterBenchmark("planning/astar/10000", astarQuery, 10000);
  benchmark::RegisterBenchmark("planning/plan_path_spline/10000", planPathQuery, 10000);
}

}  // namespace flexirob::bench
