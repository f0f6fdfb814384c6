#pragma once
// The 1 kHz real-time control worker (DESIGN §2): reads the robot backend, runs the triggers and
// the interaction controller, writes the command and steps the backend, once per period, paced
// on absolute time (clock_nanosleep with TIMER_ABSTIME, so lateness does not accumulate).
//
// The loop shares no lock with the GUI: requests come in through a lock-free single-producer /
// single-consumer queue, the state goes out through a lock-free triple buffer, and cycle
// statistics are relaxed atomics. Inside the loop nothing allocates and nothing does I/O
// (the Bullet simulation backend allocates inside Bullet only when new contact pairs appear).
// Exceptions never leave the thread: they stop the loop and show as an error status.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "learning/learner.hpp"
#include "robot/backend.hpp"
#include "robot/controllers.hpp"
#include "robot/interaction.hpp"
#include "robot/triggers.hpp"

namespace flexirob::app {

inline constexpr int kMaxDof = 16;  ///< joints the fixed-size snapshot and requests can carry

/// Bounded lock-free queue for one producer thread and one consumer thread. T must be
/// trivially copyable. push() fails (returns false) when full; nothing blocks.
template <typename T, std::size_t Capacity>
class SpscQueue {
  static_assert((Capacity & (Capacity - 1)) == 0, "capacity must be a power of two");

 public:
  bool push(const T& value) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= Capacity) return false;
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  bool pop(T& value) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    value = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

 private:
  std::array<T, Capacity> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

/// Lock-free triple buffer: one writer publishes complete values, one reader takes the newest.
/// Each side owns a slot exclusively; they swap slots through one atomic index.
template <typename T>
class TripleBuffer {
 public:
  /// Writer: the slot to fill, then publish().
  T& back() { return slots_[back_]; }
  void publish() {
    const unsigned previous = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = previous & kIndex;
  }
  /// Reader: the newest published value (the same as last time if nothing new came).
  const T& read() {
    if (middle_.load(std::memory_order_acquire) & kFresh) {
      const unsigned previous = middle_.exchange(front_, std::memory_order_acq_rel);
      front_ = previous & kIndex;
    }
    return slots_[front_];
  }

 private:
  static constexpr unsigned kFresh = 4;
  static constexpr unsigned kIndex = 3;
  std::array<T, 3> slots_{};
  unsigned back_ = 0;
  unsigned front_ = 1;
  std::atomic<unsigned> middle_{2};
};

/// A request from the GUI (or a test) to the control loop.
struct ControlRequest {
  enum class Kind { kStartMode, kSetTaskTarget, kNudgeTask, kNudgeJoints, kSetFixedPosture, kSetKeyboard };
  Kind kind = Kind::kSetTaskTarget;
  robot::InteractionMode mode = robot::InteractionMode::kHierarchicalControl;
  int count = 0;                      ///< values used (3 for task targets, dof for postures)
  std::array<double, kMaxDof> values{};
  bool flag = false;
};

/// Cycle statistics, all in microseconds.
struct CycleStatistics {
  std::uint64_t cycles = 0;
  std::uint64_t deadline_misses = 0;  ///< cycles that ended after the next cycle's start time
  double last_compute_us = 0.0;       ///< work of the last cycle (controller + backend)
  double max_compute_us = 0.0;
  double mean_compute_us = 0.0;
  double max_jitter_us = 0.0;         ///< wake-up lateness against the absolute schedule
  double p99_jitter_us = 0.0;
  double p99_compute_us = 0.0;
};

/// What the loop publishes every cycle (trivially copyable, fixed size).
struct ControlSnapshot {
  std::uint64_t cycle = 0;
  double time = 0.0;  ///< backend time [s]
  int dof = 0;
  std::array<double, kMaxDof> q{}, qd{}, q_cmd{}, tau_ext{};
  std::array<double, 3> p_WT{}, p_des{};
  robot::InteractionMode mode = robot::InteractionMode::kHierarchicalControl;
  std::uint64_t on_affected = 0, on_converged = 0;  ///< trigger counts
  double last_trigger_time = -1.0;
  robot::TriggerKind last_trigger = robot::TriggerKind::kOnAffected;
  std::uint64_t clamps = 0;            ///< limiter + controller clamps
  std::uint64_t rejected_commands = 0; ///< commands the backend refused
  std::uint64_t dropped_requests = 0;  ///< requests the full queue refused
  bool running = false;
  bool failed = false;  ///< the loop stopped on an exception
};

/// q_c(x) from a learner of the learning library (input x ∈ R³, output q ∈ R^N).
class LearnerRedundancyMap final : public robot::RedundancyMap {
 public:
  explicit LearnerRedundancyMap(const learning::Learner& learner, int dof) : learner_(&learner), dof_(dof) {}
  int dof() const override { return dof_; }
  void predict(const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) const override { learner_->predict(p_W, q_c); }

 private:
  const learning::Learner* learner_;
  int dof_;
};

class ControlThread {
 public:
  struct Options {
    double period = 1e-3;    ///< [s]
    /// Sleep until each period's absolute start time. Off for backends that pace themselves
    /// (FRI: step() waits for the robot's packet) or to run a simulation as fast as possible.
    bool paced = true;
    bool realtime_priority = false;  ///< try SCHED_FIFO (needs privileges; failure is ignored)
  };

  /// Backend, controller and triggers must outlive the thread and are used only by it while
  /// it runs. Triggers may be null.
  ControlThread(robot::RobotBackend& backend, robot::InteractionController& controller,
                robot::InteractionTriggers* triggers, Options options);
  ~ControlThread();
  ControlThread(const ControlThread&) = delete;
  ControlThread& operator=(const ControlThread&) = delete;

  /// Starts the loop in `mode` from the backend's current state.
  void start(robot::InteractionMode mode);
  void stop();
  bool running() const { return running_.load(std::memory_order_acquire); }

  /// From one other thread (the GUI): queue a request; false if the queue is full.
  bool post(const ControlRequest& request);
  /// From one other thread (the GUI): the newest snapshot.
  const ControlSnapshot& snapshot() { return snapshots_.read(); }
  /// From any thread.
  CycleStatistics statistics() const;

 private:
  void loop();
  void apply(const ControlRequest& request);
  void publish();

  static constexpr int kHistogramBins = 20000;  // 0.5 µs bins up to 10 ms
  static constexpr double kBinWidthUs = 0.5;
  static void record(std::array<std::atomic<std::uint32_t>, kHistogramBins>& histogram, double us);
  static double percentile(const std::array<std::atomic<std::uint32_t>, kHistogramBins>& histogram, double fraction);

  robot::RobotBackend* backend_;
  robot::InteractionController* controller_;
  robot::InteractionTriggers* triggers_;
  Options options_;
  robot::InteractionMode start_mode_ = robot::InteractionMode::kHierarchicalControl;
  robot::RobotState state_;
  robot::JointImpedanceCommand command_;
  Eigen::VectorXd scratch_;
  SpscQueue<ControlRequest, 256> requests_;
  TripleBuffer<ControlSnapshot> snapshots_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> failed_{false};
  std::atomic<std::uint64_t> dropped_requests_{0};
  std::thread thread_;
  // Statistics, written by the loop only.
  std::atomic<std::uint64_t> cycles_{0}, deadline_misses_{0}, rejected_commands_{0};
  std::atomic<double> last_compute_us_{0.0}, max_compute_us_{0.0}, sum_compute_us_{0.0}, max_jitter_us_{0.0};
  std::unique_ptr<std::array<std::atomic<std::uint32_t>, kHistogramBins>> jitter_histogram_, compute_histogram_;
  std::uint64_t on_affected_ = 0, on_converged_ = 0;
  double last_trigger_time_ = -1.0;
  robot::TriggerKind last_trigger_ = robot::TriggerKind::kOnAffected;
};

}  // namespace flexirob::app
