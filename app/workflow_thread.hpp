#pragma once
// The teaching workflow inside the 1 kHz real-time control thread (DESIGN §2): each period the
// thread takes the GUI's requests, runs Workflow::update() (triggers, recording, the interaction
// controller of the sub-stage, the command), steps the backend, and publishes a snapshot.
//
// GUI -> thread: WorkflowRequest through a lock-free SPSC queue (post() never blocks; false
// when full). Thread -> GUI: WorkflowSnapshot through a lock-free triple buffer (snapshot()
// returns the newest complete one). The snapshot's fixed part (state, stage, events, counters)
// is rewritten every cycle without allocation; the heavy data (areas, teach-ins, ITM, planned
// path, learned map, confidence model, transition checks) are immutable shared_ptr snapshots
// that the thread replaces only when their version changes (the ITM at most every
// itm_publish_period) — the only allocations of the loop, at those moments.
//
// The thread never waits for the GUI, the disk or learning: batch learning runs on the
// workflow's own thread. With a session recorder attached (setRecorder), each cycle pushes the
// robot state (1 kHz, a fixed-size record into a ring: no allocation) and, every 20 ms while a
// RECORDING runs, a training sample (a record that allocates its vectors) into the recorder's
// lock-free queues; its own thread writes them to disk.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "app/control_thread.hpp"
#include "app/workflow.hpp"
#include "app/workflow_session.hpp"
#include "planning/itm.hpp"
#include "planning/path_planner.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::robot {
class Simulation;
}

namespace flexirob::app {

/// One request from the GUI (or a test) to the thread. Build it with the factories.
struct WorkflowRequest {
  enum class Kind {
    kButton,        ///< button
    kTrigger,       ///< trigger (keyboard binding, Sect. 8.1)
    kRemoveArea,    ///< index = area
    kReteachArea,   ///< index = area
    kHandForce,     ///< index = body (1..dof), point = point on the body in ITS frame [m], vector = force in W [N]
    kReleaseHand,   ///< the hand lets go (force and joint torques)
    kNudgeTask,     ///< vector = Δx [m, W]
    kNudgeJoint,    ///< index = joint (0-based), amount = Δq [rad]
    kKeyboardMode,  ///< flag
    kReplayTeachIn, ///< index = teach-in
    kPlanTo,        ///< point = goal [m, W]
  };
  Kind kind = Kind::kButton;
  std::uint64_t id = 0;  ///< set by WorkflowThread::post(); echoed as the snapshot's last_request_id
  Button button = Button::kStartConfiguration;
  Trigger trigger = Trigger::kOnAffected;
  int index = -1;
  std::array<double, 3> point{}, vector{};
  double amount = 0.0;
  bool flag = false;

  static WorkflowRequest press(Button button);
  static WorkflowRequest fire(Trigger trigger);
  static WorkflowRequest removeArea(int area);
  static WorkflowRequest reteachArea(int area);
  static WorkflowRequest handForce(int body, const Eigen::Vector3d& point_B, const Eigen::Vector3d& force_W);
  static WorkflowRequest releaseHand();
  static WorkflowRequest nudgeTask(const Eigen::Vector3d& dx);
  static WorkflowRequest nudgeJoint(int joint, double dq);
  static WorkflowRequest keyboardMode(bool keyboard);
  static WorkflowRequest replayTeachIn(int teach_in);
  static WorkflowRequest planTo(const Eigen::Vector3d& goal);
};
const char* toString(WorkflowRequest::Kind kind);

/// A workflow event in the snapshot's ring (fixed size; longer texts are cut with "…"). The
/// detail holds the longest warnings the workflow gives (a transition between two long area
/// names with its first contact; a contact warning with what to do) whole.
struct EventRecord {
  std::uint64_t sequence = 0;  ///< 1, 2, 3, ... in order of occurrence
  double time = 0.0;           ///< [s] backend time
  WorkflowEvent::Kind kind = WorkflowEvent::Kind::kStage;
  int area = -1;
  std::array<char, 48> name{};
  std::array<char, 448> detail{};
};

inline constexpr int kEventRingSize = 64;     ///< events kept in the snapshot
inline constexpr int kMaxContactBodies = 16;  ///< colliding links listed in the snapshot

/// Everything the GUI draws, published every cycle.
struct WorkflowSnapshot {
  // The robot.
  std::uint64_t cycle = 0;
  double time = 0.0;  ///< backend time [s]
  int dof = 0;
  std::array<double, kMaxDof> q{}, qd{}, q_cmd{}, tau_ext{};
  std::array<double, 3> p_WT{};   ///< measured tip [m, W]
  /// Task target x_des of the controller [m, W]; NaN where the controller in force holds a
  /// posture instead (π_q and π_rec under the hand).
  std::array<double, 3> p_des{};

  // The workflow.
  Stage stage = Stage::kIdle;
  SubStage sub_stage = SubStage::kNone;
  InteractionController controller = InteractionController::kHierarchicalControl;
  double alpha = 0.0;        ///< α = C(x) of assistance blending (Eq. 6.2)
  bool keyboard_mode = false;
  bool execution_done = true;
  int reteach_area = -1;  ///< the area the next RECORDING replaces (Re-teach); -1: it adds one

  // The last request handled (refused requests changed nothing).
  std::uint64_t last_request_id = 0;  ///< 0: none yet
  WorkflowRequest::Kind last_request_kind = WorkflowRequest::Kind::kButton;
  bool last_request_accepted = false;
  std::array<char, 208> last_request_reason{};  ///< empty when accepted

  // Events: the one with sequence s is events[(s - 1) % kEventRingSize]; the GUI remembers
  // the last sequence it showed and reads the newer ones (at most kEventRingSize back).
  std::uint64_t event_sequence = 0;  ///< of the newest event (0: none)
  std::array<EventRecord, kEventRingSize> events{};

  // Counts and versions of the heavy data (a version increases whenever the data changes).
  int areas = 0, teach_ins = 0, itm_nodes = 0, itm_edges = 0;
  std::uint64_t areas_version = 0, teach_ins_version = 0, model_version = 0, itm_version = 0, path_version = 0;
  // The heavy data, immutable; null until there is some. Compare pointers or versions to see
  // a change; hold the shared_ptr as long as it is drawn.
  std::shared_ptr<const std::vector<TrainingArea>> area_data;  ///< samples, q_fixed, centres
  std::shared_ptr<const std::vector<Eigen::MatrixXd>> teach_in_data;  ///< 3 x T each [m, W]
  std::shared_ptr<const planning::Itm> itm;                     ///< nodes, edges, node postures
  std::shared_ptr<const planning::PlannedPath> path;           ///< the last planned path
  std::shared_ptr<const learning::Learner> model;              ///< the learned q_c(x)
  std::shared_ptr<const learning::ConfidenceModel> confidence; ///< C(x) of the areas (Eq. 6.1)
  std::shared_ptr<const std::vector<TransitionCheck>> checks;  ///< after learning with >= 2 areas

  // Learning.
  bool learning = false;     ///< a background fit is running
  double learning_seconds = 0.0;  ///< [s] wall time of the running (or last) fit
  bool model_ready = false;

  // Warnings (Sect. 4.3.4, 4.4).
  int joint_limit_warnings = 0;      ///< postures chosen near a joint limit so far
  int inconsistent_transitions = 0;  ///< transition checks that failed (of the current map)

  // Collisions (simulation only; zeros on a real robot).
  int contacts = 0;                                   ///< contacts after the last step
  std::uint64_t collision_events = 0;                 ///< E_coll since start
  int contact_link_count = 0;
  std::array<const char*, kMaxContactBodies> contact_links{};  ///< link names (static storage of the model)

  // Triggers and the hand.
  std::uint64_t on_affected = 0, on_converged = 0;
  bool hand_active = false;
  int hand_body = -1;
  std::array<double, 3> hand_point_W{}, hand_force_W{};  ///< [m], [N]

  // The loop.
  CycleStatistics statistics;
  std::uint64_t dropped_requests = 0;
  bool running = false;
  bool failed = false;  ///< the loop stopped on an exception
  std::array<char, 208> failure{};

  int model_samples = 0;  ///< the samples `model` was learned from (0 without one)
};

class WorkflowThread {
 public:
  struct Options {
    double period = 1e-3;         ///< [s]
    bool paced = true;            ///< sleep to absolute period starts (off: as fast as possible)
    /// The backend's step() waits for the robot's next measurement (FRI): the robot
    /// controller's clock paces the loop, which then sleeps on no clock of its own (two clocks
    /// at the same rate beat, and the loop falls behind the measurements), and the wait is not
    /// counted as computing. A cycle then misses its deadline when computing took longer than
    /// the period.
    bool backend_paces = false;
    bool realtime_priority = false;
    double itm_publish_period = 0.1;  ///< [s] of backend time between ITM snapshots
  };

  /// The workflow (and its backend) must outlive the thread and are used only by it while it
  /// runs. `simulation` (may be null) is the workflow's backend when it is the simulation:
  /// hand forces and contacts need it.
  WorkflowThread(Workflow& workflow, robot::Simulation* simulation, Options options);
  WorkflowThread(Workflow& workflow, robot::Simulation* simulation) : WorkflowThread(workflow, simulation, Options{}) {}
  ~WorkflowThread();
  WorkflowThread(const WorkflowThread&) = delete;
  WorkflowThread& operator=(const WorkflowThread&) = delete;

  void start();
  void stop();
  bool running() const { return running_.load(std::memory_order_acquire); }

  /// From one other thread: queue a request; returns its id (> 0), or 0 if the queue is full.
  std::uint64_t post(WorkflowRequest request);
  /// From one other thread (the same as post's or another single reader): the newest snapshot.
  const WorkflowSnapshot& snapshot() { return snapshots_.read(); }
  CycleStatistics statistics() const;

  /// Attaches a session recorder (null detaches; it must stay alive until detached). From the
  /// next cycle on, every cycle records the robot state, the samples of a RECORDING as they are
  /// taken and each area when it is created or removed; the areas taught before are written
  /// whole, a few samples per cycle. The caller may wait a moment for the lock; the cycle never does: a cycle that
  /// finds it taken records nothing and counts it (recorderSkips()).
  void setRecorder(SessionRecorder* recorder);
  std::uint64_t recorderSkips() const { return recorder_skips_.load(std::memory_order_relaxed); }

 private:
  void loop();
  void apply(const WorkflowRequest& request);
  void applyHand();
  void publish(const CycleStatistics& statistics);
  void refreshHeavyData();
  void recordCycle(std::size_t events_before);

  Workflow* workflow_;
  robot::Simulation* simulation_;
  Options options_;
  robot::Kinematics kinematics_;
  SpscQueue<WorkflowRequest, 256> requests_;
  TripleBuffer<WorkflowSnapshot> snapshots_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<std::uint64_t> next_request_id_{1};
  std::atomic<std::uint64_t> dropped_requests_{0};
  std::thread thread_;

  // Loop-side state.
  std::uint64_t last_request_id_ = 0;
  WorkflowRequest::Kind last_request_kind_ = WorkflowRequest::Kind::kButton;
  bool last_request_accepted_ = false;
  std::array<char, 208> last_request_reason_{};
  std::array<EventRecord, kEventRingSize> ring_{};
  std::uint64_t event_sequence_ = 0;
  std::size_t events_published_ = 0;
  int joint_limit_warnings_ = 0;
  bool hand_active_ = false;
  int hand_body_ = -1;
  Eigen::Vector3d hand_point_B_ = Eigen::Vector3d::Zero(), hand_force_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_point_W_ = Eigen::Vector3d::Zero();
  std::uint64_t on_affected_ = 0, on_converged_ = 0;
  bool failed_ = false;
  std::array<char, 208> failure_{};
  // The heavy data and the versions they were taken at.
  std::shared_ptr<const std::vector<TrainingArea>> area_data_;
  std::shared_ptr<const std::vector<Eigen::MatrixXd>> teach_in_data_;
  std::shared_ptr<const planning::Itm> itm_;
  std::shared_ptr<const planning::PlannedPath> path_;
  std::shared_ptr<const learning::Learner> model_;
  std::shared_ptr<const learning::ConfidenceModel> confidence_;
  std::shared_ptr<const std::vector<TransitionCheck>> checks_;
  std::uint64_t areas_version_ = ~0ULL, teach_ins_version_ = ~0ULL, model_version_ = ~0ULL, itm_version_ = ~0ULL,
                path_version_ = ~0ULL;
  double itm_published_time_ = -1e9;
  // Session recording: the GUI swaps the recorder under the mutex; the loop only try-locks it.
  std::mutex recorder_mutex_;
  SessionRecorder* recorder_ = nullptr;  // guarded by recorder_mutex_
  TrainingSampleStream recorder_samples_;  // guarded
  WorkflowActivityStream recorder_activity_;  // guarded
  std::atomic<std::uint64_t> recorder_skips_{0};
  // Statistics (loop writes, any thread reads).
  std::atomic<std::uint64_t> cycles_{0}, deadline_misses_{0};
  std::atomic<double> last_compute_us_{0.0}, max_compute_us_{0.0}, sum_compute_us_{0.0}, max_jitter_us_{0.0};
};

}  // namespace flexirob::app
