#include "app/control_thread.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>

#include "app/realtime.hpp"

namespace flexirob::app {
namespace {

using realtime::advance;
using realtime::atomicMax;
using realtime::copyInto;
using realtime::microsBetween;
using realtime::now;

}  // namespace

ControlThread::ControlThread(robot::RobotBackend& backend, robot::InteractionController& controller,
                             robot::InteractionTriggers* triggers, Options options)
    : backend_(&backend),
      controller_(&controller),
      triggers_(triggers),
      options_(options),
      jitter_histogram_(std::make_unique<std::array<std::atomic<std::uint32_t>, kHistogramBins>>()),
      compute_histogram_(std::make_unique<std::array<std::atomic<std::uint32_t>, kHistogramBins>>()) {
  const int n = backend.model().dof();
  if (n > kMaxDof) throw std::invalid_argument("control thread: at most 16 joints, got " + std::to_string(n));
  if (!(options.period > 0.0) || options.period > 1.0) throw std::invalid_argument("control thread: period must be in (0, 1] s");
  state_.resize(n);
  command_.resize(n);
  scratch_.setZero(n);
  for (auto& bin : *jitter_histogram_) bin.store(0, std::memory_order_relaxed);
  for (auto& bin : *compute_histogram_) bin.store(0, std::memory_order_relaxed);
}

ControlThread::~ControlThread() { stop(); }

void ControlThread::start(robot::InteractionMode mode) {
  if (thread_.joinable()) return;
  start_mode_ = mode;
  backend_->readState(state_);
  controller_->start(mode, state_);
  if (triggers_ != nullptr) triggers_->reset();
  stop_requested_.store(false);
  failed_.store(false);
  running_.store(true, std::memory_order_release);
  publish();
  thread_ = std::thread([this] { loop(); });
  realtime::nameThread(thread_, "fr-control");
  if (options_.realtime_priority) {
    realtime::requestRealtimePriority(thread_);
  }
}

void ControlThread::stop() {
  stop_requested_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

bool ControlThread::post(const ControlRequest& request) {
  if (requests_.push(request)) return true;
  dropped_requests_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

void ControlThread::apply(const ControlRequest& request) {
  const int n = backend_->model().dof();
  switch (request.kind) {
    case ControlRequest::Kind::kStartMode:
      controller_->start(request.mode, state_);
      break;
    case ControlRequest::Kind::kSetTaskTarget:
      if (request.count == 3) controller_->setTaskTarget(Eigen::Vector3d(request.values[0], request.values[1], request.values[2]));
      break;
    case ControlRequest::Kind::kNudgeTask:
      if (request.count == 3) controller_->nudgeTask(Eigen::Vector3d(request.values[0], request.values[1], request.values[2]));
      break;
    case ControlRequest::Kind::kNudgeJoints:
    case ControlRequest::Kind::kSetFixedPosture:
      if (request.count != n) break;
      for (int j = 0; j < n; ++j) scratch_[j] = request.values[static_cast<std::size_t>(j)];
      if (request.kind == ControlRequest::Kind::kNudgeJoints) {
        controller_->nudgeJoints(scratch_);
      } else {
        controller_->setFixedPosture(scratch_);
      }
      break;
    case ControlRequest::Kind::kSetKeyboard:
      controller_->setKeyboardMode(request.flag);
      break;
  }
}

void ControlThread::record(std::array<std::atomic<std::uint32_t>, kHistogramBins>& histogram, double us) {
  const auto bin = static_cast<std::size_t>(std::clamp(us / kBinWidthUs, 0.0, static_cast<double>(kHistogramBins - 1)));
  histogram[bin].fetch_add(1, std::memory_order_relaxed);
}

double ControlThread::percentile(const std::array<std::atomic<std::uint32_t>, kHistogramBins>& histogram, double fraction) {
  std::uint64_t total = 0;
  for (const auto& bin : histogram) total += bin.load(std::memory_order_relaxed);
  if (total == 0) return 0.0;
  const auto wanted = static_cast<std::uint64_t>(std::ceil(fraction * static_cast<double>(total)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < histogram.size(); ++i) {
    seen += histogram[i].load(std::memory_order_relaxed);
    if (seen >= wanted) return static_cast<double>(i + 1) * kBinWidthUs;  // upper edge of the bin
  }
  return static_cast<double>(kHistogramBins) * kBinWidthUs;
}

CycleStatistics ControlThread::statistics() const {
  CycleStatistics statistics;
  statistics.cycles = cycles_.load(std::memory_order_relaxed);
  statistics.deadline_misses = deadline_misses_.load(std::memory_order_relaxed);
  statistics.last_compute_us = last_compute_us_.load(std::memory_order_relaxed);
  statistics.max_compute_us = max_compute_us_.load(std::memory_order_relaxed);
  statistics.mean_compute_us =
      statistics.cycles > 0 ? sum_compute_us_.load(std::memory_order_relaxed) / static_cast<double>(statistics.cycles) : 0.0;
  statistics.max_jitter_us = max_jitter_us_.load(std::memory_order_relaxed);
  statistics.p99_jitter_us = percentile(*jitter_histogram_, 0.99);
  statistics.p99_compute_us = percentile(*compute_histogram_, 0.99);
  return statistics;
}

void ControlThread::publish() {
  ControlSnapshot& snapshot = snapshots_.back();
  const int n = static_cast<int>(state_.q.size());
  snapshot.cycle = cycles_.load(std::memory_order_relaxed);
  snapshot.time = state_.time;
  snapshot.dof = n;
  copyInto(snapshot.q, state_.q);
  copyInto(snapshot.qd, state_.qd);
  copyInto(snapshot.q_cmd, state_.q_cmd);
  copyInto(snapshot.tau_ext, state_.tau_ext);
  const Eigen::Vector3d p = state_.p_WT();
  const Eigen::Vector3d p_des = controller_->taskTarget();
  for (int i = 0; i < 3; ++i) {
    snapshot.p_WT[static_cast<std::size_t>(i)] = p[i];
    snapshot.p_des[static_cast<std::size_t>(i)] = p_des[i];
  }
  snapshot.mode = controller_->mode();
  snapshot.on_affected = on_affected_;
  snapshot.on_converged = on_converged_;
  snapshot.last_trigger_time = last_trigger_time_;
  snapshot.last_trigger = last_trigger_;
  snapshot.clamps = controller_->limiter().counters().total() + controller_->hierarchical().counters().total();
  snapshot.rejected_commands = rejected_commands_.load(std::memory_order_relaxed);
  snapshot.dropped_requests = dropped_requests_.load(std::memory_order_relaxed);
  snapshot.running = !stop_requested_.load(std::memory_order_relaxed) && !failed_.load(std::memory_order_relaxed);
  snapshot.failed = failed_.load(std::memory_order_relaxed);
  snapshots_.publish();
}

void ControlThread::loop() {
  const long period_ns = std::lround(options_.period * 1e9);
  timespec next = now();
  try {
    while (!stop_requested_.load(std::memory_order_acquire)) {
      // Absolute schedule: lateness of one cycle does not shift the next ones.
      advance(next, period_ns);
      if (options_.paced) {
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
        }
      }
      const timespec woke = now();
      const double jitter_us = options_.paced ? std::max(0.0, microsBetween(next, woke)) : 0.0;

      ControlRequest request;
      for (int i = 0; i < 16 && requests_.pop(request); ++i) apply(request);

      backend_->readState(state_);
      if (triggers_ != nullptr) {
        if (const auto event = triggers_->update(state_)) {
          (event->kind == robot::TriggerKind::kOnAffected ? on_affected_ : on_converged_)++;
          last_trigger_time_ = event->time;
          last_trigger_ = event->kind;
        }
      }
      controller_->update(state_, command_);
      if (backend_->writeCommand(command_) != robot::CommandStatus::kAccepted) {
        rejected_commands_.fetch_add(1, std::memory_order_relaxed);
      }
      backend_->step();

      const timespec done = now();
      const double compute_us = microsBetween(woke, done);
      cycles_.fetch_add(1, std::memory_order_relaxed);
      last_compute_us_.store(compute_us, std::memory_order_relaxed);
      atomicMax(max_compute_us_, compute_us);
      sum_compute_us_.store(sum_compute_us_.load(std::memory_order_relaxed) + compute_us, std::memory_order_relaxed);
      if (options_.paced) {
        atomicMax(max_jitter_us_, jitter_us);
        record(*jitter_histogram_, jitter_us);
        timespec deadline = next;
        advance(deadline, period_ns);
        if (microsBetween(deadline, done) > 0.0) deadline_misses_.fetch_add(1, std::memory_order_relaxed);
      }
      record(*compute_histogram_, compute_us);
      publish();
    }
  } catch (...) {
    // Never let an exception leave the real-time thread: stop and report it in the snapshot.
    failed_.store(true, std::memory_order_relaxed);
  }
  publish();
  running_.store(false, std::memory_order_release);
}

}  // namespace flexirob::app
