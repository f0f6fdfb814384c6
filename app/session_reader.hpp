#pragma once
// Reads a session database written by SessionRecorder (schema in docs/SESSIONS.md).
//
// Opening is cheap regardless of the recording's length: it reads the file header, the meta
// table and the ends of the state index (no table scan), so a 30-minute recording opens in
// milliseconds. State ranges are read through the index on time.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/session_recorder.hpp"

namespace flexirob::app {

class SessionReader {
 public:
  /// Opens `file` read-only. Throws flexirob::InputError with a one-line reason if the file is
  /// missing, empty, not SQLite, not a FlexIRob session, of a newer schema, truncated or damaged.
  explicit SessionReader(const std::filesystem::path& file);
  ~SessionReader();
  SessionReader(SessionReader&&) noexcept;
  SessionReader& operator=(SessionReader&&) noexcept;

  const std::filesystem::path& file() const { return file_; }
  int schemaVersion() const { return schema_version_; }
  const SessionMetadata& metadata() const { return metadata_; }
  /// Every meta key/value (metadata plus free keys such as end_time_utc).
  const std::map<std::string, std::string>& meta() const { return meta_; }
  /// A meta value or `fallback`.
  std::string meta(const std::string& key, const std::string& fallback = "") const;

  /// What SQLite's quick check finds wrong with the file's pages (its first finding), empty when
  /// it finds nothing. Reads the whole file once: a reader that reads only part of it (the review
  /// window seeks states by time) would otherwise never learn of damage elsewhere. A connection
  /// of its own, so that it may run on another thread than the reader's.
  static std::string damageOf(const std::filesystem::path& file);
  std::string damage() const { return damageOf(file_); }

  // --- Robot state at control rate.
  std::int64_t stateCount() const { return state_count_; }
  /// [s] first and last state time (0, 0 without states).
  double startTime() const { return start_time_; }
  double endTime() const { return end_time_; }
  /// [s] first and last time the session records anything: its states' times, or, where it holds
  /// no state (none recorded, or the rows deleted since), those of its events (stages, signals,
  /// areas, samples, motions, contacts, models, graphs); 0, 0 if it holds neither.
  std::pair<double, double> recordedTimeSpan() const;
  /// States with t0 <= time <= t1 in time order; every `stride`-th row only (stride >= 1), for
  /// plots of long ranges.
  std::vector<StateRecord> states(double t0, double t1, int stride = 1) const;
  /// The last state at or before `time` (the first state if `time` precedes it).
  std::optional<StateRecord> stateAt(double time) const;
  /// Up to `limit` states in the order they were recorded, after the row `after_row` (0: from the
  /// first); `last_row` receives the row to continue after. For replays that must not depend on
  /// the recorded times (a damaged file may hold any, 1e300 or out of order).
  std::vector<StateRecord> statesInRecordedOrder(std::int64_t after_row, std::int64_t limit, std::int64_t& last_row) const;

  // --- Events, all in time order.
  std::vector<StageRecord> stages() const;
  std::vector<SignalRecord> signals() const;
  std::vector<CollisionRecord> collisions(double t0 = -1e300, double t1 = 1e300) const;
  std::vector<AreaRecord> areas() const;
  /// Samples of one area, or of all areas when area < 0.
  std::vector<SampleRecord> samples(int area = -1) const;
  /// Sample count per area index.
  std::map<int, std::int64_t> sampleCounts() const;
  /// Models in the order they were recorded (with their bytes).
  std::vector<ModelRecord> models() const;
  std::vector<ItmRecord> itmSnapshots() const;
  /// The newest ITM snapshot alone (a long session holds many; only its bytes are read).
  std::optional<ItmRecord> lastItmSnapshot() const;
  std::int64_t itmSnapshotCount() const;
  /// All trajectories, or those of one kind.
  std::vector<TrajectoryRecord> trajectories() const;
  std::vector<TrajectoryRecord> trajectories(TrajectoryKind kind) const;
  std::optional<TrajectoryRecord> trajectory(std::int64_t id) const;

 private:
  struct Impl;
  std::filesystem::path file_;
  std::unique_ptr<Impl> impl_;
  int schema_version_ = 0;
  SessionMetadata metadata_;
  std::map<std::string, std::string> meta_;
  std::int64_t state_count_ = 0;
  double start_time_ = 0.0;
  double end_time_ = 0.0;
};

}  // namespace flexirob::app
