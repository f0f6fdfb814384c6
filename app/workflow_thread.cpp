#include "app/workflow_thread.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <string_view>

#include "app/realtime.hpp"
#include "robot/errors.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {
namespace {

using realtime::advance;
using realtime::atomicMax;
using realtime::copyInto;
using realtime::copyText;
using realtime::microsBetween;
using realtime::now;

void copyInto(std::array<double, 3>& destination, const Eigen::Vector3d& source) {
  for (int i = 0; i < 3; ++i) destination[static_cast<std::size_t>(i)] = source[i];
}

Eigen::Vector3d vector3(const std::array<double, 3>& values) { return {values[0], values[1], values[2]}; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Requests

WorkflowRequest WorkflowRequest::press(Button button) {
  WorkflowRequest request;
  request.kind = Kind::kButton;
  request.button = button;
  return request;
}

WorkflowRequest WorkflowRequest::fire(Trigger trigger) {
  WorkflowRequest request;
  request.kind = Kind::kTrigger;
  request.trigger = trigger;
  return request;
}

WorkflowRequest WorkflowRequest::removeArea(int area) {
  WorkflowRequest request;
  request.kind = Kind::kRemoveArea;
  request.index = area;
  return request;
}

WorkflowRequest WorkflowRequest::reteachArea(int area) {
  WorkflowRequest request;
  request.kind = Kind::kReteachArea;
  request.index = area;
  return request;
}

WorkflowRequest WorkflowRequest::handForce(int body, const Eigen::Vector3d& point_B, const Eigen::Vector3d& force_W) {
  WorkflowRequest request;
  request.kind = Kind::kHandForce;
  request.index = body;
  copyInto(request.point, point_B);
  copyInto(request.vector, force_W);
  return request;
}

WorkflowRequest WorkflowRequest::releaseHand() {
  WorkflowRequest request;
  request.kind = Kind::kReleaseHand;
  return request;
}

WorkflowRequest WorkflowRequest::nudgeTask(const Eigen::Vector3d& dx) {
  WorkflowRequest request;
  request.kind = Kind::kNudgeTask;
  copyInto(request.vector, dx);
  return request;
}

WorkflowRequest WorkflowRequest::nudgeJoint(int joint, double dq) {
  WorkflowRequest request;
  request.kind = Kind::kNudgeJoint;
  request.index = joint;
  request.amount = dq;
  return request;
}

WorkflowRequest WorkflowRequest::keyboardMode(bool keyboard) {
  WorkflowRequest request;
  request.kind = Kind::kKeyboardMode;
  request.flag = keyboard;
  return request;
}

WorkflowRequest WorkflowRequest::replayTeachIn(int teach_in) {
  WorkflowRequest request;
  request.kind = Kind::kReplayTeachIn;
  request.index = teach_in;
  return request;
}

WorkflowRequest WorkflowRequest::planTo(const Eigen::Vector3d& goal) {
  WorkflowRequest request;
  request.kind = Kind::kPlanTo;
  copyInto(request.point, goal);
  return request;
}

const char* toString(WorkflowRequest::Kind kind) {
  using K = WorkflowRequest::Kind;
  switch (kind) {
    case K::kButton: return "button";
    case K::kTrigger: return "trigger";
    case K::kRemoveArea: return "remove_area";
    case K::kReteachArea: return "reteach_area";
    case K::kHandForce: return "hand_force";
    case K::kReleaseHand: return "release_hand";
    case K::kNudgeTask: return "nudge_task";
    case K::kNudgeJoint: return "nudge_joint";
    case K::kKeyboardMode: return "keyboard_mode";
    case K::kReplayTeachIn: return "replay";
    case K::kPlanTo: return "plan";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------

WorkflowThread::WorkflowThread(Workflow& workflow, robot::Simulation* simulation, Options options)
    : workflow_(&workflow), simulation_(simulation), options_(options), kinematics_(workflow.robotModel()) {
  if (simulation != nullptr && static_cast<robot::RobotBackend*>(simulation) != &workflow.backend()) {
    throw InputError("workflow thread: the simulation must be the workflow's backend");
  }
  if (workflow.robotModel().dof() > kMaxDof) {
    throw InputError("workflow thread: at most " + std::to_string(kMaxDof) + " joints");
  }
  if (!(options.period > 0.0) || options.period > 1.0) throw InputError("workflow thread: period must be in (0, 1] s");
  if (!(options.itm_publish_period >= 0.0)) throw InputError("workflow thread: itm_publish_period must be >= 0");
  refreshHeavyData();
  publish(CycleStatistics{});
}

WorkflowThread::~WorkflowThread() { stop(); }

void WorkflowThread::start() {
  if (thread_.joinable()) return;
  stop_requested_.store(false);
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { loop(); });
  realtime::nameThread(thread_, "fr-workflow");
  if (options_.realtime_priority) {
    realtime::requestRealtimePriority(thread_);
  }
}

void WorkflowThread::stop() {
  stop_requested_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

std::uint64_t WorkflowThread::post(WorkflowRequest request) {
  request.id = next_request_id_.fetch_add(1, std::memory_order_relaxed);
  if (requests_.push(request)) return request.id;
  dropped_requests_.fetch_add(1, std::memory_order_relaxed);
  return 0;
}

CycleStatistics WorkflowThread::statistics() const {
  CycleStatistics statistics;
  statistics.cycles = cycles_.load(std::memory_order_relaxed);
  statistics.deadline_misses = deadline_misses_.load(std::memory_order_relaxed);
  statistics.last_compute_us = last_compute_us_.load(std::memory_order_relaxed);
  statistics.max_compute_us = max_compute_us_.load(std::memory_order_relaxed);
  statistics.mean_compute_us =
      statistics.cycles > 0 ? sum_compute_us_.load(std::memory_order_relaxed) / static_cast<double>(statistics.cycles) : 0.0;
  statistics.max_jitter_us = max_jitter_us_.load(std::memory_order_relaxed);
  return statistics;
}

void WorkflowThread::apply(const WorkflowRequest& request) {
  using K = WorkflowRequest::Kind;
  RequestResult result{true, ""};
  switch (request.kind) {
    case K::kButton: result = workflow_->press(request.button); break;
    case K::kTrigger: result = workflow_->fire(request.trigger); break;
    case K::kRemoveArea: result = workflow_->removeArea(request.index); break;
    case K::kReteachArea: result = workflow_->reteachArea(request.index); break;
    case K::kHandForce: {
      const Eigen::Vector3d point = vector3(request.point), force = vector3(request.vector);
      if (simulation_ == nullptr) {
        result = {false, "hand_force: only the simulation can be pushed"};
      } else if (request.index < 1 || request.index > workflow_->robotModel().dof() || !point.allFinite() ||
                 !force.allFinite()) {
        result = {false, "hand_force: expected a body in [1, " + std::to_string(workflow_->robotModel().dof()) +
                             "] and finite point and force"};
      } else {
        hand_active_ = true;
        hand_body_ = request.index;
        hand_point_B_ = point;
        hand_force_W_ = force;
      }
      break;
    }
    case K::kReleaseHand:
      hand_active_ = false;
      if (simulation_ != nullptr) simulation_->clearHandForce();
      break;
    case K::kNudgeTask: result = workflow_->nudgeTask(vector3(request.vector)); break;
    case K::kNudgeJoint: result = workflow_->nudgeJoint(request.index, request.amount); break;
    case K::kKeyboardMode: workflow_->setKeyboardMode(request.flag); break;
    case K::kReplayTeachIn: result = workflow_->replayTeachIn(request.index); break;
    case K::kPlanTo: result = workflow_->planTo(vector3(request.point)); break;
  }
  last_request_id_ = request.id;
  last_request_kind_ = request.kind;
  last_request_accepted_ = result.accepted;
  copyText(last_request_reason_, result.reason);
}

void WorkflowThread::applyHand() {
  if (!hand_active_ || simulation_ == nullptr) return;
  // The point is fixed to the body: its world position follows the measured posture.
  kinematics_.update(workflow_->state().q);
  hand_point_W_ = kinematics_.X_WB(hand_body_) * hand_point_B_;
  simulation_->setHandForce(hand_body_, hand_point_W_, hand_force_W_);
}

void WorkflowThread::refreshHeavyData() {
  const Workflow& workflow = *workflow_;
  if (workflow.areasVersion() != areas_version_) {
    areas_version_ = workflow.areasVersion();
    area_data_ = std::make_shared<const std::vector<TrainingArea>>(workflow.areas());
  }
  if (workflow.teachInsVersion() != teach_ins_version_) {
    teach_ins_version_ = workflow.teachInsVersion();
    teach_in_data_ = std::make_shared<const std::vector<Eigen::MatrixXd>>(workflow.teachIns());
  }
  if (workflow.modelVersion() != model_version_) {
    model_version_ = workflow.modelVersion();
    model_ = workflow.model();
    confidence_ = std::make_shared<const learning::ConfidenceModel>(workflow.confidence());
    checks_ = std::make_shared<const std::vector<TransitionCheck>>(workflow.transitionChecks());
  }
  if (workflow.pathVersion() != path_version_) {
    path_version_ = workflow.pathVersion();
    path_ = workflow.plannedPath();
  }
  // The ITM changes with every sample of the configuration stage: copy it at a display rate.
  if (workflow.itmVersion() != itm_version_ &&
      workflow.state().time - itm_published_time_ >= options_.itm_publish_period - 1e-9) {
    itm_version_ = workflow.itmVersion();
    itm_published_time_ = workflow.state().time;
    itm_ = std::make_shared<const planning::Itm>(workflow.itm());
  }
}

void WorkflowThread::publish(const CycleStatistics& statistics) {
  const Workflow& workflow = *workflow_;
  // New events into the ring (the workflow keeps them all; the ring the newest).
  const auto& events = workflow.events();
  for (; events_published_ < events.size(); ++events_published_) {
    const WorkflowEvent& event = events[events_published_];
    EventRecord& record = ring_[static_cast<std::size_t>(event_sequence_ % kEventRingSize)];
    ++event_sequence_;
    record.sequence = event_sequence_;
    record.time = event.time;
    record.kind = event.kind;
    record.area = event.area;
    copyText(record.name, event.name);
    copyText(record.detail, event.detail);
    if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "joint_limit") ++joint_limit_warnings_;
  }

  WorkflowSnapshot& snapshot = snapshots_.back();
  const robot::RobotState& state = workflow.state();
  snapshot.cycle = cycles_.load(std::memory_order_relaxed);
  snapshot.time = state.time;
  snapshot.dof = static_cast<int>(state.q.size());
  copyInto(snapshot.q, state.q);
  copyInto(snapshot.qd, state.qd);
  copyInto(snapshot.q_cmd, workflow.lastCommand().q_cmd);
  copyInto(snapshot.tau_ext, state.tau_ext);
  copyInto(snapshot.p_WT, state.X_WT.translation());
  if (workflow.tracksTaskTarget()) {
    copyInto(snapshot.p_des, workflow.taskTarget());
  } else {
    snapshot.p_des.fill(std::numeric_limits<double>::quiet_NaN());
  }

  snapshot.stage = workflow.stage();
  snapshot.sub_stage = workflow.subStage();
  snapshot.controller = workflow.controller();
  snapshot.alpha = workflow.alpha();
  snapshot.keyboard_mode = workflow.keyboardMode();
  snapshot.execution_done = workflow.executionDone();

  snapshot.last_request_id = last_request_id_;
  snapshot.last_request_kind = last_request_kind_;
  snapshot.last_request_accepted = last_request_accepted_;
  if (snapshot.last_request_reason != last_request_reason_) snapshot.last_request_reason = last_request_reason_;

  if (snapshot.event_sequence != event_sequence_) {
    snapshot.events = ring_;
    snapshot.event_sequence = event_sequence_;
  }

  snapshot.areas = static_cast<int>(workflow.areas().size());
  snapshot.reteach_area = workflow.recordingArea() < snapshot.areas ? workflow.recordingArea() : -1;
  snapshot.teach_ins = static_cast<int>(workflow.teachIns().size());
  snapshot.itm_nodes = workflow.itm().nodeCount();
  snapshot.itm_edges = workflow.itm().edgeCount();
  snapshot.areas_version = areas_version_;
  snapshot.teach_ins_version = teach_ins_version_;
  snapshot.model_version = model_version_;
  snapshot.itm_version = itm_version_;
  snapshot.path_version = path_version_;
  // Pointer assignments only when the data changed (no reference-count traffic otherwise).
  if (snapshot.area_data != area_data_) snapshot.area_data = area_data_;
  if (snapshot.teach_in_data != teach_in_data_) snapshot.teach_in_data = teach_in_data_;
  if (snapshot.itm != itm_) snapshot.itm = itm_;
  if (snapshot.path != path_) snapshot.path = path_;
  if (snapshot.model != model_) snapshot.model = model_;
  if (snapshot.confidence != confidence_) snapshot.confidence = confidence_;
  if (snapshot.checks != checks_) snapshot.checks = checks_;

  snapshot.learning = workflow.learning();
  snapshot.learning_seconds = workflow.learningSeconds();
  snapshot.model_ready = model_ != nullptr;
  snapshot.model_samples = static_cast<int>(workflow.modelSamples());
  snapshot.joint_limit_warnings = joint_limit_warnings_;
  int inconsistent = 0;
  if (checks_) {
    for (const auto& check : *checks_) inconsistent += check.ok ? 0 : 1;
  }
  snapshot.inconsistent_transitions = inconsistent;

  snapshot.contacts = 0;
  snapshot.contact_link_count = 0;
  if (simulation_ != nullptr) {
    const auto& contacts = simulation_->contacts();
    const auto& bodies = workflow.robotModel().bodies();
    snapshot.contacts = static_cast<int>(contacts.size());
    snapshot.collision_events = simulation_->collisions().events();
    for (const auto& contact : contacts) {
      for (const int body : {contact.body, contact.other_body}) {
        if (body < 0 || body >= static_cast<int>(bodies.size())) continue;
        const char* name = bodies[static_cast<std::size_t>(body)].name.c_str();
        const auto listed = snapshot.contact_links.begin() + snapshot.contact_link_count;
        if (std::find(snapshot.contact_links.begin(), listed, name) != listed) continue;
        if (snapshot.contact_link_count < kMaxContactBodies) snapshot.contact_links[static_cast<std::size_t>(snapshot.contact_link_count++)] = name;
      }
    }
  }

  snapshot.on_affected = on_affected_;
  snapshot.on_converged = on_converged_;
  snapshot.hand_active = hand_active_;
  snapshot.hand_body = hand_active_ ? hand_body_ : -1;
  copyInto(snapshot.hand_point_W, hand_point_W_);
  copyInto(snapshot.hand_force_W, hand_active_ ? hand_force_W_ : Eigen::Vector3d::Zero());

  snapshot.statistics = statistics;
  snapshot.dropped_requests = dropped_requests_.load(std::memory_order_relaxed);
  snapshot.running = !stop_requested_.load(std::memory_order_relaxed) && !failed_;
  snapshot.failed = failed_;
  if (snapshot.failure != failure_) snapshot.failure = failure_;
  snapshots_.publish();
}

void WorkflowThread::setRecorder(SessionRecorder* recorder) {
  const std::lock_guard lock(recorder_mutex_);
  recorder_ = recorder;
  recorder_samples_.restart();
  recorder_activity_.restart();
}

void WorkflowThread::recordCycle(std::size_t events_before) {
  // A few samples of the areas taught before the recorder per cycle: the queue stays far from
  // full and the cycle's work bounded.
  constexpr int kBacklogSamplesPerCycle = 32;
  std::unique_lock lock(recorder_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) {
    recorder_skips_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (recorder_ == nullptr) return;
  for (std::size_t i = events_before; i < workflow_->events().size(); ++i) {
    const WorkflowEvent& event = workflow_->events()[i];
    if (event.kind == WorkflowEvent::Kind::kAreaCreated) {
      recorder_samples_.finishArea(*workflow_, *recorder_, event.area, event.time);
    } else if (event.kind == WorkflowEvent::Kind::kAreaRemoved) {
      recorder_->recordButton(event.time, "remove_area " + std::to_string(event.area));  // indices above shift down
    } else {
      recorder_activity_.event(*workflow_, *recorder_, event, i);
    }
  }
  recorder_samples_.writeAreasBacklog(*workflow_, *recorder_, kBacklogSamplesPerCycle);
  recorder_samples_.stream(*workflow_, *recorder_);
  recorder_->recordState(workflow_->state());
  recorder_activity_.afterCycle(*workflow_, *recorder_, simulation_);
}

void WorkflowThread::loop() {
  const long period_ns = std::lround(options_.period * 1e9);
  timespec next = now();
  CycleStatistics statistics;
  try {
    while (!stop_requested_.load(std::memory_order_acquire)) {
      // Absolute schedule: lateness of one cycle does not shift the next ones.
      advance(next, period_ns);
      const bool sleeps = options_.paced && !options_.backend_paces;
      if (sleeps) {
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
        }
      }
      const timespec woke = now();
      const double jitter_us = sleeps ? std::max(0.0, microsBetween(next, woke)) : 0.0;

      // Triggers fired by requests (the keyboard's) count as well as those the workflow detects.
      const std::size_t events_before = workflow_->events().size();
      WorkflowRequest request;
      for (int i = 0; i < 16 && requests_.pop(request); ++i) apply(request);
      applyHand();
      workflow_->update();
      for (std::size_t i = events_before; i < workflow_->events().size(); ++i) {
        const WorkflowEvent& event = workflow_->events()[i];
        if (event.kind != WorkflowEvent::Kind::kTrigger) continue;
        (event.name == toString(Trigger::kOnAffected) ? on_affected_ : on_converged_)++;
      }
      recordCycle(events_before);
      const timespec step_start = now();
      workflow_->backend().step();
      const double waited_us = options_.backend_paces ? microsBetween(step_start, now()) : 0.0;
      refreshHeavyData();

      const timespec done = now();
      const double compute_us = microsBetween(woke, done) - waited_us;
      cycles_.fetch_add(1, std::memory_order_relaxed);
      last_compute_us_.store(compute_us, std::memory_order_relaxed);
      atomicMax(max_compute_us_, compute_us);
      sum_compute_us_.store(sum_compute_us_.load(std::memory_order_relaxed) + compute_us, std::memory_order_relaxed);
      if (sleeps) {
        atomicMax(max_jitter_us_, jitter_us);
        timespec deadline = next;
        advance(deadline, period_ns);
        if (microsBetween(deadline, done) > 0.0) deadline_misses_.fetch_add(1, std::memory_order_relaxed);
      } else if (options_.backend_paces && compute_us > options_.period * 1e6) {
        deadline_misses_.fetch_add(1, std::memory_order_relaxed);
      }
      statistics.cycles = cycles_.load(std::memory_order_relaxed);
      statistics.deadline_misses = deadline_misses_.load(std::memory_order_relaxed);
      statistics.last_compute_us = compute_us;
      statistics.max_compute_us = max_compute_us_.load(std::memory_order_relaxed);
      statistics.mean_compute_us = sum_compute_us_.load(std::memory_order_relaxed) / static_cast<double>(statistics.cycles);
      statistics.max_jitter_us = max_jitter_us_.load(std::memory_order_relaxed);
      publish(statistics);
    }
  } catch (const std::exception& e) {
    // Never let an exception leave the real-time thread: stop and report it in the snapshot.
    failed_ = true;
    copyText(failure_, e.what());
  } catch (...) {
    failed_ = true;
    copyText(failure_, "unknown exception");
  }
  // The collisions of the last step, which no cycle recorded after it (recordCycle runs
  // before the step), and any a late recorder has not got yet.
  try {
    const std::lock_guard lock(recorder_mutex_);
    if (recorder_ != nullptr) recorder_activity_.recordCollisions(*recorder_, simulation_);
  } catch (...) {
    // The recording loses these few records; the thread still ends cleanly.
  }
  publish(statistics);
  running_.store(false, std::memory_order_release);
}

}  // namespace flexirob::app
