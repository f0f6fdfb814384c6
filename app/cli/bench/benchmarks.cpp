#include "app/cli/bench/benchmarks.hpp"

namespace flexirob::bench {

void registerAllBenchmarks() {
  static bool registered = false;
  if (registered) return;
  registered = true;
  // One line per module.
  registerKinematicsBenchmarks();
  registerLearningBenchmarks();
  registerPlanningBenchmarks();
  registerRenderBenchmarks();
  registerSessionBenchmarks();
  registerControlBenchmarks();
  registerEvaluationBenchmarks();
}

}  // namespace flexirob::bench
