// `bench`: runs the product's benchmarks in-process and prints one entry per case with its
// median time per iteration in microseconds (and the other statistics).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <vector>

#include "app/cli/bench/benchmarks.hpp"
#include "app/cli/cli_support.hpp"
#include "robot/errors.hpp"

namespace flexirob::cli {
namespace {

// Collects per-repetition times (the aggregates are computed here so that every statistic
// comes from the same samples).
class CollectingReporter : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& run : runs) {
      if (run.run_type != Run::RT_Iteration || run.error_occurred) continue;
      const double seconds_per_iteration = run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit);
      samples_[run.run_name.function_name].push_back(seconds_per_iteration * 1e6);  // microseconds
      iterations_[run.run_name.function_name] += run.iterations;
      std::fprintf(stderr, ".");
    }
  }
  Json results() const {
    Json entries = Json::array();
    for (const auto& [name, values] : samples_) {
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      const auto at = [&](double p) {
        const double index = p * static_cast<double>(sorted.size() - 1);
        const auto low = static_cast<std::size_t>(index);
        const auto high = std::min(low + 1, sorted.size() - 1);
        return sorted[low] + (index - static_cast<double>(low)) * (sorted[high] - sorted[low]);
      };
      double mean = 0.0;
      for (double v : sorted) mean += v;
      mean /= static_cast<double>(sorted.size());
      entries.push_back({{"name", name},
                         {"median_us", at(0.5)},
                         {"mean_us", mean},
                         {"min_us", sorted.front()},
                         {"max_us", sorted.back()},
                         {"repetitions", sorted.size()},
                         {"iterations", iterations_.at(name)}});
    }
    return entries;
  }

 private:
  std::map<std::string, std::vector<double>> samples_;
  std::map<std::string, std::int64_t> iterations_;
};

}  // namespace

void registerBenchCommand(CLI::App& app, CommandRunner& runner) {
  auto* bench = app.add_subcommand("bench", "run the product's benchmarks; median time per case");
  auto filter = std::make_shared<std::string>(".*");
  auto repetitions = std::make_shared<int>(5);
  auto min_time = std::make_shared<double>(0.1);
  bench->add_option("--filter", *filter, "regular expression over benchmark names")->capture_default_str();
  bench->add_option("--repetitions", *repetitions, "repetitions per case")->check(CLI::Range(1, 1000))->capture_default_str();
  bench->add_option("--min-time", *min_time, "minimum seconds per repetition")->check(CLI::Range(0.001, 60.0))->capture_default_str();
  bench->callback([&runner, filter, repetitions, min_time] {
    runner.select([filter, repetitions, min_time] {
      bench::registerAllBenchmarks();
      // Google Benchmark reads its settings from argv-style flags.
      std::vector<std::string> args{"flexirob-cli", "--benchmark_filter=" + *filter,
                                    "--benchmark_repetitions=" + std::to_string(*repetitions),
                                    "--benchmark_min_time=" + std::to_string(*min_time)};
      std::vector<char*> argv;
      for (auto& arg : args) argv.push_back(arg.data());
      int argc = static_cast<int>(argv.size());
      benchmark::Initialize(&argc, argv.data());
      CollectingReporter reporter;
      std::fprintf(stderr, "benchmarks: ");
      const std::size_t count = benchmark::RunSpecifiedBenchmarks(&reporter);
      std::fprintf(stderr, " done\n");
      if (count == 0) throw InputError("no benchmark matches '" + *filter + "'");
      return Json{{"benchmarks", reporter.results()}};
    });
  });
}

}  // namespace flexirob::cli
