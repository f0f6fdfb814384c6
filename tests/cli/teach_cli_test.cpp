// `flexirob-cli teach`: the simulated tutor teaches through the direct simulation and through the
// FRI backend against the in-process controller stand-in (`--backend fri-sim`), and writes a
// session; bad backends are refused with one line.
#include <array>
#include <sstream>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <vector>

#include "app/session_schema.hpp"
#include "app/session_write_lock.hpp"
#include "cli_test_support.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"

namespace flexirob {
namespace {

namespace fs = std::filesystem;
using flexirob::testing::runCliBinary;

fs::path scratch(const std::string& name) {
  return fs::temp_directory_path() / ("flexirob-teach-cli-" + std::to_string(::getpid()) + "-" + name);
}

std::string text(const fs::path& file) {
  std::stringstream content;
  content << std::ifstream(file).rdbuf();
  return content.str();
}

TEST(TeachCli, RefusesAnOutputAnotherRunIsStillWriting) {
  const fs::path out = scratch("being-written.db");
  const app::SessionWriteLock other_run(out, "--out");
  const auto result = runCliBinary("teach --backend sim --scene setup_A --areas 1 --seed 3 --out " + out.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("--out: '" + out.string() + "' is being written by another run"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(TeachCli, NeverWritesOverAnExistingFileUnlessToldToAndNeverOverItsOwnScene) {
  const fs::path notes = scratch("notes.db");
  std::ofstream(notes) << "a recording of last week";
  const auto refused = runCliBinary("teach --scene setup_A --areas 1 --seed 3 --out " + notes.string());
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("exists; teach does not write over a file (give --overwrite"), std::string::npos) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_TRUE(refused.out.empty()) << refused.out;
  std::stringstream kept;
  kept << std::ifstream(notes).rdbuf();
  EXPECT_EQ(kept.str(), "a recording of last week");

  // The scene the run reads is refused as its output even with --overwrite.
  const fs::path scene = scratch("own_scene.yaml");
  std::ofstream(scene) << robot::sceneToYaml(robot::loadScene("setup_A"));
  const auto own = runCliBinary("teach --scene " + scene.string() + " --areas 1 --seed 3 --overwrite --out " + scene.string());
  EXPECT_EQ(own.exit_code, 2) << own.err;
  EXPECT_NE(own.err.find("is the scene the run reads"), std::string::npos) << own.err;
  EXPECT_NO_THROW(robot::loadScene(scene.string()));

  // With --overwrite the old file gives way to the session; an upper-case .JSON is JSON.
  const fs::path upper = scratch("S.JSON");
  std::ofstream(upper) << "old";
  const auto replaced = runCliBinary("teach --scene setup_A --areas 1 --seed 3 --check-points 0 --overwrite --out " + upper.string());
  ASSERT_EQ(replaced.exit_code, 0) << replaced.err;
  std::stringstream written;
  written << std::ifstream(upper).rdbuf();
  EXPECT_NE(written.str().find("flexirob-session-json"), std::string::npos);
  // A recording replaces the old file once the run has taught: nothing is left beside it.
  const auto recorded = runCliBinary("teach --scene setup_A --areas 1 --seed 3 --check-points 0 --overwrite --out " + notes.string());
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  EXPECT_NE(recorded.out.find("\"session\": \"" + notes.string() + "\""), std::string::npos) << recorded.out;
  EXPECT_EQ(runCliBinary("review --session " + notes.string()).exit_code, 0);
  EXPECT_FALSE(fs::exists(notes.string() + ".new"));
  fs::remove(notes);
  fs::remove(scene);
  fs::remove(upper);
}

// A session teach recorded in the simulation holds tip positions that are its robot's forward
// kinematics; its stored robot edited to another geometry (the forearm 10 cm longer) no longer
// fits them, and plan refuses it as it refuses such a JSON session, rather than planning the
// other arm to positions taught with this one.
TEST(TeachCli, ASimulatedSessionWhoseStoredRobotWasEditedIsRefused) {
  const fs::path out = scratch("edited_robot.flexirob");
  const auto taught = runCliBinary("teach --scene setup_A --areas 1 --seed 3 --check-points 0 --out " + out.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  const auto intact = runCliBinary("plan --session " + out.string() + " --goals 1 --seed 1");
  ASSERT_EQ(intact.exit_code, 0) << intact.err;
  {
    app::SqliteDatabase db(out.string(), 0x00000002);  // SQLITE_OPEN_READWRITE
    db.exec("UPDATE meta SET value = replace(value, '<origin xyz=\"0 0 0.3900\"', '<origin xyz=\"0 0 0.4900\"') "
            "WHERE key = 'robot_urdf'");
    ASSERT_NE(db.queryText("SELECT value FROM meta WHERE key = 'robot_urdf'").find("0 0 0.4900"), std::string::npos);
  }
  const auto edited = runCliBinary("plan --session " + out.string() + " --goals 1 --seed 1");
  EXPECT_EQ(edited.exit_code, 2) << edited.err;
  EXPECT_NE(edited.err.find("from where its joint values put the tip"), std::string::npos) << edited.err;
  EXPECT_NE(edited.err.find("differs from the copy the session stores"), std::string::npos) << edited.err;
  fs::remove(out);
}

// A mistaken re-run with --overwrite, stopped before it taught anything, must not cost the
// recording it was about to replace (paced at wall-clock speed: 2 s teach nothing).
TEST(TeachCli, AnOverwritingRunStoppedBeforeItTaughtLeavesTheEarlierFileAsItWas) {
  const fs::path out = scratch("earlier.flexirob");
  const fs::path err = scratch("earlier.err"), code = scratch("earlier.code");
  std::ofstream(out) << "last week's recording";
  const std::string script = std::string(FLEXIROB_CLI_EXECUTABLE) + " teach --scene setup_I --areas 12 --seed 1 --realtime --overwrite --out " +
                             out.string() + " > /dev/null 2> " + err.string() + " & p=$!; sleep 2; kill -TERM $p; wait $p; echo $? > " +
                             code.string();
  ASSERT_EQ(std::system(("sh -c '" + script + "'").c_str()), 0);
  EXPECT_EQ(text(code), "143\n") << text(err);
  EXPECT_NE(text(err).find("(0 of 12 areas, 0 samples) was not written; '" + out.string() + "' was left as it was (nothing was taught)"),
            std::string::npos)
      << text(err);
  EXPECT_TRUE(text(out) == "last week's recording");  // not printed: it may be a database
  EXPECT_FALSE(fs::exists(out.string() + ".new"));
  EXPECT_FALSE(fs::exists(out.string() + ".new-wal"));
  for (const fs::path& file : {out, err, code}) fs::remove(file);
}

// The output's folder deleted while the run teaches: what was taught is kept in a copy in the
// temporary directory, named with the failure (exit 1: the command ran), not lost with an error
// of bad input (JSON) or reported as written to a file nobody can open (SQLite).
TEST(TeachCli, AnOutputFolderRemovedDuringTheRunLeavesTheSessionInACopy) {
  for (const std::string name : {"v.json", "v.flexirob"}) {
    const fs::path folder = scratch("vanishing-" + name);
    const fs::path out = folder / name, json = scratch("vanishing.out"), err = scratch("vanishing.err"), code = scratch("vanishing.code");
    fs::create_directories(folder);
    // The run's lock first, then (SQLite) the database and its journal: the folder goes once
    // the database writes (before that, a journal that cannot be created is another failure).
    const bool json_session = name == "v.json";
    const fs::path waited = json_session ? fs::path(out.string() + ".lock") : fs::path(out.string() + "-wal");
    const std::string script = std::string(FLEXIROB_CLI_EXECUTABLE) + " teach --scene setup_I --areas 3 --seed 1 --out " + out.string() +
                               " > " + json.string() + " 2> " + err.string() + " & p=$!; for i in $(seq 600); do [ -e " + waited.string() +
                               " ] && break; sleep 0.02; done; mv " + folder.string() + " " + folder.string() + ".gone; rm -rf " +
                               folder.string() + ".gone; wait $p; echo $? > " + code.string();
    ASSERT_EQ(std::system(("sh -c '" + script + "'").c_str()), 0);
    EXPECT_EQ(text(code), "1\n") << name << ": " << text(err);
    const nlohmann::json result = nlohmann::json::parse(text(json));
    EXPECT_TRUE(result.at("session").is_null()) << result.dump();
    const std::string copy = result.at("session_copy").get<std::string>();
    EXPECT_NE(text(err).find("the whole session was saved to " + copy), std::string::npos) << text(err);
    if (!json_session) {
      EXPECT_NE(text(err).find("was removed or replaced while the run recorded"), std::string::npos) << text(err);
    }
    int areas_in_copy = -1;
    if (json_session) {
      areas_in_copy = static_cast<int>(nlohmann::json::parse(text(copy)).at("areas").size());
    } else {
      const auto review = runCliBinary("review --session " + copy);
      ASSERT_EQ(review.exit_code, 0) << review.err;
      areas_in_copy = review.json().at("areas").get<int>();
    }
    EXPECT_EQ(areas_in_copy, result.at("areas").get<int>()) << name;
    EXPECT_GT(areas_in_copy, 0) << name;
    // A finished session stands alone: its readers leave nothing beside it.
    EXPECT_FALSE(fs::exists(copy + "-wal")) << name;
    EXPECT_FALSE(fs::exists(copy + "-shm")) << name;
    for (const fs::path& file : {fs::path(copy), fs::path(copy + "-wal"), fs::path(copy + "-shm"), json, err, code}) fs::remove(file);
  }
}

TEST(TeachCli, StoppedBySigtermWritesWhatWasRecordedAndSaysSo) {
  const fs::path out = scratch("interrupted.db");
  const fs::path json = scratch("interrupted.json"), err = scratch("interrupted.err"), code = scratch("interrupted.code");
  // The run would take tens of seconds; SIGTERM once its first area is stored (the progress line
  // past 0 %; a run stopped before that writes nothing). SIGINT, Ctrl-C, takes the same way, but a
  // job started in the background by a shell ignores it.
  const std::string script = "FLEXIROB_PROGRESS=1 " + std::string(FLEXIROB_CLI_EXECUTABLE) + " teach --scene setup_I --areas 12 --seed 1 --out " +
                             out.string() + " > " + json.string() + " 2> " + err.string() +
                             " & p=$!; for i in $(seq 1200); do grep -qE \"teach: +[1-9]\" " + err.string() +
                             " && break; sleep 0.05; done; kill -TERM $p; wait $p; echo $? > " + code.string();
  ASSERT_EQ(std::system(("sh -c '" + script + "'").c_str()), 0);
  EXPECT_EQ(text(code), "143\n") << text(err);
  EXPECT_NE(text(err).find("error: teach: stopped by SIGTERM after"), std::string::npos) << text(err);
  // The wall time the signal came after, the simulated time beside it, each named.
  EXPECT_NE(text(err).find(" s of simulated teaching); what was recorded"), std::string::npos) << text(err);
  EXPECT_NE(text(err).find("was written to " + out.string()), std::string::npos) << text(err);
  EXPECT_NE(text(json).find("\"interrupted\": true"), std::string::npos) << text(json);
  // The session was closed as at the end of a run: one file, readable, closed cleanly.
  EXPECT_FALSE(fs::exists(out.string() + "-wal"));
  const auto review = runCliBinary("review --session " + out.string());
  ASSERT_EQ(review.exit_code, 0) << review.err;
  EXPECT_NE(review.out.find("\"closed_cleanly\": true"), std::string::npos) << review.out;
  for (const fs::path& file : {out, json, err, code}) fs::remove(file);
}

// Before the first area the tutor draws check points where some posture reaches (Sect. 3.3.2);
// an arm whose first joint turns 0.2 rad reaches little of its grid, and each miss is a search of
// 24 IK runs: minutes. A stop asked for meanwhile ends the command within seconds, not after the
// search, and the progress line it interrupted is ended before the error.
TEST(TeachCli, AStopEndsTheSearchForCheckPointsAtOnce) {
  const fs::path robot = scratch("wedge.urdf"), scene = scratch("wedge.yaml"), out = scratch("wedge.flexirob");
  const fs::path err = scratch("wedge.err"), code = scratch("wedge.code");
  std::ofstream(robot) << R"(<robot name="wedge">
  <link name="base"><visual><geometry><cylinder radius="0.06" length="0.3"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit lower="-0.1" upper="0.1" velocity="2" effort="100"/></joint>
  <link name="l1"><inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" velocity="2" effort="100"/></joint>
  <link name="l2"><inertial><origin xyz="0 0 0.15"/><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></visual></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" velocity="2" effort="100"/></joint>
  <link name="l3"><inertial><origin xyz="0 0 0.15"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.03" length="0.3"/></geometry></visual></link>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" velocity="2" effort="100"/></joint>
  <link name="l4"><inertial><origin xyz="0 0 0.05"/><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="tool" type="fixed"><parent link="l4"/><child link="tip"/><origin xyz="0 0 0.1"/></joint>
  <link name="tip"/>
</robot>
)";
  std::ofstream(scene) << "name: wedge\nrobot: " << robot.filename().string()
                       << "\ngrid: {lower: [-0.6, -0.6, 0.1], upper: [0.6, 0.6, 0.8], spacing: 0.1}\n";
  // SIGTERM a second into the search; then at most 15 s for the command to end.
  const std::string script =
      "FLEXIROB_PROGRESS=1 " + std::string(FLEXIROB_CLI_EXECUTABLE) + " teach --scene " + scene.string() +
      " --areas 3 --check-points 1000 --seed 1 --out " + out.string() + " > /dev/null 2> " + err.string() +
      " & p=$!; for i in $(seq 600); do grep -q \"check points\" " + err.string() +
      " && break; sleep 0.1; done; sleep 1; kill -TERM $p; for i in $(seq 150); do kill -0 $p 2>/dev/null || break; sleep 0.1; "
      "done; if kill -0 $p 2>/dev/null; then kill -KILL $p; wait $p; echo late > " + code.string() + "; else wait $p; echo $? > " +
      code.string() + "; fi";
  ASSERT_EQ(std::system(("sh -c '" + script + "'").c_str()), 0);
  EXPECT_EQ(text(code), "143\n") << text(err);
  const std::string said = text(err);
  EXPECT_NE(said.find("\nerror: teach: stopped by SIGTERM"), std::string::npos) << said;
  // Nothing taught: no file that would refuse the run started again (--out exists).
  EXPECT_NE(said.find("(0 of 3 areas, 0 samples) was not written (nothing was taught)"), std::string::npos) << said;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out.string() + "-wal"));
  for (const fs::path& file : {robot, scene, out, err, code}) fs::remove(file);
}

TEST(TeachCli, TeachesOneAreaOverTheFriLinkWithNothingLost) {
  const fs::path out = scratch("fri.json");
  const auto result = runCliBinary("teach --backend fri-sim --scene setup_A --areas 1 --seed 3 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("backend"), "fri-sim");
  EXPECT_EQ(json.at("areas").get<int>(), 1);
  EXPECT_GT(json.at("samples").get<int>(), 100);
  EXPECT_TRUE(json.at("model_learned").get<bool>());
  EXPECT_EQ(json.at("collisions").get<int>(), 0);
  const auto& link = json.at("fri_link");
  // One measurement per simulated millisecond, each answered, none lost, no fault.
  const double simulated_ms = 1e3 * json.at("simulated_time_s").get<double>();
  EXPECT_NEAR(link.at("measurements").get<double>(), simulated_ms, 0.01 * simulated_ms);
  EXPECT_EQ(link.at("lost_measurements").get<int>(), 0);
  EXPECT_EQ(link.at("watchdog_trips").get<int>(), 0);
  EXPECT_EQ(link.at("commands_rejected").get<int>(), 0);
  EXPECT_EQ(link.at("commands_refused_by_controller").get<int>(), 0);
  EXPECT_GT(link.at("commands_applied_by_controller").get<double>(), 0.9 * simulated_ms);
  EXPECT_TRUE(fs::exists(out));
  fs::remove(out);
}

TEST(TeachCli, TheSameSeedTeachesTheSameAreaOnBothBackends) {
  const fs::path sim_out = scratch("sim.json");
  const fs::path fri_out = scratch("fri2.json");
  const auto sim = runCliBinary("teach --backend sim --scene setup_A --areas 1 --seed 3 --out " + sim_out.string());
  const auto fri = runCliBinary("teach --backend fri-sim --scene setup_A --areas 1 --seed 3 --out " + fri_out.string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  ASSERT_EQ(fri.exit_code, 0) << fri.err;
  EXPECT_TRUE(sim.json().at("fri_link").is_null());
  // The tutor chooses the same posture and leads the arm there through either path; the FRI
  // link adds a cycle of delay, not a different teaching.
  const auto read = [](const fs::path& file) {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
  };
  const auto sim_session = read(sim_out);
  const auto fri_session = read(fri_out);
  ASSERT_EQ(sim_session.at("areas").size(), 1U);
  ASSERT_EQ(fri_session.at("areas").size(), 1U);
  // The session names the area as the scene and the tutor's report do.
  EXPECT_EQ(sim_session.at("areas")[0].at("name"), sim.json().at("tutor").at(0).at("name"));
  EXPECT_EQ(sim_session.at("areas")[0].at("name"), robot::loadScene("setup_A").training_areas.at(0).name);
  const auto q_sim = sim_session.at("areas")[0].at("q_fixed").get<std::vector<double>>();
  const auto q_fri = fri_session.at("areas")[0].at("q_fixed").get<std::vector<double>>();
  ASSERT_EQ(q_sim.size(), 7U);
  ASSERT_EQ(q_fri.size(), 7U);
  for (std::size_t j = 0; j < 7; ++j) EXPECT_NEAR(q_sim[j], q_fri[j], 0.02) << "joint " << j + 1;
  fs::remove(sim_out);
  fs::remove(fri_out);
}

TEST(TeachCli, RefusesAnUnknownBackendFriForTheNineJointArmAndAHelixUnderACentimetreWithOneLine) {
  for (const std::string arguments : {"teach --backend carrier-pigeon --scene setup_A --areas 1",
                                      "teach --backend fri-sim --robot arm9 --scene arm9_areas --areas 1",
                                      "teach --scene setup_A --areas 1 --diameter 0.005"}) {
    const auto result = runCliBinary(arguments + " --out " + scratch("refused.json").string());
    EXPECT_NE(result.exit_code, 0) << arguments;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(fs::exists(scratch("refused.json")));
  }
}

// A scene's posture for an area is where the tutor's search starts; it shows the posture nearest
// where the arm stands (here A7 turned 2.5 rad, which does not move the tip) and says so, or,
// with --scene-postures, the scene's own (A7 at 0).
TEST(TeachCli, ShowsTheScenesPostureWhenAskedAndSaysWhenItShowedAnother) {
  const fs::path scene = scratch("scene-postures.yaml");
  std::ofstream(scene) << "name: scene_postures\n"
                          "home_posture: [0, 0.6, 0, -1.6, 0, 0.9, 2.5]\n"
                          "training_areas:\n"
                          "  - {name: front, centre: [-0.5, 0.25, 0.3], posture: [-0.3073, 0.6386, -0.1907, -1.6904, -0.0092, 0.3138, 0.0]}\n";
  const std::vector<double> suggested{-0.3073, 0.6386, -0.1907, -1.6904, -0.0092, 0.3138, 0.0};
  const auto offset = [&suggested](const nlohmann::json& posture) {
    double sum = 0.0;
    for (std::size_t j = 0; j < suggested.size(); ++j) sum += std::pow(posture.at(j).get<double>() - suggested[j], 2);
    return std::sqrt(sum);
  };
  for (const bool follow : {false, true}) {
    const fs::path out = scratch(follow ? "followed.json" : "nearest.json");
    const auto result = runCliBinary("teach --scene " + scene.string() + " --areas 1 --seed 1 --out " + out.string() +
                                     (follow ? " --scene-postures" : ""));
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json area = result.json().at("tutor").at(0);
    ASSERT_TRUE(area.at("taught").get<bool>()) << area.dump();
    const nlohmann::json& posture = area.at("posture");
    ASSERT_EQ(posture.size(), 7U);
    EXPECT_NEAR(area.at("scene_posture_offset_rad").get<double>(), offset(posture), 1e-9);
    if (follow) {
      EXPECT_LT(offset(posture), 0.05) << posture.dump();
      EXPECT_EQ(result.err.find("--scene-postures shows the scene's"), std::string::npos) << result.err;
    } else {
      EXPECT_NEAR(posture.at(6).get<double>(), 2.5, 0.05) << posture.dump();
      EXPECT_NE(result.err.find("note: 1 of the 1 taught areas with a posture in the scene were shown in another"), std::string::npos)
          << result.err;
    }
    fs::remove(out);
  }
  fs::remove(scene);
}

// The grid's exclude box covers the whole workspace: the tutor teaches the listed area and finds
// no place of its own to add, and says so instead of teaching inside the excluded box.
TEST(TeachCli, TeachesNoPlaceOfItsOwnInsideTheGridsExcludedBoxes) {
  const fs::path scene = scratch("excluded.yaml");
  const fs::path out = scratch("excluded.json");
  std::ofstream(scene) << "name: excluded\n"
                          "training_areas:\n  - {name: L, centre: [-0.5, 0.3, 0.3]}\n"
                          "grid: {lower: [-0.8, -0.5, 0.05], upper: [0, 0.5, 0.7], spacing: 0.15,"
                          " exclude: [{lower: [-1, -1, 0], upper: [1, 1, 1]}]}\n";
  const auto result = runCliBinary("teach --scene " + scene.string() + " --areas 2 --seed 1 --check-points 0 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("areas").get<int>(), 1);
  ASSERT_EQ(json.at("tutor").size(), 2U);
  EXPECT_FALSE(json.at("tutor").at(1).at("taught").get<bool>());
  // An area never taught has no posture whose clearance could be 0 m ("touching").
  EXPECT_TRUE(json.at("tutor").at(1).at("clearance_m").is_null()) << json.at("tutor").at(1).dump();
  const auto& taught_clearance = json.at("tutor").at(0).at("clearance_m");
  EXPECT_TRUE(taught_clearance.is_null() || taught_clearance.get<double>() > 0.0) << taught_clearance;
  // Every random point is counted under why it was passed over: here the excluded box, for
  // all 200 (beyond the box the arm cannot reach them either, so the box is what is said).
  const std::string failure = json.at("tutor").at(1).at("failure").get<std::string>();
  EXPECT_NE(failure.find("no place of its own found: of 200 random points of the evaluation grid, 200 in an excluded box"),
            std::string::npos)
      << failure;
  fs::remove(scene);
  fs::remove(out);
}

// A scene where no posture keeps its distance (walls 0.2 m around the robot's axis): teach ends
// with exit code 1 and one line saying why, and still writes the session and its JSON report,
// so a script sees the failure and nothing of the attempt is lost.
TEST(TeachCli, FailsWithOneLineWhenNoAreaCouldBeTaughtAndStillWritesTheSession) {
  const fs::path scene = scratch("cage.yaml");
  const fs::path out = scratch("cage.json");
  std::ofstream(scene) << "name: cage\nobstacles:\n"
                          "  - {name: front, shape: box, size: [0.05, 1.0, 1.5], position: [-0.25, 0, 0.75]}\n"
                          "  - {name: back, shape: box, size: [0.05, 1.0, 1.5], position: [0.25, 0, 0.75]}\n"
                          "  - {name: left, shape: box, size: [0.5, 0.05, 1.5], position: [0, 0.25, 0.75]}\n"
                          "  - {name: right, shape: box, size: [0.5, 0.05, 1.5], position: [0, -0.25, 0.75]}\n"
                          "training_areas:\n  - {name: far, centre: [-0.7, 0, 0.3], radius: 0.08}\n";
  const auto result = runCliBinary("teach --scene " + scene.string() + " --areas 1 --seed 1 --candidates 2 --check-points 0 --out " +
                                   out.string());
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(result.err.rfind("error: teach: no training area could be taught", 0), 0U) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  // The listed place and the one the tutor looked for itself, each failure by kind.
  EXPECT_NE(result.err.find("(2 tried: 1 × every posture found that reaches it makes a contact, 1 × no place of its own found; "
                            "the first: "),
            std::string::npos)
      << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("areas").get<int>(), 0);
  EXPECT_FALSE(json.at("model_learned").get<bool>());
  ASSERT_FALSE(json.at("tutor").empty());
  EXPECT_EQ(json.at("tutor").at(0).at("name"), "far");
  EXPECT_FALSE(json.at("tutor").at(0).at("taught").get<bool>());
  EXPECT_EQ(json.at("tutor").at(0).at("assistance_lead_m").get<double>(), 0.0);  // π_q: nothing to lead out of
  EXPECT_TRUE(fs::exists(out));
  fs::remove(out);
  fs::remove(scene);
}

// A scene names the robot it was made for: without --robot, teach uses it; the session names
// the scene file by its absolute path, so eval finds it from another working directory.
TEST(TeachCli, TeachesTheScenesRobotAndTheSessionResolvesFromAnyFolder) {
  const fs::path scene = scratch("nine.yaml");
  const fs::path out = scratch("nine.json");
  std::ofstream(scene) << "name: nine\nrobot: arm9\n"
                          "home_posture: [0, 0.0705, 0, -1.2312, 0, -1.3737, 0, 0.9916, 0]\n"
                          "training_areas:\n  - {name: front, centre: [0.45, 0.0, 0.75], radius: 0.08}\n";
  const fs::path relative_scene = fs::relative(scene, fs::current_path());
  ASSERT_TRUE(relative_scene.is_relative());
  const auto result = runCliBinary("teach --scene " + relative_scene.string() + " --areas 1 --seed 1 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  std::ifstream in(out);
  const auto session = nlohmann::json::parse(in);
  EXPECT_EQ(session.at("robot"), "arm9");
  EXPECT_EQ(session.at("dof").get<int>(), 9);
  EXPECT_EQ(fs::path(session.at("scene").get<std::string>()), fs::absolute(scene).lexically_normal());
  const auto reachable = runCliBinary("eval reachable --spacing 0.3 --session " + out.string());
  EXPECT_EQ(reachable.exit_code, 0) << reachable.err;
  // Each target from the nearest posture the arm stood in (a target reached, a sample), unless told otherwise.
  EXPECT_EQ(nlohmann::json::parse(reachable.out).at("approach"), "visited");
  fs::remove(out);
  fs::remove(scene);
}

// An area the tip cannot get to at all (beside the base, inside the joint limits' hole) and one
// it reaches only touching something (between two slabs 2 cm apart) are given up with
// different reasons: the tutor tells the person which it is.
TEST(TeachCli, SaysWhetherAnAreaIsBeyondTheJointsOrOnlyReachedWithAContact) {
  const fs::path scene = scratch("reasons.yaml");
  const fs::path out = scratch("reasons.json");
  std::ofstream(scene) << "name: reasons\n"
                          "training_areas:\n"
                          "  - {name: hole, centre: [-0.12, 0, 0.12], radius: 0.05}\n"
                          "  - {name: pressed, centre: [-0.5, 0, 0.215], radius: 0.05}\n"
                          "obstacles:\n"
                          "  - {name: slab, shape: box, size: [0.3, 0.3, 0.02], position: [-0.5, 0, 0.2]}\n"
                          "  - {name: lid, shape: box, size: [0.3, 0.3, 0.02], position: [-0.5, 0, 0.24]}\n";
  const auto result = runCliBinary("teach --scene " + scene.string() + " --areas 2 --seed 1 --candidates 4 --check-points 0 --out " +
                                   out.string());
  ASSERT_FALSE(result.out.empty()) << result.err;
  const auto tutor = result.json().at("tutor");
  ASSERT_GE(tutor.size(), 2U);
  EXPECT_EQ(tutor.at(0).at("name"), "hole");
  EXPECT_FALSE(tutor.at(0).at("taught").get<bool>());
  EXPECT_EQ(tutor.at(0).at("failure").get<std::string>().rfind("no posture within the joint limits puts the tip there", 0), 0U)
      << tutor.at(0).at("failure");
  EXPECT_EQ(tutor.at(1).at("name"), "pressed");
  EXPECT_FALSE(tutor.at(1).at("taught").get<bool>());
  EXPECT_EQ(tutor.at(1).at("failure").get<std::string>(), "every posture found that reaches it makes a contact");
  // Each of the scene's areas given up is said on stderr, though places of the tutor's own made
  // the count up.
  EXPECT_NE(result.err.find("warning: the scene's area 'hole' was not taught: no posture within the joint limits"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("warning: the scene's area 'pressed' was not taught: every posture found that reaches it makes a contact\n"),
            std::string::npos)
      << result.err;
  // The tutor's warnings are said, not only counted.
  const auto lines = result.json().at("warning_lines");
  ASSERT_FALSE(lines.empty()) << "the replacement areas lie near a joint limit";
  EXPECT_EQ(lines.size(), result.json().at("warnings").get<std::size_t>());
  // The scene's areas given up are among the lines the count counts.
  EXPECT_EQ(std::count_if(lines.begin(), lines.end(),
                          [](const auto& line) { return line.template get<std::string>().rfind("the scene's area '", 0) == 0; }),
            2);
  for (const auto& line : lines) {
    EXPECT_NE(result.err.find("warning: " + line.get<std::string>() + "\n"), std::string::npos) << result.err;
  }
  fs::remove(out);
  fs::remove(scene);
}

// A place of the tutor's own 5 cm in front of the robot's torso (two arms on a torso, the right
// one taught): every π_rec posture of even a 2 cm helix there came within 1.5 cm of the torso,
// and the wrist touched it while recording (2 contacts). The tutor now leaves such a place for
// a roomier one, as a person picking a place would.
TEST(TeachCli, LeavesAPlaceOfItsOwnWithoutRoomForAHelixBesideTheRobotsTorso) {
  const fs::path urdf = fs::path(FLEXIROB_TEST_DATA_DIR) / "robots" / "two_arms_on_a_torso.urdf";
  const fs::path out = scratch("torso.json");
  const auto result = runCliBinary("teach --robot " + urdf.string() + " --tip R_iiwa_link_ee --scene empty --areas 2 --seed 1 --out " +
                                   out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("collisions").get<int>(), 0) << json.at("collision_events").dump();
  EXPECT_EQ(json.at("areas").get<int>(), 2);
  bool left = false;
  for (const auto& area : json.at("tutor")) {
    if (area.at("automatic").get<bool>() && !area.at("taught").get<bool>() &&
        area.at("failure").get<std::string>().rfind("no room there for even a 2.0 cm helix", 0) == 0) {
      left = true;
    }
  }
  EXPECT_TRUE(left) << json.at("tutor").dump();
  fs::remove(out);
}

// A 6-joint arm of 0.3 m reach (joints about z, y, y, z, y, z), light links and capsules of 1.5 cm.
std::string smallArmUrdf() {
  const std::array<const char*, 6> axes{"0 0 1", "0 1 0", "0 1 0", "0 0 1", "0 1 0", "0 0 1"};
  const std::array<double, 6> lengths{0.05, 0.12, 0.1, 0.04, 0.04, 0.03};
  std::ostringstream urdf;
  urdf << "<?xml version=\"1.0\"?>\n<robot name=\"small\">\n  <link name=\"base\"/>\n";
  double offset = 0.03;
  for (std::size_t j = 0; j < axes.size(); ++j) {
    const std::string parent = j == 0 ? "base" : "l" + std::to_string(j);
    const std::string child = "l" + std::to_string(j + 1);
    urdf << "  <joint name=\"j" << j + 1 << "\" type=\"revolute\"><parent link=\"" << parent << "\"/><child link=\"" << child
         << "\"/><origin xyz=\"0 0 " << offset << "\"/><axis xyz=\"" << axes[j]
         << "\"/><limit lower=\"-2.9\" upper=\"2.9\" velocity=\"1.5\" effort=\"20\"/></joint>\n"
         << "  <link name=\"" << child << "\"><inertial><origin xyz=\"0 0 " << lengths[j] / 2 << "\"/><mass value=\"0.3\"/>"
         << "<inertia ixx=\"0.001\" ixy=\"0\" ixz=\"0\" iyy=\"0.001\" iyz=\"0\" izz=\"0.0005\"/></inertial>"
         << "<collision><origin xyz=\"0 0 " << lengths[j] / 2 << "\"/><geometry><cylinder radius=\"0.015\" length=\""
         << lengths[j] << "\"/></geometry></collision></link>\n";
    offset = lengths[j];
  }
  urdf << "</robot>\n";
  return urdf.str();
}

TEST(TeachCli, TeachesASmallArmInAWorkspaceBoxMostlyBeyondItsReach) {
  const fs::path robot = scratch("small_arm.urdf");
  flexirob::testing::writeText(robot, smallArmUrdf());
  const fs::path out = scratch("small_arm.json");
  const auto result = runCliBinary("teach --robot " + robot.string() + " --scene empty --areas 2 --seed 1 --check-points 0 --out " +
                                   out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("areas"), 2);
  // Every place the tutor tried lies within the arm's reach, and the arm took every touch.
  std::vector<std::string> taught;
  for (const auto& area : json.at("tutor")) {
    EXPECT_TRUE(area.at("taught").get<bool>()) << area.dump();
    if (area.at("taught").get<bool>()) taught.push_back(area.at("name").get<std::string>());
  }
  // The transition checks name the areas they index (the taught ones, not the tutor's attempts).
  ASSERT_FALSE(json.at("transition_checks").empty());
  for (const auto& check : json.at("transition_checks")) {
    EXPECT_EQ(check.at("from_name").get<std::string>(), taught.at(check.at("from").get<std::size_t>()));
    EXPECT_EQ(check.at("to_name").get<std::string>(), taught.at(check.at("to").get<std::size_t>()));
  }
  fs::remove(robot);
  fs::remove(out);
}

TEST(TeachCli, RefusesASceneWhosePosturesBelongToAnotherRobotWithOneLine) {
  const auto result = runCliBinary("teach --robot lwr4 --scene arm9_areas --areas 1 --out " + scratch("mismatch.json").string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
  EXPECT_NE(result.err.find("home_posture has 9 joint values, the robot 'lwr4' has 7 joints"), std::string::npos) << result.err;
  // The joint count is the chain's to the tip, which --tip can change: both ends said.
  EXPECT_NE(result.err.find("the robot's chain runs from 'base_link' to the tip 'flange' (--tip chooses another tip)"), std::string::npos)
      << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(fs::exists(scratch("mismatch.json")));
}

// A home posture that puts a link into an obstacle is refused before anything is taught; the
// session file the run had opened went with it, so the corrected run is not told --out exists.
TEST(TeachCli, RefusesAStartPostureInAnObstacleAndLeavesNoSessionBehind) {
  const fs::path scene = scratch("start_in_box.yaml");
  std::ofstream(scene) << "name: start_in_box\nhome_posture: [0, 0, 0, 0, 0, 0, 0]\n"
                          "obstacles:\n  - {name: post, shape: box, size: [0.2, 0.2, 0.2], position: [0.12, 0, 0.6]}\n";
  const fs::path out = scratch("start_in_box.flexirob");
  fs::remove(out);
  const auto result = runCliBinary("teach --robot lwr4 --scene " + scene.string() + " --areas 1 --out " + out.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("into post"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(out)) << "a refused run leaves no session";
  const auto again = runCliBinary("teach --robot lwr4 --scene " + scene.string() + " --areas 1 --out " + out.string());
  EXPECT_NE(again.err.find("into post"), std::string::npos) << "the same reason, not '--out exists': " << again.err;
  fs::remove(scene);
}

TEST(TeachCli, RefusesADirectoryAsTheSessionFileBeforeTeaching) {
  const fs::path folder = scratch("sessions_folder");
  fs::create_directories(folder);
  for (const fs::path& out : {folder, folder / "."}) {
    const auto result = runCliBinary("teach --scene setup_A --areas 1 --out " + out.string());
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find("is a directory"), std::string::npos) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_TRUE(result.out.empty()) << "refused before any teaching: " << result.out;
  }
  fs::remove_all(folder);
}

TEST(TeachCli, RefusesASessionFileInAMissingFolderBeforeTeaching) {
  const fs::path out = scratch("no_such_folder") / "deeper" / "s.db";
  const auto result = runCliBinary("teach --scene setup_A --areas 1 --out " + out.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("does not exist"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_TRUE(result.out.empty()) << "refused before any teaching: " << result.out;
  const auto render = runCliBinary("render --robot lwr4 --width 64 --height 48 --out " + (out.parent_path() / "x.png").string());
  EXPECT_EQ(render.exit_code, 2) << render.err;
  EXPECT_NE(render.err.find("does not exist"), std::string::npos) << render.err;
  // A file where the folder should be is named as such.
  const fs::path file = scratch("a_file.txt");
  std::ofstream(file) << "notes";
  const auto under_file = runCliBinary("teach --scene setup_A --areas 1 --out " + (file / "s.db").string());
  EXPECT_EQ(under_file.exit_code, 2) << under_file.err;
  EXPECT_NE(under_file.err.find("'" + file.string() + "' is a file, not a folder"), std::string::npos) << under_file.err;
  fs::remove(file);
}


TEST(TeachCli, CountsAnArmThatCannotHoldItselfUpAtItsStartAmongItsWarnings) {
  // The LWR IV with every joint limited to 3 Nm, drawn as capsules (no meshes to resolve): its
  // shoulder needs about 32 Nm to hold setup_A's start posture, which leans forward.
  std::ifstream in(resolveRobotPath("lwr4"));
  std::stringstream text;
  text << in.rdbuf();
  std::string urdf = std::regex_replace(text.str(), std::regex(R"(<visual>[\s\S]*?</visual>|<collision>[\s\S]*?</collision>)"), "");
  urdf = std::regex_replace(urdf, std::regex(R"(effort="[0-9.]+")"), "effort=\"3\"");
  const fs::path robot = scratch("weak-lwr4.urdf");
  flexirob::testing::writeText(robot, urdf);
  const fs::path out = scratch("weak.flexirob");
  const auto result = runCliBinary("teach --robot " + robot.string() + " --scene setup_A --areas 1 --seed 1 --check-points 0 --out " +
                                   out.string());
  fs::remove(robot);
  fs::remove(out);
  // Nothing can be taught with it (exit 1), and the JSON still counts what the tutor was told.
  EXPECT_EQ(result.exit_code, 1) << result.err;
  const nlohmann::json json = result.json();
  const nlohmann::json lines = json.at("warning_lines");
  ASSERT_FALSE(lines.empty()) << result.out;
  EXPECT_EQ(json.at("warnings").get<std::size_t>(), lines.size());
  EXPECT_NE(lines.front().get<std::string>().find("cannot hold itself up at its start posture"), std::string::npos) << lines.front();
  EXPECT_NE(lines.front().get<std::string>().find("of its effort limit of 3.0 Nm"), std::string::npos) << lines.front();
  EXPECT_NE(result.err.find("warning: the arm cannot hold itself up"), std::string::npos) << result.err;
}

}  // namespace
}  // namespace flexirob
