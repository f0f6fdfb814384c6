#pragma once
// Writes a teaching session as it happens: stages, buttons, triggers, areas with their samples,
// learned models, teach-ins, executed motions, ITM snapshots and collisions go to the
// SessionRecorder when they occur, not at the end, so that a crash or kill -9 loses at most the
// recorder's commit interval (100 ms) plus the ITM snapshot period. The recorder never blocks
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
  /// Where models and graphs are serialized before they are recorded (created, removed after).
  std::filesystem::path scratch_directory;
};

class WorkflowSessionWriter {
 public:
  /// recorder and workflow (and simulation, may be null: no collisions) must outlive the writer.
  WorkflowSessionWriter(SessionRecorder& recorder, const Workflow& workflow, robot::Simulation* simulation,
                        WorkflowSessionOptions options = {});
  ~WorkflowSessionWriter();
  WorkflowSessionWriter(const WorkflowSessionWriter&) = delete;
  WorkflowSessionWriter& operator=(const WorkflowSessionWriter&) = delete;

  /// Records what is new since the last call. Cheap when nothing happened.
  void poll();
  /// The last ITM snapshot (if the graph changed since) and anything still new.
  void finish();

  std::uint64_t recordsQueued() const { return records_; }

 private:
  void recordEvent(const WorkflowEvent& event);
  void recordModel(double time);
  void recordItm(double time);
  void trackExecution();
  std::vector<std::uint8_t> serialized(const std::string& name, const std::function<void(const std::filesystem::path&)>& save);

  SessionRecorder* recorder_;
  const Workflow* workflow_;
  robot::Simulation* simulation_;
  WorkflowSessionOptions options_;
  std::filesystem::path scratch_;
  std::size_t events_seen_ = 0;
  std::size_t collisions_seen_ = 0;
  std::uint64_t itm_version_ = 0;
  double itm_time_ = -1e9;
  std::uint64_t records_ = 0;
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

}  // namespace flexirob::app
