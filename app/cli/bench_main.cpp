// flexirob-bench: the Google Benchmark suite of every module (same cases as `flexirob-cli bench`).
#include <benchmark/benchmark.h>

#include "app/cli/bench/benchmarks.hpp"

int main(int argc, char** argv) {
  flexirob::bench::registerAllBenchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
