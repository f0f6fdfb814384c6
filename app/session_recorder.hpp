#pragma once
// Session recordings: every teaching session is written into one SQLite database (WAL mode,
// synchronous=NORMAL) by a recorder thread. The control thread hands robot states over through
// a bounded lock-free ring of fixed-size records and never blocks; the rarer events (stages,
// triggers, buttons, samples, models, graphs, trajectories, collisions) go through a bounded
// lock-free multi-producer queue. Both pushes are try-pushes: a full queue drops the record
// and counts it. The recorder commits a transaction at least every `commit_interval`, so a
// crash or `kill -9` loses at most the last second. The schema is in docs/SESSIONS.md.
//
// A database that cannot be created (read-only location) or that fails while recording
// (disk full) is reported in status(); the recording then goes on in memory (everything
// written so far is copied into an in-memory database, the file is left as it was after its
// last good commit) and saveCopy() can write it elsewhere later.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace flexirob::robot {
struct RobotState;
}

namespace flexirob::app {

/// Largest joint count a state record holds (LWR IV 7, arm9 9, any URDF up to 16).
inline constexpr int kMaxRecordedJoints = 16;

/// One robot state at control rate: a fixed-size, trivially copyable record so that the
/// control thread copies it into the ring without allocating.
struct StateRecord {
  double time = 0.0;                                 ///< [s] session time
  std::int32_t dof = 0;                              ///< joints used (<= kMaxRecordedJoints)
  std::array<double, kMaxRecordedJoints> q{};        ///< measured joint positions [rad]
  std::array<double, kMaxRecordedJoints> q_cmd{};    ///< commanded joint positions [rad]
  std::array<double, kMaxRecordedJoints> tau_ext{};  ///< external joint torques [Nm]
  std::array<double, 3> p_WT{};                      ///< tip position in the world [m]
  std::array<double, 4> quat_WT{1.0, 0.0, 0.0, 0.0}; ///< tip orientation in the world (w,x,y,z)

  /// Copies a backend state (time, q, q_cmd, tau_ext, X_WT). Joints beyond
  /// kMaxRecordedJoints are cut off (dof is clamped). Does not allocate.
  static StateRecord fromRobotState(const robot::RobotState& state) noexcept;
  Eigen::VectorXd qVector() const;
  Eigen::VectorXd qCmdVector() const;
  Eigen::VectorXd tauExtVector() const;
  Eigen::Vector3d position() const { return {p_WT[0], p_WT[1], p_WT[2]}; }
};

/// Stage (CONFIGURATION, PROGRAMMING, EXECUTION, ...) and sub-stage (APPROACHING,
/// RECORDING, TEACH-IN, ...) entered at `time`. Names are free text chosen by the workflow.
struct StageRecord {
  double time = 0.0;  ///< [s]
  std::string stage;
  std::string sub_stage;
};

/// A trigger that fired (`on_affected`, `on_converged`, ...) or a button pressed
/// (`start_configuration`, `finished_configuration`, `start_programming`,
/// `finished_programming`, ...).
// The scoped enumerators share their names with the types app::Trigger and app::Button of
// the workflow; always written SignalKind::Trigger, they cannot be confused with them.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
enum class SignalKind { Trigger = 0, Button = 1 };
#pragma GCC diagnostic pop
struct SignalRecord {
  double time = 0.0;  ///< [s]
  SignalKind kind = SignalKind::Trigger;
  std::string name;
};

/// A training area as the tutor chose it: where it started and the posture shown there.
struct AreaRecord {
  int area = 0;             ///< area index (0-based, as in the training samples)
  double time = 0.0;        ///< [s] when the area's RECORDING ended (the area was created)
  Eigen::VectorXd x_init;   ///< task-space position (M = 3) or pose the area is centred at
  Eigen::VectorXd q_fixed;  ///< the posture the tutor chose there [rad] (N)
  std::string name;         ///< as the tutor or the scene named it (empty: unnamed, and in version 1 files)
};

/// One training sample (x, q) of an area (Sect. 3.2.1).
struct SampleRecord {
  double time = 0.0;  ///< [s]
  int area = 0;
  Eigen::VectorXd x;  ///< task-space input (M)
  Eigen::VectorXd q;  ///< joint posture [rad] (N)
};

/// A learned model: the learner's own model-file bytes (learning::Learner::modelText).
struct ModelRecord {
  double time = 0.0;          ///< [s] when the model was swapped in
  std::string learner_kind;   ///< "elm", "oselm", "llm", "bpdc"
  int samples = 0;            ///< samples it was trained on
  double train_seconds = 0.0; ///< [s] training wall time
  std::vector<std::uint8_t> bytes;
};

/// An ITM graph snapshot: the bytes of a graph file (planning::itmToBytes).
struct ItmRecord {
  double time = 0.0;  ///< [s]
  int nodes = 0;
  int edges = 0;
  std::vector<std::uint8_t> bytes;
};

/// Teach-in trajectories, target (evaluation) trajectories and executed motions.
enum class TrajectoryKind { TeachIn = 0, Target = 1, Executed = 2 };

/// A trajectory: K points with their times, tip positions and postures.
struct TrajectoryRecord {
  std::int64_t id = -1;  ///< unique within the session; < 0: assigned by the recorder
  TrajectoryKind kind = TrajectoryKind::TeachIn;
  std::string name;
  /// For an executed motion: the id of the trajectory it follows (teach-in or target), or -1.
  std::int64_t reference_id = -1;
  Eigen::VectorXd times;      ///< [s] session time of each point (K)
  Eigen::MatrixXd positions;  ///< tip positions p_WT [m] (3 x K)
  Eigen::MatrixXd postures;   ///< joint postures [rad] (N x K; may have 0 rows)
  /// Outcome of an executed motion, free text ("reached", "collision", "cancelled"); may be empty.
  std::string outcome;
};

/// A collision the simulator (or the collision world) reported.
struct CollisionRecord {
  double time = 0.0;  ///< [s]
  std::string body_a;
  std::string body_b;
  double depth = 0.0;                          ///< [m] penetration depth (>= 0)
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< contact point in the world [m]
};

/// What the session was recorded with. Written once when the recorder opens the database.
struct SessionMetadata {
  std::string robot_name;        ///< "lwr4", "arm9" or the URDF's robot name
  std::string robot_urdf;        ///< the URDF text used
  std::string tip_link;
  std::string scene_name;        ///< "harting", "setup_I", a file name, or "empty"
  std::string scene_text;        ///< the scene file text (robot::writeScene)
  std::string mesh_digests;      ///< the robot's and the scene's meshes (app::meshDigestsText); may be empty
  std::string parameters;        ///< parameters in use, as text (JSON object recommended)
  std::string software_version;  ///< e.g. "0.1.0"
  std::string participant;       ///< free text (study participant id), may be empty
  std::string start_time_utc;    ///< ISO 8601; filled with the current time when empty
};

struct RecorderOptions {
  std::size_t state_capacity = 16384;  ///< ring slots for states (16 s at 1 kHz)
  std::size_t event_capacity = 4096;   ///< queue slots for all other records
  std::chrono::milliseconds commit_interval{100};  ///< longest time between commits
  /// Refuse to record into an existing file (InputError) unless true; then it is replaced.
  bool overwrite = false;
  /// Largest database size in bytes (0: unlimited). A recording that reaches it behaves as on
  /// a full disk; meant for tests and for capping a long session.
  std::uint64_t max_bytes = 0;
};

enum class RecorderHealth {
  Recording,  ///< writing into the file
  InMemory,   ///< the file failed (see message); recording goes on in memory
  Closed,
};

struct RecorderStatus {
  RecorderHealth health = RecorderHealth::Recording;
  std::string message;  ///< one line, empty while all is well
  std::uint64_t states_written = 0;
  std::uint64_t states_dropped = 0;  ///< states lost because the ring was full
  std::uint64_t events_written = 0;
  std::uint64_t events_dropped = 0;  ///< events lost because the queue was full
  std::uint64_t commits = 0;
};

/// Removes an SQLite database file and its journal files (-wal, -shm), where they exist.
void removeDatabaseFiles(const std::filesystem::path& file);

/// Writes one session database. Construction opens (creates) the file and starts the
/// recorder thread; destruction flushes, checkpoints and closes it.
class SessionRecorder {
 public:
  /// Throws flexirob::InputError if `file` exists and options.overwrite is false. A file that
  /// cannot be created is not an exception: status() reports it and recording goes on in memory.
  SessionRecorder(const std::filesystem::path& file, const SessionMetadata& metadata,
                  const RecorderOptions& options = {});
  ~SessionRecorder();
  SessionRecorder(const SessionRecorder&) = delete;
  SessionRecorder& operator=(const SessionRecorder&) = delete;

  // --- Real-time safe (one producer: the control thread): never blocks, never allocates.
  /// Queues a state; false (and counted in states_dropped) if the ring is full.
  bool recordState(const StateRecord& state) noexcept;
  bool recordState(const robot::RobotState& state) noexcept;

  // --- Any thread: never blocks on the recorder or the disk; these allocate (copies of the
  // record). False (and counted in events_dropped) if the event queue is full.
  bool recordStage(const StageRecord& record);
  bool recordSignal(const SignalRecord& record);
  bool recordTrigger(double time, const std::string& name);
  bool recordButton(double time, const std::string& name);
  bool recordArea(const AreaRecord& record);
  bool recordSample(const SampleRecord& record);
  bool recordModel(ModelRecord record);
  bool recordItm(ItmRecord record);
  /// Returns the trajectory's id (assigned if record.id < 0), or -1 if dropped.
  std::int64_t recordTrajectory(TrajectoryRecord record);
  bool recordCollision(const CollisionRecord& record);
  /// Free key/value metadata (meta table), e.g. "teach.seed" = "7". Later values replace.
  bool recordMeta(const std::string& key, const std::string& value);

  /// Blocks until everything queued before the call is committed (not for the control thread).
  void flush();
  /// Flushes, checkpoints the WAL into the database and stops the thread. Idempotent.
  void close();

  RecorderStatus status() const;
  const std::filesystem::path& file() const { return file_; }
  /// Whether file() holds the recording and it goes on into it: recording (not in memory,
  /// not closed) and file() still the file opened (not removed or replaced since).
  bool fileHoldsTheRecording() const;

  /// Closes the recorder, then writes a complete copy of the recording (file or in-memory) to
  /// `target` (SQLite online backup). Use it after a disk failure to keep the session.
  /// Throws InputError on failure.
  void saveCopy(const std::filesystem::path& target);
  /// Writes a complete copy of everything recorded so far to `target` (created or replaced)
  /// and goes on recording into file(). The copy is written beside `target` and renamed over
  /// it, so a failure leaves `target` as it was. Throws InputError on failure, and when the
  /// recording is not on disk (in memory, closed, or its file removed: use saveCopy()).
  void saveSnapshot(const std::filesystem::path& target);

 private:
  bool fileIsTheOneOpened() const;

  struct Impl;
  std::filesystem::path file_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace flexirob::app
