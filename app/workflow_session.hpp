#pragma once
// Writes a teaching session as it happens: stages, buttons, triggers, training samples while
// they are recorded, areas, learned models, teach-ins, executed motions, ITM snapshots and
// collisions go to the SessionRecorder when they occur, not at the end, so that a crash or
// kill -9 loses at most the recorder's commit interval (100 ms) plus the ITM snapshot period. The recorder never blocks
// (bounded queues) and reports a full disk or a read-only location in its status while the
// session goes on in memory.
//
// poll() runs in the thread that owns the workflow, between control cycles (the headless
// tutor's per-cycle callback). Not for the real-time loop: models and graphs are serialized
// here (the GUI calls it from its own thread on the workflow it drives synchronously, or
// records from WorkflowThread snapshots).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <vector>
#include <string>

#include "app/session_recorder.hpp"
#include "app/workflow.hpp"

namespace flexirob::robot {
class Simulation;
}

namespace flexirob::app {

struct WorkflowSessionOptions {
  double itm_period = 1.0;        ///< [s] of backend time between ITM snapshots (when it changed)
  double executed_period = 0.02;  ///< [s] between recorded points of an executed motion
};

/// Bytes of ITM snapshots a session may take per second of backend time. Each snapshot holds the
/// whole graph, so at a fixed period a long configuration with a large graph grew the file with
/// the square of its length (100 areas: 3.4 GB of snapshots).
inline constexpr double kItmSnapshotBytesPerSecond = 10e3;

/// The time [s] to wait after a snapshot of `last_bytes` before the next: the configured period,
/// or longer as the graph grows, so that snapshots take at most kItmSnapshotBytesPerSecond.
double itmSnapshotPeriod(double configured_period, std::size_t last_bytes);

/// Streams the training samples of each RECORDING to a recorder as they are taken and ends each
/// take with its area record (docs/SESSIONS.md), so that a kill -9 mid-RECORDING keeps the
/// samples taken so far. Only the recorder's non-blocking pushes: WorkflowSessionWriter uses it
/// between cycles, WorkflowThread inside the control cycle.
class TrainingSampleStream {
 public:
  /// The samples of the RECORDING in progress taken since the last call; returns how many.
  std::uint64_t stream(const Workflow& workflow, SessionRecorder& recorder);
  /// At the workflow's area_created event for `area` at `time`: the samples not streamed yet
  /// (those of the RECORDING's last cycles), then the area record. Returns the records written.
  std::uint64_t finishArea(const Workflow& workflow, SessionRecorder& recorder, int area, double time);
  /// The areas the workflow holds, whole, for a recorder attached after they were taught: at most
  /// `budget` samples per call (each area's record after its last sample), stamped before the
  /// RECORDING in progress if any. Call once per cycle until it returns true. Starts over with a
  /// later stamp when the areas change meanwhile (the later copy is the take that holds).
  bool writeAreasBacklog(const Workflow& workflow, SessionRecorder& recorder, int budget);
  /// Forgets everything (a new recorder): the RECORDING in progress is streamed from its first
  /// sample and the areas taught so far are written by writeAreasBacklog.
  void restart();

 private:
  std::uint64_t serial_ = 0;  // of the RECORDING being streamed
  int area_ = -1;             // the area it will create
  Eigen::Index written_ = 0;  // its samples written so far
  // The backlog of areas taught before the recorder: next area and sample, stamp, areas version.
  bool backlog_done_ = true;
  std::size_t backlog_area_ = 0;
  Eigen::Index backlog_sample_ = 0;
  double backlog_time_ = 0.0;
  std::uint64_t backlog_version_ = 0;
};

/// Records what the workflow did besides its samples and areas: teach-ins, executed motions,
/// collisions of the simulated arm, and refusals, warnings and checks as meta lines
/// (docs/SESSIONS.md). Only the recorder's non-blocking pushes and small copies:
/// WorkflowSessionWriter uses it between cycles, WorkflowThread inside the control cycle (the
/// GUI's recordings), so both kinds of session hold the same records.
class WorkflowActivityStream {
 public:
  explicit WorkflowActivityStream(double executed_period = 0.02) : executed_period_(executed_period) {}
  /// The workflow's event number `index` (its place in Workflow::events()).
  void event(const Workflow& workflow, SessionRecorder& recorder, const WorkflowEvent& event, std::size_t index);
  /// After the cycle's events: the executed motion in progress, the simulation's new collisions
  /// (simulation may be null: none).
  void afterCycle(const Workflow& workflow, SessionRecorder& recorder, robot::Simulation* simulation);
  /// The simulation's collisions not recorded yet, at most `limit` of them (the session's end:
  /// all; the control thread's cycle: a few).
  void recordCollisions(SessionRecorder& recorder, robot::Simulation* simulation,
                        std::size_t limit = std::numeric_limits<std::size_t>::max());
  /// A new recorder: the simulation's collisions from its first again, no motion in progress, no
  /// teach-in to refer to.
  void restart();
  std::uint64_t records() const { return records_; }

 private:
  void trackExecution(const Workflow& workflow, SessionRecorder& recorder);

  double executed_period_;
  std::uint64_t records_ = 0;
  std::size_t collisions_seen_ = 0;
  // The executed motion in progress.
  bool executing_ = false;
  std::string execution_name_;
  std::int64_t execution_reference_ = -1;
  double last_execution_sample_ = -1e9;
  std::vector<double> execution_times_;
  std::vector<Eigen::Vector3d> execution_positions_;
  std::vector<Eigen::VectorXd> execution_postures_;
  std::vector<std::int64_t> teach_in_ids_;
};

class WorkflowSessionWriter {
 public:
  /// recorder and workflow (and simulation, may be null: no collisions) must outlive the writer.
  WorkflowSessionWriter(SessionRecorder& recorder, const Workflow& workflow, robot::Simulation* simulation,
                        WorkflowSessionOptions options = {});
  ~WorkflowSessionWriter() = default;
  WorkflowSessionWriter(const WorkflowSessionWriter&) = delete;
  WorkflowSessionWriter& operator=(const WorkflowSessionWriter&) = delete;

  /// Records what is new since the last call. Cheap when nothing happened.
  void poll();
  /// The last ITM snapshot (if the graph changed since) and anything still new.
  void finish();

  std::uint64_t recordsQueued() const { return records_ + activity_.records(); }

 private:
  void recordEvent(const WorkflowEvent& event);
  void recordModel(double time);
  void recordItm(double time);

  SessionRecorder* recorder_;
  const Workflow* workflow_;
  robot::Simulation* simulation_;
  WorkflowSessionOptions options_;
  std::size_t events_seen_ = 0;
  std::uint64_t itm_version_ = 0;
  double itm_time_ = -1e9;
  std::size_t itm_bytes_ = 0;  ///< size of the last snapshot
  std::uint64_t records_ = 0;
  TrainingSampleStream samples_;
  WorkflowActivityStream activity_;
};

}  // namespace flexirob::app
