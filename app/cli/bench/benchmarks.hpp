#pragma once
// Google Benchmark cases of every module, registered explicitly (static registration would be
// dropped from a static library). Shared by the `flexirob-bench` executable and by
// `flexirob-cli bench`, which reports each case's median in microseconds.
namespace flexirob::bench {

void registerKinematicsBenchmarks();
void registerLearningBenchmarks();
void registerPlanningBenchmarks();
void registerRenderBenchmarks();
void registerSessionBenchmarks();
void registerControlBenchmarks();
void registerEvaluationBenchmarks();
// Each module adds its register function here and calls it from registerAllBenchmarks().

/// Registers every benchmark of the product once.
void registerAllBenchmarks();

}  // namespace flexirob::bench
