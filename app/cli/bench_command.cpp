// `bench`: runs the product's benchmarks in-process and prints one entry per case with its
// median time per iteration in microseconds (and the other statistics), with the thesis'
// figure beside it where the work is the same. `bench --peers`: our reaching and planning
// against orocos-kdl and OMPL in the same run, as ratios (peer / ours for times and lengths,
// ours / peer for success rates: > 1 means we are ahead).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <regex>
#include <sstream>
#include <vector>

#include "app/cli/bench/benchmarks.hpp"
#include "app/cli/bench/peers/planning_peers.hpp"
#include "app/cli/bench/peers/reaching_peers.hpp"
#include "app/cli/cli_support.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

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
      for (const auto& [counter, value] : run.counters) counters_[run.run_name.function_name][counter] = value.value;
      if (progressShown()) std::fprintf(stderr, ".");
    }
  }
  Json results() const {
    // Figures the thesis reports for the same work (DESIGN §7), in microseconds.
    struct ThesisFigure {
      const char* prefix;
      double us;
      const char* source;
    };
    static const ThesisFigure kThesis[] = {
        {"planning/itm_insert_delta4/", 1000.0, "Sect. 7.4: < 1 ms per sample with 300+ nodes, delta = 4 (upper bound)"},
        {"control/cycle", 1000.0, "FRI cycle 1 ms (Sect. 8.1): the whole budget of one control cycle"},
        {"learning/elm_fit/", 5.3e6,
         "Sect. 4.3.3: 5.3 +- 1.0 s of learning per configuration (2012 hardware, with its model selection)"},
    };
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
                         {"iterations", iterations_.at(name)},
                         {"counters", Json::object()}});
      if (const auto found = counters_.find(name); found != counters_.end()) {
        for (const auto& [counter, value] : found->second) entries.back()["counters"][counter] = value;
      }
      for (const auto& figure : kThesis) {
        if (name.rfind(figure.prefix, 0) != 0) continue;
        entries.back()["thesis_us"] = figure.us;
        entries.back()["thesis_source"] = figure.source;
        entries.back()["ratio_thesis_over_ours"] = figure.us / at(0.5);
      }
    }
    return entries;
  }

 private:
  std::map<std::string, std::vector<double>> samples_;
  std::map<std::string, std::int64_t> iterations_;
  std::map<std::string, std::map<std::string, double>> counters_;  // of the last repetition
};

struct PeerOptions {
  bool enabled = false;
  int targets = 200;
  int goals = 20;
  int areas = 3;
  std::uint64_t seed = 1;
};

Json runPeers(const PeerOptions& options) {
  Json report;
  report["kdl_available"] = bench::peers::kdlAvailable();
  report["ompl_available"] = bench::peers::omplAvailable();

  Json reaching = Json::array();
  for (const char* robot_name : {"lwr4", "arm9"}) {
    const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot_name));
    bench::peers::ReachingOptions reaching_options;
    reaching_options.targets = options.targets;
    reaching_options.seed = options.seed;
    const auto methods = bench::peers::compareReaching(model, reaching_options);
    Json entry{{"robot", robot_name}, {"targets", options.targets}, {"seed", options.seed},
               {"success_tolerance_m", reaching_options.success_tolerance}, {"methods", Json::array()}};
    for (const auto& method : methods) {
      Json json{{"name", method.name},
                {"reached", method.reached},
                {"success_rate", method.success_rate},
                {"time_per_target_us", method.time_per_target_us},
                {"mean_iterations", method.mean_iterations},
                {"median_error_m", method.median_error_m}};
      // Ratios of each peer against both of ours (task only: the same problem as KDL's LMA;
      // hierarchical: with the posture preference).
      if (method.name.rfind("flexirob_", 0) != 0) {
        for (const auto& ours : methods) {
          if (ours.name.rfind("flexirob_", 0) != 0) continue;
          const std::string suffix = ours.name.substr(std::string("flexirob_").size());
          json["ratio_time_peer_over_ours_" + suffix] = method.time_per_target_us / ours.time_per_target_us;
          json["ratio_success_ours_" + suffix + "_over_peer"] =
              method.success_rate > 0.0 ? Json(ours.success_rate / method.success_rate) : Json(nullptr);
        }
      }
      entry["methods"].push_back(json);
    }
    reaching.push_back(entry);
  }
  report["reaching"] = reaching;

  bench::peers::PlanningOptions planning_options;
  planning_options.goals = options.goals;
  planning_options.areas = options.areas;
  planning_options.seed = options.seed;
  const auto planning = bench::peers::comparePlanning(planning_options);
  Json methods = Json::array();
  for (std::size_t m = 0; m < planning.methods.size(); ++m) {
    const auto& method = planning.methods[m];
    Json json{{"name", method.name},
              {"queries", method.queries},
              {"found", method.found},
              {"succeeded", method.succeeded},
              {"success_rate", method.success_rate},
              {"median_plan_ms", method.median_plan_ms},
              {"mean_plan_ms", method.mean_plan_ms},
              {"mean_task_length_m", method.mean_task_length_m},
              {"mean_joint_length_rad", method.mean_joint_length_rad},
              {"mean_execution_compute_ms", method.mean_execution_compute_ms}};
    if (planning.common_successes > 0) {
      json["common_task_length_m"] = planning.common_task_length_m[m];
      json["common_joint_length_rad"] = planning.common_joint_length_rad[m];
    }
    if (m > 0) {
      const auto& ours = planning.methods.front();
      json["ratio_plan_time_peer_over_ours"] = method.median_plan_ms / ours.median_plan_ms;
      json["ratio_success_ours_over_peer"] =
          method.success_rate > 0.0 ? Json(ours.success_rate / method.success_rate) : Json(nullptr);
      if (planning.common_successes > 0) {
        json["ratio_task_length_peer_over_ours"] = planning.common_task_length_m[m] / planning.common_task_length_m[0];
        json["ratio_joint_length_peer_over_ours"] = planning.common_joint_length_rad[m] / planning.common_joint_length_rad[0];
      }
    }
    methods.push_back(json);
  }
  report["planning"] = {{"robot", planning_options.robot},
                        {"scene", planning_options.scene},
                        {"areas", planning_options.areas},
                        {"seed", planning_options.seed},
                        {"itm_nodes", planning.itm_nodes},
                        {"samples", planning.samples},
                        {"teach_wall_s", planning.teach_wall_s},
                        {"common_successes", planning.common_successes},
                        {"methods", methods}};
  return report;
}

}  // namespace

void registerBenchCommand(CLI::App& app, CommandRunner& runner) {
  auto* bench = app.add_subcommand("bench", "run the product's benchmarks; median time per case");
  auto filter = std::make_shared<std::string>(".*");
  auto repetitions = std::make_shared<int>(5);
  auto min_time = std::make_shared<double>(0.1);
  bench->add_option("--filter", *filter, "regular expression over benchmark names")->capture_default_str();
  bench->add_option("--repetitions", *repetitions, "repetitions per case")->check(finiteRange(1, 1000))->capture_default_str();
  bench->add_option("--min-time", *min_time, "minimum seconds per repetition")->check(finiteRange(0.001, 60.0))->capture_default_str();
  auto peers = std::make_shared<PeerOptions>();
  bench->add_flag("--peers", peers->enabled,
                  "instead of the suite: reaching against orocos-kdl and planning against OMPL, as ratios");
  bench->add_option("--peer-targets", peers->targets, "reaching targets per robot (--peers)")->check(finiteRange(1, 100000))->capture_default_str();
  bench->add_option("--peer-goals", peers->goals, "planning queries on arm9_areas (--peers)")->check(finiteRange(1, 10000))->capture_default_str();
  bench->add_option("--peer-areas", peers->areas, "areas the tutor teaches for planning (--peers)")->check(finiteRange(1, 50))->capture_default_str();
  bench->add_option("--peer-seed", peers->seed, "seed of targets, queries and teaching (--peers)")
      ->check(seedValidator())
      ->capture_default_str();
  bench->callback([&runner, filter, repetitions, min_time, peers] {
    if (peers->enabled) {
      runner.select([peers] { return runPeers(*peers); });
      return;
    }
    runner.select([filter, repetitions, min_time] {
      // Google Benchmark reads the filter as a POSIX extended expression and, when it does not
      // compile, matches nothing: said as what it is.
      try {
        std::regex(*filter, std::regex::extended);
      } catch (const std::regex_error&) {
        throw InputError("--filter: '" + printable(*filter) + "' is not a valid regular expression");
      }
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
      // What Google Benchmark says itself ("Failed to match any benchmarks ...") is held back:
      // a filter that matches nothing is said once, in one line; anything else it says follows.
      std::ostringstream library_says;
      reporter.SetErrorStream(&library_says);
      if (progressShown()) std::fprintf(stderr, "benchmarks: ");
      const std::size_t count = benchmark::RunSpecifiedBenchmarks(&reporter);
      if (progressShown()) std::fprintf(stderr, " done\n");
      if (count == 0) throw InputError("no benchmark matches '" + printable(*filter) + "'");
      std::fputs(library_says.str().c_str(), stderr);
      return Json{{"benchmarks", reporter.results()}};
    });
  });
}

}  // namespace flexirob::cli
