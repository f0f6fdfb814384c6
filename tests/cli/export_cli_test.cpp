// `flexirob-cli export`: a session taught by `teach` handed to the offline tools. The exported
// configuration stream maps to the session's own ITM graph under `itm build`, the training
// samples fit under `learn fit` with the session's sample count and are the forward kinematics
// of their postures, the model and graph files are read by `learn predict` and `itm path`; bad
// requests are refused with one line and write nothing.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <unistd.h>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/session_recorder.hpp"
#include "app/session_schema.hpp"
#include "app/table_text.hpp"
#include "cli_test_support.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

namespace flexirob {
namespace {

namespace fs = std::filesystem;
using testing::runCliBinary;

fs::path scratchDir() { return testing::scratchDir("export-cli-test"); }

std::vector<std::string> lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::string fileBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// One area of setup_A, taught once for the whole suite.
class ExportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    session_ = new fs::path(scratchDir() / "taught.flexirob");
    const auto taught = runCliBinary("teach --scene setup_A --areas 1 --seed 3 --check-points 0 --out " + session_->string());
    ASSERT_EQ(taught.exit_code, 0) << taught.err;
    taught_ = new nlohmann::json(taught.json());
  }
  static void TearDownTestSuite() {
    delete session_;
    delete taught_;
  }
  static fs::path* session_;
  static nlohmann::json* taught_;
};
fs::path* ExportCli::session_ = nullptr;
nlohmann::json* ExportCli::taught_ = nullptr;

// itm build on the exported stream, with the parameters export prints, against the graph the
// session recorded: the same file, node for node, posture for posture.
void expectTheStreamRebuildsTheSessionsGraph(const fs::path& session) {
  const std::string name = session.stem().string();
  const fs::path stream = scratchDir() / (name + "-stream.csv");
  const fs::path graph_file = scratchDir() / (name + "-as-taught.itm");
  const fs::path rebuilt_file = scratchDir() / (name + "-rebuilt.itm");
  const auto exported = runCliBinary("export --session " + session.string() + " --stream " + stream.string() + " --graph " +
                                     graph_file.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const nlohmann::json entry = exported.json().at("stream");
  EXPECT_TRUE(entry.at("rebuilds_session_graph").get<bool>());
  EXPECT_EQ(lines(stream).front(), "x,y,z,q1,q2,q3,q4,q5,q6,q7");
  EXPECT_EQ(static_cast<int>(lines(stream).size()) - 1, entry.at("rows").get<int>());
  EXPECT_GT(entry.at("rows").get<int>(), 100);

  const nlohmann::json graph = entry.at("session_graph");
  // The arguments export prints, as a user pastes them.
  const std::string arguments = graph.at("itm_build_arguments").get<std::string>();
  EXPECT_NE(arguments.find("--variant " + graph.at("variant").get<std::string>()), std::string::npos) << arguments;
  EXPECT_NE(arguments.find("--delta " + std::to_string(graph.at("parameters").at("delta").get<int>())), std::string::npos) << arguments;
  const auto rebuilt = runCliBinary("itm build --data " + stream.string() + " --out " + rebuilt_file.string() + " " + arguments);
  ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.err;
  EXPECT_EQ(rebuilt.json().at("samples").get<int>(), entry.at("rows").get<int>());
  EXPECT_EQ(rebuilt.json().at("nodes").get<int>(), graph.at("nodes").get<int>());
  EXPECT_EQ(rebuilt.json().at("edges").get<int>(), graph.at("edges").get<int>());
  EXPECT_EQ(fileBytes(rebuilt_file), fileBytes(graph_file)) << session;
}

TEST_F(ExportCli, TheStreamMapsToTheSessionsOwnGraphUnderItmBuild) {
  expectTheStreamRebuildsTheSessionsGraph(*session_);
  // At another period the stream holds other positions: it does not rebuild the graph, and
  // export says so.
  for (const char* period : {"0.05", "10"}) {
    const auto other = runCliBinary("export --session " + session_->string() + " --sample-period " + period + " --stream " +
                                    (scratchDir() / "other-period.csv").string());
    ASSERT_EQ(other.exit_code, 0) << other.err;
    EXPECT_FALSE(other.json().at("stream").at("rebuilds_session_graph").get<bool>()) << period;
  }
  // Seed 23 ends its configuration stage with a position taken in the cycle whose trigger came
  // at the time of the finishing button: a replay that told buttons from triggers by their
  // times alone lost it.
  const fs::path other = scratchDir() / "seed23.flexirob";
  const auto taught = runCliBinary("teach --scene setup_A --areas 1 --seed 23 --check-points 0 --out " + other.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  expectTheStreamRebuildsTheSessionsGraph(other);
}

TEST_F(ExportCli, TheSamplesAreTheTaughtOnesAndFitUnderLearnFit) {
  const fs::path samples = scratchDir() / "samples.csv";
  const auto exported = runCliBinary("export --session " + session_->string() + " --samples " + samples.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const int taught_samples = taught_->at("samples").get<int>();
  EXPECT_EQ(exported.json().at("samples").at("rows").get<int>(), taught_samples);

  // Each row's position is where its posture puts the tip of the LWR IV.
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  robot::Kinematics kinematics(model);
  const std::vector<std::string> rows = lines(samples);
  ASSERT_EQ(rows.front(), "area,x,y,z,q1,q2,q3,q4,q5,q6,q7");
  ASSERT_EQ(static_cast<int>(rows.size()) - 1, taught_samples);
  for (std::size_t r = 1; r < rows.size(); r += 97) {
    const std::vector<std::string> fields = app::splitCommaFields(rows[r]);
    ASSERT_EQ(fields.size(), 11u) << rows[r];
    EXPECT_EQ(fields[0], "0");
    Eigen::VectorXd q(7);
    for (int j = 0; j < 7; ++j) q[j] = std::stod(fields[static_cast<std::size_t>(4 + j)]);
    kinematics.update(q);
    const Eigen::Vector3d x(std::stod(fields[1]), std::stod(fields[2]), std::stod(fields[3]));
    EXPECT_LT((kinematics.p_WT() - x).norm(), 1e-9) << rows[r];
  }

  const fs::path model_file = scratchDir() / "refit.flm";
  const auto fit = runCliBinary("learn fit --learner elm --data " + samples.string() + " --out " + model_file.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_EQ(fit.json().at("samples").get<int>(), taught_samples);
  EXPECT_EQ(fit.json().at("areas").get<int>(), 1);
  EXPECT_FALSE(fit.json().at("areas_inferred").get<bool>());
}

TEST_F(ExportCli, TheModelAndGraphAreReadByLearnPredictAndItmPath) {
  const fs::path model = scratchDir() / "session.flm";
  const fs::path graph = scratchDir() / "session.itm";
  const fs::path samples = scratchDir() / "for-predict.csv";
  const auto exported = runCliBinary("export --session " + session_->string() + " --model " + model.string() + " --graph " +
                                     graph.string() + " --samples " + samples.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  const nlohmann::json result = exported.json();
  EXPECT_EQ(result.at("model").at("learner").get<std::string>(), "elm");
  EXPECT_EQ(result.at("model").at("samples").get<int>(), taught_->at("samples").get<int>());
  // learn fit with the arguments export prints learns the session's model again, byte for byte
  // (the session's ELM was drawn with teach's seed 3, not learn fit's default 1).
  const std::string arguments = result.at("model").at("learn_fit_arguments").get<std::string>();
  EXPECT_NE(arguments.find("--seed 3"), std::string::npos) << arguments;
  const fs::path refit = scratchDir() / "session-refit.flm";
  const auto fit = runCliBinary("learn fit " + arguments + " --data " + samples.string() + " --out " + refit.string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_EQ(fileBytes(refit), fileBytes(model));

  const auto predicted = runCliBinary("learn predict --model " + model.string() + " --data " + samples.string());
  ASSERT_EQ(predicted.exit_code, 0) << predicted.err;
  // The session's own model on its own training data: within a few hundredths of a radian.
  EXPECT_LT(predicted.json().at("rmse_rad").get<double>(), 0.05);

  // A path between two positions the stream passed through, through the exported graph.
  const std::vector<std::string> rows = lines(samples);
  const std::vector<std::string> a = app::splitCommaFields(rows[1]);
  const std::vector<std::string> b = app::splitCommaFields(rows.back());
  const auto path = runCliBinary("itm path --graph " + graph.string() + " --from " + a[1] + "," + a[2] + "," + a[3] + " --to " +
                                 b[1] + "," + b[2] + "," + b[3]);
  ASSERT_EQ(path.exit_code, 0) << path.err;
  EXPECT_EQ(path.json().at("graph_nodes").get<int>(), result.at("graph").at("nodes").get<int>());
  EXPECT_TRUE(path.json().at("found").get<bool>()) << path.out;
}

TEST_F(ExportCli, BadRequestsAreRefusedWithOneLineAndWriteNothing) {
  const fs::path out = scratchDir() / "refused.csv";
  const fs::path relative = "flexirob-export-refused-" + std::to_string(::getpid()) + ".csv";
  const fs::path json_session = scratchDir() / "hand.json";
  testing::writeText(json_session, R"({"format": "flexirob-session-json", "version": 1})");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"export --session " + session_->string(), "nothing to write"},
      {"export --session " + session_->string() + " --samples " + out.string() + " --stream " + out.string(), "its own file"},
      {"export --session " + session_->string() + " --samples " + session_->string(), "--session file"},
      {"export --session " + json_session.string() + " --samples " + out.string(), "JSON session"},
      {"export --session " + (scratchDir() / "missing.flexirob").string() + " --samples " + out.string(), "missing.flexirob"},
      {"export --session " + session_->string() + " --samples " + (scratchDir() / "no" / "x.csv").string(), "does not exist"},
      {"export --session " + session_->string() + " --stream " + out.string() + " --sample-period 0", "--sample-period"},
      {"export --session " + session_->string() + " --samples " + out.string() + " --stream " + session_->string() + "-wal",
       "a file SQLite keeps beside it"},
      // Two spellings of one file that does not exist yet (relative to the working folder).
      {"export --session " + session_->string() + " --samples " + relative.string() + " --stream ./" + relative.string(),
       "its own file"},
  };
  for (const auto& [arguments, reason] : cases) {
    const auto result = runCliBinary(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments;
    EXPECT_NE(result.err.find(reason), std::string::npos) << arguments << "\n" << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(fs::exists(out)) << arguments;
    EXPECT_FALSE(fs::exists(relative)) << arguments;
  }
  EXPECT_TRUE(fs::exists(*session_));
  // The null device is the one file that takes several outputs: nothing is kept of any.
  const auto discarded = runCliBinary("export --session " + session_->string() + " --samples /dev/null --stream /dev/null");
  EXPECT_EQ(discarded.exit_code, 0) << discarded.err;
}

// The robot's meshes are read for the stream's contacts: an output named in their place is
// refused, and the mesh stays as it was (--robot names a copy of the arm, as for a moved cell).
TEST_F(ExportCli, AnOutputInPlaceOfAMeshTheRobotReadsIsRefused) {
  const fs::path robot_dir = scratchDir() / "robot-copy" / "lwr4";
  fs::remove_all(robot_dir.parent_path());
  fs::create_directories(robot_dir.parent_path());
  fs::copy(resolveRobotPath("lwr4").parent_path(), robot_dir, fs::copy_options::recursive);
  const fs::path mesh = robot_dir / "meshes" / "link1_collision.stl";
  ASSERT_TRUE(fs::exists(mesh));
  const std::string mesh_bytes = fileBytes(mesh);
  const fs::path stream = scratchDir() / "over-mesh-stream.csv";
  const auto result = runCliBinary("export --session " + session_->string() + " --robot " + (robot_dir / "lwr4.urdf").string() +
                                   " --stream " + stream.string() + " --graph " + mesh.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("is the mesh of link 'link1' collision 0, which the run reads"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_EQ(fileBytes(mesh), mesh_bytes);
  EXPECT_FALSE(fs::exists(stream));
  fs::remove_all(robot_dir.parent_path());
}

// A built-in name given to --robot or --scene reads the file among the resources: an output of
// that name in the working folder is another file, and is written.
TEST_F(ExportCli, AnOutputNamedAsABuiltInRobotOrSceneIsNotTakenForIt) {
  const fs::path folder = scratchDir() / "named-as-builtins";
  fs::create_directories(folder);
  struct WorkingFolder {
    fs::path before = fs::current_path();
    explicit WorkingFolder(const fs::path& folder) { fs::current_path(folder); }
    ~WorkingFolder() { fs::current_path(before); }
  };
  testing::CliResult result;
  {
    const WorkingFolder inside(folder);
    result = runCliBinary("export --session " + session_->string() + " --robot lwr4 --scene setup_A --samples lwr4 --stream setup_A");
  }
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(fs::is_regular_file(folder / "lwr4"));
  EXPECT_TRUE(fs::is_regular_file(folder / "setup_A"));
  fs::remove_all(folder);
}

// No output replaces a recorded session: a table or a picture named in its place (a slip of the
// shell's completion) is refused before any work, and the recording stays whole.
TEST_F(ExportCli, AnOutputNamedAsARecordedSessionIsRefusedAndTheSessionStays) {
  const fs::path other = scratchDir() / "other-recording.flexirob";
  fs::copy_file(*session_, other, fs::copy_options::overwrite_existing);
  const std::string bytes = fileBytes(other);
  const fs::path data = scratchDir() / "other-samples.csv";
  ASSERT_EQ(runCliBinary("export --session " + session_->string() + " --samples " + data.string()).exit_code, 0);
  for (const std::string& command :
       {"export --session " + session_->string() + " --samples " + other.string(), "render --scene setup_A --out " + other.string(),
        "sweep --tables 3.3 --only setup_I:1 --spacing 0.2 --json " + other.string(),
        "learn fit --data " + data.string() + " --out " + other.string()}) {
    const auto result = runCliBinary(command);
    EXPECT_EQ(result.exit_code, 2) << command << "\n" << result.err;
    EXPECT_NE(result.err.find("is a recorded session, which this output would replace"), std::string::npos) << command << "\n" << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(fileBytes(other), bytes) << command;
  }
  // teach --overwrite replaces a session by design; another file that merely looks alike does not
  // stop an output.
  const fs::path not_a_session = scratchDir() / "notes.flexirob";
  testing::writeText(not_a_session, "SQLite format 3 is what a session starts with\n");
  const auto replaced = runCliBinary("export --session " + session_->string() + " --samples " + not_a_session.string());
  EXPECT_EQ(replaced.exit_code, 0) << replaced.err;
  fs::remove(other);
}

// A file damaged where export does not read can still hold wrong values where it does: export
// refuses it unless told, and then says so in a note and in the JSON.
TEST_F(ExportCli, ADamagedSessionIsExportedOnlyWhenAskedAndSaysSo) {
  const std::string bytes = fileBytes(*session_);
  constexpr std::size_t kPage = 4096;
  const std::size_t at = bytes.size() / 2 / kPage * kPage;  // a page of the state table, which export --samples does not read
  ASSERT_GT(bytes.size(), 8 * kPage);
  const fs::path damaged = scratchDir() / "damaged-pages.flexirob";
  testing::writeText(damaged, bytes.substr(0, at) + std::string(kPage, '\xA5') + bytes.substr(at + kPage));
  const fs::path out = scratchDir() / "from-damaged.csv";
  const auto refused = runCliBinary("export --session " + damaged.string() + " --samples " + out.string());
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("session file " + damaged.string() + " is damaged ("), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--accept-damage"), std::string::npos) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_FALSE(fs::exists(out));
  const auto accepted = runCliBinary("export --session " + damaged.string() + " --samples " + out.string() + " --accept-damage");
  ASSERT_EQ(accepted.exit_code, 0) << accepted.err;
  EXPECT_TRUE(accepted.json().at("damage").is_string()) << accepted.out;
  EXPECT_NE(accepted.err.find("note: the session file is damaged"), std::string::npos) << accepted.err;
  EXPECT_TRUE(fs::exists(out));
  // A whole file says so too.
  const auto whole = runCliBinary("export --session " + session_->string() + " --samples " + out.string());
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_TRUE(whole.json().at("damage").is_null()) << whole.out;
  fs::remove(damaged);
}

// A session records what its robot's meshes held: one changed after teaching is said when the
// session is drawn or exported again (the stored URDF names the mesh, not its shape).
TEST_F(ExportCli, AMeshChangedSinceTeachingIsNoted) {
  const fs::path cell = scratchDir() / "changed-mesh-cell";
  fs::remove_all(cell);
  fs::create_directories(cell);
  fs::copy(resolveRobotPath("lwr4").parent_path(), cell / "lwr4", fs::copy_options::recursive);
  const fs::path session = cell / "taught.flexirob";
  const auto taught = runCliBinary("teach --robot " + (cell / "lwr4" / "lwr4.urdf").string() +
                                   " --scene setup_A --areas 1 --seed 3 --check-points 0 --out " + session.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  const std::string render = "render --session " + session.string() + " --width 64 --height 48 --out " + (cell / "view.png").string();
  const std::string note = "note: the mesh of link 'link1' collision 0 (";
  const auto before = runCliBinary(render);
  ASSERT_EQ(before.exit_code, 0) << before.err;
  EXPECT_EQ(before.err.find(note), std::string::npos) << before.err;
  fs::copy_file(cell / "lwr4" / "meshes" / "link2_collision.stl", cell / "lwr4" / "meshes" / "link1_collision.stl",
                fs::copy_options::overwrite_existing);
  const auto after = runCliBinary(render);
  ASSERT_EQ(after.exit_code, 0) << after.err;
  EXPECT_NE(after.err.find(note), std::string::npos) << after.err;
  const auto exported =
      runCliBinary("export --session " + session.string() + " --stream " + (cell / "stream.csv").string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_NE(exported.err.find(note), std::string::npos) << exported.err;
  fs::remove_all(cell);
}

// The files of a cell taught in (its URDF, its scene file, their meshes) are inputs of every
// command that reads the cell, named by a session or by option: no output replaces them,
// teach --overwrite included.
TEST_F(ExportCli, NoOutputReplacesAFileOfTheCellTaughtIn) {
  const fs::path cell = scratchDir() / "own-cell";
  fs::remove_all(cell);
  fs::create_directories(cell);
  fs::copy(resolveRobotPath("lwr4").parent_path(), cell / "lwr4", fs::copy_options::recursive);
  fs::copy_file(resourceDir() / "scenes" / "setup_A.yaml", cell / "setup_A.yaml");
  const fs::path urdf = cell / "lwr4" / "lwr4.urdf";
  const fs::path scene = cell / "setup_A.yaml";
  const fs::path mesh = cell / "lwr4" / "meshes" / "link3_collision.stl";
  const fs::path session = cell / "taught.flexirob";
  const auto taught = runCliBinary("teach --robot " + urdf.string() + " --scene " + scene.string() +
                                   " --areas 1 --seed 3 --check-points 0 --out " + session.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  const std::string urdf_bytes = fileBytes(urdf), scene_bytes = fileBytes(scene), mesh_bytes = fileBytes(mesh);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"export --session " + session.string() + " --samples " + urdf.string(), "is the robot's URDF the session was taught with"},
      {"export --session " + session.string() + " --stream " + scene.string(), "is the scene file the session was taught with"},
      {"render --robot " + urdf.string() + " --out " + mesh.string(), "is the mesh of link 'link3' collision 0, which the run reads"},
      {"teach --robot " + urdf.string() + " --scene setup_A --areas 1 --out " + mesh.string() + " --overwrite",
       "is the mesh of link 'link3' collision 0, which the run reads"},
  };
  for (const auto& [command, reason] : cases) {
    const auto result = runCliBinary(command);
    EXPECT_EQ(result.exit_code, 2) << command << "\n" << result.err;
    EXPECT_NE(result.err.find(reason), std::string::npos) << command << "\n" << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  }
  EXPECT_EQ(fileBytes(urdf), urdf_bytes);
  EXPECT_EQ(fileBytes(scene), scene_bytes);
  EXPECT_EQ(fileBytes(mesh), mesh_bytes);
  // A scene file given as the session is none, and said so: one whose first word is "name" had
  // been called a JSON session (JSON may start with "null").
  testing::writeText(cell / "scene.flexirob", "name: my cell\nobstacles: []\n");
  const auto not_a_session =
      runCliBinary("export --session " + (cell / "scene.flexirob").string() + " --samples " + (cell / "s.csv").string());
  EXPECT_EQ(not_a_session.exit_code, 2);
  EXPECT_NE(not_a_session.err.find("is not a session file"), std::string::npos) << not_a_session.err;
  fs::remove_all(cell);
}

// A session taught to a tip short of the chain's end is drawn with that tip when --robot names
// its own robot again (the default tip, the chain's end, had made its postures not fit).
TEST_F(ExportCli, RenderKeepsTheSessionsTipWhenRobotIsGiven) {
  const fs::path session = scratchDir() / "tip-link6.flexirob";
  const auto taught = runCliBinary("teach --robot lwr4 --tip link6 --scene empty --areas 1 --seed 3 --check-points 0 --out " +
                                   session.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  const auto drawn = runCliBinary("render --session " + session.string() + " --robot lwr4 --width 64 --height 48 --out " +
                                  (scratchDir() / "tip-link6.png").string());
  EXPECT_EQ(drawn.exit_code, 0) << drawn.err;
  fs::remove(session);
}

// A copy of the session edited with `sql`, handed to `command` with `--session COPY` and an
// output `output_option NAME`: refused in one line naming `reason`, the output not written.
auto expectAnEditedCopyRefused(const fs::path& session, const std::string& name, const std::string& sql, const std::string& command,
                               const std::string& output_option, const std::string& output_name, const std::string& reason) {
  const fs::path edited = scratchDir() / (name + ".flexirob");
  const fs::path out = scratchDir() / output_name;
  fs::copy_file(session, edited, fs::copy_options::overwrite_existing);
  {
    app::SqliteDatabase db(edited.string(), 0x00000002);  // SQLITE_OPEN_READWRITE
    db.exec(sql);
  }
  const auto result = runCliBinary(command + " --session " + edited.string() + " " + output_option + " " + out.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find(reason), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove(edited);
  return result;
}

// A model damaged in the file is not handed on as one learn predict would refuse, as a damaged
// ITM snapshot is not: refused with the reason, and nothing written.
TEST_F(ExportCli, ADamagedModelIsRefusedAndNotWritten) {
  expectAnEditedCopyRefused(*session_, "damaged-model", "UPDATE model SET bytes = x'00ff00ff'", "export", "--model", "damaged.model",
                            "--model: the session's last model does not read");
}

// The samples are written for learn fit: a value it would refuse (a posture of 1e308 in a
// damaged or hand-edited file) refuses the export instead of a CSV learn cannot read.
TEST_F(ExportCli, ASampleLearnWouldRefuseIsRefusedAndNotWritten) {
  // 7 joint values of 1e308 (little-endian doubles) in the first sample.
  std::string huge;
  for (int j = 0; j < 7; ++j) huge += "a0c8eb85f3cce17f";
  expectAnEditedCopyRefused(*session_, "huge-sample", "UPDATE sample SET q = x'" + huge + "' WHERE id = (SELECT min(id) FROM sample)",
                            "export", "--samples", "huge-sample.csv",
                            "sample 1: a value beyond ±1e6 or not finite, which learn does not read");
}

// A recorded sample of 1e308 m had render's camera arithmetic overflow into a blank picture
// (and OpenSceneGraph's NaN warning before the JSON); the recording is refused as the JSON is.
TEST_F(ExportCli, RenderRefusesARecordedSampleBeyondAMegametre) {
  // x, y, z = 1e308 m (little-endian doubles) in the first sample.
  const auto result = expectAnEditedCopyRefused(
      *session_, "far-sample", "UPDATE sample SET x = x'a0c8eb85f3cce17fa0c8eb85f3cce17fa0c8eb85f3cce17f' WHERE id = (SELECT min(id) FROM sample)",
      "render --width 64 --height 48", "--out", "far-sample.png", "--session: area sample: [1e+308, 1e+308, 1e+308] lies beyond ±1e6 m");
  EXPECT_TRUE(result.out.empty()) << result.out;
}

// Outputs are written through temporaries renamed into place; an output that happens to be
// named as another's temporary would have been replaced by it.
TEST_F(ExportCli, AnOutputNamedLikeAnothersTemporaryIsKept) {
  const fs::path stream = scratchDir() / "pair.csv";
  const fs::path samples = scratchDir() / "pair.csv.tmp";
  const auto exported = runCliBinary("export --session " + session_->string() + " --samples " + samples.string() + " --stream " +
                                     stream.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_EQ(lines(samples).front(), "area,x,y,z,q1,q2,q3,q4,q5,q6,q7");
  EXPECT_EQ(lines(stream).front(), "x,y,z,q1,q2,q3,q4,q5,q6,q7");
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(scratchDir())) files += entry.path().string().find("pair.csv") != std::string::npos;
  EXPECT_EQ(files, 2u) << "a temporary was left behind";
}

// An output that is a symbolic link: the file it points at is written and the link stays. A
// session reached through a link: the log SQLite keeps beside the file it points at is refused.
TEST_F(ExportCli, WritesThroughALinkAndRefusesTheLogBesideALinkedSession) {
  const fs::path target = scratchDir() / "pointed-at.csv";
  const fs::path link = scratchDir() / "link.csv";
  testing::writeText(target, "old\n");
  fs::remove(link);
  fs::create_symlink(target, link);
  const auto written = runCliBinary("export --session " + session_->string() + " --samples " + link.string());
  ASSERT_EQ(written.exit_code, 0) << written.err;
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(lines(target).front(), "area,x,y,z,q1,q2,q3,q4,q5,q6,q7");

  const fs::path linked_session = scratchDir() / "linked.flexirob";
  fs::remove(linked_session);
  fs::create_symlink(*session_, linked_session);
  const fs::path log = session_->string() + "-wal";
  const auto refused = runCliBinary("export --session " + linked_session.string() + " --samples " + log.string());
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("a file SQLite keeps beside it"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(log) && lines(log).size() > 0 && lines(log).front().rfind("area,", 0) == 0);
}

TEST(ExportCliWithoutModel, ASessionLackingOneRequestedOutputWritesNoneOfThem) {
  const fs::path session = scratchDir() / "no-model.flexirob";
  {
    app::SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.scene_name = "empty";
    app::SessionRecorder recorder(session, metadata);
    ASSERT_TRUE(recorder.recordSample({1.0, 0, Eigen::Vector3d(0.5, 0.0, 0.5), Eigen::VectorXd::Zero(7)}));
    ASSERT_TRUE(recorder.recordArea({0, 1.1, Eigen::Vector3d(0.5, 0.0, 0.5), Eigen::VectorXd::Zero(7), ""}));
  }
  const fs::path samples = scratchDir() / "lonely.csv";
  const fs::path model = scratchDir() / "absent.flm";
  const auto result = runCliBinary("export --session " + session.string() + " --samples " + samples.string() + " --model " + model.string());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--model: the session recorded no learned model"), std::string::npos) << result.err;
  EXPECT_FALSE(fs::exists(samples));
  EXPECT_FALSE(fs::exists(model));
  const auto alone = runCliBinary("export --session " + session.string() + " --samples " + samples.string());
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_EQ(lines(samples).size(), 2u);
}

}  // namespace
}  // namespace flexirob
