// `flexirob-cli review`: one recording's metrics against a recording built by hand with known
// content, a study folder as the GUI leaves it (*.flexirob) with a foreign file in it, and
// damaged files refused with one line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sqlite3.h>

#include "app/session_recorder.hpp"
#include "app/session_schema.hpp"
#include "cli_test_support.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;
using flexirob::testing::runCliBinary;

class ReviewCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flexirob-review-cli-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Two seconds at 1 kHz; area 0 taught twice (the second take holds), area 1 once, a RECORDING
  // of area 2 cut off by the end; a target line and an executed motion 1 cm above it.
  fs::path writeSession(const std::string& name, const std::string& participant, double posture_shift) {
    const fs::path file = dir_ / name;
    SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.tip_link = "lwr_link_7";
    metadata.scene_name = "setup_I";
    metadata.participant = participant;
    SessionRecorder recorder(file, metadata);
    const Eigen::VectorXd q = (Eigen::VectorXd(7) << 0.0, 0.6, 0.0, -1.4, 0.0, 0.7, 0.0).finished();
    for (int i = 0; i < 2000; ++i) {
      StateRecord state;
      state.time = 1e-3 * i;
      state.dof = 7;
      for (int j = 0; j < 7; ++j) state.q[static_cast<std::size_t>(j)] = q[j];
      state.p_WT = {-0.5, 0.0, 0.4};
      state.quat_WT = {1.0, 0.0, 0.0, 0.0};
      while (!recorder.recordState(state)) usleep(1000);
    }
    recorder.recordStage({0.0, "CONFIGURATION", "WAITING"});
    recorder.recordStage({0.5, "CONFIGURATION", "RECORDING"});
    recorder.recordStage({1.5, "EXECUTION", ""});
    const auto sample = [&](double t, int area) {
      recorder.recordSample({t, area, Eigen::Vector3d(-0.5, 0.1 * area, 0.4), q});
    };
    const Eigen::VectorXd q_fixed = q + Eigen::VectorXd::Constant(7, posture_shift);
    for (int l = 0; l < 5; ++l) sample(0.1 + 0.01 * l, 0);
    recorder.recordArea({0, 0.2, Eigen::Vector3d(-0.5, 0.0, 0.4), q_fixed, "front"});
    for (int l = 0; l < 3; ++l) sample(0.3 + 0.01 * l, 1);
    recorder.recordArea({1, 0.4, Eigen::Vector3d(-0.5, 0.1, 0.4), q_fixed, "left"});
    for (int l = 0; l < 7; ++l) sample(0.5 + 0.01 * l, 0);
    recorder.recordArea({0, 0.6, Eigen::Vector3d(-0.5, 0.0, 0.4), q_fixed, "front"});
    for (int l = 0; l < 4; ++l) sample(1.9 + 0.01 * l, 2);

    TrajectoryRecord target;
    target.kind = TrajectoryKind::Target;
    target.name = "line";
    target.times = Eigen::VectorXd::LinSpaced(11, 1.5, 1.9);
    target.positions.resize(3, 11);
    for (int k = 0; k < 11; ++k) target.positions.col(k) = Eigen::Vector3d(-0.5, -0.2 + 0.04 * k, 0.4);
    const std::int64_t target_id = recorder.recordTrajectory(target);
    TrajectoryRecord executed = target;
    executed.id = -1;
    executed.kind = TrajectoryKind::Executed;
    executed.name = "executed";
    executed.reference_id = target_id;
    executed.positions.row(2).array() += 0.01;
    executed.outcome = "reached";
    recorder.recordTrajectory(executed);
    recorder.close();
    return file;
  }

  fs::path dir_;
};

TEST_F(ReviewCli, SessionReportsWhatWasRecorded) {
  const fs::path file = writeSession("alice.flexirob", "alice", 0.0);
  const auto result = runCliBinary("review --session " + file.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("robot"), "lwr4");
  EXPECT_EQ(json.at("scene"), "setup_I");
  EXPECT_EQ(json.at("participant"), "alice");
  EXPECT_TRUE(json.at("closed_cleanly").get<bool>());
  EXPECT_TRUE(json.at("damage").is_null()) << json.at("damage");
  EXPECT_EQ(json.at("states").get<int>(), 2000);
  EXPECT_NEAR(json.at("duration_s").get<double>(), 1.999, 1e-9);
  // Area 0's second take (7 samples) holds; area 2 never ended.
  EXPECT_EQ(json.at("areas").get<int>(), 2);
  EXPECT_EQ(json.at("samples").get<int>(), 7 + 3);
  EXPECT_EQ(json.at("samples_per_area").at("0").get<int>(), 7);
  EXPECT_EQ(json.at("samples_per_area").at("1").get<int>(), 3);
  // By the names the areas were given, as teach and export give them; a re-take's name holds.
  ASSERT_EQ(json.at("taught_areas").size(), 2U);
  EXPECT_EQ(json.at("taught_areas")[0].at("index").get<int>(), 0);
  EXPECT_EQ(json.at("taught_areas")[0].at("name"), "front");
  EXPECT_EQ(json.at("taught_areas")[0].at("samples").get<int>(), 7);
  EXPECT_EQ(json.at("taught_areas")[1].at("name"), "left");
  EXPECT_EQ(json.at("taught_areas")[1].at("samples").get<int>(), 3);
  EXPECT_EQ(json.at("unfinished_recording_samples").get<int>(), 4);
  // Every executed point lies 1 cm above its target (Eq. 3.20).
  EXPECT_NEAR(json.at("e_task").get<double>(), 0.01, 1e-12);
  ASSERT_EQ(json.at("executed_motions").size(), 1U);
  EXPECT_EQ(json.at("executed_motions")[0].at("outcome"), "reached");
  EXPECT_NEAR(json.at("time_per_phase_s").at("EXECUTION").get<double>(), 1.999 - 1.5, 1e-9);
}

TEST_F(ReviewCli, StudyReadsTheGuisRecordingsAndSkipsAForeignFile) {
  writeSession("alice.flexirob", "alice", 0.0);
  writeSession("bob.flexirob", "bob", 0.3);
  { std::ofstream(dir_ / "notes.db") << "not a session"; }
  const fs::path tables = dir_ / "tables";
  const auto result = runCliBinary("review --study " + dir_.string() + " --csv-dir " + tables.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  ASSERT_EQ(json.at("participants").size(), 2U);
  EXPECT_EQ(json.at("participants")[0].at("participant"), "alice");
  EXPECT_EQ(json.at("participants")[1].at("participant"), "bob");
  EXPECT_EQ(json.at("participants")[1].at("areas").get<int>(), 2);
  // The fields STUDY.md names, the replay's count among them.
  for (const char* field : {"participant", "file", "robot", "scene", "closed_cleanly", "duration_s", "areas", "samples", "e_task",
                            "max_deviation_m", "procrustes_m", "jerk_mean", "e_coll", "colliding_samples", "replayed_samples",
                            "e_coll_recorded", "clusters", "time_per_phase_s"}) {
    EXPECT_TRUE(json.at("participants")[0].contains(field)) << field;
  }
  ASSERT_EQ(json.at("skipped").size(), 1U);
  EXPECT_NE(json.at("skipped")[0].get<std::string>().find("notes.db"), std::string::npos);
  ASSERT_FALSE(json.at("csv_files").empty());
  for (const auto& csv : json.at("csv_files")) EXPECT_TRUE(fs::exists(csv.get<std::string>())) << csv;
}

// Centres of an area no session taught: the study says so, and --plot writes no blank picture.
TEST_F(ReviewCli, StudyCentresThatFitNoSessionAreNamedAndNoBlankPlotIsWritten) {
  writeSession("alice.flexirob", "alice", 0.0);
  writeSession("bob.flexirob", "bob", 0.3);
  const fs::path centres = dir_ / "centres.csv";
  { std::ofstream(centres) << "7,A,0,0,0,0,0,0\n7,B,1,1,1,1,1,1\n"; }
  const fs::path plot = dir_ / "mds.png";
  const auto result = runCliBinary("review --study " + dir_.string() + " --centres " + centres.string() + " --plot " + plot.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_TRUE(json.at("clusterings").empty());
  EXPECT_TRUE(json.at("plot").is_null()) << json.at("plot");
  EXPECT_FALSE(fs::exists(plot));
  EXPECT_NE(result.err.find("note: not clustered: area 7: its centres name an area no session of 'lwr4' taught"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("note: --plot: no area was clustered, so no picture was written"), std::string::npos) << result.err;
}

// The study's outputs never take the place of what it reads: a participant's recording named as
// --plot, the --centres file named as --plot or lying where --csv-dir puts a table. Each is
// refused with one line before anything is written, and the files stay as they were.
TEST_F(ReviewCli, StudyOutputsNeverReplaceTheSessionsOrTheCentresItReads) {
  const fs::path alice = writeSession("alice.flexirob", "alice", 0.0);
  writeSession("bob.flexirob", "bob", 0.3);
  const fs::path tables = dir_ / "tables";
  fs::create_directories(tables);
  const fs::path centres = tables / "centres_area0.csv";
  const std::string centres_text = "0,L1,0,1.5708,-1.5708,-1.5708,1.5708,1.5708\n";
  { std::ofstream(centres) << centres_text; }
  const auto bytes = [](const fs::path& file) {
    std::ostringstream text;
    text << std::ifstream(file, std::ios::binary).rdbuf();
    return text.str();
  };
  const std::string alice_bytes = bytes(alice);
  const std::string study = "review --study " + dir_.string();
  for (const auto& [arguments, refusal] : std::vector<std::pair<std::string, std::string>>{
           {" --plot " + alice.string(), "is the --study file the run reads"},
           {" --centres " + centres.string() + " --plot " + centres.string(), "is the --centres file the run reads"},
           {" --centres " + centres.string() + " --csv-dir " + tables.string(), "is the --centres file the run reads"}}) {
    const auto result = runCliBinary(study + arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << "\n" << result.err;
    EXPECT_NE(result.err.find(refusal), std::string::npos) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  }
  EXPECT_EQ(bytes(alice), alice_bytes);
  EXPECT_EQ(bytes(centres), centres_text);
  EXPECT_FALSE(fs::exists(tables / "participants.csv"));
}

TEST_F(ReviewCli, RefusesTruncatedForeignAndMissingFilesWithOneLine) {
  const fs::path file = writeSession("cut.flexirob", "carol", 0.0);
  fs::resize_file(file, fs::file_size(file) / 2);
  { std::ofstream(dir_ / "foreign.flexirob") << "SQLite format 3 but not really"; }
  for (const fs::path& bad : {file, dir_ / "foreign.flexirob", dir_ / "missing.flexirob"}) {
    const auto result = runCliBinary("review --session " + bad.string());
    EXPECT_NE(result.exit_code, 0) << bad;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_TRUE(result.out.empty()) << result.out;
  }
  const auto empty_study = runCliBinary("review --study " + (dir_ / "nothing").string());
  EXPECT_NE(empty_study.exit_code, 0);
  EXPECT_EQ(empty_study.err.rfind("error: ", 0), 0U) << empty_study.err;
}

// A row SQLite reads but the reader cannot take (a sample's posture of 2 bytes, as a damaged
// disk or a hand edit leaves it): the header and the schema are intact, so the damage shows
// only while the rows are read, and the error names the file.
TEST_F(ReviewCli, ASessionDamagedInsideIsNamedWithOneLine) {
  const fs::path file = writeSession("damaged.flexirob", "dan", 0.0);
  {
    SqliteDatabase database(file.string(), SQLITE_OPEN_READWRITE);
    database.exec("UPDATE sample SET q = x'0102' WHERE id = (SELECT MIN(id) FROM sample)");
  }
  const auto result = runCliBinary("review --session " + file.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_EQ(result.err.rfind("error: session file " + file.string() + " is damaged: ", 0), 0U) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_TRUE(result.out.empty()) << result.out;
}

}  // namespace
}  // namespace flexirob::app
