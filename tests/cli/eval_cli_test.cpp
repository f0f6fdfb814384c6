// The command-line contract of `eval scene-model`, `eval trajectories` and `sweep`, exercised
// through the real binary on tiny inputs: the JSON's structure, its values against facts known
// independently of the evaluation (the scene's boxes, the requested counts, the grid's
// lattice), and exit code 2 with a one-line reason for bad arguments.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/session_recorder.hpp"
#include "cli_test_support.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob {
namespace {

using testing::runCliBinary;

std::filesystem::path scratchDir() { return testing::scratchDir("eval-cli-test"); }

using testing::writeText;

// A closed tetrahedron of 10 cm edges at the origin, as an ASCII STL.
void writeWedgeStl(const std::filesystem::path& file) {
  writeText(file,
            "solid wedge\n"
            "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\nvertex 0 0.1 0\nendloop\nendfacet\n"
            "facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 0 0 0.1\nvertex 0.1 0 0\nendloop\nendfacet\n"
            "facet normal -1 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0.1 0\nvertex 0 0 0.1\nendloop\nendfacet\n"
            "facet normal 1 1 1\nouter loop\nvertex 0.1 0 0\nvertex 0 0 0.1\nvertex 0 0.1 0\nendloop\nendfacet\n"
            "endsolid wedge\n");
}

// A session as `teach --out F.json` writes it, made by hand: in each area the postures are
// q_fixed plus small joint offsets and the task positions their forward kinematics, so the
// training data are exact; the ITM graph is a chain through some samples.
// Two of setup_I's suggested areas (I1 in front, I2 front-right): collision-free postures.
std::vector<Eigen::VectorXd> tinySessionPostures() {
  return {(Eigen::VectorXd(7) << 0.1177, 0.6076, 0.0937, -1.7010, 0.0132, 0.9237, 0.0).finished(),
          (Eigen::VectorXd(7) << 0.4676, 0.5650, 0.3476, -1.3731, 0.0518, 0.8482, 0.0).finished()};
}

std::filesystem::path tinySession(const std::string& scene_name, const std::string& name) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  const robot::Scene scene = robot::loadScene(scene_name);
  const std::vector<Eigen::VectorXd> postures = tinySessionPostures();
  robot::Kinematics kinematics(model);
  nlohmann::json areas = nlohmann::json::array();
  nlohmann::json nodes = nlohmann::json::array();
  nlohmann::json edges = nlohmann::json::array();
  for (const Eigen::VectorXd& q_fixed : postures) {
    const std::string area_name = "I" + std::to_string(areas.size() + 1);  // as teach names taught areas
    nlohmann::json x = nlohmann::json::array();
    nlohmann::json q = nlohmann::json::array();
    for (int l = 0; l < 40; ++l) {
      Eigen::VectorXd q_l = q_fixed;
      // Deterministic offsets of up to 0.06 rad on the first four joints.
      for (int j = 0; j < 4; ++j) q_l[j] += 0.06 * std::sin(0.7 * l + 1.3 * j);
      kinematics.update(q_l);
      const Eigen::Vector3d p = kinematics.p_WT();
      x.push_back({p.x(), p.y(), p.z()});
      q.push_back(std::vector<double>(q_l.data(), q_l.data() + q_l.size()));
      if (l % 10 == 0) {
        if (!nodes.empty()) edges.push_back({nodes.size() - 1, nodes.size()});
        nodes.push_back({{"x", {p.x(), p.y(), p.z()}}, {"q", q.back()}});
      }
    }
    areas.push_back({{"name", area_name}, {"q_fixed", std::vector<double>(q_fixed.data(), q_fixed.data() + q_fixed.size())}, {"x", x}, {"q", q}});
  }
  const nlohmann::json session = {{"format", "flexirob-session-json"},
                                  {"version", 1},
                                  {"robot", "lwr4"},
                                  {"tip", ""},
                                  {"scene", scene_name},
                                  {"areas", areas},
                                  {"itm", {{"nodes", nodes}, {"edges", edges}}}};
  const auto file = scratchDir() / name;
  writeText(file, session.dump());
  return file;
}

TEST(EvalSceneModelCli, ModelPointsLieOnTheGridAndTheEnclosedObstaclePointsInsideTheScenesBoxes) {
  const auto session = tinySession("setup_I", "scene-model.json");
  const auto result = runCliBinary("eval scene-model --session " + session.string() + " --spacing 0.2");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  for (const char* key : {"workspace_points", "model_points", "obstacle_points", "obstacle_points_enclosed",
                          "obstacle_enclosed_fraction", "free_points_in_model", "reachable_fraction", "model"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json.at("areas"), 2);
  EXPECT_DOUBLE_EQ(json.at("spacing_m").get<double>(), 0.2);
  const nlohmann::json& model = json.at("model");
  ASSERT_EQ(model.size(), json.at("model_points").get<std::size_t>());
  EXPECT_LE(json.at("model_points").get<int>(), json.at("workspace_points").get<int>());
  // Count again, with the scene's own obstacle boxes, which points of S lie inside an obstacle.
  const robot::Scene scene = robot::loadScene("setup_I");
  ASSERT_TRUE(scene.grid.has_value());
  int inside = 0;
  for (const auto& point : model) {
    const Eigen::Vector3d p(point.at(0).get<double>(), point.at(1).get<double>(), point.at(2).get<double>());
    // S is a subset of the grid G (Eq. 4.1): every point on its 0.2 m lattice, within its box.
    const Eigen::Vector3d steps = (p - scene.grid->lower) / 0.2;
    EXPECT_NEAR((steps - steps.array().round().matrix()).norm(), 0.0, 1e-6) << p.transpose();
    EXPECT_TRUE((p.array() >= scene.grid->lower.array() - 1e-9).all() && (p.array() <= scene.grid->upper.array() + 1e-9).all())
        << p.transpose();
    inside += robot::obstacleAt(scene, p) != nullptr ? 1 : 0;
  }
  EXPECT_EQ(inside, json.at("obstacle_points_enclosed").get<int>());
  EXPECT_EQ(json.at("free_points_in_model").get<int>(), json.at("model_points").get<int>() - inside);
  EXPECT_LE(json.at("obstacle_points_enclosed").get<int>(), json.at("obstacle_points").get<int>());
  // The box (0.2 x 0.2 x 0.8 m) and the board hold grid points at 0.2 m spacing.
  EXPECT_GT(json.at("obstacle_points").get<int>(), 0);
  EXPECT_NEAR(json.at("obstacle_enclosed_fraction").get<double>(),
              static_cast<double>(inside) / json.at("obstacle_points").get<int>(), 1e-12);
  std::filesystem::remove(session);
}

// 0 of 0 targets is no fraction: the command fails with one line that says where the grid's
// points went, and its JSON holds null fractions (it reported reachable_fraction 0).
TEST(EvalReachableCli, AGridWithNoTargetFailsSayingWhereItsPointsWent) {
  const auto scene = scratchDir() / "far_grid.yaml";
  writeText(scene, "name: far_grid\ngrid: {lower: [2.5, 2.5, 0.1], upper: [3.0, 3.0, 0.5], spacing: 0.25}\n");
  const auto session = tinySession(scene.string(), "far-grid.json");
  const auto result = runCliBinary("eval reachable --session " + session.string());
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_NE(result.err.find("none of the grid's 18 points is a target (18 out of reach"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  const nlohmann::json json = result.json();
  EXPECT_EQ(json.at("targets"), 0);
  EXPECT_EQ(json.at("out_of_reach"), 18);  // 3 x 3 x 2 points
  EXPECT_TRUE(json.at("reachable_fraction").is_null());
  EXPECT_TRUE(json.at("explored_fraction").is_null());
  std::filesystem::remove(session);
  std::filesystem::remove(scene);
}

// Eq. 4.1's model is built from the reachability run's final postures: without a target there
// are none, and scene-model fails as eval reachable does (it reported every point as model).
TEST(EvalSceneModelCli, AGridWithNoTargetFailsAsEvalReachableDoes) {
  const auto scene = scratchDir() / "far_grid_model.yaml";
  writeText(scene, "name: far_grid_model\ngrid: {lower: [2.5, 2.5, 0.1], upper: [3.0, 3.0, 0.5], spacing: 0.25}\n");
  const auto session = tinySession(scene.string(), "far-grid-model.json");
  const auto result = runCliBinary("eval scene-model --session " + session.string());
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_NE(result.err.find("eval scene-model: none of the grid's 18 points is a target (18 out of reach"), std::string::npos)
      << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  const nlohmann::json json = result.json();
  EXPECT_EQ(json.at("targets"), 0);
  EXPECT_FALSE(json.contains("model")) << json.dump();
  std::filesystem::remove(session);
  std::filesystem::remove(scene);
}

// A grid with no point inside an obstacle has no fraction of such points enclosed (0 of 0).
TEST(EvalSceneModelCli, WithoutObstaclePointsTheEnclosedFractionIsNull) {
  const auto scene = scratchDir() / "free_grid.yaml";
  writeText(scene, "name: free_grid\ngrid: {lower: [0.3, -0.2, 0.3], upper: [0.5, 0.2, 0.5], spacing: 0.2}\n");
  const auto session = tinySession(scene.string(), "free-grid.json");
  const auto result = runCliBinary("eval scene-model --session " + session.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  EXPECT_EQ(json.at("obstacle_points"), 0);
  EXPECT_TRUE(json.at("obstacle_enclosed_fraction").is_null()) << json.at("obstacle_enclosed_fraction");
  std::filesystem::remove(session);
  std::filesystem::remove(scene);
}

// A session taught with the LLM is evaluated and planned with the LLM unless another learner is
// asked for; one without a learner (written before sessions named it) with the ELM.
TEST(EvalReachableCli, UsesTheLearnerTheSessionWasTaughtWithUnlessAskedForAnother) {
  const auto session = tinySession("setup_I", "taught-with-llm.json");
  nlohmann::json json = nlohmann::json::parse(std::ifstream(session));
  const auto learnerOf = [](const testing::CliResult& result) {
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return result.exit_code == 0 ? result.json().at("learner").get<std::string>() : std::string();
  };
  const std::string reachable = "eval reachable --spacing 0.4 --session " + session.string();
  EXPECT_EQ(learnerOf(runCliBinary(reachable)), "elm");
  json["learner"] = "llm";
  writeText(session, json.dump());
  EXPECT_EQ(learnerOf(runCliBinary(reachable)), "llm");
  EXPECT_EQ(learnerOf(runCliBinary("plan --goals 1 --session " + session.string())), "llm");
  EXPECT_EQ(learnerOf(runCliBinary(reachable + " --learner elm")), "elm");
  // A learner eval does not learn with (a BPDC model, a hand-edited name): the ELM, said.
  json["learner"] = "bpdc";
  writeText(session, json.dump());
  const auto bpdc = runCliBinary(reachable);
  EXPECT_EQ(learnerOf(bpdc), "elm");
  EXPECT_NE(bpdc.err.find("taught with the learner 'bpdc'"), std::string::npos) << bpdc.err;
  std::filesystem::remove(session);
}

// A result is drawn over a session's picture later (render --reachable, --scene-model, --plan):
// it says which session, robot and scene it was measured in.
TEST(EvalCli, EveryResultNamesTheSessionRobotAndSceneItWasMeasuredIn) {
  const auto session = tinySession("setup_I", "named-results.json");
  for (const std::string command : {"eval reachable --spacing 0.4", "eval scene-model --spacing 0.4", "plan --goals 1"}) {
    const auto result = runCliBinary(command + " --session " + session.string());
    ASSERT_EQ(result.exit_code, 0) << command << ": " << result.err;
    const nlohmann::json json = result.json();
    EXPECT_EQ(json.value("session", ""), session.string()) << command;
    EXPECT_EQ(json.value("robot", ""), "lwr4") << command;
    EXPECT_EQ(json.value("scene", ""), "setup_I") << command;
  }
  std::filesystem::remove(session);
}

// The stored scene and the scene file both name a mesh that has gone: the error says that both
// fail, and why each does, rather than blame a scene file that is itself fine.
TEST(EvalReachableCli, AMeshGoneFromBesideTheSceneIsNamedAsTheCause) {
  const auto directory = scratchDir() / "mesh_gone";
  std::filesystem::create_directories(directory);
  const auto mesh = directory / "wedge.stl";
  writeWedgeStl(mesh);
  const auto scene = directory / "cell.yaml";
  writeText(scene, "name: cell\nobstacles:\n  - {name: wedge, shape: mesh, file: wedge.stl, position: [-2.0, 0.0, 0.3]}\n");
  const auto session = tinySession(scene.string(), "mesh-gone.json");
  {
    // The copy of the scene a taught session keeps, as teach stores it.
    std::ifstream in(session);
    nlohmann::json json = nlohmann::json::parse(in);
    json["scene_text"] = robot::sceneToYaml(robot::loadScene(scene.string()));
    writeText(session, json.dump());
  }
  std::filesystem::remove(mesh);
  const auto result = runCliBinary("eval reachable --spacing 0.3 --session " + session.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("mesh file"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("; the scene file does not read either: "), std::string::npos) << result.err;
  EXPECT_EQ(result.err.find("cannot be read"), std::string::npos) << result.err;
  std::filesystem::remove(session);
  std::filesystem::remove_all(directory);
}

TEST(EvalReachableCli, EvaluatesTheScenesSingleTargetsToo) {
  // One target where the first area's posture puts the tip, one far beyond the arm's reach.
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  const Eigen::Vector3d taught = robot::tipPose(model, tinySessionPostures().front()).translation();
  const auto scene = scratchDir() / "single_targets.yaml";
  std::ostringstream text;
  text << "name: single_targets\ntargets: [[" << taught.x() << ", " << taught.y() << ", " << taught.z() << "], [-3.0, 0.0, 0.3]]\n"
       << "obstacles:\n  - {name: far_box, shape: box, size: [0.2, 0.2, 0.2], position: [-3.0, 0.0, 0.3]}\n";
  writeText(scene, text.str());
  const auto session = tinySession(scene.string(), "single-targets.json");
  const auto result = runCliBinary("eval reachable --spacing 0.3 --session " + session.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  const nlohmann::json& targets = json.at("scene_targets");
  ASSERT_EQ(targets.size(), 2U);
  EXPECT_TRUE(targets[0].at("reached").get<bool>()) << targets[0].dump();
  EXPECT_LT(targets[0].at("error_m").get<double>(), 0.01);
  EXPECT_FALSE(targets[1].at("reached").get<bool>());
  EXPECT_GT(targets[1].at("error_m").get<double>(), 1.0);
  EXPECT_EQ(json.at("scene_targets_reached"), 1);
  // A target inside an obstacle is named as such, in the JSON and in a note when the scene loads.
  EXPECT_TRUE(targets[0].at("inside_obstacle").is_null()) << targets[0].dump();
  EXPECT_EQ(targets[1].at("inside_obstacle"), "far_box");
  EXPECT_NE(result.err.find("note: targets[1] (-3.000, 0.000, 0.300) m lies inside obstacle 'far_box'"), std::string::npos)
      << result.err;
  // And one out of reach as such: 3 m from the shoulder (z = 0.31 m), whose reach is under 1 m.
  EXPECT_TRUE(targets[0].at("beyond_reach_m").is_null()) << targets[0].dump();
  EXPECT_GT(targets[1].at("beyond_reach_m").get<double>(), 2.0) << targets[1].dump();
  EXPECT_LT(targets[1].at("beyond_reach_m").get<double>(), 2.2) << targets[1].dump();
  EXPECT_NE(result.err.find("note: scene target (-3.000, 0.000, 0.300) m lies"), std::string::npos) << result.err;
  // Both distances, each named: the target's from the shoulder and the arm's reach.
  EXPECT_NE(result.err.find(" m from the shoulder, reach 0."), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("beyond the arm's reach (3."), std::string::npos) << result.err;
  std::filesystem::remove(session);
  std::filesystem::remove(scene);
}

// A point both a grid target and a scene target: every grid target reached is reached as a scene
// target too, started the same way (`visited`: from where the arm stood nearest, at a grid
// target reached or at a sample; `nearest`: at a grid target reached). Scene targets had started
// from the demonstration alone, and 78 of setup_I's 483 reached grid targets were missed as
// scene targets in the same run; under `nearest` they started from the area's taught posture
// (5 of this one-area session's 39 missed).
TEST(EvalReachableCli, AGridTargetReachedIsReachedAsASceneTargetAtTheSamePoint) {
  const auto plain = scratchDir() / "grid-only.flexirob";
  const auto scene = scratchDir() / "grid_as_targets.yaml";
  const auto session = scratchDir() / "grid-as-targets.flexirob";
  const std::string teach = "teach --areas 1 --seed 1 --check-points 0 --overwrite";
  const auto taught = runCliBinary(teach + " --scene setup_I --out " + plain.string());
  ASSERT_EQ(taught.exit_code, 0) << taught.err;
  for (const std::string approach : {"visited", "nearest"}) {
    SCOPED_TRACE(approach);
    const std::string eval = "eval reachable --spacing 0.2 --approach " + approach + " --session ";
    const auto grid_run = runCliBinary(eval + plain.string());
    ASSERT_EQ(grid_run.exit_code, 0) << grid_run.err;
    const nlohmann::json points = grid_run.json().at("target_points");
    ASSERT_GE(points.size(), 5U);
    writeText(scene, robot::sceneToYaml(robot::loadScene("setup_I")) + "\ntargets: " + points.dump() + "\n");
    const auto taught_again = runCliBinary(teach + " --scene " + scene.string() + " --out " + session.string());
    ASSERT_EQ(taught_again.exit_code, 0) << taught_again.err;
    const auto result = runCliBinary(eval + session.string());
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = result.json();
    ASSERT_EQ(json.at("target_points"), points);
    const nlohmann::json& reached = json.at("target_reached");
    const nlohmann::json& targets = json.at("scene_targets");
    ASSERT_EQ(targets.size(), points.size());
    int grid_reached = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!reached[i].get<bool>()) continue;
      ++grid_reached;
      EXPECT_TRUE(targets[i].at("reached").get<bool>()) << points[i].dump() << " " << targets[i].dump();
    }
    EXPECT_GT(grid_reached, 0);
    EXPECT_GE(json.at("scene_targets_reached").get<int>(), grid_reached);
  }
  std::filesystem::remove(session);
  std::filesystem::remove(plain);
  std::filesystem::remove(scene);
}

// teach stores the robot and scene it taught with in the session; a JSON session made by hand
// gets the same copies here.
void storeTaughtCopies(const std::filesystem::path& session_file, const std::filesystem::path& urdf,
                       const std::string& scene_name) {
  std::ifstream in(session_file);
  nlohmann::json session = nlohmann::json::parse(in);
  in.close();
  std::ifstream urdf_in(urdf);
  std::ostringstream urdf_text;
  urdf_text << urdf_in.rdbuf();
  session["robot"] = urdf.string();
  session["robot_urdf"] = urdf_text.str();
  session["scene_text"] = robot::sceneToYaml(robot::loadScene(scene_name));
  writeText(session_file, session.dump());
}

TEST(EvalReachableCli, EvaluatesTheRobotAndSceneTheSessionStoresNotTheFilesChangedSinceTeaching) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  const Eigen::Vector3d taught = robot::tipPose(model, tinySessionPostures().front()).translation();
  const auto scene = scratchDir() / "edited_after_teaching.yaml";
  // The robot as a file of its own, with its meshes beside it as package://lwr4 expects.
  const auto robot_dir = scratchDir() / "moved-robot" / "lwr4";
  std::filesystem::remove_all(robot_dir.parent_path());
  std::filesystem::create_directories(robot_dir.parent_path());
  std::filesystem::copy(resolveRobotPath("lwr4").parent_path(), robot_dir, std::filesystem::copy_options::recursive);
  // The scene names the robot's file, which the stored scene copy keeps naming after it has gone.
  std::ostringstream text;
  text << "name: edited_after_teaching\nrobot: " << (robot_dir / "lwr4.urdf").string() << "\ntargets: [[" << taught.x() << ", "
       << taught.y() << ", " << taught.z() << "], [-3.0, 0.0, 0.3]]\n";
  writeText(scene, text.str());
  // Taught with link1 drawn only: the stored copy's notes are said as a file's are.
  std::ostringstream urdf_text;
  urdf_text << std::ifstream(robot_dir / "lwr4.urdf").rdbuf();
  std::string drawn_only = urdf_text.str();
  const std::size_t collision = drawn_only.find("<collision><geometry><mesh filename=\"package://lwr4/meshes/link1_collision.stl\"/></geometry></collision>");
  ASSERT_NE(collision, std::string::npos);
  drawn_only.erase(collision, drawn_only.find("</collision>", collision) + 12 - collision);
  writeText(robot_dir / "lwr4.urdf", drawn_only);
  const auto session = tinySession(scene.string(), "edited-after-teaching.json");
  storeTaughtCopies(session, robot_dir / "lwr4.urdf", scene.string());

  writeText(scene, "name: edited_after_teaching\ntargets: [[-3.0, 0.0, 0.3]]\n");  // the taught target is gone
  std::filesystem::remove(robot_dir / "lwr4.urdf");                                 // and the URDF moved away
  const auto result = runCliBinary("eval reachable --spacing 0.3 --session " + session.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  const nlohmann::json& targets = json.at("scene_targets");
  ASSERT_EQ(targets.size(), 2U);
  EXPECT_TRUE(targets[0].at("reached").get<bool>()) << targets[0].dump();
  EXPECT_NE(result.err.find("note: the scene '" + scene.string() + "' differs from the copy the session stores"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("note: the robot '"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("note: link 'link1' has a visual but no collision element"), std::string::npos) << result.err;
  std::filesystem::remove(session);
  std::filesystem::remove(scene);
  std::filesystem::remove_all(robot_dir.parent_path());
}

// A cell moved to another folder with its session (a robot's URDF and meshes, a scene naming
// them and a mesh of its own by relative path): the stored copies name files that are gone, the
// error says how to name where they lie now, and --robot and --scene read them there; a scene
// changed since is said to differ, one merely moved is not.
TEST(EvalReachableCli, ASessionWhoseFilesMovedIsEvaluatedFromWhereTheyLieNow) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  const Eigen::Vector3d taught = robot::tipPose(model, tinySessionPostures().front()).translation();
  const auto cell = scratchDir() / "cell-before-moving";
  const auto moved = scratchDir() / "cell-after-moving";
  std::filesystem::remove_all(cell);
  std::filesystem::remove_all(moved);
  std::filesystem::create_directories(cell / "robots");
  std::filesystem::copy(resolveRobotPath("lwr4").parent_path(), cell / "robots" / "lwr4", std::filesystem::copy_options::recursive);
  std::filesystem::create_directories(cell / "meshes");
  writeWedgeStl(cell / "meshes" / "wedge.stl");
  std::ostringstream text;
  text << "name: cell\nrobot: robots/lwr4/lwr4.urdf\n"
       << "obstacles:\n  - {name: wedge, shape: mesh, file: meshes/wedge.stl, position: [-2.0, 0.0, 0.3]}\n"
       << "targets: [[" << taught.x() << ", " << taught.y() << ", " << taught.z() << "]]\n";
  writeText(cell / "cell.yaml", text.str());
  const auto session = tinySession((cell / "cell.yaml").string(), "moved-cell.json");
  storeTaughtCopies(session, cell / "robots" / "lwr4" / "lwr4.urdf", (cell / "cell.yaml").string());
  std::filesystem::rename(cell, moved);

  const std::string evaluate = "eval reachable --spacing 0.3 --session " + session.string();
  const auto robot_gone = runCliBinary(evaluate);
  EXPECT_EQ(robot_gone.exit_code, 2) << robot_gone.err;
  EXPECT_NE(robot_gone.err.find("--robot names its URDF where it lies now"), std::string::npos) << robot_gone.err;
  const std::string with_robot = evaluate + " --robot " + (moved / "robots" / "lwr4" / "lwr4.urdf").string();
  const auto scene_gone = runCliBinary(with_robot);
  EXPECT_EQ(scene_gone.exit_code, 2) << scene_gone.err;
  EXPECT_NE(scene_gone.err.find("--scene names the scene file where it lies now"), std::string::npos) << scene_gone.err;

  const std::string with_both = with_robot + " --scene " + (moved / "cell.yaml").string();
  const auto result = runCliBinary(with_both);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.json().at("scene_targets").at(0).at("reached").get<bool>()) << result.out;
  EXPECT_EQ(result.err.find("differs from the copy the session stores"), std::string::npos) << result.err;

  // The wedge moved by 1 cm after teaching: what is evaluated is no longer what was taught in.
  std::string edited = text.str();
  edited.replace(edited.find("[-2.0, 0.0, 0.3]"), 16, "[-2.0, 0.01, 0.3]");
  writeText(moved / "cell.yaml", edited);
  const auto changed = runCliBinary(with_both);
  ASSERT_EQ(changed.exit_code, 0) << changed.err;
  EXPECT_NE(changed.err.find("note: the scene '" + (moved / "cell.yaml").string() + "' differs from the copy the session stores; it is used as --scene asks"),
            std::string::npos)
      << changed.err;
  std::filesystem::remove(session);
  std::filesystem::remove_all(moved);
}

// A session whose stored scene and robot copies were damaged (the files beside it intact): the
// files serve, each with a note that says which copy did not read, instead of an error about
// the damaged copy after a note that blames the intact file.
TEST(EvalReachableCli, ADamagedStoredSceneOrRobotFallsBackToTheIntactFiles) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  const Eigen::Vector3d taught = robot::tipPose(model, tinySessionPostures().front()).translation();
  const auto scene = scratchDir() / "intact.yaml";
  std::ostringstream text;
  text << "name: intact\ntargets: [[" << taught.x() << ", " << taught.y() << ", " << taught.z() << "]]\n";
  writeText(scene, text.str());
  const auto robot_dir = scratchDir() / "intact-robot" / "lwr4";
  std::filesystem::remove_all(robot_dir.parent_path());
  std::filesystem::create_directories(robot_dir.parent_path());
  std::filesystem::copy(resolveRobotPath("lwr4").parent_path(), robot_dir, std::filesystem::copy_options::recursive);
  const auto session = tinySession(scene.string(), "damaged-copies.json");
  storeTaughtCopies(session, robot_dir / "lwr4.urdf", scene.string());
  nlohmann::json json = nlohmann::json::parse(std::ifstream(session));
  json["scene_text"] = "name: [unclosed";
  json["robot_urdf"] = "<robot name=\"cut";
  writeText(session, json.dump());

  const auto result = runCliBinary("eval reachable --spacing 0.3 --session " + session.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.json().at("scene_targets").at(0).at("reached").get<bool>()) << result.out;
  EXPECT_NE(result.err.find("note: the scene stored in the session does not read"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("'" + scene.string() + "' is used instead"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("note: the robot stored in the session does not read"), std::string::npos) << result.err;
  EXPECT_EQ(result.err.find("differs from the copy the session stores"), std::string::npos) << result.err;

  // Without the files as well, the one-line error says both.
  std::filesystem::remove(scene);
  const auto lost = runCliBinary("eval reachable --spacing 0.3 --session " + session.string());
  EXPECT_EQ(lost.exit_code, 2);
  EXPECT_NE(lost.err.find("; the scene file does not read either: scene "), std::string::npos) << lost.err;
  std::filesystem::remove(session);
  std::filesystem::remove_all(robot_dir.parent_path());
}

TEST(EvalReachableCli, ASessionStillBeingWrittenIsNotedAndWithoutAFinishedAreaSaysItWasInterrupted) {
  const auto file = scratchDir() / "interrupted.db";
  std::filesystem::remove(file);
  app::SessionMetadata metadata;
  metadata.robot_name = "lwr4";
  metadata.scene_name = "setup_I";
  app::SessionRecorder recorder(file, metadata);  // open: as if teach were still running or was killed
  recorder.recordSample({0.1, 0, Eigen::Vector3d(-0.5, 0.0, 0.4), Eigen::VectorXd::Zero(7)});
  recorder.flush();
  const auto result = runCliBinary("eval reachable --session " + file.string());
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("note: the session '" + file.string() + "' was not closed cleanly"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("was interrupted before any area was finished"), std::string::npos) << result.err;
  // render draws the unfinished recording's sample and says it is not learned from.
  const auto picture = scratchDir() / "interrupted.png";
  const auto drawn = runCliBinary("render --width 64 --height 48 --supersample 1 --session " + file.string() + " --out " + picture.string());
  EXPECT_EQ(drawn.exit_code, 0) << drawn.err;
  EXPECT_EQ(drawn.json().at("overlays").at("samples"), 1) << drawn.out;
  EXPECT_NE(drawn.err.find("note: 1 sample of a RECORDING that no area record closed"), std::string::npos) << drawn.err;
  recorder.close();
  std::filesystem::remove(file);
}

TEST(EvalTrajectoriesCli, RefusesTheScenesTrajectoriesWhereItListsNoneAndAnUnknownSource) {
  const auto session = tinySession("empty", "trajectories-source.json");
  const auto scene = runCliBinary("eval trajectories --session " + session.string() + " --source scene");
  EXPECT_EQ(scene.exit_code, 2) << scene.err;
  EXPECT_NE(scene.err.find("the scene lists no trajectories"), std::string::npos) << scene.err;
  EXPECT_EQ(std::count(scene.err.begin(), scene.err.end(), '\n'), 1) << scene.err;
  const auto unknown = runCliBinary("eval trajectories --session " + session.string() + " --source samples");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.err;
  const auto drawn = runCliBinary("eval trajectories --session " + session.string() + " --source training-data --per-area 1");
  ASSERT_EQ(drawn.exit_code, 0) << drawn.err;
  EXPECT_EQ(drawn.json().at("source"), "training-data");
  std::filesystem::remove(session);
}

TEST(EvalTrajectoriesCli, DrawsTheRequestedTrajectoriesPerRegion) {
  // The empty scene lists no trajectories: per area `per-area` are drawn, twice as many between.
  const auto session = tinySession("empty", "trajectories.json");
  const auto result = runCliBinary("eval trajectories --session " + session.string() + " --per-area 2 --speed 0.2 --seed 3");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  EXPECT_EQ(json.at("source"), "training-data");
  EXPECT_DOUBLE_EQ(json.at("speed_m_s").get<double>(), 0.2);
  const nlohmann::json& regions = json.at("regions");
  ASSERT_EQ(regions.size(), 3U);
  EXPECT_EQ(regions[0].at("region"), "I1");
  EXPECT_EQ(regions[1].at("region"), "I2");
  EXPECT_EQ(regions[2].at("region"), "between I1 and I2");
  EXPECT_EQ(regions[0].at("trajectories"), 2);
  EXPECT_EQ(regions[1].at("trajectories"), 2);
  EXPECT_EQ(regions[2].at("trajectories"), 4);
  for (const auto& region : regions) {
    const double mean = region.at("e_task_mean_mm").get<double>();
    const double max = region.at("e_task_max_mm").get<double>();
    EXPECT_TRUE(std::isfinite(mean) && mean >= 0.0) << region.dump();
    EXPECT_GE(max, mean) << region.dump();
    EXPECT_GE(region.at("e_task_std_mm").get<double>(), 0.0);
    EXPECT_GE(region.at("e_coll").get<int>(), 0);
    EXPECT_LE(region.at("e_coll").get<int>(), region.at("trajectories").get<int>());
    EXPECT_TRUE(region.at("impossible_trajectories").empty()) << "drawn within reach and clear of the obstacles";
    // E_task is over the trajectories whose start the arm reached without a contact; the
    // largest error names the trajectory it occurred on.
    EXPECT_GE(region.at("e_task_trajectories").get<int>(), region.at("trajectories").get<int>() - region.at("e_coll").get<int>());
    EXPECT_LE(region.at("e_task_trajectories").get<int>(), region.at("trajectories").get<int>());
    EXPECT_TRUE(region.at("e_task_max_trajectory").get<std::string>().starts_with(region.at("region").get<std::string>() + "_"));
    EXPECT_GE(region.at("e_task_max_time_s").get<double>(), 0.0);
    // Each collided trajectory is named after its region and counted under its first contact.
    const nlohmann::json& collided = region.at("collided_trajectories");
    EXPECT_EQ(collided.size(), region.at("e_coll").get<std::size_t>());
    int counted = 0;
    for (const auto& [contact, count] : region.at("contacts").items()) counted += count.get<int>();
    EXPECT_EQ(counted, region.at("e_coll").get<int>());
    for (const auto& trajectory : collided) {
      EXPECT_TRUE(trajectory.at("name").get<std::string>().starts_with(region.at("region").get<std::string>() + "_"));
      EXPECT_EQ(trajectory.at("target_m").size(), 3U);
      EXPECT_GE(trajectory.at("contact_time_s").get<double>(), 0.0);
      EXPECT_TRUE(trajectory.at("on_way_to_start").is_boolean());
    }
  }
  // Deterministic for a seed.
  const auto again = runCliBinary("eval trajectories --session " + session.string() + " --per-area 2 --speed 0.2 --seed 3");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.json().at("regions"), regions);
  std::filesystem::remove(session);
}

TEST(SweepCli, WritesOneRowPerRequestedRowAndOnlyTheRequestedTables) {
  const auto markdown = scratchDir() / "sweep.md";
  // Tab. 3.3 with at most one area: setup_I and setup_II with one area each, on a coarse grid.
  const auto result = runCliBinary("sweep --tables 3.3 --max-areas 1 --spacing 0.3 --markdown " + markdown.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json json = result.json();
  EXPECT_EQ(json.size(), 1U) << json.dump();
  const nlohmann::json& rows = json.at("tab_3_3");
  ASSERT_EQ(rows.size(), 2U);
  EXPECT_EQ(rows[0].at("scene"), "setup_I");
  EXPECT_EQ(rows[1].at("scene"), "setup_II");
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("areas_requested"), 1);
    EXPECT_LE(row.at("reached").get<int>(), row.at("targets").get<int>());
    EXPECT_NEAR(row.at("reachable_fraction").get<double>(),
                row.at("targets").get<int>() > 0 ? row.at("reached").get<double>() / row.at("targets").get<int>() : 0.0, 1e-12);
    EXPECT_DOUBLE_EQ(row.at("spacing_m").get<double>(), 0.3);
  }
  // The markdown holds the same rows: one table line per row after the header and separator.
  std::ifstream in(markdown);
  std::string line;
  int table_rows = 0;
  while (std::getline(in, line)) table_rows += line.rfind("| setup_", 0) == 0 ? 1 : 0;
  EXPECT_EQ(table_rows, 2);
  std::filesystem::remove(markdown);
}

TEST(EvalCli, BadArgumentsGiveExitCodeTwoAndOneLine) {
  const auto dir = scratchDir();
  writeText(dir / "not-a-session.json", R"({"format": "something else"})");
  writeText(dir / "broken.json", "{ not json");
  const auto session = tinySession("empty", "bad-args.json");
  const std::vector<std::string> bad = {
      "eval scene-model",
      "eval scene-model --session /nonexistent/session.json",
      "eval scene-model --session " + (dir / "not-a-session.json").string(),
      "eval trajectories --session " + (dir / "broken.json").string(),
      "eval scene-model --session " + session.string() + " --spacing 5",
      "eval trajectories --session " + session.string() + " --per-area 0",
      "eval trajectories --session " + session.string() + " --speed -1",
      "eval trajectories --session " + session.string() + " --learner nonsense",
      "eval nonsense",
      "eval reachable --session " + session.string() + " --spacing nan",
      "eval reachable --session " + session.string() + " --approach home",
      "eval scene-model --session " + session.string() + " --spacing -nan",
      "plan --session " + session.string() + " --seed -1",
      "plan --session " + session.string() + " --seed 18446744073709551616",
      "eval trajectories --session " + session.string() + " --seed 010",
      "sweep --tables 9.9",
      "sweep --spacing 0",
      "sweep --seeds 0",
      "sweep --tables 3.3 --only setup_I:3",     // no such row
      "sweep --tables 3.2 --only setup_I:1"};    // rows of a table not run
  for (const std::string& arguments : bad) {
    const auto result = runCliBinary(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << ": " << result.err;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << arguments << ": " << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << arguments << ": " << result.err;
    EXPECT_TRUE(result.out.empty()) << arguments;
  }
  std::filesystem::remove_all(dir);
}

TEST(EvalCli, RefusesAHandEditedSessionWhosePosturesLieOutsideTheJointLimitsOrWhoseGraphIsMalformed) {
  const auto dir = scratchDir();
  const auto good = tinySession("empty", "limits-good.json");
  std::ifstream in(good);
  const nlohmann::json session = nlohmann::json::parse(in);
  // A hand-edited q_fixed, a damaged training sample, an ITM node posture out of range, an edge
  // between fractional nodes, a JSON array instead of a session.
  nlohmann::json q_fixed = session;
  q_fixed["areas"][1]["q_fixed"][0] = 10.0;
  nlohmann::json sample = session;
  sample["areas"][0]["q"][5][3] = 1e308;
  nlohmann::json node = session;
  node["itm"]["nodes"][2]["q"][6] = -3.5;
  nlohmann::json fractional_edge = session;
  fractional_edge["itm"]["edges"][0] = {0.7, 1.9};
  // A tip position that its joint values do not put the tip at, and a future version.
  nlohmann::json far_tip = session;
  far_tip["areas"][1]["x"][7] = {5.0, 5.0, 5.0};
  nlohmann::json future = session;
  future["version"] = 99;
  // A joint count edited to another robot's, or to a word.
  nlohmann::json nine_joints = session;
  nine_joints["dof"] = 9;
  nlohmann::json dof_word = session;
  dof_word["dof"] = "seven";
  // Two areas of one name (their figures would be merged under it), an area emptied by hand.
  nlohmann::json same_name = session;
  same_name["areas"][1]["name"] = "left";
  same_name["areas"][0]["name"] = "left";
  nlohmann::json emptied = session;
  emptied["areas"][1]["name"] = "right";
  emptied["areas"][1]["x"] = nlohmann::json::array();
  emptied["areas"][1]["q"] = nlohmann::json::array();
  const std::vector<std::pair<nlohmann::json, std::string>> broken = {
      {same_name, "session: two areas are named 'left' (areas 1 and 2)"},
      {emptied, "session: area 'right' holds no samples"},
      {nine_joints, "session: dof is 9, but the robot 'lwr4' has 7 joints"},
      {dof_word, "session: dof is \"seven\", but the robot 'lwr4' has 7 joints"},
      {q_fixed, "q_fixed of area 2: joint 1 (A1) at 10 lies outside its limits"},
      {sample, "training sample 6: joint 4"},
      {node, "ITM node 2: joint 7"},
      {fractional_edge, "ITM edge: expected a whole number, got 0.7"},
      {far_tip, "training sample 48: its tip position lies"},
      {future, "has version 99; this build reads version 1"},
      {nlohmann::json::array({1, 2}), "is not a flexirob session"},
      {nlohmann::json(nullptr), "is not a flexirob session"},
      {nlohmann::json(42), "is not a flexirob session"}};
  for (const auto& [json, expected] : broken) {
    const auto file = dir / "limits-broken.json";
    writeText(file, json.dump());
    for (const std::string command : {"eval reachable --spacing 0.3", "plan --goals 2"}) {
      const auto result = runCliBinary(command + " --session " + file.string());
      EXPECT_EQ(result.exit_code, 2) << command << ": " << result.err;
      EXPECT_NE(result.err.find(expected), std::string::npos) << result.err;
      EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    }
  }
  // render draws what the file holds, but not a version or a joint count it does not read, nor
  // a point of 1e308 m (its camera had been aimed there and a blank picture written).
  nlohmann::json huge_position = session;
  huge_position["areas"][0]["x"][5][1] = 1e308;
  const auto picture = dir / "limits-broken.png";
  for (const auto& [json, expected] : std::vector<std::pair<nlohmann::json, std::string>>{
           {future, "has version 99; this build reads version 1"},
           {nine_joints, "session: dof is 9, but the robot 'lwr4' has 7 joints"},
           {dof_word, "session: dof is \"seven\", but the robot 'lwr4' has 7 joints"},
           {huge_position, "lies beyond ±1e6 m"}}) {
    const auto file = dir / "limits-broken.json";
    writeText(file, json.dump());
    const auto result = runCliBinary("render --width 64 --height 48 --out " + picture.string() + " --session " + file.string());
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find(expected), std::string::npos) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_TRUE(result.out.empty()) << result.out;
    EXPECT_FALSE(std::filesystem::exists(picture)) << expected;
  }
  // The untouched session is accepted, and so is a sample 0.1 rad past a limit: sessions
  // simulated before the limit stops held have such samples and stay readable.
  EXPECT_EQ(runCliBinary("plan --goals 2 --session " + good.string()).exit_code, 0);
  nlohmann::json overshoot = session;
  Eigen::VectorXd q_over(7);
  for (int j = 0; j < 7; ++j) q_over[j] = session["areas"][0]["q"][3][j].get<double>();
  q_over[1] = 2.094395 + 0.1;  // A2's hardware limit is 120 deg
  const robot::RobotModel lwr4 = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  robot::Kinematics kinematics(lwr4);
  kinematics.update(q_over);
  overshoot["areas"][0]["q"][3][1] = q_over[1];
  overshoot["areas"][0]["x"][3] = {kinematics.p_WT().x(), kinematics.p_WT().y(), kinematics.p_WT().z()};
  const auto overshoot_file = dir / "limits-overshoot.json";
  writeText(overshoot_file, overshoot.dump());
  const auto accepted = runCliBinary("plan --goals 2 --session " + overshoot_file.string());
  EXPECT_EQ(accepted.exit_code, 0) << accepted.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace flexirob
