// The reachable-workspace analysis of setup I (Sect. 3.3.2, Tab. 3.3) as app::evaluateReachable
// runs it: every target of the evaluation grid approached from the home posture with the
// hierarchical controller, the command limiter and a learned q_c(x), contacts checked every
// 10 ms. The grid is coarsened to 0.2 m so that one pass stays around a second; the counter
// us_per_target scales it to the scene's 5 cm grid (about 8x the targets).
#include <benchmark/benchmark.h>

#include <chrono>
#include <random>

#include "app/cli/bench/benchmarks.hpp"
#include "app/evaluation.hpp"
#include "learning/elm.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"

namespace flexirob::bench {
namespace {

void reachableWorkspaceSetupI(benchmark::State& state, double spacing) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const robot::Scene scene = robot::loadScene("setup_I");
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  parameters.applyOverrides(scene.parameters, robot::sceneOrigin(scene));
  const int n = model.dof();
  const Eigen::VectorXd home = scene.home_posture.value_or(model.midPosture());
  // q_c(x): an ELM on 500 postures around the home posture, as a taught session would give.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> offset(-0.4, 0.4);
  learning::TrainingSet data;
  data.X.resize(3, 500);
  data.Y.resize(n, 500);
  for (int l = 0; l < 500; ++l) {
    Eigen::VectorXd q = home;
    for (int j = 0; j < n; ++j) q[j] += offset(rng);
    q = q.cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
    data.X.col(l) = robot::tipPose(model, q).translation();
    data.Y.col(l) = q;
  }
  learning::Elm elm(3, n);
  elm.fit(data);
  robot::EvaluationGrid grid = scene.grid.value_or(robot::EvaluationGrid{});
  grid.spacing = spacing;
  app::ReachableResult result;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    result = app::evaluateReachable(model, scene, parameters, elm, home, grid, data);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(result.reached);
  }
  state.counters["targets"] = result.targets;
  state.counters["reached"] = result.reached;
  state.counters["us_per_target"] = 1e6 * seconds / (static_cast<double>(result.targets) * static_cast<double>(state.iterations()));
}

}  // namespace

void registerEvaluationBenchmarks() {
  benchmark::RegisterBenchmark("evaluation/reachable_setup_I/spacing_0.2m", reachableWorkspaceSetupI, 0.2)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
}

}  // namespace flexirob::bench
