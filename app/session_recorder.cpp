#include "app/session_recorder.hpp"

#include <pthread.h>
#include <sys/stat.h>

#include <sqlite3.h>

#include <algorithm>
#include <condition_variable>
#include <ctime>
#include <mutex>
#include <thread>
#include <variant>

#include "app/lockfree_queue.hpp"
#include "app/session_schema.hpp"
#include "robot/backend.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {

// ---------------------------------------------------------------------------------------------
// StateRecord

StateRecord StateRecord::fromRobotState(const robot::RobotState& state) noexcept {
  StateRecord record;
  record.time = state.time;
  const auto n = std::min<Eigen::Index>(state.q.size(), kMaxRecordedJoints);
  record.dof = static_cast<std::int32_t>(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    record.q[static_cast<std::size_t>(i)] = state.q[i];
    record.q_cmd[static_cast<std::size_t>(i)] = i < state.q_cmd.size() ? state.q_cmd[i] : 0.0;
    record.tau_ext[static_cast<std::size_t>(i)] = i < state.tau_ext.size() ? state.tau_ext[i] : 0.0;
  }
  const Eigen::Vector3d p = state.X_WT.translation();
  const Eigen::Quaterniond quat(state.X_WT.rotation());
  record.p_WT = {p.x(), p.y(), p.z()};
  record.quat_WT = {quat.w(), quat.x(), quat.y(), quat.z()};
  return record;
}

Eigen::VectorXd StateRecord::qVector() const { return Eigen::Map<const Eigen::VectorXd>(q.data(), dof); }
Eigen::VectorXd StateRecord::qCmdVector() const { return Eigen::Map<const Eigen::VectorXd>(q_cmd.data(), dof); }
Eigen::VectorXd StateRecord::tauExtVector() const {
  return Eigen::Map<const Eigen::VectorXd>(tau_ext.data(), dof);
}

// ---------------------------------------------------------------------------------------------
// Implementation

namespace {

struct MetaRecord {
  std::string key;
  std::string value;
};

using Event = std::variant<StageRecord, SignalRecord, AreaRecord, SampleRecord, ModelRecord, ItmRecord,
                           TrajectoryRecord, CollisionRecord, MetaRecord>;

const char* trajectoryKindName(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::TeachIn: return "teach_in";
    case TrajectoryKind::Target: return "target";
    case TrajectoryKind::Executed: return "executed";
  }
  return "teach_in";
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

// Prepared inserts of one connection.
struct Inserts {
  SqliteStatement state, stage, signal, area, sample, model, itm, trajectory, collision, meta;
  explicit Inserts(const SqliteDatabase& db)
      : state(db, "INSERT INTO state(t,dof,q,q_cmd,tau_ext,p_WT,quat_WT) VALUES(?,?,?,?,?,?,?)"),
        stage(db, "INSERT INTO stage(t,stage,sub_stage) VALUES(?,?,?)"),
        signal(db, "INSERT INTO signal(t,kind,name) VALUES(?,?,?)"),
        area(db, "INSERT INTO area(area,t,x_init,q_fixed,name) VALUES(?,?,?,?,?)"),
        sample(db, "INSERT INTO sample(t,area,x,q) VALUES(?,?,?,?)"),
        model(db, "INSERT INTO model(t,learner,samples,train_seconds,bytes) VALUES(?,?,?,?,?)"),
        itm(db, "INSERT INTO itm(t,nodes,edges,bytes) VALUES(?,?,?,?)"),
        trajectory(db,
                   "INSERT OR REPLACE INTO trajectory(id,kind,name,reference_id,t_start,t_end,points,dof,"
                   "times,positions,postures,outcome) VALUES(?,?,?,?,?,?,?,?,?,?,?,?)"),
        collision(db, "INSERT INTO collision(t,body_a,body_b,depth,p_W) VALUES(?,?,?,?,?)"),
        meta(db, "INSERT OR REPLACE INTO meta(key,value) VALUES(?,?)") {}
};

void bindVector(SqliteStatement& statement, int index, const Eigen::VectorXd& v) {
  statement.bindBlob(index, v.data(), static_cast<std::size_t>(v.size()) * sizeof(double));
}

void bindMatrix(SqliteStatement& statement, int index, const Eigen::MatrixXd& m) {
  // Eigen's default storage is column-major: one point's values lie together.
  statement.bindBlob(index, m.data(), static_cast<std::size_t>(m.size()) * sizeof(double));
}

void writeState(Inserts& inserts, const StateRecord& s) {
  const auto n = static_cast<std::size_t>(std::clamp(s.dof, 0, kMaxRecordedJoints));
  auto& st = inserts.state;
  st.bind(1, s.time).bind(2, static_cast<std::int64_t>(n));
  st.bindBlob(3, s.q.data(), n * sizeof(double));
  st.bindBlob(4, s.q_cmd.data(), n * sizeof(double));
  st.bindBlob(5, s.tau_ext.data(), n * sizeof(double));
  st.bindBlob(6, s.p_WT.data(), sizeof s.p_WT);
  st.bindBlob(7, s.quat_WT.data(), sizeof s.quat_WT);
  st.run();
}

void writeEvent(Inserts& in, const Event& event) {
  std::visit(
      [&in](const auto& r) {
        using R = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<R, StageRecord>) {
          in.stage.bind(1, r.time).bind(2, r.stage).bind(3, r.sub_stage).run();
        } else if constexpr (std::is_same_v<R, SignalRecord>) {
          in.signal.bind(1, r.time)
              .bind(2, std::string(r.kind == SignalKind::Button ? "button" : "trigger"))
              .bind(3, r.name)
              .run();
        } else if constexpr (std::is_same_v<R, AreaRecord>) {
          in.area.bind(1, r.area).bind(2, r.time);
          bindVector(in.area, 3, r.x_init);
          bindVector(in.area, 4, r.q_fixed);
          in.area.bind(5, r.name);
          in.area.run();
        } else if constexpr (std::is_same_v<R, SampleRecord>) {
          in.sample.bind(1, r.time).bind(2, r.area);
          bindVector(in.sample, 3, r.x);
          bindVector(in.sample, 4, r.q);
          in.sample.run();
        } else if constexpr (std::is_same_v<R, ModelRecord>) {
          in.model.bind(1, r.time).bind(2, r.learner_kind).bind(3, r.samples).bind(4, r.train_seconds);
          in.model.bindBlob(5, r.bytes.data(), r.bytes.size());
          in.model.run();
        } else if constexpr (std::is_same_v<R, ItmRecord>) {
          in.itm.bind(1, r.time).bind(2, r.nodes).bind(3, r.edges);
          in.itm.bindBlob(4, r.bytes.data(), r.bytes.size());
          in.itm.run();
        } else if constexpr (std::is_same_v<R, TrajectoryRecord>) {
          auto& st = in.trajectory;
          st.bind(1, r.id).bind(2, std::string(trajectoryKindName(r.kind))).bind(3, r.name);
          if (r.reference_id >= 0) st.bind(4, r.reference_id); else st.bindNull(4);
          if (r.times.size() > 0) {
            st.bind(5, r.times[0]).bind(6, r.times[r.times.size() - 1]);
          } else {
            st.bindNull(5).bindNull(6);
          }
          st.bind(7, static_cast<std::int64_t>(r.times.size())).bind(8, static_cast<std::int64_t>(r.postures.rows()));
          bindVector(st, 9, r.times);
          bindMatrix(st, 10, r.positions);
          bindMatrix(st, 11, r.postures);
          st.bind(12, r.outcome);
          st.run();
        } else if constexpr (std::is_same_v<R, CollisionRecord>) {
          in.collision.bind(1, r.time).bind(2, r.body_a).bind(3, r.body_b).bind(4, r.depth);
          in.collision.bindBlob(5, r.p_W.data(), 3 * sizeof(double));
          in.collision.run();
        } else if constexpr (std::is_same_v<R, MetaRecord>) {
          in.meta.bind(1, r.key).bind(2, r.value).run();
        }
      },
      event);
}

void createSchema(SqliteDatabase& db, const SessionMetadata& metadata) {
  db.exec("BEGIN", "begin");
  db.exec(sessionSchemaSql(), "create schema");
  db.exec("PRAGMA application_id = " + std::to_string(kSessionApplicationId), "application_id");
  db.exec("PRAGMA user_version = " + std::to_string(kSessionSchemaVersion), "user_version");
  SqliteStatement meta(db, "INSERT INTO meta(key,value) VALUES(?,?)");
  const auto put = [&meta](const std::string& key, const std::string& value) { meta.bind(1, key).bind(2, value).run(); };
  put("format", std::string(kSessionFormatName));
  put("schema_version", std::to_string(kSessionSchemaVersion));
  put("robot_name", metadata.robot_name);
  put("robot_urdf", metadata.robot_urdf);
  put("tip_link", metadata.tip_link);
  put("scene_name", metadata.scene_name);
  put("scene_text", metadata.scene_text);
  put("mesh_digests", metadata.mesh_digests);
  put("parameters", metadata.parameters);
  put("software_version", metadata.software_version);
  put("participant", metadata.participant);
  put("start_time_utc", metadata.start_time_utc.empty() ? utcNow() : metadata.start_time_utc);
  put("sqlite_version", sqlite3_libversion());
  db.exec("COMMIT", "commit");
}

}  // namespace

void removeDatabaseFiles(const std::filesystem::path& file) {
  std::error_code ignored;
  std::filesystem::remove(file, ignored);
  std::filesystem::remove(file.string() + "-wal", ignored);
  std::filesystem::remove(file.string() + "-shm", ignored);
}

struct SessionRecorder::Impl {
  RecorderOptions options;
  // The file the connection writes, to notice it removed or replaced while the run records
  // (its folder deleted): the connection would go on writing into a file nobody can open.
  bool file_identity_known = false;  // the file opened (else recording in memory from the start)
  dev_t file_device = 0;             // 0 and 0 where the file was gone by the time it was looked at
  ino_t file_inode = 0;
  SessionMetadata metadata;
  SpscRing<StateRecord> states;
  BoundedMpmcQueue<std::unique_ptr<Event>> events;

  std::atomic<std::uint64_t> states_dropped{0};
  std::atomic<std::uint64_t> events_dropped{0};
  std::atomic<std::int64_t> next_trajectory_id{1};

  // Recorder thread only.
  SqliteDatabase db;
  std::unique_ptr<Inserts> inserts;
  std::vector<StateRecord> pending_states;
  std::vector<std::unique_ptr<Event>> pending_events;

  // Shared with status() and flush(), under `mutex`.
  mutable std::mutex mutex;
  std::condition_variable flushed_cv;
  std::condition_variable wake_cv;
  RecorderStatus status;
  std::uint64_t flush_requested = 0;
  std::uint64_t flush_done = 0;
  bool stop = false;
  bool wake = false;

  std::thread thread;

  Impl(const RecorderOptions& o, const SessionMetadata& m)
      : options(o), metadata(m), states(o.state_capacity), events(o.event_capacity) {}

  void setHealth(RecorderHealth health, const std::string& message) {
    std::lock_guard lock(mutex);
    status.health = health;
    status.message = message;
  }

  // Opens the file with its schema; on failure continues in memory.
  void open(const std::filesystem::path& file) {
    try {
      db = SqliteDatabase(file.string(), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX);
      const std::string mode = db.queryText("PRAGMA journal_mode=WAL");
      if (mode != "wal") throw SqliteError("the file system refuses WAL mode (journal_mode " + mode + ")", SQLITE_CANTOPEN);
      db.exec("PRAGMA synchronous=NORMAL", "synchronous");
      if (options.max_bytes > 0) {
        const std::int64_t page = db.queryInt("PRAGMA page_size");
        db.queryInt("PRAGMA max_page_count=" + std::to_string(std::max<std::uint64_t>(options.max_bytes / static_cast<std::uint64_t>(page), 1)));
      }
      createSchema(db, metadata);
      inserts = std::make_unique<Inserts>(db);
      file_identity_known = true;
      struct stat opened {};
      if (::stat(file.c_str(), &opened) == 0) {
        file_device = opened.st_dev;
        file_inode = opened.st_ino;
      }
    } catch (const SqliteError& e) {
      inserts.reset();
      db.close();
      startInMemory(nullptr, "cannot record into " + file.string() + ": " + e.what() + "; recording in memory");
    }
  }

  // Moves the recording into an in-memory database: the committed content of `from` (if any)
  // is copied first, so saveCopy() later writes the whole session.
  void startInMemory(SqliteDatabase* from, const std::string& message) {
    inserts.reset();
    try {
      SqliteDatabase memory(":memory:", SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX);
      bool copied = false;
      if (from && from->isOpen()) {
        sqlite3_backup* backup = sqlite3_backup_init(memory.handle(), "main", from->handle(), "main");
        if (backup) {
          copied = sqlite3_backup_step(backup, -1) == SQLITE_DONE;
          sqlite3_backup_finish(backup);
        }
        // max_page_count belongs to the file's connection, so the in-memory copy grows freely.
      }
      if (!copied) {
        memory.close();
        memory = SqliteDatabase(":memory:", SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX);
        createSchema(memory, metadata);
      }
      if (from) from->close();
      db = std::move(memory);
      inserts = std::make_unique<Inserts>(db);
      setHealth(RecorderHealth::InMemory, message);
    } catch (const SqliteError& e) {
      if (from) from->close();
      db.close();
      setHealth(RecorderHealth::InMemory, message + " (the in-memory copy failed too: " + e.what() + ")");
    }
  }

  // Writes everything pending in one transaction. On failure of the file, switches to memory
  // and writes the same batch there, so nothing drained is lost.
  void commitPending() {
    if (pending_states.empty() && pending_events.empty()) return;
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (!inserts) break;
      try {
        db.exec("BEGIN", "begin");
        for (const auto& s : pending_states) writeState(*inserts, s);
        for (const auto& e : pending_events) writeEvent(*inserts, *e);
        db.exec("COMMIT", "commit");
        std::lock_guard lock(mutex);
        status.states_written += pending_states.size();
        status.events_written += pending_events.size();
        ++status.commits;
        break;
      } catch (const SqliteError& e) {
        sqlite3_exec(db.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
        RecorderHealth health;
        {
          std::lock_guard lock(mutex);
          health = status.health;
        }
        if (health == RecorderHealth::InMemory) {
          setHealth(RecorderHealth::InMemory, std::string("recording in memory failed: ") + e.what());
          break;
        }
        startInMemory(&db, "recording into the session file failed (" + std::string(e.what()) +
                               "); the file keeps everything up to the last commit, recording goes on in memory");
      }
    }
    pending_states.clear();
    pending_events.clear();
  }

  // Moves what the producers queued into the pending batch; returns how many records.
  std::size_t drain() {
    std::size_t count = 0;
    StateRecord state;
    while (states.tryPop(state)) {
      pending_states.push_back(state);
      ++count;
    }
    std::unique_ptr<Event> event;
    while (events.tryPop(event)) {
      pending_events.push_back(std::move(event));
      ++count;
    }
    return count;
  }

  void run() {
    using Clock = std::chrono::steady_clock;
    auto last_commit = Clock::now();
    for (;;) {
      std::uint64_t requested;
      bool stopping;
      {
        std::lock_guard lock(mutex);
        requested = flush_requested;
        stopping = stop;
      }
      drain();
      const auto now = Clock::now();
      if (now - last_commit >= options.commit_interval || requested != flush_done || stopping) {
        commitPending();
        last_commit = now;
      }
      if (requested != flush_done) {
        std::lock_guard lock(mutex);
        flush_done = requested;
        flushed_cv.notify_all();
      }
      if (stopping) break;
      // Sleep a short while: the producers never signal (the control thread must not touch a
      // mutex), so the recorder polls. 2 ms keeps the ring far from full at 1 kHz.
      std::unique_lock lock(mutex);
      wake_cv.wait_for(lock, std::chrono::milliseconds(2), [this] { return wake || stop; });
      wake = false;
    }
  }

  bool pushEvent(Event&& event) {
    auto boxed = std::make_unique<Event>(std::move(event));
    if (events.tryPush(boxed)) return true;
    events_dropped.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
};

SessionRecorder::SessionRecorder(const std::filesystem::path& file, const SessionMetadata& metadata,
                                 const RecorderOptions& options)
    : file_(file) {
  std::error_code ec;
  if (std::filesystem::exists(file, ec)) {
    if (!options.overwrite) throw InputError("session file " + file.string() + " exists already");
    removeDatabaseFiles(file);
  }
  impl_ = std::make_unique<Impl>(options, metadata);
  impl_->open(file);
  impl_->thread = std::thread([this] { impl_->run(); });
  pthread_setname_np(impl_->thread.native_handle(), "fr-recorder");
}

SessionRecorder::~SessionRecorder() { close(); }

bool SessionRecorder::recordState(const StateRecord& state) noexcept {
  if (impl_->states.tryPush(state)) return true;
  impl_->states_dropped.fetch_add(1, std::memory_order_relaxed);
  return false;
}

bool SessionRecorder::recordState(const robot::RobotState& state) noexcept {
  return recordState(StateRecord::fromRobotState(state));
}

bool SessionRecorder::recordStage(const StageRecord& record) { return impl_->pushEvent(Event(record)); }
bool SessionRecorder::recordSignal(const SignalRecord& record) { return impl_->pushEvent(Event(record)); }
bool SessionRecorder::recordTrigger(double time, const std::string& name) {
  return recordSignal({time, SignalKind::Trigger, name});
}
bool SessionRecorder::recordButton(double time, const std::string& name) {
  return recordSignal({time, SignalKind::Button, name});
}
bool SessionRecorder::recordArea(const AreaRecord& record) { return impl_->pushEvent(Event(record)); }
bool SessionRecorder::recordSample(const SampleRecord& record) { return impl_->pushEvent(Event(record)); }
bool SessionRecorder::recordModel(ModelRecord record) { return impl_->pushEvent(Event(std::move(record))); }
bool SessionRecorder::recordItm(ItmRecord record) { return impl_->pushEvent(Event(std::move(record))); }
bool SessionRecorder::recordCollision(const CollisionRecord& record) { return impl_->pushEvent(Event(record)); }
bool SessionRecorder::recordMeta(const std::string& key, const std::string& value) {
  return impl_->pushEvent(Event(MetaRecord{key, value}));
}

std::int64_t SessionRecorder::recordTrajectory(TrajectoryRecord record) {
  if (record.times.size() != record.positions.cols() ||
      (record.postures.size() > 0 && record.postures.cols() != record.times.size()) ||
      (record.positions.size() > 0 && record.positions.rows() != 3)) {
    throw std::invalid_argument("recordTrajectory: expected times (K), positions (3 x K), postures (N x K)");
  }
  if (record.id < 0) {
    record.id = impl_->next_trajectory_id.fetch_add(1);
  } else {
    // Keep assigned ids above any id the caller chose.
    std::int64_t next = impl_->next_trajectory_id.load();
    while (next <= record.id && !impl_->next_trajectory_id.compare_exchange_weak(next, record.id + 1)) {
    }
  }
  const std::int64_t id = record.id;
  return impl_->pushEvent(Event(std::move(record))) ? id : -1;
}

void SessionRecorder::flush() {
  if (!impl_->thread.joinable()) return;
  std::unique_lock lock(impl_->mutex);
  const std::uint64_t ticket = ++impl_->flush_requested;
  impl_->wake = true;
  impl_->wake_cv.notify_all();
  impl_->flushed_cv.wait(lock, [this, ticket] { return impl_->flush_done >= ticket || impl_->stop; });
}

void SessionRecorder::close() {
  if (!impl_ || !impl_->thread.joinable()) return;
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
    impl_->wake_cv.notify_all();
  }
  impl_->thread.join();
  // The thread's last pass drained and committed everything queued before stop was seen; a
  // producer racing with close() may leave a record behind, written here.
  impl_->drain();
  impl_->commitPending();
  if (impl_->inserts) {
    impl_->inserts.reset();
    try {
      SqliteStatement meta(impl_->db, "INSERT OR REPLACE INTO meta(key,value) VALUES(?,?)");
      meta.bind(1, std::string("end_time_utc")).bind(2, utcNow()).run();
      const auto stats = status();
      meta.bind(1, std::string("states_dropped")).bind(2, std::to_string(stats.states_dropped)).run();
      meta.bind(1, std::string("events_dropped")).bind(2, std::to_string(stats.events_dropped)).run();
    } catch (const SqliteError&) {
      // The file is full or gone: its content up to the last commit stays valid.
    }
    if (status().health == RecorderHealth::Recording && !fileIsTheOneOpened()) {
      // Still readable through the connection: copied into memory, for saveCopy().
      impl_->startInMemory(&impl_->db, "the session file " + file_.string() + " was removed or replaced while the run recorded");
      return;
    }
    // Fold the WAL into the database so the file stands alone, and leave WAL mode: readers of
    // a WAL file create -wal and -shm files beside it (and, read-only, leave them behind).
    // A reader still attached keeps the mode; the file is complete either way.
    sqlite3_wal_checkpoint_v2(impl_->db.handle(), nullptr, SQLITE_CHECKPOINT_TRUNCATE, nullptr, nullptr);
    sqlite3_exec(impl_->db.handle(), "PRAGMA journal_mode=DELETE", nullptr, nullptr, nullptr);
  }
  std::lock_guard lock(impl_->mutex);
  if (impl_->status.health == RecorderHealth::Recording) impl_->status.health = RecorderHealth::Closed;
}

bool SessionRecorder::fileIsTheOneOpened() const {
  struct stat now {};
  return impl_->file_identity_known && ::stat(file_.c_str(), &now) == 0 && now.st_dev == impl_->file_device &&
         now.st_ino == impl_->file_inode;
}

bool SessionRecorder::fileHoldsTheRecording() const {
  return impl_->thread.joinable() && status().health == RecorderHealth::Recording && fileIsTheOneOpened();
}

RecorderStatus SessionRecorder::status() const {
  std::lock_guard lock(impl_->mutex);
  RecorderStatus s = impl_->status;
  s.states_dropped = impl_->states_dropped.load(std::memory_order_relaxed);
  s.events_dropped = impl_->events_dropped.load(std::memory_order_relaxed);
  return s;
}

namespace {

// SQLite online backup of `from` into `target`, which it creates or replaces.
void copyDatabase(SqliteDatabase& from, const std::filesystem::path& target) {
  SqliteDatabase out;
  try {
    out = SqliteDatabase(target.string(), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  } catch (const SqliteError& e) {
    throw InputError(e.what());
  }
  sqlite3_backup* backup = sqlite3_backup_init(out.handle(), "main", from.handle(), "main");
  if (!backup) throw InputError("cannot copy the recording to " + target.string() + ": " + sqlite3_errmsg(out.handle()));
  const int rc = sqlite3_backup_step(backup, -1);
  sqlite3_backup_finish(backup);
  if (rc != SQLITE_DONE) throw InputError("cannot copy the recording to " + target.string() + ": " + sqlite3_errstr(rc));
  // The backup carries the WAL mode of the recording it came from; a finished session leaves
  // it, so that readers leave no -wal and -shm files beside the copy.
  sqlite3_exec(out.handle(), "PRAGMA journal_mode=DELETE", nullptr, nullptr, nullptr);
}

}  // namespace

void SessionRecorder::saveCopy(const std::filesystem::path& target) {
  // The recorder thread owns the connection while it runs; copy after closing it.
  close();
  if (!impl_->db.isOpen()) throw InputError("no recording to copy (the in-memory database failed)");
  copyDatabase(impl_->db, target);
}

void SessionRecorder::saveSnapshot(const std::filesystem::path& target) {
  if (!impl_->thread.joinable() || status().health != RecorderHealth::Recording) {
    throw InputError("the recording is not on disk (" + file_.string() + "): only a copy that ends it can be saved");
  }
  std::error_code same_ec;
  if (std::filesystem::equivalent(target, file_, same_ec)) {
    throw InputError(target.string() + " is the file this run records into; choose another");
  }
  flush();
  // A commit that failed in the flush moved the recording into memory: the file lacks it.
  if (status().health != RecorderHealth::Recording) {
    throw InputError("the recording could not be written to " + file_.string() + ": " + status().message);
  }
  // The connection still writes into a file removed (or replaced) under it: nothing to read.
  if (!fileIsTheOneOpened()) {
    throw InputError("the session file " + file_.string() + " was removed or replaced while the run recorded");
  }
  // Written beside the target and renamed over it: a failure leaves the target as it was.
  const std::filesystem::path part = target.string() + ".part";
  removeDatabaseFiles(part);
  try {
    // A second connection reads the committed recording while the recorder's thread goes on
    // writing (WAL: neither waits for the other).
    SqliteDatabase in(file_.string(), SQLITE_OPEN_READONLY);
    copyDatabase(in, part);
  } catch (const SqliteError& e) {
    removeDatabaseFiles(part);
    throw InputError("cannot copy the recording to " + target.string() + ": " + e.what());
  } catch (...) {
    removeDatabaseFiles(part);
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(part, target, ec);
  if (ec) {
    removeDatabaseFiles(part);
    throw InputError("cannot write " + target.string() + ": " + ec.message());
  }
}

}  // namespace flexirob::app
