// Benchmarks of session recordings: opening a 30-minute recording (1.8 M states at 1 kHz,
// DESIGN §5: review must open it within 2 s), scrubbing its timeline, reading a second of
// states for the plots, and the control thread's cost of handing one state to the recorder.
//
// The 30-minute recording is generated once (about 450 MB, a minute or so) in the temporary
// directory as flexirob_bench_session_30min.flexirob and reused while it opens and is complete.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <thread>

#include "app/cli/bench/benchmarks.hpp"
#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"

namespace flexirob::bench {
namespace {

namespace fs = std::filesystem;

constexpr int kRate = 1000;                 // [Hz] control rate
constexpr int kStates = 30 * 60 * kRate;    // 30 minutes

app::StateRecord syntheticState(int i) {
  app::StateRecord s;
  s.time = static_cast<double>(i) / kRate;
  s.dof = 7;
  for (std::size_t j = 0; j < 7; ++j) {
    s.q[j] = 0.5 * std::sin(0.1 * s.time + static_cast<double>(j));
    s.q_cmd[j] = s.q[j] + 1e-3;
    s.tau_ext[j] = 0.1 * std::cos(s.time);
  }
  s.p_WT = {-0.5 + 0.1 * std::sin(s.time), 0.2 * std::cos(s.time), 0.4};
  return s;
}

fs::path longRecording() {
  static const fs::path file = [] {
    const fs::path path = fs::temp_directory_path() / "flexirob_bench_session_30min.flexirob";
    try {
      const app::SessionReader existing(path);
      if (existing.stateCount() == kStates) return path;
    } catch (const std::exception&) {
      // Missing or incomplete: write it again.
    }
    app::SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.scene_name = "harting";
    metadata.software_version = "bench";
    app::RecorderOptions options;
    options.overwrite = true;
    options.state_capacity = 1 << 16;
    app::SessionRecorder recorder(path, metadata, options);
    for (int i = 0; i < kStates; ++i) {
      const auto state = syntheticState(i);
      while (!recorder.recordState(state)) std::this_thread::sleep_for(std::chrono::microseconds(200));
      if (i % (60 * kRate) == 0) recorder.recordStage({state.time, "PROGRAMMING", (i / (60 * kRate)) % 2 ? "TEACH-IN" : "APPROACHING"});
    }
    recorder.close();
    return path;
  }();
  return file;
}

// Opening checks the header, the schema, the meta table and the ends of the time index.
void BM_SessionOpen30Minutes(benchmark::State& state) {
  const fs::path file = longRecording();
  for (auto _ : state) {
    app::SessionReader reader(file);
    benchmark::DoNotOptimize(reader.endTime());
  }
  state.counters["states"] = static_cast<double>(kStates);
}

// Scrubbing the timeline: the state at a random time, through the index on t.
void BM_SessionStateAtRandomTime(benchmark::State& state) {
  const app::SessionReader reader(longRecording());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> time(reader.startTime(), reader.endTime());
  for (auto _ : state) benchmark::DoNotOptimize(reader.stateAt(time(rng)));
}

// One second of states (1000 rows) for the plots.
void BM_SessionReadOneSecond(benchmark::State& state) {
  const app::SessionReader reader(longRecording());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> time(reader.startTime(), reader.endTime() - 1.0);
  for (auto _ : state) {
    const double t0 = time(rng);
    benchmark::DoNotOptimize(reader.states(t0, t0 + 1.0));
  }
}

// The control thread's side: one try-push into the state ring while the recorder drains it.
void BM_RecordStatePush(benchmark::State& state) {
  const fs::path file = fs::temp_directory_path() / "flexirob_bench_session_push.flexirob";
  app::RecorderOptions options;
  options.overwrite = true;
  auto recorder = std::make_unique<app::SessionRecorder>(file, app::SessionMetadata{}, options);
  const auto record = syntheticState(1);
  for (auto _ : state) benchmark::DoNotOptimize(recorder->recordState(record));
  recorder.reset();
  std::error_code ignored;
  fs::remove(file, ignored);
}

}  // namespace

void registerSessionBenchmarks() {
  benchmark::RegisterBenchmark("session/open_30min", BM_SessionOpen30Minutes)->Unit(benchmark::kMillisecond)->Iterations(5);
  benchmark::RegisterBenchmark("session/state_at_random_time", BM_SessionStateAtRandomTime)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("session/read_one_second", BM_SessionReadOneSecond)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("session/record_state_push", BM_RecordStatePush)->Unit(benchmark::kNanosecond);
}

}  // namespace flexirob::bench
