#include "app/workflow_session.hpp"

#include <algorithm>

#include "planning/itm_file.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {

WorkflowSessionWriter::WorkflowSessionWriter(SessionRecorder& recorder, const Workflow& workflow,
                                             robot::Simulation* simulation, WorkflowSessionOptions options)
    : recorder_(&recorder),
      workflow_(&workflow),
      simulation_(simulation),
      options_(std::move(options)),
      activity_(options_.executed_period) {
  itm_version_ = workflow.itmVersion();
}

void WorkflowSessionWriter::recordModel(double time) {
  const auto model = workflow_->model();
  if (!model) return;
  ModelRecord record;
  record.time = time;
  record.learner_kind = model->kind();
  record.samples = static_cast<int>(workflow_->trainingSet().size());
  record.train_seconds = workflow_->learningSeconds();
  const std::string text = model->modelText();
  record.bytes.assign(text.begin(), text.end());
  recorder_->recordModel(std::move(record));
  ++records_;
}

double itmSnapshotPeriod(double configured_period, std::size_t last_bytes) {
  return std::max(configured_period, static_cast<double>(last_bytes) / kItmSnapshotBytesPerSecond);
}

void WorkflowSessionWriter::recordItm(double time) {
  const planning::Itm& itm = workflow_->itm();
  ItmRecord record;
  record.time = time;
  record.nodes = itm.nodeCount();
  record.edges = itm.edgeCount();
  record.bytes = planning::itmToBytes(itm);
  itm_bytes_ = record.bytes.size();
  recorder_->recordItm(std::move(record));
  itm_version_ = workflow_->itmVersion();
  itm_time_ = time;
  ++records_;
}

void WorkflowSessionWriter::recordEvent(const WorkflowEvent& event) {
  using K = WorkflowEvent::Kind;
  switch (event.kind) {
    case K::kStage: {
      const auto slash = event.name.find('/');
      recorder_->recordStage({event.time, event.name.substr(0, slash),
                              slash == std::string::npos ? std::string() : event.name.substr(slash + 1)});
      break;
    }
    case K::kTrigger: recorder_->recordTrigger(event.time, event.name); break;
    case K::kButton: recorder_->recordButton(event.time, event.name); break;
    case K::kAreaCreated:
      // A re-taught area is recorded again under its index; the later take holds
      // (app/session_teaching.hpp).
      records_ += samples_.finishArea(*workflow_, *recorder_, event.area, event.time);
      break;
    case K::kAreaRemoved: recorder_->recordButton(event.time, "remove_area " + std::to_string(event.area)); break;
    case K::kModelLearned: recordModel(event.time); break;
    case K::kTeachIn:
    case K::kExecution:
    case K::kRefused:
    case K::kWarning:
    case K::kCheck: activity_.event(*workflow_, *recorder_, event, events_seen_); return;
  }
  ++records_;
}

void WorkflowActivityStream::event(const Workflow& workflow, SessionRecorder& recorder, const WorkflowEvent& event,
                                   std::size_t index) {
  using K = WorkflowEvent::Kind;
  switch (event.kind) {
    case K::kTeachIn: {
      if (event.area < 0 || event.area >= static_cast<int>(workflow.teachIns().size())) break;
      const Eigen::MatrixXd& points = workflow.teachIns()[static_cast<std::size_t>(event.area)];
      TrajectoryRecord record;
      record.kind = TrajectoryKind::TeachIn;
      record.name = "teach_in_" + std::to_string(event.area);
      record.positions = points;
      // Recorded every sample_period, ending at the event.
      record.times.resize(points.cols());
      for (Eigen::Index i = 0; i < points.cols(); ++i) {
        record.times[i] = event.time - static_cast<double>(points.cols() - 1 - i) * workflow.options().sample_period;
      }
      const std::int64_t id = recorder.recordTrajectory(std::move(record));
      teach_in_ids_.resize(workflow.teachIns().size(), -1);
      teach_in_ids_[static_cast<std::size_t>(event.area)] = id;
      break;
    }
    case K::kExecution:
      execution_name_ = event.name == "replay" ? "replay_teach_in_" + std::to_string(event.area) : "planned_motion";
      execution_reference_ = event.name == "replay" && event.area >= 0 &&
                                     event.area < static_cast<int>(teach_in_ids_.size())
                                 ? teach_in_ids_[static_cast<std::size_t>(event.area)]
                                 : -1;
      recorder.recordSignal({event.time, SignalKind::Button, event.name});
      break;
    case K::kRefused:
    case K::kWarning:
    case K::kCheck:
      // Kept as free text: "<kind> <name>: <detail>" under a numbered meta key.
      recorder.recordMeta("event." + std::to_string(index),
                          std::string(toString(event.kind)) + " " + event.name + ": " + event.detail);
      break;
    default: return;
  }
  ++records_;
}

void WorkflowActivityStream::afterCycle(const Workflow& workflow, SessionRecorder& recorder, robot::Simulation* simulation) {
  trackExecution(workflow, recorder);
  // A recorder attached late gets the log's earlier events (the first 1000 are kept) a few per
  // cycle, so that no cycle pushes more than the recorder's queue takes at once.
  constexpr std::size_t kCollisionsPerCycle = 32;
  recordCollisions(recorder, simulation, kCollisionsPerCycle);
}

void WorkflowActivityStream::recordCollisions(SessionRecorder& recorder, robot::Simulation* simulation, std::size_t limit) {
  if (simulation == nullptr) return;
  robot::CollisionWorld* world = simulation->collisionWorld();
  const auto& log = simulation->collisions().eventLog();
  if (collisions_seen_ > log.size()) collisions_seen_ = 0;  // the monitor started over
  const std::size_t end = log.size() - collisions_seen_ > limit ? collisions_seen_ + limit : log.size();
  for (; collisions_seen_ < end; ++collisions_seen_) {
    if (world == nullptr) continue;
    const auto& event = log[collisions_seen_];
    recorder.recordCollision({event.time, world->bodyName(event.contact.body), world->otherName(event.contact),
                              event.contact.depth, event.contact.p_W});
    ++records_;
  }
}

void WorkflowActivityStream::restart() {
  const std::uint64_t records = records_;
  *this = WorkflowActivityStream(executed_period_);
  records_ = records;
}

void WorkflowActivityStream::trackExecution(const Workflow& workflow, SessionRecorder& recorder) {
  const bool moving = workflow.stage() == Stage::kExecution && !workflow.executionDone();
  const robot::RobotState& state = workflow.state();
  if (moving) {
    if (!executing_) {
      executing_ = true;
      execution_times_.clear();
      execution_positions_.clear();
      execution_postures_.clear();
      last_execution_sample_ = -1e9;
    }
    if (state.time - last_execution_sample_ >= executed_period_ - 1e-9) {
      last_execution_sample_ = state.time;
      execution_times_.push_back(state.time);
      execution_positions_.push_back(state.p_WT());
      execution_postures_.push_back(state.q);
    }
    return;
  }
  if (!executing_) return;
  executing_ = false;
  TrajectoryRecord record;
  record.kind = TrajectoryKind::Executed;
  record.name = execution_name_.empty() ? "executed_motion" : execution_name_;
  record.reference_id = execution_reference_;
  const auto k = static_cast<Eigen::Index>(execution_times_.size());
  record.times.resize(k);
  record.positions.resize(3, k);
  record.postures.resize(workflow.robotModel().dof(), k);
  for (Eigen::Index i = 0; i < k; ++i) {
    record.times[i] = execution_times_[static_cast<std::size_t>(i)];
    record.positions.col(i) = execution_positions_[static_cast<std::size_t>(i)];
    record.postures.col(i) = execution_postures_[static_cast<std::size_t>(i)];
  }
  record.outcome = workflow.stage() == Stage::kExecution ? "reached" : "cancelled";
  recorder.recordTrajectory(std::move(record));
  ++records_;
}

std::uint64_t TrainingSampleStream::stream(const Workflow& workflow, SessionRecorder& recorder) {
  const Eigen::Index count = workflow.recordingSamples();
  if (count == 0) return 0;
  if (serial_ != workflow.recordingSerial() || area_ != workflow.recordingArea()) {
    serial_ = workflow.recordingSerial();
    area_ = workflow.recordingArea();
    written_ = 0;
  }
  // Samples are taken every sample_period, the newest at lastSampleTime().
  const double period = workflow.options().sample_period;
  const Eigen::Index first = written_;
  for (Eigen::Index l = first; l < count; ++l) {
    const double t = workflow.lastSampleTime() - static_cast<double>(count - 1 - l) * period;
    recorder.recordSample({t, area_, workflow.recordingX().col(l), workflow.recordingQ().col(l)});
  }
  written_ = count;
  return static_cast<std::uint64_t>(count - first);
}

std::uint64_t TrainingSampleStream::finishArea(const Workflow& workflow, SessionRecorder& recorder, int area, double time) {
  if (area < 0 || area >= static_cast<int>(workflow.areas().size())) return 0;
  const TrainingArea& created = workflow.areas()[static_cast<std::size_t>(area)];
  // The samples written so far belong to this area's RECORDING, the last one streamed (a
  // RECORDING started since, between two calls, has not been streamed yet).
  const bool streamed = area_ == area;
  const Eigen::Index first = streamed ? std::min(written_, created.X.cols()) : 0;
  const double period = workflow.options().sample_period;
  for (Eigen::Index l = first; l < created.X.cols(); ++l) {
    const double t = time - static_cast<double>(created.X.cols() - 1 - l) * period;
    recorder.recordSample({t, area, created.X.col(l), created.Q.col(l)});
  }
  recorder.recordArea({area, time, created.centre, created.q_fixed, created.name});
  area_ = -1;
  written_ = 0;
  return static_cast<std::uint64_t>(created.X.cols() - first) + 1;
}

void TrainingSampleStream::restart() { *this = TrainingSampleStream{}; backlog_done_ = false; backlog_version_ = ~0ULL; }

bool TrainingSampleStream::writeAreasBacklog(const Workflow& workflow, SessionRecorder& recorder, int budget) {
  if (backlog_done_) return true;
  if (workflow.areasVersion() != backlog_version_) {
    // (Re)start: stamped now, or before the first sample of a RECORDING in progress, so that a
    // re-taught area's new take stays after its old copy. Areas do not change during a RECORDING.
    backlog_version_ = workflow.areasVersion();
    backlog_area_ = 0;
    backlog_sample_ = 0;
    const Eigen::Index recording = workflow.recordingSamples();
    const double period = workflow.options().sample_period;
    backlog_time_ = recording > 0 ? workflow.lastSampleTime() - static_cast<double>(recording) * period : workflow.state().time;
  }
  const auto& areas = workflow.areas();
  while (backlog_area_ < areas.size()) {
    const TrainingArea& area = areas[backlog_area_];
    const int index = static_cast<int>(backlog_area_);
    for (; backlog_sample_ < area.X.cols() && budget > 0; ++backlog_sample_, --budget) {
      recorder.recordSample({backlog_time_, index, area.X.col(backlog_sample_), area.Q.col(backlog_sample_)});
    }
    if (backlog_sample_ < area.X.cols()) return false;
    recorder.recordArea({index, backlog_time_, area.centre, area.q_fixed, area.name});
    ++backlog_area_;
    backlog_sample_ = 0;
  }
  backlog_done_ = true;
  return true;
}

void WorkflowSessionWriter::poll() {
  const auto& events = workflow_->events();
  for (; events_seen_ < events.size(); ++events_seen_) recordEvent(events[events_seen_]);
  // After the events: an area that ended in this cycle took its remaining samples with it.
  records_ += samples_.stream(*workflow_, *recorder_);
  const double time = workflow_->state().time;
  if (workflow_->itmVersion() != itm_version_ && time - itm_time_ >= itmSnapshotPeriod(options_.itm_period, itm_bytes_) - 1e-9) {
    recordItm(time);
  }
  activity_.afterCycle(*workflow_, *recorder_, simulation_);
}

void WorkflowSessionWriter::finish() {
  poll();
  activity_.recordCollisions(*recorder_, simulation_);
  if (workflow_->itmVersion() != itm_version_ || itm_time_ < -1e8) recordItm(workflow_->state().time);
}

}  // namespace flexirob::app
