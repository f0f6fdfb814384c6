// Learning benchmarks at the sizes of Tab. 3.4 (2 areas x 250 samples, 25 areas x 210) and the
// online paths: ELM fit and predict, OS-ELM update, LLM training to its stopping rule and the
// confidence overlay on a grid. Targets: ELM fit on 500 samples <= 20 ms, predict <= 5 µs,
// OS-ELM update <= 50 µs.
#include <benchmark/benchmark.h>

#include <cmath>

#include "app/cli/bench/benchmarks.hpp"
#include "learning/confidence.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"

namespace flexirob::bench {
namespace {

// `areas` x `per_area` samples of a smooth 7-joint map, each area a small helix (r = 5 cm)
// around a centre spread over the evaluation grid G of Sect. 3.3.2.
learning::TrainingSet demonstrations(int areas, int per_area) {
  learning::TrainingSet data;
  data.X.resize(3, areas * per_area);
  data.Y.resize(7, areas * per_area);
  for (int k = 0; k < areas; ++k) {
    const double phase = 2.399963 * k;  // golden angle: areas spread without a pattern
    const Eigen::Vector3d centre(-0.45 + 0.35 * std::cos(phase), 0.45 * std::sin(phase), 0.15 + 0.6 * (k + 0.5) / areas);
    for (int l = 0; l < per_area; ++l) {
      const double t = static_cast<double>(l) / per_area;
      const Eigen::Vector3d x = centre + 0.05 * Eigen::Vector3d(std::cos(6 * M_PI * t), std::sin(6 * M_PI * t), 2 * t - 1);
      const int column = k * per_area + l;
      data.X.col(column) = x;
      for (int j = 0; j < 7; ++j) data.Y(j, column) = 0.5 * std::sin(1.5 * x[0] + 0.7 * j) + 0.4 * std::cos(2 * x[1]) + 0.6 * x[2];
      data.area.push_back(k);
    }
  }
  return data;
}

void elmFit(benchmark::State& state, int areas, int per_area) {
  const learning::TrainingSet data = demonstrations(areas, per_area);
  for (auto _ : state) {
    learning::Elm elm(3, 7);
    elm.fit(data);
    benchmark::DoNotOptimize(elm.outputWeights().data());
  }
  state.counters["samples"] = static_cast<double>(data.size());
}

void elmPredict(benchmark::State& state) {
  learning::Elm elm(3, 7);
  elm.fit(demonstrations(2, 250));
  Eigen::Vector3d x(-0.5, 0.1, 0.4);
  Eigen::VectorXd q(7);
  for (auto _ : state) {
    x[1] += 1e-7;
    elm.predict(x, q);
    benchmark::DoNotOptimize(q.data());
  }
}

void osElmUpdate(benchmark::State& state) {
  const learning::TrainingSet data = demonstrations(2, 250);
  learning::OsElm online(3, 7, learning::InputNormalization::fromData(data.X));
  Eigen::Index l = 0;
  for (auto _ : state) {
    online.update(data.X.col(l), data.Y.col(l));
    l = (l + 1) % data.size();
  }
  benchmark::DoNotOptimize(online.outputWeights().data());
}

void llmFit(benchmark::State& state, int areas, int per_area) {
  const learning::TrainingSet data = demonstrations(areas, per_area);
  int epochs = 0;
  for (auto _ : state) {
    learning::Llm llm(3, 7);
    llm.fit(data);
    epochs = llm.epochs();
  }
  state.counters["epochs"] = epochs;
}

void llmPredict(benchmark::State& state) {
  learning::Llm llm(3, 7);
  llm.fit(demonstrations(25, 4));
  Eigen::Vector3d x(-0.5, 0.1, 0.4);
  Eigen::VectorXd q(7);
  for (auto _ : state) {
    x[1] += 1e-7;
    llm.predict(x, q);
    benchmark::DoNotOptimize(q.data());
  }
}

void confidenceGrid(benchmark::State& state) {
  const learning::ConfidenceModel model = learning::ConfidenceModel::fromTrainingSet(demonstrations(6, 200));
  const Eigen::Vector3d lower(-0.9, -0.55, 0.05), upper(0.0, 0.55, 0.8);  // grid G
  for (auto _ : state) {
    const Eigen::VectorXd c = model.evaluateGrid(lower, upper, {40, 40, 40});
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["points"] = 40 * 40 * 40;
}

}  // namespace

void registerLearningBenchmarks() {
  benchmark::RegisterBenchmark("learning/elm_fit/2x250", elmFit, 2, 250)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("learning/elm_fit/25x210", elmFit, 25, 210)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("learning/elm_predict", elmPredict);
  benchmark::RegisterBenchmark("learning/oselm_update", osElmUpdate);
  benchmark::RegisterBenchmark("learning/llm_fit/2x250", llmFit, 2, 250)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("learning/llm_fit/25x4", llmFit, 25, 4)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("learning/llm_predict/25_areas", llmPredict);
  benchmark::RegisterBenchmark("learning/confidence_grid/6_areas_40x40x40", confidenceGrid)->Unit(benchmark::kMillisecond);
}

}  // namespace flexirob::bench
