// Session recordings: round trip of every record type, refusal of damaged or foreign files,
// a kill -9 in the middle of recording, disk failures, and the lock-free hand-over.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "app/lockfree_queue.hpp"
#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_schema.hpp"
#include "app/study_metrics.hpp"
#include "robot/backend.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards.
class SessionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("flexirob_session_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path path(const std::string& name) const { return dir_ / name; }

  fs::path dir_;
};

SessionMetadata exampleMetadata() {
  SessionMetadata m;
  m.robot_name = "lwr4";
  m.robot_urdf = "<robot name=\"lwr4\"/>";
  m.tip_link = "lwr_link_7";
  m.scene_name = "harting";
  m.scene_text = "obstacles: []\n";
  m.parameters = "{\"e_max\": 0.1}";
  m.software_version = "0.1.0";
  m.participant = "P07";
  m.start_time_utc = "2026-11-22T02:00:00Z";
  return m;
}

StateRecord exampleState(int i, int dof = 7) {
  StateRecord s;
  s.time = 0.001 * i;
  s.dof = dof;
  for (int j = 0; j < dof; ++j) {
    s.q[static_cast<std::size_t>(j)] = 0.01 * i + j;
    s.q_cmd[static_cast<std::size_t>(j)] = -0.02 * i + j;
    s.tau_ext[static_cast<std::size_t>(j)] = 0.5 * j - 0.001 * i;
  }
  s.p_WT = {0.1 * i, -0.2, 0.3};
  s.quat_WT = {0.5, 0.5, -0.5, 0.5};
  return s;
}

void expectSameState(const StateRecord& a, const StateRecord& b) {
  EXPECT_EQ(a.time, b.time);
  ASSERT_EQ(a.dof, b.dof);
  for (int j = 0; j < a.dof; ++j) {
    const auto k = static_cast<std::size_t>(j);
    EXPECT_EQ(a.q[k], b.q[k]);
    EXPECT_EQ(a.q_cmd[k], b.q_cmd[k]);
    EXPECT_EQ(a.tau_ext[k], b.tau_ext[k]);
  }
  EXPECT_EQ(a.p_WT, b.p_WT);
  EXPECT_EQ(a.quat_WT, b.quat_WT);
}

// Records `count` states (dof 7) and closes.
void writeStates(const fs::path& file, int count) {
  SessionRecorder recorder(file, exampleMetadata());
  for (int i = 0; i < count; ++i) {
    while (!recorder.recordState(exampleState(i))) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  recorder.close();
}

std::string refusal(const fs::path& file) {
  try {
    SessionReader reader(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST_F(SessionTest, RoundTripsEveryRecordType) {
  const auto file = path("round_trip.flexirob");
  TrajectoryRecord teach;
  teach.kind = TrajectoryKind::TeachIn;
  teach.name = "teach-in 1";
  teach.times = Eigen::VectorXd::LinSpaced(5, 10.0, 14.0);
  teach.positions = Eigen::MatrixXd::Random(3, 5);
  teach.postures = Eigen::MatrixXd::Random(7, 5);
  TrajectoryRecord target;
  target.id = 40;
  target.kind = TrajectoryKind::Target;
  target.name = "parcours";
  target.times = Eigen::VectorXd::LinSpaced(3, 0.0, 1.0);
  target.positions = Eigen::MatrixXd::Random(3, 3);
  target.postures.resize(0, 3);
  ModelRecord model{20.0, "elm", 321, 1.25, {0, 1, 2, 255, 7, 0}};
  ItmRecord itm{21.0, 12, 30, std::vector<std::uint8_t>(1000, 0xAB)};
  AreaRecord area{1, 3.0, Eigen::Vector3d(-0.5, 0.2, 0.4), Eigen::VectorXd::LinSpaced(7, -1.0, 1.0), "behind the box"};
  SampleRecord sample0{3.5, 1, Eigen::Vector3d(-0.51, 0.21, 0.39), Eigen::VectorXd::Constant(7, 0.25)};
  SampleRecord sample1{4.5, 2, Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::VectorXd::Constant(7, -0.5)};
  CollisionRecord collision{7.5, "lwr_link_4", "box_left", 0.003, Eigen::Vector3d(0.1, -0.2, 0.5)};

  std::int64_t teach_id = -1;
  std::int64_t executed_id = -1;
  {
    SessionRecorder recorder(file, exampleMetadata());
    for (int i = 0; i < 2000; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
    ASSERT_TRUE(recorder.recordStage({0.0, "CONFIGURATION", "APPROACHING"}));
    ASSERT_TRUE(recorder.recordStage({2.5, "CONFIGURATION", "RECORDING"}));
    ASSERT_TRUE(recorder.recordTrigger(2.4, "on_affected"));
    ASSERT_TRUE(recorder.recordButton(0.1, "start_configuration"));
    ASSERT_TRUE(recorder.recordArea(area));
    ASSERT_TRUE(recorder.recordSample(sample0));
    ASSERT_TRUE(recorder.recordSample(sample1));
    ASSERT_TRUE(recorder.recordModel(model));
    ASSERT_TRUE(recorder.recordItm(itm));
    teach_id = recorder.recordTrajectory(teach);
    EXPECT_EQ(recorder.recordTrajectory(target), 40);
    TrajectoryRecord executed = teach;
    executed.kind = TrajectoryKind::Executed;
    executed.name = "replay";
    executed.reference_id = teach_id;
    executed.outcome = "reached";
    executed_id = recorder.recordTrajectory(executed);
    ASSERT_TRUE(recorder.recordCollision(collision));
    ASSERT_TRUE(recorder.recordMeta("teach.seed", "7"));
    recorder.close();
    const auto status = recorder.status();
    EXPECT_EQ(status.states_written, 2000u);
    EXPECT_EQ(status.events_written, 14u);
    EXPECT_EQ(status.states_dropped + status.events_dropped, 0u);
    EXPECT_TRUE(status.message.empty()) << status.message;
  }
  EXPECT_GE(teach_id, 0);
  EXPECT_NE(teach_id, 40);
  EXPECT_NE(executed_id, teach_id);

  SessionReader reader(file);
  EXPECT_EQ(reader.schemaVersion(), kSessionSchemaVersion);
  const auto expected_meta = exampleMetadata();
  EXPECT_EQ(reader.metadata().robot_name, expected_meta.robot_name);
  EXPECT_EQ(reader.metadata().robot_urdf, expected_meta.robot_urdf);
  EXPECT_EQ(reader.metadata().tip_link, expected_meta.tip_link);
  EXPECT_EQ(reader.metadata().scene_name, expected_meta.scene_name);
  EXPECT_EQ(reader.metadata().scene_text, expected_meta.scene_text);
  EXPECT_EQ(reader.metadata().parameters, expected_meta.parameters);
  EXPECT_EQ(reader.metadata().software_version, expected_meta.software_version);
  EXPECT_EQ(reader.metadata().participant, expected_meta.participant);
  EXPECT_EQ(reader.metadata().start_time_utc, expected_meta.start_time_utc);
  EXPECT_EQ(reader.meta("teach.seed"), "7");
  EXPECT_FALSE(reader.meta("end_time_utc").empty());

  EXPECT_EQ(reader.stateCount(), 2000);
  EXPECT_DOUBLE_EQ(reader.startTime(), 0.0);
  EXPECT_DOUBLE_EQ(reader.endTime(), 1.999);
  const auto states = reader.states(0.0, 10.0);
  ASSERT_EQ(states.size(), 2000u);
  for (int i = 0; i < 2000; i += 97) expectSameState(states[static_cast<std::size_t>(i)], exampleState(i));

  const auto stages = reader.stages();
  ASSERT_EQ(stages.size(), 2u);
  EXPECT_EQ(stages[1].stage, "CONFIGURATION");
  EXPECT_EQ(stages[1].sub_stage, "RECORDING");
  EXPECT_EQ(stages[1].time, 2.5);
  const auto signals = reader.signals();
  ASSERT_EQ(signals.size(), 2u);  // in time order: the button at 0.1 s, then the trigger
  EXPECT_EQ(signals[0].kind, SignalKind::Button);
  EXPECT_EQ(signals[0].name, "start_configuration");
  EXPECT_EQ(signals[1].kind, SignalKind::Trigger);
  EXPECT_EQ(signals[1].name, "on_affected");

  const auto areas = reader.areas();
  ASSERT_EQ(areas.size(), 1u);
  EXPECT_EQ(areas[0].area, 1);
  EXPECT_EQ(areas[0].x_init, area.x_init);
  EXPECT_EQ(areas[0].q_fixed, area.q_fixed);
  EXPECT_EQ(areas[0].name, "behind the box");
  const auto samples = reader.samples(1);
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0].x, sample0.x);
  EXPECT_EQ(samples[0].q, sample0.q);
  EXPECT_EQ(reader.samples().size(), 2u);
  EXPECT_EQ(reader.sampleCounts(), (std::map<int, std::int64_t>{{1, 1}, {2, 1}}));

  const auto models = reader.models();
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0].learner_kind, "elm");
  EXPECT_EQ(models[0].samples, 321);
  EXPECT_EQ(models[0].train_seconds, 1.25);
  EXPECT_EQ(models[0].bytes, model.bytes);
  const auto graphs = reader.itmSnapshots();
  ASSERT_EQ(graphs.size(), 1u);
  EXPECT_EQ(graphs[0].nodes, 12);
  EXPECT_EQ(graphs[0].edges, 30);
  EXPECT_EQ(graphs[0].bytes, itm.bytes);

  EXPECT_EQ(reader.trajectories().size(), 3u);
  const auto teach_back = reader.trajectory(teach_id);
  ASSERT_TRUE(teach_back.has_value());
  EXPECT_EQ(teach_back->kind, TrajectoryKind::TeachIn);
  EXPECT_EQ(teach_back->name, teach.name);
  EXPECT_EQ(teach_back->times, teach.times);
  EXPECT_EQ(teach_back->positions, teach.positions);
  EXPECT_EQ(teach_back->postures, teach.postures);
  const auto target_back = reader.trajectories(TrajectoryKind::Target);
  ASSERT_EQ(target_back.size(), 1u);
  EXPECT_EQ(target_back[0].id, 40);
  EXPECT_EQ(target_back[0].postures.rows(), 0);
  EXPECT_EQ(target_back[0].positions, target.positions);
  const auto executed_back = reader.trajectories(TrajectoryKind::Executed);
  ASSERT_EQ(executed_back.size(), 1u);
  EXPECT_EQ(executed_back[0].reference_id, teach_id);
  EXPECT_EQ(executed_back[0].outcome, "reached");

  const auto collisions = reader.collisions();
  ASSERT_EQ(collisions.size(), 1u);
  EXPECT_EQ(collisions[0].body_a, collision.body_a);
  EXPECT_EQ(collisions[0].body_b, collision.body_b);
  EXPECT_EQ(collisions[0].depth, collision.depth);
  EXPECT_EQ(collisions[0].p_W, collision.p_W);
  EXPECT_TRUE(reader.collisions(0.0, 7.0).empty());
}

// E_task (Eq. 3.20) of an executed motion read back from a recording: a motion that follows
// its target 5 mm off everywhere has E_task = 5 mm, and its maximum deviation is 5 mm too.
TEST_F(SessionTest, ExecutedMotionReadsBackWithItsTargetForTaskError) {
  const auto file = path("e_task.flexirob");
  TrajectoryRecord target;
  target.kind = TrajectoryKind::Target;
  target.times = Eigen::VectorXd::LinSpaced(11, 0.0, 1.0);
  target.positions.resize(3, 11);
  for (int i = 0; i < 11; ++i) target.positions.col(i) << -0.6 + 0.03 * i, 0.1 * std::sin(0.3 * i), 0.4;
  TrajectoryRecord executed;
  executed.kind = TrajectoryKind::Executed;
  executed.times = target.times.array() + 30.0;
  executed.positions = target.positions.colwise() + Eigen::Vector3d(0.0, 0.0, 0.005);
  {
    SessionRecorder recorder(file, exampleMetadata());
    executed.reference_id = recorder.recordTrajectory(target);
    recorder.recordTrajectory(executed);
  }
  SessionReader reader(file);
  const auto motions = reader.trajectories(TrajectoryKind::Executed);
  ASSERT_EQ(motions.size(), 1u);
  const auto reference = reader.trajectory(motions[0].reference_id);
  ASSERT_TRUE(reference.has_value());
  EXPECT_NEAR(taskSpaceError(targetsForExecution(motions[0], *reference), motions[0].positions), 0.005, 1e-12);
  EXPECT_NEAR(maxDeviation(motions[0].positions, reference->positions), 0.005, 1e-12);
}

TEST_F(SessionTest, CopiesRobotStateIncludingTipPose) {
  robot::RobotState state;
  state.resize(9);
  state.time = 12.5;
  state.q = Eigen::VectorXd::LinSpaced(9, -0.8, 0.8);
  state.q_cmd = state.q * 2.0;
  state.tau_ext = Eigen::VectorXd::Constant(9, 1.5);
  state.X_WT = Eigen::Translation3d(0.1, 0.2, 0.3) * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ());
  const auto record = StateRecord::fromRobotState(state);
  EXPECT_EQ(record.dof, 9);
  EXPECT_EQ(record.qVector(), state.q);
  EXPECT_EQ(record.qCmdVector(), state.q_cmd);
  EXPECT_EQ(record.tauExtVector(), state.tau_ext);
  EXPECT_EQ(record.position(), Eigen::Vector3d(0.1, 0.2, 0.3));
  // A rotation of 0.7 rad about z: q = (cos 0.35, 0, 0, sin 0.35).
  EXPECT_NEAR(record.quat_WT[0], std::cos(0.35), 1e-15);
  EXPECT_NEAR(record.quat_WT[3], std::sin(0.35), 1e-15);
  EXPECT_NEAR(record.quat_WT[1], 0.0, 1e-15);
}

TEST_F(SessionTest, QueriesStatesByTimeRange) {
  const auto file = path("range.flexirob");
  writeStates(file, 5000);
  SessionReader reader(file);
  const auto range = reader.states(1.0, 1.0995);
  ASSERT_EQ(range.size(), 100u);
  EXPECT_DOUBLE_EQ(range.front().time, 1.0);
  expectSameState(range.back(), exampleState(1099));
  EXPECT_EQ(reader.states(0.0, 4.999, 10).size(), 500u);
  const auto at = reader.stateAt(2.0005);
  ASSERT_TRUE(at.has_value());
  expectSameState(*at, exampleState(2000));
  EXPECT_DOUBLE_EQ(reader.stateAt(-5.0)->time, 0.0);
}

TEST_F(SessionTest, AClosedSessionIsOneFileThatReadingLeavesAlone) {
  const auto file = path("alone.flexirob");
  writeStates(file, 200);
  {
    SessionReader reader(file);
    EXPECT_EQ(reader.states(0.0, 1.0).size(), 200u);
  }
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"alone.flexirob"}) << "no -wal or -shm files beside a finished session";
}

// A session is told by its header, and while it is written (or after a crash) by its
// write-ahead log, which holds the header's application_id until SQLite copies it back.
TEST_F(SessionTest, ASessionIsKnownWhileRecordedAndAfterItClosed) {
  const auto file = path("live.flexirob");
  {
    SessionRecorder recorder(file, exampleMetadata());
    for (int i = 0; i < 10; ++i) {
      while (!recorder.recordState(exampleState(i))) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    while (recorder.status().commits == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_GT(fs::file_size(file.string() + "-wal"), 0U) << "the recording is still in its log";
    EXPECT_TRUE(isSessionDatabase(file));
    recorder.close();
  }
  EXPECT_TRUE(isSessionDatabase(file));
  // Another application's SQLite database, with its own log beside it, is none; nor is text.
  const auto other = path("other.db");
  {
    SqliteDatabase db(other.string(), 0x00000002 | 0x00000004);  // SQLITE_OPEN_READWRITE | CREATE
    db.exec("PRAGMA journal_mode=WAL", "wal");
    db.exec("CREATE TABLE t(x); INSERT INTO t VALUES(1)", "table");
    EXPECT_GT(fs::file_size(other.string() + "-wal"), 0U);
    EXPECT_FALSE(isSessionDatabase(other));
  }
  EXPECT_FALSE(isSessionDatabase(other));
  std::ofstream(path("text.flexirob")) << "SQLite format 3 is how a session begins";
  EXPECT_FALSE(isSessionDatabase(path("text.flexirob")));
  EXPECT_FALSE(isSessionDatabase(path("absent.flexirob")));
}

TEST_F(SessionTest, RefusesToOverwriteAnExistingFile) {
  const auto file = path("exists.flexirob");
  std::ofstream(file) << "keep me";
  EXPECT_THROW(SessionRecorder(file, exampleMetadata()), InputError);
  RecorderOptions options;
  options.overwrite = true;
  SessionRecorder recorder(file, exampleMetadata(), options);
  recorder.close();
  EXPECT_NO_THROW(SessionReader{file});
}

TEST_F(SessionTest, RefusesMissingEmptyAndNonSqliteFiles) {
  EXPECT_NE(refusal(path("missing.flexirob")).find("does not exist"), std::string::npos);
  std::ofstream(path("empty.flexirob")).close();
  EXPECT_NE(refusal(path("empty.flexirob")).find("is empty"), std::string::npos);
  std::ofstream(path("text.flexirob")) << "time,q1,q2\n0,1,2\n";
  EXPECT_NE(refusal(path("text.flexirob")).find("not an SQLite database"), std::string::npos);
  // teach's JSON sessions hold areas and the map, not the stream: said as such.
  std::ofstream(path("taught.json")) << "\n  {\"format\": \"flexirob-session\", \"areas\": []}";
  const std::string json_refusal = refusal(path("taught.json"));
  EXPECT_NE(json_refusal.find("is a JSON session"), std::string::npos) << json_refusal;
  EXPECT_NE(json_refusal.find("teach --out taught.flexirob"), std::string::npos) << json_refusal;
}

TEST_F(SessionTest, RefusesForeignSqliteDatabase) {
  const auto file = path("foreign.sqlite");
  {
    SqliteDatabase db(file.string(), 0x00000002 | 0x00000004);  // SQLITE_OPEN_READWRITE | CREATE
    db.exec("CREATE TABLE contacts(name TEXT); INSERT INTO contacts VALUES('x')");
  }
  const std::string reason = refusal(file);
  EXPECT_NE(reason.find("not a FlexIRob session"), std::string::npos) << reason;
  EXPECT_EQ(reason.find('\n'), std::string::npos);
}

// Version 1 had no area names: such a file is read as it was written, its areas unnamed.
TEST_F(SessionTest, ReadsAVersionOneFileWithoutAreaNames) {
  const auto file = path("version1.flexirob");
  {
    SessionRecorder recorder(file, exampleMetadata());
    ASSERT_TRUE(recorder.recordArea({0, 1.0, Eigen::Vector3d(-0.5, 0.0, 0.4), Eigen::VectorXd::Zero(7), "front"}));
    ASSERT_TRUE(recorder.recordSample({0.5, 0, Eigen::Vector3d(-0.5, 0.0, 0.4), Eigen::VectorXd::Zero(7)}));
    recorder.close();
  }
  {
    SqliteDatabase db(file.string(), 0x00000002);  // SQLITE_OPEN_READWRITE
    db.exec("ALTER TABLE area DROP COLUMN name; PRAGMA user_version = 1; UPDATE meta SET value = '1' WHERE key = 'schema_version'");
  }
  SessionReader reader(file);
  EXPECT_EQ(reader.schemaVersion(), 1);
  const auto areas = reader.areas();
  ASSERT_EQ(areas.size(), 1u);
  EXPECT_EQ(areas[0].area, 0);
  EXPECT_EQ(areas[0].x_init, Eigen::Vector3d(-0.5, 0.0, 0.4));
  EXPECT_TRUE(areas[0].name.empty());
  EXPECT_EQ(reader.samples(0).size(), 1u);
}

TEST_F(SessionTest, RefusesAFileWhoseTwoVersionRecordsDisagree) {
  const auto file = path("disagreeing.flexirob");
  writeStates(file, 10);
  {
    SqliteDatabase db(file.string(), 0x00000002);  // SQLITE_OPEN_READWRITE
    db.exec("UPDATE meta SET value = '1\n2' WHERE key = 'schema_version'");
  }
  const std::string message = refusal(file);
  EXPECT_NE(message.find("meta.schema_version says '1?2'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST_F(SessionTest, RefusesAVersionTwoFileWithoutAreaNames) {
  const auto file = path("unnamed_v2.flexirob");
  writeStates(file, 10);
  {
    SqliteDatabase db(file.string(), 0x00000002);
    db.exec("ALTER TABLE area DROP COLUMN name");
  }
  EXPECT_NE(refusal(file).find("lacks the column 'name'"), std::string::npos);
}

TEST_F(SessionTest, RefusesNewerSchemaAndMissingTables) {
  const auto newer = path("newer.flexirob");
  writeStates(newer, 10);
  {
    SqliteDatabase db(newer.string(), 0x00000002);
    db.exec("PRAGMA user_version = " + std::to_string(kSessionSchemaVersion + 1));
  }
  EXPECT_NE(refusal(newer).find("schema version"), std::string::npos);

  const auto damaged = path("no_samples.flexirob");
  writeStates(damaged, 10);
  {
    SqliteDatabase db(damaged.string(), 0x00000002);
    db.exec("DROP TABLE sample");
  }
  EXPECT_NE(refusal(damaged).find("lacks the table 'sample'"), std::string::npos);
}

// A damaged state row (no joints, empty or short vectors) is refused when it is read, with the
// reason; the reader never copies from the empty blob SQLite returns as a null pointer.
TEST_F(SessionTest, RefusesDamagedStateRowsWhenTheyAreRead) {
  const auto file = path("damaged_rows.flexirob");
  writeStates(file, 10);
  const auto readFirstState = [&file]() -> std::string {
    try {
      SessionReader reader(file);
      (void)reader.stateAt(0.0);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  ASSERT_EQ(readFirstState(), "");
  {
    SqliteDatabase db(file.string(), 0x00000002);
    db.exec("UPDATE state SET dof = 0, q = x'', q_cmd = x'', tau_ext = x''");
  }
  EXPECT_NE(readFirstState().find("state row with 0 joints"), std::string::npos);
  {
    SqliteDatabase db(file.string(), 0x00000002);
    db.exec("UPDATE state SET dof = 7, q = x''");
  }
  EXPECT_NE(readFirstState().find("wrongly sized vector"), std::string::npos);
}

TEST_F(SessionTest, RefusesTruncatedSession) {
  const auto file = path("truncated.flexirob");
  writeStates(file, 20000);
  const auto size = fs::file_size(file);
  ASSERT_GT(size, 1'000'000u);
  fs::resize_file(file, size / 2);
  const std::string reason = refusal(file);
  EXPECT_NE(reason.find("truncated"), std::string::npos) << reason;
  // Cut inside the header.
  fs::resize_file(file, 60);
  EXPECT_NE(refusal(file).find("truncated"), std::string::npos);
}

// The control loop at 1 kHz for one second: every push succeeds and everything is written.
TEST_F(SessionTest, RecordsAtControlRateWithoutDrops) {
  const auto file = path("rate.flexirob");
  SessionRecorder recorder(file, exampleMetadata());
  using Clock = std::chrono::steady_clock;
  auto next = Clock::now();
  const int cycles = 1000;
  std::uint64_t failed_pushes = 0;
  for (int i = 0; i < cycles; ++i) {
    if (!recorder.recordState(exampleState(i))) ++failed_pushes;
    if (i % 100 == 0) recorder.recordStage({0.001 * i, "PROGRAMMING", "TEACH-IN"});
    next += std::chrono::microseconds(1000);
    std::this_thread::sleep_until(next);
  }
  recorder.close();
  const auto status = recorder.status();
  EXPECT_EQ(failed_pushes, 0u);
  EXPECT_EQ(status.states_dropped, 0u);
  EXPECT_EQ(status.events_dropped, 0u);
  EXPECT_EQ(status.states_written, static_cast<std::uint64_t>(cycles));
  EXPECT_GE(status.commits, 5u);  // batches of at most ~100 ms
  EXPECT_EQ(SessionReader(file).stateCount(), cycles);
}

// A producer far faster than the disk: pushes fail without blocking and every loss is counted.
TEST_F(SessionTest, CountsDroppedStatesWhenTheRingIsFull) {
  const auto file = path("burst.flexirob");
  RecorderOptions options;
  options.state_capacity = 64;
  SessionRecorder recorder(file, exampleMetadata(), options);
  const int pushed = 20000;
  int accepted = 0;
  for (int i = 0; i < pushed; ++i) accepted += recorder.recordState(exampleState(i)) ? 1 : 0;
  recorder.close();
  const auto status = recorder.status();
  EXPECT_GT(status.states_dropped, 0u);
  EXPECT_EQ(status.states_written, static_cast<std::uint64_t>(accepted));
  EXPECT_EQ(status.states_written + status.states_dropped, static_cast<std::uint64_t>(pushed));
  EXPECT_EQ(SessionReader(file).meta("states_dropped"), std::to_string(status.states_dropped));
}

// kill -9 of a process recording at 1 kHz: the file opens and holds all but the last second.
TEST_F(SessionTest, SurvivesKillNineLosingAtMostOneSecond) {
  const auto file = path("killed.flexirob");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(ready[0]);
    SessionRecorder recorder(file, exampleMetadata());
    const auto start = std::chrono::steady_clock::now();
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(3);
    auto next = start;
    for (int i = 0;; ++i) {
      StateRecord s = exampleState(i);
      s.time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      recorder.recordState(s);
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
    }
  }
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const double killed_at = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ::kill(child, SIGKILL);
  int wait_status = 0;
  ::waitpid(child, &wait_status, 0);
  ::close(ready[0]);
  ASSERT_TRUE(WIFSIGNALED(wait_status));

  SessionReader reader(file);
  EXPECT_GE(reader.endTime(), killed_at - 1.0);
  EXPECT_LE(reader.endTime(), killed_at + 0.05);
  // Rows are whole: each one reads back with its 7 joints.
  const auto tail = reader.states(reader.endTime() - 0.1, reader.endTime());
  ASSERT_FALSE(tail.empty());
  EXPECT_EQ(tail.back().dof, 7);
  EXPECT_EQ(reader.metadata().scene_name, "harting");
}

TEST_F(SessionTest, FullDiskKeepsTheFileReadableAndGoesOnInMemory) {
  const auto file = path("full.flexirob");
  RecorderOptions options;
  options.max_bytes = 400 * 1024;
  SessionRecorder recorder(file, exampleMetadata(), options);
  const int pushed = 6000;
  for (int i = 0; i < pushed; ++i) {
    while (!recorder.recordState(exampleState(i))) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (i % 500 == 0) recorder.flush();
  }
  recorder.flush();
  const auto status = recorder.status();
  EXPECT_EQ(status.health, RecorderHealth::InMemory);
  EXPECT_NE(status.message.find("full"), std::string::npos) << status.message;
  EXPECT_EQ(status.states_written, static_cast<std::uint64_t>(pushed));

  // The file holds a clean prefix of the session.
  {
    SessionReader partial(file);
    EXPECT_GT(partial.stateCount(), 0);
    EXPECT_LT(partial.stateCount(), pushed);
    expectSameState(*partial.stateAt(0.0), exampleState(0));
  }
  // The whole session survives in memory and can be saved elsewhere.
  const auto copy = path("copy.flexirob");
  recorder.saveCopy(copy);
  SessionReader whole(copy);
  EXPECT_EQ(whole.stateCount(), pushed);
  expectSameState(*whole.stateAt(5.9995), exampleState(5999));
}

TEST_F(SessionTest, UnwritableLocationRecordsInMemory) {
  std::ofstream(path("not_a_directory")) << "x";
  const auto file = path("not_a_directory") / "session.flexirob";
  SessionRecorder recorder(file, exampleMetadata());
  EXPECT_EQ(recorder.status().health, RecorderHealth::InMemory);
  EXPECT_NE(recorder.status().message.find(file.string()), std::string::npos);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  recorder.flush();
  EXPECT_EQ(recorder.status().states_written, 100u);
  const auto copy = path("rescued.flexirob");
  recorder.saveCopy(copy);
  EXPECT_EQ(SessionReader(copy).stateCount(), 100);
}

TEST_F(SessionTest, ASnapshotHoldsWhatWasRecordedAndRecordingGoesOnIntoTheSameFile) {
  const auto file = path("run.flexirob");
  SessionRecorder recorder(file, exampleMetadata());
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  const auto saved = path("saved.flexirob");
  recorder.saveSnapshot(saved);
  EXPECT_EQ(SessionReader(saved).stateCount(), 100);
  // The recorder goes on into its own file, and a second snapshot replaces the first.
  EXPECT_EQ(recorder.status().health, RecorderHealth::Recording);
  for (int i = 100; i < 250; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  recorder.saveSnapshot(saved);
  EXPECT_EQ(SessionReader(saved).stateCount(), 250);
  EXPECT_FALSE(std::filesystem::exists(saved.string() + ".part"));
  // A snapshot that cannot be written leaves the last one as it was.
  std::filesystem::create_directory(path("blocker.flexirob.part"));
  std::ofstream(path("blocker.flexirob.part") / "inside") << "x";
  const auto blocked = path("blocker.flexirob");
  std::filesystem::copy_file(saved, blocked);
  for (int i = 250; i < 300; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  EXPECT_THROW(recorder.saveSnapshot(blocked), InputError);
  EXPECT_EQ(SessionReader(blocked).stateCount(), 250);
  // The run's own file is no target: renamed over, its live WAL would belong to another file.
  EXPECT_THROW(recorder.saveSnapshot(file), InputError);
  recorder.close();
  EXPECT_EQ(SessionReader(file).stateCount(), 300);
  // Closed, it has nothing live to copy from: saveCopy() is the way.
  EXPECT_THROW(recorder.saveSnapshot(path("late.flexirob")), InputError);
  EXPECT_FALSE(recorder.fileHoldsTheRecording());
}

TEST_F(SessionTest, AFileRemovedWhileRecordingIsNoSnapshotSourceButTheWholeRunIsCopied) {
  const auto file = path("removed.flexirob");
  SessionRecorder recorder(file, exampleMetadata());
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  recorder.flush();
  EXPECT_TRUE(recorder.fileHoldsTheRecording());
  std::filesystem::remove(file);
  EXPECT_FALSE(recorder.fileHoldsTheRecording());
  for (int i = 100; i < 150; ++i) ASSERT_TRUE(recorder.recordState(exampleState(i)));
  try {
    recorder.saveSnapshot(path("snapshot.flexirob"));
    ADD_FAILURE() << "a snapshot of a removed file was written";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("was removed or replaced"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path("snapshot.flexirob")));
  // The connection still holds every row: the copy that ends the recording keeps them all.
  recorder.saveCopy(path("copy.flexirob"));
  EXPECT_EQ(SessionReader(path("copy.flexirob")).stateCount(), 150);
}

TEST(LockFreeQueue, SpscRingDeliversEverythingInOrderAcrossThreads) {
  SpscRing<std::uint64_t> ring(256);
  const std::uint64_t count = 200000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < count;) {
      if (ring.tryPush(i)) ++i;
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t value = 0;
  while (expected < count) {
    if (ring.tryPop(value)) {
      ASSERT_EQ(value, expected);
      ++expected;
    }
  }
  producer.join();
  EXPECT_FALSE(ring.tryPop(value));
}

TEST(LockFreeQueue, SpscRingRefusesWhenFull) {
  SpscRing<int> ring(4);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.tryPush(i));
  EXPECT_FALSE(ring.tryPush(99));
  int out = -1;
  EXPECT_TRUE(ring.tryPop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(ring.tryPush(4));
}

TEST(LockFreeQueue, MpmcQueueLosesNothingWithFourProducers) {
  BoundedMpmcQueue<std::uint64_t> queue(64);
  const int producers = 4;
  const std::uint64_t per_producer = 20000;
  std::vector<std::thread> threads;
  for (int p = 0; p < producers; ++p) {
    threads.emplace_back([&queue, p, per_producer] {
      for (std::uint64_t i = 0; i < per_producer;) {
        std::uint64_t v = static_cast<std::uint64_t>(p) * per_producer + i;
        if (queue.tryPush(v)) ++i;
      }
    });
  }
  std::vector<std::uint64_t> last(producers, 0);
  std::vector<bool> seen(producers, false);
  std::uint64_t received = 0;
  std::uint64_t sum = 0;
  std::uint64_t v = 0;
  while (received < producers * per_producer) {
    if (queue.tryPop(v)) {
      // Each producer's values arrive in its own order.
      const auto p = static_cast<std::size_t>(v / per_producer);
      if (seen[p]) {
        ASSERT_GT(v, last[p]);
      }
      seen[p] = true;
      last[p] = v;
      sum += v;
      ++received;
    }
  }
  for (auto& t : threads) t.join();
  const std::uint64_t n = producers * per_producer;
  EXPECT_EQ(sum, n * (n - 1) / 2);
}

}  // namespace
}  // namespace flexirob::app
