// Scene files: every element read and written back, the built-in thesis scenes load and are
// geometrically sensible for their robot, and broken or hostile files are refused with a
// one-line InputError naming the file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {
namespace {

// A mesh obstacle's file is loaded with the scene: the fixtures' mesh is a real one.
constexpr const char* kOneTriangleStl =
    "solid triangle\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 0.1 0 0\n   vertex 0 0.1 0\n"
    "  endloop\n endfacet\nendsolid triangle\n";

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

// A fresh folder per test under the system's temp dir, removed afterwards.
class SceneFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("flexirob_scene_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path file = dir_ / name;
    fs::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

  // Loads `text` as a scene file and returns the error message; fails the test if it loads.
  std::string refusal(const std::string& text, const std::string& name = "broken.yaml") const {
    const fs::path file = write(name, text);
    try {
      loadSceneFile(file);
    } catch (const InputError& error) {
      return error.what();
    }
    ADD_FAILURE() << "accepted:\n" << text.substr(0, 400);
    return {};
  }

  fs::path dir_;
};

// A refusal is one line that names the file.
void expectOneLineNamingFile(const std::string& message, const std::string& file_name) {
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(file_name), std::string::npos) << message;
  EXPECT_LT(message.size(), 400U) << message;
}

// ---------------------------------------------------------------------------------------------
// Reading every element

constexpr const char* kFullScene = R"(# every element once
version: 1
name: workcell
description: A test cell with every kind of element.
robot: lwr4
home_posture: {unit: deg, values: [0, 30, 0, -90, 0, 60, 0]}
table: false
obstacles:
  - name: table_leg
    shape: box
    size: [0.1, 0.2, 0.3]
    position: [-0.5, 0.25, 0.15]
    rotation: {rpy: [0, 0, 90], unit: deg}
    colour: [0.1, 0.2, 0.3]
  - name: pipe
    shape: cylinder
    radius: 0.05
    length: 0.6
    position: [0.4, 0, 0.3]
    rotation: {quaternion: [0.7071067811865476, 0.7071067811865476, 0, 0]}
    color: [1, 0, 0, 0.5]
  - name: ball
    shape: sphere
    radius: 0.07
    position: [-0.3, -0.4, 0.5]
  - name: fixture
    shape: mesh
    file: meshes/fixture.stl
    scale: 0.001
    position: [0, 0.6, 0]
    rotation: {rpy: [0, 0, 1.5707963267948966]}
  - shape: mesh
    file: meshes/fixture.stl
    scale: [1, 2, 3]
training_areas:
  - name: left
    centre: [-0.55, 0.37, 0.3]
    radius: 0.1
    box: [0.2, 0.2, 0.2]
    posture: [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]
  - center: [-0.55, -0.37, 0.3]
    posture: {unit: rad, values: [-0.1, 0.2, -0.3, 0.4, -0.5, 0.6, -0.7]}
working_areas:
  - name: interpolation
    centre: [-0.55, 0, 0.3]
    radius: 0.2
grid:
  lower: [-0.9, -0.55, 0.05]
  upper: [0, 0.55, 0.8]
  spacing: 0.05
  tolerance: 0.01
  exclude:
    - {lower: [-0.8, 0.08, 0.56], upper: [-0.25, 0.55, 0.8]}
    - lower: [-0.1, -0.1, 0]
      upper: [0, 0.1, 0.8]
targets:
  - [-0.5, 0, 0.4]
  - [-0.4, 0.1, +0.2]
trajectories:
  - name: sweep
    group: interpolation
    waypoints: [[-0.5, 0.3, 0.3], [-0.5, -0.3, 0.3], [-0.6, -0.3, 0.2]]
  - waypoints:
      - [-0.4, 0, 0.5]
      - [-0.4, 0, 0.2]
parameters:
  hierarchical.kappa_q: 4
  sim.gravity: 9.81
)";

TEST_F(SceneFileTest, ReadsEveryElementWithUnitsAndDefaults) {
  write("meshes/fixture.stl", kOneTriangleStl);
  const fs::path file = write("cell/../workcell.yaml", kFullScene);
  const Scene scene = loadSceneFile(file);

  EXPECT_EQ(scene.name, "workcell");
  EXPECT_EQ(scene.description, "A test cell with every kind of element.");
  EXPECT_EQ(scene.robot, "lwr4");
  EXPECT_EQ(scene.source, file);
  EXPECT_FALSE(scene.table);
  ASSERT_TRUE(scene.home_posture.has_value());
  ASSERT_EQ(scene.home_posture->size(), 7);
  EXPECT_NEAR((*scene.home_posture)[1], kPi / 6.0, 1e-15);
  EXPECT_NEAR((*scene.home_posture)[3], -kPi / 2.0, 1e-15);

  ASSERT_EQ(scene.obstacles.size(), 5U);
  const Obstacle& box = scene.obstacles[0];
  EXPECT_EQ(box.shape, Obstacle::Shape::kBox);
  EXPECT_TRUE(box.size.isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_TRUE(box.X_WO.translation().isApprox(Eigen::Vector3d(-0.5, 0.25, 0.15)));
  // Yaw 90 deg turns the box's x axis onto the world's y axis.
  EXPECT_TRUE((box.X_WO.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE(box.rgba.isApprox(Eigen::Vector4f(0.1F, 0.2F, 0.3F, 1.0F)));

  const Obstacle& pipe = scene.obstacles[1];
  EXPECT_EQ(pipe.shape, Obstacle::Shape::kCylinder);
  EXPECT_DOUBLE_EQ(pipe.size.x(), 0.05);
  EXPECT_DOUBLE_EQ(pipe.size.y(), 0.6);
  // 90 deg about x: the cylinder's axis (z) points along -y.
  EXPECT_TRUE((pipe.X_WO.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_FLOAT_EQ(pipe.rgba[3], 0.5F);

  EXPECT_EQ(scene.obstacles[2].shape, Obstacle::Shape::kSphere);
  EXPECT_DOUBLE_EQ(scene.obstacles[2].size.x(), 0.07);
  EXPECT_TRUE(scene.obstacles[2].X_WO.linear().isIdentity());
  EXPECT_TRUE(scene.obstacles[2].rgba.isApprox(Obstacle{}.rgba));

  const Obstacle& mesh = scene.obstacles[3];
  EXPECT_EQ(mesh.shape, Obstacle::Shape::kMesh);
  EXPECT_TRUE(fs::equivalent(mesh.mesh_file, dir_ / "meshes" / "fixture.stl"));
  EXPECT_TRUE(mesh.mesh_scale.isApprox(Eigen::Vector3d::Constant(0.001)));
  EXPECT_EQ(scene.obstacles[4].name, "obstacle_4");
  EXPECT_TRUE(scene.obstacles[4].mesh_scale.isApprox(Eigen::Vector3d(1, 2, 3)));

  ASSERT_EQ(scene.training_areas.size(), 2U);
  EXPECT_EQ(scene.training_areas[0].name, "left");
  ASSERT_TRUE(scene.training_areas[0].box.has_value());
  EXPECT_TRUE(scene.training_areas[0].box->isApprox(Eigen::Vector3d::Constant(0.2)));
  EXPECT_EQ(scene.training_areas[1].name, "area_2");
  EXPECT_DOUBLE_EQ(scene.training_areas[1].radius, Area{}.radius);
  EXPECT_FALSE(scene.training_areas[1].box.has_value());
  EXPECT_TRUE(scene.training_areas[1].p_WA.isApprox(Eigen::Vector3d(-0.55, -0.37, 0.3)));
  EXPECT_DOUBLE_EQ((*scene.training_areas[1].posture)[6], -0.7);
  ASSERT_EQ(scene.working_areas.size(), 1U);
  EXPECT_DOUBLE_EQ(scene.working_areas[0].radius, 0.2);

  ASSERT_TRUE(scene.grid.has_value());
  EXPECT_DOUBLE_EQ(scene.grid->tolerance, 0.01);
  ASSERT_EQ(scene.grid->excluded.size(), 2U);
  EXPECT_TRUE(scene.grid->excluded[0].min().isApprox(Eigen::Vector3d(-0.8, 0.08, 0.56)));
  EXPECT_TRUE(scene.grid->excluded[0].max().isApprox(Eigen::Vector3d(-0.25, 0.55, 0.8)));
  EXPECT_TRUE(scene.grid->excludes(Eigen::Vector3d(-0.5, 0.3, 0.7)));
  EXPECT_TRUE(scene.grid->excludes(Eigen::Vector3d(-0.5, 0.3, 0.56)));  // on the boundary
  EXPECT_FALSE(scene.grid->excludes(Eigen::Vector3d(-0.5, 0.3, 0.5)));   // under the first box
  EXPECT_TRUE(scene.grid->excludes(Eigen::Vector3d(-0.05, 0.0, 0.4)));  // in the second
  ASSERT_EQ(scene.targets.size(), 2U);
  EXPECT_DOUBLE_EQ(scene.targets[1].z(), 0.2);
  ASSERT_EQ(scene.trajectories.size(), 2U);
  EXPECT_EQ(scene.trajectories[0].group, "interpolation");
  EXPECT_EQ(scene.trajectories[0].waypoints.size(), 3U);
  EXPECT_EQ(scene.trajectories[1].name, "trajectory_2");
  EXPECT_TRUE(scene.trajectories[1].group.empty());
  EXPECT_EQ(scene.parameters.size(), 2U);
  EXPECT_DOUBLE_EQ(scene.parameters.at("hierarchical.kappa_q"), 4.0);
}

void expectScenesEqual(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.description, b.description);
  EXPECT_EQ(a.robot, b.robot);
  EXPECT_EQ(a.table, b.table);
  ASSERT_EQ(a.home_posture.has_value(), b.home_posture.has_value());
  if (a.home_posture) {
    EXPECT_EQ(*a.home_posture, *b.home_posture);
  }
  ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    const Obstacle& p = a.obstacles[i];
    const Obstacle& q = b.obstacles[i];
    EXPECT_EQ(p.name, q.name);
    EXPECT_EQ(p.shape, q.shape);
    EXPECT_EQ(p.size, q.size);
    EXPECT_EQ(p.X_WO.translation(), q.X_WO.translation());
    // Rotations travel as quaternions: equal up to rounding.
    EXPECT_TRUE(p.X_WO.linear().isApprox(q.X_WO.linear(), 1e-14)) << p.name;
    EXPECT_EQ(p.mesh_file, q.mesh_file);
    EXPECT_EQ(p.mesh_scale, q.mesh_scale);
    EXPECT_EQ(p.rgba, q.rgba);
  }
  for (const auto areas : {&Scene::training_areas, &Scene::working_areas}) {
    const auto& x = a.*areas;
    const auto& y = b.*areas;
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_EQ(x[i].name, y[i].name);
      EXPECT_EQ(x[i].p_WA, y[i].p_WA);
      EXPECT_EQ(x[i].radius, y[i].radius);
      EXPECT_TRUE(x[i].box == y[i].box) << x[i].name;
      EXPECT_TRUE(x[i].posture == y[i].posture) << x[i].name;
    }
  }
  ASSERT_EQ(a.grid.has_value(), b.grid.has_value());
  if (a.grid) {
    EXPECT_EQ(a.grid->lower, b.grid->lower);
    EXPECT_EQ(a.grid->upper, b.grid->upper);
    EXPECT_EQ(a.grid->spacing, b.grid->spacing);
    EXPECT_EQ(a.grid->tolerance, b.grid->tolerance);
    ASSERT_EQ(a.grid->excluded.size(), b.grid->excluded.size());
    for (std::size_t i = 0; i < a.grid->excluded.size(); ++i) {
      EXPECT_EQ(a.grid->excluded[i].min(), b.grid->excluded[i].min());
      EXPECT_EQ(a.grid->excluded[i].max(), b.grid->excluded[i].max());
    }
  }
  EXPECT_EQ(a.targets, b.targets);
  ASSERT_EQ(a.trajectories.size(), b.trajectories.size());
  for (std::size_t i = 0; i < a.trajectories.size(); ++i) {
    EXPECT_EQ(a.trajectories[i].name, b.trajectories[i].name);
    EXPECT_EQ(a.trajectories[i].group, b.trajectories[i].group);
    EXPECT_EQ(a.trajectories[i].waypoints, b.trajectories[i].waypoints);
  }
  EXPECT_EQ(a.parameters, b.parameters);
}

TEST_F(SceneFileTest, WritesEveryElementBackToAnEqualScene) {
  write("meshes/fixture.stl", kOneTriangleStl);
  const Scene original = loadSceneFile(write("workcell.yaml", kFullScene));
  const std::string text = sceneToYaml(original);
  const Scene again = loadSceneFile(write("again/workcell.yaml", text));
  expectScenesEqual(original, again);
  EXPECT_NE(text.find("quaternion"), std::string::npos);
}

TEST_F(SceneFileTest, RandomScenesSurviveAWriteReadCycleExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  std::uniform_real_distribution<double> size(0.001, 2.0);
  std::uniform_real_distribution<double> height(0.0, 1.0);  // places lie on or above the table top
  for (int trial = 0; trial < 20; ++trial) {
    Scene scene;
    scene.name = "random_" + std::to_string(trial);
    scene.table = trial % 2 == 0;
    scene.description = "line one: with a colon, 'quotes' and #hash";
    scene.home_posture = Eigen::VectorXd::NullaryExpr(7, [&] { return coordinate(rng) * kPi; });
    for (int i = 0; i < 6; ++i) {
      Obstacle obstacle;
      obstacle.name = "o" + std::to_string(i);
      obstacle.shape = static_cast<Obstacle::Shape>(i % 3);
      obstacle.size = Eigen::Vector3d(size(rng), size(rng), size(rng));
      if (obstacle.shape == Obstacle::Shape::kCylinder) obstacle.size.z() = 0.0;
      if (obstacle.shape == Obstacle::Shape::kSphere) obstacle.size.tail<2>().setZero();
      obstacle.X_WO.translation() = Eigen::Vector3d(coordinate(rng), coordinate(rng), coordinate(rng));
      obstacle.X_WO.linear() =
          Eigen::Quaterniond(coordinate(rng), coordinate(rng), coordinate(rng), coordinate(rng)).normalized().toRotationMatrix();
      obstacle.rgba = Eigen::Vector4f(0.25F, 0.5F, 0.125F, 1.0F / 3.0F);
      scene.obstacles.push_back(obstacle);
    }
    Area area;
    area.name = "a";
    area.p_WA = Eigen::Vector3d(coordinate(rng), coordinate(rng), height(rng));
    area.radius = size(rng);
    area.posture = Eigen::VectorXd::NullaryExpr(9, [&] { return coordinate(rng); });
    scene.training_areas.push_back(area);
    scene.targets.emplace_back(coordinate(rng), coordinate(rng), height(rng));
    scene.trajectories.push_back({"t", "g", {scene.targets.front(), area.p_WA}});
    scene.parameters["sim.gravity"] = 10.0 * height(rng);  // within its declared range [0, 20]
    const Scene again = parseScene(sceneToYaml(scene), dir_, "generated");
    expectScenesEqual(scene, again);
  }
}

TEST_F(SceneFileTest, ResolvesRelativeMeshAndRobotPathsAgainstTheSceneFolder) {
  write("cell/parts/clamp.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write("cell/robots/arm.urdf", "<robot name='x'/>\n");
  const fs::path file = write("cell/scene.yaml",
                              "robot: robots/arm.urdf\n"
                              "obstacles:\n  - {shape: mesh, file: parts/clamp.obj}\n");
  // Loading from another working directory must not matter.
  const Scene scene = loadSceneFile(file);
  EXPECT_TRUE(fs::equivalent(scene.obstacles.at(0).mesh_file, dir_ / "cell" / "parts" / "clamp.obj"));
  EXPECT_TRUE(fs::equivalent(scene.robot, dir_ / "cell" / "robots" / "arm.urdf"));
  EXPECT_EQ(scene.name, "scene");  // no name given: the file's stem
  // A path that is not a built-in name loads as a file.
  EXPECT_EQ(loadScene(file.string()).obstacles.size(), 1U);
}

// A scene from another machine names a URDF file this one lacks: it reads, a program told
// another robot uses that one, and one that would use the scene's own says where it is named.
TEST_F(SceneFileTest, ARobotFileThatIsMissingIsRefusedOnlyWhereNoOtherRobotIsGiven) {
  const fs::path file = write("cell/scene.yaml", "name: cell\nrobot: robots/theirs.urdf\n");
  const Scene scene = loadSceneFile(file);
  EXPECT_EQ(robotFor("lwr4", scene), "lwr4");
  EXPECT_EQ(robotFor("/somewhere/mine.urdf", scene), "/somewhere/mine.urdf");
  try {
    robotFor("", scene);
    FAIL() << "the missing robot file was used";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.string() + ":2: robot: 'robots/theirs.urdf' is neither a built-in robot"), std::string::npos) << message;
  }
  // Present, it is the scene's robot.
  write("cell/robots/theirs.urdf", "<robot name='x'/>\n");
  EXPECT_TRUE(fs::equivalent(robotFor("", loadSceneFile(file)), dir_ / "cell" / "robots" / "theirs.urdf"));
}

TEST(SceneNotes, AScenePlacedTensOfMetresAwayIsNotedAsPerhapsWrittenInMillimetres) {
  const Scene metres = parseScene("training_areas:\n  - {name: a, centre: [-0.5, 0.3, 0.4]}\n", ".", "metres");
  EXPECT_TRUE(sceneNotes(metres).empty());
  const Scene millimetres = parseScene("training_areas:\n  - {name: a, centre: [-500, 300, 400]}\n", ".", "mm");
  ASSERT_EQ(sceneNotes(millimetres).size(), 1U);
  EXPECT_EQ(sceneNotes(millimetres)[0],
            "training area 'a' lies 707 m from the robot's base; lengths are read in metres (was the scene written in millimetres?)");
}

TEST(SceneNotes, AnAreaTensOfMetresWideIsNotedAsPerhapsWrittenInMillimetres) {
  EXPECT_TRUE(sceneNotes(parseScene("training_areas:\n  - {name: a, centre: [-0.5, 0.3, 0.4], radius: 0.15}\n", ".", "m")).empty());
  const Scene wide = parseScene("training_areas:\n  - {name: a, centre: [-0.5, 0.3, 0.4], radius: 999}\n", ".", "wide");
  ASSERT_EQ(sceneNotes(wide).size(), 1U);
  EXPECT_EQ(sceneNotes(wide)[0],
            "training area 'a' reaches 999 m from its centre; lengths are read in metres (was the scene written in millimetres?)");
  // Wider than any arm reaches, though not tens of metres: centimetres, most likely.
  const Scene centimetres = parseScene("working_areas:\n  - {name: w, centre: [-0.5, 0.3, 0.4], radius: 8}\n", ".", "cm");
  ASSERT_EQ(sceneNotes(centimetres).size(), 1U);
  EXPECT_EQ(sceneNotes(centimetres)[0],
            "working area 'w' reaches 8.0 m from its centre; lengths are read in metres (was the scene written in centimetres or "
            "millimetres?)");
  EXPECT_TRUE(sceneNotes(parseScene("working_areas:\n  - {name: w, centre: [-0.5, 0.3, 0.4], radius: 2.5}\n", ".", "m")).empty());
}

// A grid spacing in centimetres leaves one point; eval said so only when run, as "no target".
TEST(SceneNotes, AGridOfAHandfulOfPointsIsNotedAsPerhapsSpacedInCentimetres) {
  const Scene coarse = parseScene("grid: {spacing: 5}\n", ".", "coarse");
  ASSERT_EQ(sceneNotes(coarse).size(), 1U);
  EXPECT_EQ(sceneNotes(coarse)[0],
            "the grid holds 1 point (spacing 5 m); lengths are read in metres (was 'spacing' written in centimetres?)");
  EXPECT_TRUE(sceneNotes(parseScene("grid: {spacing: 0.05}\n", ".", "fine")).empty());
  EXPECT_TRUE(sceneNotes(parseScene("grid: {spacing: 0.4}\n", ".", "coarse but whole")).empty());  // 3 x 3 x 2 points
}

// rpy: [0, 0, 45] meant 45 degrees; read as 45 rad it turned the fixture by 58.3 degrees.
TEST_F(SceneFileTest, RefusesAnRpyAngleBeyondATurnInRadiansAsDegreesWithoutTheirUnit) {
  const std::string message = refusal("obstacles:\n  - {shape: box, size: [0.1, 0.1, 0.1], rotation: {rpy: [0, 0, 45]}}\n");
  expectOneLineNamingFile(message, "broken.yaml:2");
  EXPECT_NE(message.find("rotation.rpy: angles are read in radians and one exceeds a turn; for degrees add 'unit: deg'"), std::string::npos)
      << message;
  EXPECT_NO_THROW(loadSceneFile(write("deg.yaml", "obstacles:\n  - {shape: box, size: [0.1, 0.1, 0.1], rotation: {rpy: [0, 0, 45], unit: deg}}\n")));
  EXPECT_NE(refusal("obstacles:\n  - {shape: box, size: [0.1, 0.1, 0.1], rotation: {rpy: [0, 90, 0], unit: rad}}\n").find("exceeds a turn"),
            std::string::npos);
  EXPECT_NO_THROW(loadSceneFile(write("rad.yaml", "obstacles:\n  - {shape: box, size: [0.1, 0.1, 0.1], rotation: {rpy: [0, 0, -6.28]}}\n")));
}

TEST(SceneNotes, AnObstacleWhollyUnderTheTableTopIsNotedUnlessThereIsNoTable) {
  const std::string obstacles =
      "obstacles:\n"
      "  - {name: buried, shape: box, size: [0.2, 0.2, 0.1], position: [-0.5, 0, -0.1]}\n"
      "  - {name: half_sunk, shape: box, size: [0.2, 0.2, 0.4], position: [-0.5, 0.4, -0.1]}\n"
      "  - {name: tilted, shape: box, size: [0.2, 0.2, 0.1], position: [-0.5, -0.4, -0.1], rotation: {rpy: [0, 90, 0], unit: deg}}\n"
      "  - {name: ball, shape: sphere, radius: 0.05, position: [0, -0.5, -0.06]}\n";
  const std::vector<std::string> notes = sceneNotes(parseScene(obstacles, ".", "sunk"));
  ASSERT_EQ(notes.size(), 2U);
  EXPECT_EQ(notes[0], "obstacle 'buried' lies wholly under the table top (its top at z = -0.050 m), where no link reaches: was z meant to be positive?");
  EXPECT_NE(notes[1].find("obstacle 'ball'"), std::string::npos) << notes[1];  // 'tilted' stands 0.2 m tall: its top at z = 0
  EXPECT_TRUE(sceneNotes(parseScene("table: false\n" + obstacles, ".", "no_table")).empty());
}

TEST(SceneNotes, ATargetInsideAnObstacleIsNamedWithTheObstacle) {
  const std::string obstacles = "obstacles:\n  - {name: box, shape: box, size: [0.2, 0.2, 0.4], position: [-0.5, 0, 0.2]}\n";
  const Scene outside = parseScene(obstacles + "targets:\n  - [-0.5, 0.3, 0.2]\n", ".", "outside");
  EXPECT_TRUE(sceneNotes(outside).empty());
  const Scene inside = parseScene(obstacles + "targets:\n  - [-0.5, 0.3, 0.2]\n  - [-0.45, 0.05, 0.3]\n", ".", "inside");
  const std::vector<std::string> notes = sceneNotes(inside);
  ASSERT_EQ(notes.size(), 1U);
  EXPECT_EQ(notes[0], "targets[1] (-0.450, 0.050, 0.300) m lies inside obstacle 'box': no posture reaches it");
}

// An open mesh counts as the solid it surrounds. A sheet-metal housing open at the floor,
// around the robot, would hold every area and target inside it without a word of why.
TEST(SceneNotes, AnOpenMeshAroundTheRobotsBaseIsNoted) {
  const fs::path dir = fs::temp_directory_path() / ("flexirob_hood_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // Four walls and a roof over [-1, 1]^2 x [0, 1.5] m, no floor; each quad two triangles.
  std::ostringstream stl;
  stl << "solid hood\n";
  const auto quad = [&stl](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
    for (const auto& t : {std::array<Eigen::Vector3d, 3>{a, b, c}, std::array<Eigen::Vector3d, 3>{a, c, d}}) {
      stl << " facet normal 0 0 0\n  outer loop\n";
      for (const Eigen::Vector3d& v : t) stl << "   vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
      stl << "  endloop\n endfacet\n";
    }
  };
  const double h = 1.5;
  quad({-1, -1, 0}, {1, -1, 0}, {1, -1, h}, {-1, -1, h});
  quad({1, -1, 0}, {1, 1, 0}, {1, 1, h}, {1, -1, h});
  quad({1, 1, 0}, {-1, 1, 0}, {-1, 1, h}, {1, 1, h});
  quad({-1, 1, 0}, {-1, -1, 0}, {-1, -1, h}, {-1, 1, h});
  quad({-1, -1, h}, {1, -1, h}, {1, 1, h}, {-1, 1, h});
  stl << "endsolid hood\n";
  std::ofstream(dir / "hood.stl") << stl.str();
  const std::string hood = "obstacles:\n  - {name: hood, shape: mesh, file: hood.stl, position: [";
  const Scene around = parseScene(hood + "0, 0, 0]}\n", dir, "around");
  const std::vector<std::string> notes = sceneNotes(around);
  ASSERT_EQ(notes.size(), 1U);
  EXPECT_NE(notes[0].find("obstacle 'hood' holds the robot's base inside it"), std::string::npos) << notes[0];
  // The same housing beside the robot holds nothing of it.
  EXPECT_TRUE(sceneNotes(parseScene(hood + "-3, 0, 0]}\n", dir, "beside")).empty());
  fs::remove_all(dir);
}

TEST(EvaluationGrid, SpansTheThesisGridWithItsUpperBoundsIncluded) {
  EvaluationGrid grid;  // the defaults are G of Sect. 3.3.2
  grid.spacing = 0.05;
  const Eigen::Vector3i n = grid.counts();
  // 0.9 / 0.05 + 1 = 19, 1.1 / 0.05 + 1 = 23, 0.75 / 0.05 + 1 = 16.
  EXPECT_EQ(n, Eigen::Vector3i(19, 23, 16));
  const auto points = grid.points();
  ASSERT_EQ(points.size(), 19U * 23U * 16U);
  EXPECT_TRUE(points.front().isApprox(grid.lower));
  EXPECT_NEAR((points.back() - grid.upper).norm(), 0.0, 1e-12);
  for (const auto& p : points) {
    EXPECT_TRUE((p.array() >= grid.lower.array() - 1e-12).all() && (p.array() <= grid.upper.array() + 1e-9).all());
  }
  grid.spacing = 0.01;
  EXPECT_EQ(grid.counts(), Eigen::Vector3i(91, 111, 76));
}

TEST(ObstacleGeometry, NamesTheFirstObstacleHoldingAPointAndNoneInFreeSpace) {
  Scene scene;
  Obstacle low;
  low.name = "low";
  low.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  low.X_WO.translation() = Eigen::Vector3d(0.5, 0, 0.1);
  Obstacle high = low;
  high.name = "high";
  high.X_WO.translation() = Eigen::Vector3d(0.5, 0, 0.3);
  scene.obstacles = {low, high};
  EXPECT_EQ(obstacleAt(scene, Eigen::Vector3d(0.5, 0, 0.35)), &scene.obstacles[1]);
  // On the shared face both contain the point; the scene's order decides.
  EXPECT_EQ(obstacleAt(scene, Eigen::Vector3d(0.5, 0, 0.2)), &scene.obstacles[0]);
  EXPECT_EQ(obstacleAt(scene, Eigen::Vector3d(0.5, 0, 0.45)), nullptr);
  EXPECT_EQ(obstacleAt(scene, Eigen::Vector3d(0.5, 0, 0.45), 0.06), &scene.obstacles[1]);
  EXPECT_EQ(obstacleAt(Scene{}, Eigen::Vector3d::Zero()), nullptr);
}

TEST(ObstacleGeometry, ContainsPointsInsideAndWithinTheMarginOnly) {
  Obstacle box;
  box.size = Eigen::Vector3d(0.2, 0.4, 0.8);
  box.X_WO.translation() = Eigen::Vector3d(1, 0, 0.4);
  box.X_WO.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  // Turned by 90 deg the box spans 0.4 m along x and 0.2 m along y.
  EXPECT_TRUE(obstacleContains(box, Eigen::Vector3d(1.19, 0.0, 0.4)));
  EXPECT_FALSE(obstacleContains(box, Eigen::Vector3d(1.0, 0.11, 0.4)));
  EXPECT_TRUE(obstacleContains(box, Eigen::Vector3d(1.0, 0.11, 0.4), 0.02));
  Obstacle cylinder;
  cylinder.shape = Obstacle::Shape::kCylinder;
  cylinder.size = Eigen::Vector3d(0.1, 1.0, 0.0);
  EXPECT_TRUE(obstacleContains(cylinder, Eigen::Vector3d(0.07, 0.07, 0.49)));
  EXPECT_FALSE(obstacleContains(cylinder, Eigen::Vector3d(0.08, 0.08, 0.0)));
  EXPECT_FALSE(obstacleContains(cylinder, Eigen::Vector3d(0.0, 0.0, 0.51)));
  Obstacle sphere;
  sphere.shape = Obstacle::Shape::kSphere;
  sphere.size = Eigen::Vector3d(0.3, 0, 0);
  EXPECT_TRUE(obstacleContains(sphere, Eigen::Vector3d(0.2, 0.2, 0.0)));
  EXPECT_FALSE(obstacleContains(sphere, Eigen::Vector3d(0.3, 0.3, 0.0)));
  Area area;
  area.radius = 0.1;
  EXPECT_TRUE(area.contains(Eigen::Vector3d(0.06, 0.06, 0.0)));
  EXPECT_FALSE(area.contains(Eigen::Vector3d(0.08, 0.08, 0.0)));
  area.box = Eigen::Vector3d(0.2, 0.2, 0.2);
  EXPECT_TRUE(area.contains(Eigen::Vector3d(0.09, 0.09, 0.09)));
}

// The cube [-0.5, 0.5]^3 as an OBJ, triangles facing outwards.
constexpr const char* kCenteredCubeObj =
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
    "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

// An L: [0, 2] x [0, 2] without the notch [1, 2] x [1, 2], from z = 0 to 1, triangles facing
// outwards.
constexpr const char* kLShapeObj =
    "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\n"
    "v 0 0 1\nv 2 0 1\nv 2 1 1\nv 1 1 1\nv 1 2 1\nv 0 2 1\n"
    "f 1 3 2\nf 1 4 3\nf 1 5 4\nf 1 6 5\nf 7 8 9\nf 7 9 10\nf 7 10 11\nf 7 11 12\n"
    "f 1 2 8\nf 1 8 7\nf 2 3 9\nf 2 9 8\nf 3 4 10\nf 3 10 9\n"
    "f 4 5 11\nf 4 11 10\nf 5 6 12\nf 5 12 11\nf 6 1 7\nf 6 7 12\n";

// A mesh cube scaled to a box's size and posed like it holds the same points, inside, outside
// and within a margin of the surface (points too close to the box's surface or margin for the
// mesh's float coordinates to decide are left out).
TEST_F(SceneFileTest, MeshObstacleHoldsWhatItsBoxTwinHoldsWhereverItIsPutTurnedOrScaled) {
  write("meshes/cube.obj", kCenteredCubeObj);
  const Scene scene = loadSceneFile(write("twins.yaml",
                                          "obstacles:\n"
                                          "  - {name: mesh, shape: mesh, file: meshes/cube.obj, scale: [0.2, 0.4, 0.6],\n"
                                          "     position: [-0.5, 0.2, 0.4], rotation: {rpy: [0.3, -0.5, 0.8]}}\n"
                                          "  - {name: box, shape: box, size: [0.2, 0.4, 0.6],\n"
                                          "     position: [-0.5, 0.2, 0.4], rotation: {rpy: [0.3, -0.5, 0.8]}}\n"));
  const Obstacle& mesh = scene.obstacles.at(0);
  const Obstacle& box = scene.obstacles.at(1);
  ASSERT_NE(mesh.mesh_solid, nullptr);  // built with the scene, not per point
  Obstacle built_in_code = mesh;        // without it, the file is read through the cache
  built_in_code.mesh_solid.reset();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> around(-0.5, 0.5);
  int inside = 0, compared = 0;
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3d p_W = box.X_WO.translation() + Eigen::Vector3d(around(rng), around(rng), around(rng));
    const Eigen::Vector3d p_O = box.X_WO.inverse() * p_W;
    const Eigen::Vector3d beyond = p_O.cwiseAbs() - 0.5 * box.size;
    const double signed_distance = beyond.maxCoeff() > 0.0 ? beyond.cwiseMax(0.0).norm() : beyond.maxCoeff();
    for (const double margin : {0.0, 0.03}) {
      if (std::abs(signed_distance - margin) < 1e-5 || std::abs(signed_distance) < 1e-5) continue;
      ++compared;
      const bool expected = obstacleContains(box, p_W, margin);
      inside += expected ? 1 : 0;
      ASSERT_EQ(obstacleContains(mesh, p_W, margin), expected) << p_W.transpose() << " margin " << margin;
      ASSERT_EQ(obstacleContains(built_in_code, p_W, margin), expected) << p_W.transpose() << " margin " << margin;
    }
  }
  EXPECT_GT(inside, 300);
  EXPECT_GT(compared - inside, 300);
  EXPECT_EQ(obstacleAt(scene, box.X_WO.translation()), &mesh);
}

TEST_F(SceneFileTest, ConcaveMeshObstacleLeavesItsNotchFreeWhenTurnedAndScaled) {
  write("l_shape.obj", kLShapeObj);
  // 0.2 x 0.2 x 0.1 m, turned by 90 degrees about z: the L's local (x, y) lies along world (y, -x).
  const Scene scene = loadSceneFile(write("notch.yaml",
                                          "obstacles:\n"
                                          "  - {name: ell, shape: mesh, file: l_shape.obj, scale: 0.1, position: [-0.5, 0, 0.1],\n"
                                          "     rotation: {rpy: [0, 0, 90], unit: deg}}\n"));
  const Obstacle& ell = scene.obstacles.at(0);
  EXPECT_TRUE(obstacleContains(ell, Eigen::Vector3d(-0.55, 0.05, 0.15)));   // the corner square
  EXPECT_TRUE(obstacleContains(ell, Eigen::Vector3d(-0.55, 0.15, 0.15)));   // one arm
  EXPECT_TRUE(obstacleContains(ell, Eigen::Vector3d(-0.65, 0.05, 0.15)));   // the other arm
  const Eigen::Vector3d notch(-0.65, 0.15, 0.15);
  EXPECT_FALSE(obstacleContains(ell, notch));
  EXPECT_FALSE(obstacleContains(ell, notch, 0.04));  // 5 cm from both inner faces
  EXPECT_TRUE(obstacleContains(ell, notch, 0.06));
  EXPECT_FALSE(obstacleContains(ell, Eigen::Vector3d(-0.55, 0.05, 0.21)));  // above it
}

// ---------------------------------------------------------------------------------------------
// Refusing broken and hostile files

TEST_F(SceneFileTest, RefusesMalformedYamlNamingTheLine) {
  const std::string message = refusal("name: x\nobstacles:\n  - {shape: box, size: [1, 2, 3]\n");
  expectOneLineNamingFile(message, "broken.yaml");
  EXPECT_NE(message.find("malformed YAML"), std::string::npos) << message;
  const std::string tab_message = refusal("name: x\n\tdescription: tab\n");
  expectOneLineNamingFile(tab_message, "broken.yaml");
}

TEST_F(SceneFileTest, RefusesUnknownKeysNamingKeyAndLine) {
  const std::string message = refusal("name: x\nobstacles:\n  - shape: box\n    size: [1, 1, 1]\n    posiiton: [0, 0, 0]\n");
  expectOneLineNamingFile(message, "broken.yaml:5");
  EXPECT_NE(message.find("posiiton"), std::string::npos) << message;
  EXPECT_NE(message.find("obstacles[0]"), std::string::npos) << message;
  expectOneLineNamingFile(refusal("name: x\nobstacle: []\n"), "broken.yaml:2");
  expectOneLineNamingFile(refusal("grid: {lower: [0, 0, 0], upper: [1, 1, 1], step: 0.1}\n"), "broken.yaml:1");
  // A key given twice is as suspicious as a misspelt one.
  expectOneLineNamingFile(refusal("name: x\nname: y\n"), "broken.yaml:2");
}

TEST_F(SceneFileTest, RefusesValuesOfTheWrongType) {
  for (const char* text : {
           "name: [a, b]\n",
           "obstacles: {shape: box}\n",
           "obstacles:\n  - {shape: box, size: 0.2}\n",
           "obstacles:\n  - {shape: box, size: [0.2, 0.2]}\n",
           "obstacles:\n  - {shape: box, size: [0.2, 0.2, abc]}\n",
           "obstacles:\n  - {shape: box, size: [0.2, 0.2, '0.2']}\n",
           "obstacles:\n  - {shape: box, size: [0.2, 0.2, 0.2x]}\n",
           "obstacles:\n  - {shape: pyramid, size: [1, 1, 1]}\n",
           "obstacles:\n  - {shape: box, radius: 1, size: [1, 1, 1]}\n",
           "obstacles:\n  - {size: [1, 1, 1]}\n",
           "obstacles:\n  - {shape: cylinder, radius: 0.1}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], rotation: {rpy: [0, 0, 0], quaternion: [1, 0, 0, 0]}}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], rotation: {quaternion: [1, 1, 0, 0]}}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], rotation: {rpy: [0, 0, 90], unit: grad}}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], colour: [0, 2, 0]}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], colour: [0, 0, 0], color: [0, 0, 0]}\n",
           "obstacles:\n  - {name: a, shape: sphere, radius: 1}\n  - {name: a, shape: sphere, radius: 1}\n",
           "home_posture: 0.5\n",
           "table: yes\n",
           "table: 'false'\n",
           "table: 0\n",
           "table: [true]\n",
           "table:\n",
           "home_posture: {unit: deg}\n",
           "home_posture: []\n",
           "training_areas:\n  - {radius: 0.1}\n",
           "training_areas:\n  - {centre: [0, 0, 0], center: [0, 0, 0]}\n",
           "trajectories:\n  - {waypoints: [[0, 0, 0]]}\n",
           "parameters: {'bad name': 1}\n",
           "parameters: {sim.gravity: [1]}\n",
           "version: 2\n",
           "grid: {lower: [0, 0, 1], upper: [1, 1, 0]}\n",
           "grid: {exclude: [{lower: [0, 0, 1], upper: [1, 1, 0]}]}\n",
           "grid: {exclude: [{lower: [0, 0, 0]}]}\n",
           "grid: {exclude: [{upper: [1, 1, 1]}]}\n",
           "grid: {exclude: {lower: [0, 0, 0], upper: [1, 1, 1]}}\n",
           "grid: {exclude: [[0, 0, 0]]}\n",
           "grid: {exclude: [{lower: [0, 0, 0], upper: [1, 1, 1], margin: 0.1}]}\n",
           "grid: {exclude: [{lower: [0, 0], upper: [1, 1, 1]}]}\n",
           "grid: {exclude: [{lower: [0, 0, .nan], upper: [1, 1, 1]}]}\n",
           "grid: {tolerance: 0.3}\n",
       }) {
    SCOPED_TRACE(text);
    expectOneLineNamingFile(refusal(text), "broken.yaml");
  }
}

TEST_F(SceneFileTest, CountsTheLengthOfANameInCharactersNotBytes) {
  std::string umlauts;
  for (int i = 0; i < 200; ++i) umlauts += "\u00e4";  // 400 bytes of UTF-8
  EXPECT_EQ(loadSceneFile(write("umlauts.yaml", "name: \"" + umlauts + "\"\n")).name, umlauts);
  expectOneLineNamingFile(refusal("name: \"" + umlauts + "\u00e4\"\n"), "broken.yaml:1");
  EXPECT_NE(refusal("name: " + std::string(201, 'a') + "\n").find("text longer than 200 characters"), std::string::npos);
}

TEST_F(SceneFileTest, RefusesAParameterNoComponentDeclaresNamingTheOneMeant) {
  const std::string slip = refusal("name: cell\nparameters:\n  sim.gravity: 9.81\n  hierarchical.kapa_q: 4\n");
  expectOneLineNamingFile(slip, "broken.yaml:4");
  EXPECT_NE(slip.find("unknown parameter 'hierarchical.kapa_q' (did you mean 'hierarchical.kappa_q'?)"), std::string::npos) << slip;
  EXPECT_NE(refusal("parameters: {sim_gravity: 9}\n").find("did you mean 'sim.gravity'?"), std::string::npos);
  // Nothing near: no guess, but the names there are.
  const std::string stranger = refusal("parameters: {itm.e_max: 0.05}\n");
  EXPECT_EQ(stranger.find("did you mean"), std::string::npos) << stranger;
  expectOneLineNamingFile(stranger, "broken.yaml:1");
  EXPECT_NE(stranger.find("the parameters are hierarchical.{kappa_x, kappa_q, "), std::string::npos) << stranger;
  EXPECT_NE(stranger.find(", interaction.{joint_damping, "), std::string::npos) << stranger;
  // A guess only where one name is meant: the start of a name, or a slip within the component.
  EXPECT_NE(refusal("parameters: {hierarchical.sigma: 0.1}\n").find("(did you mean 'hierarchical.sigma_threshold'?)"), std::string::npos);
  const std::string two = refusal("parameters: {hierarchical.kappa: 3}\n");
  EXPECT_EQ(two.find("did you mean"), std::string::npos) << two;
  EXPECT_NE(two.find("the parameters are hierarchical.{kappa_x, kappa_q, sigma_threshold, damping_max}"), std::string::npos) << two;
  EXPECT_EQ(refusal("parameters: {interaction.joint_stiffness: 3}\n").find("did you mean"), std::string::npos);
  // The triggers follow the workflow's options, so a scene cannot set them.
  EXPECT_NE(refusal("parameters: {triggers.converged_time: 3}\n").find("unknown parameter"), std::string::npos);
  // Out of its declared range, said where it is written (render applies no parameter at all).
  const std::string range = refusal("parameters:\n  hierarchical.kappa_q: 1000\n");
  expectOneLineNamingFile(range, "broken.yaml:2");
  EXPECT_NE(range.find("parameters: parameter 'hierarchical.kappa_q': expected a value in [0, 100] 1/s, got 1000"), std::string::npos) << range;
  // A copy a session stored before names were checked still reads: the name is left out and said.
  const Scene stored = parseScene("parameters: {hierarchical.kapa_q: 4, sim.gravity: 9}\n", dir_, "stored", SceneText::kSessionCopy);
  EXPECT_EQ(stored.ignored_parameters, std::vector<std::string>{"hierarchical.kapa_q"});
  EXPECT_EQ(stored.parameters.count("hierarchical.kapa_q"), 0U);
  EXPECT_DOUBLE_EQ(stored.parameters.at("sim.gravity"), 9.0);
  ASSERT_EQ(sceneNotes(stored).size(), 1U);
  EXPECT_NE(sceneNotes(stored)[0].find("parameter 'hierarchical.kapa_q' is not one a scene sets; left out"), std::string::npos) << sceneNotes(stored)[0];
  const Scene scene = loadSceneFile(write("tuned.yaml", "parameters: {interaction.joint_damping: 7, limits.acceleration: 3}\n"));
  EXPECT_DOUBLE_EQ(scene.parameters.at("interaction.joint_damping"), 7.0);
  EXPECT_DOUBLE_EQ(scene.parameters.at("limits.acceleration"), 3.0);
}

TEST_F(SceneFileTest, RefusesNonFiniteNumbers) {
  for (const char* value : {".nan", ".NaN", ".inf", "-.inf", "nan", "inf", "1e999", "-1e400"}) {
    SCOPED_TRACE(value);
    const std::string message = refusal(std::string("targets:\n  - [0, 0, ") + value + "]\n");
    expectOneLineNamingFile(message, "broken.yaml:2");
    EXPECT_NE(message.find("finite"), std::string::npos) << message;
  }
  expectOneLineNamingFile(refusal("parameters: {sim.gravity: .nan}\n"), "broken.yaml:1");
  expectOneLineNamingFile(refusal("home_posture: [0, .inf]\n"), "broken.yaml:1");
}

TEST_F(SceneFileTest, RefusesNegativeZeroAndAbsurdSizes) {
  for (const char* text : {
           "obstacles:\n  - {shape: box, size: [0.2, -0.2, 0.2]}\n",
           "obstacles:\n  - {shape: box, size: [0.2, 0, 0.2]}\n",
           "obstacles:\n  - {shape: sphere, radius: -1}\n",
           "obstacles:\n  - {shape: cylinder, radius: 0.1, length: -0.5}\n",
           "obstacles:\n  - {shape: box, size: [1e6, 1, 1]}\n",
           "obstacles:\n  - {shape: box, size: [1, 1, 1], position: [0, 5000, 0]}\n",
           "training_areas:\n  - {centre: [0, 0, 0], radius: -0.1}\n",
           "training_areas:\n  - {centre: [0, 0, 0], box: [0.1, -0.1, 0.1]}\n",
           "grid: {spacing: 0}\n",
           "grid: {spacing: 0.0001}\n",  // 10^10 points
       }) {
    SCOPED_TRACE(text);
    expectOneLineNamingFile(refusal(text), "broken.yaml");
  }
  // A grid too large for any integer says how large it is, not an overflowed count.
  const std::string huge = refusal("grid: {lower: [-1000, -1000, 0], upper: [1000, 1000, 1000], spacing: 0.0001}\n");
  EXPECT_NE(huge.find("would have 4e+21 points"), std::string::npos) << huge;
}

// The table top z = 0 the robot stands on is solid: an area, target, waypoint or grid below it
// could only be reached through it (and with `table: false` the collision model would not even
// notice).
TEST_F(SceneFileTest, RefusesPlacesBelowTheTableTop) {
  for (const std::string text : {
           "training_areas:\n  - {centre: [0.5, 0.3, -0.2]}\n",
           "working_areas:\n  - {centre: [0.5, 0.3, -0.01]}\n",
           "targets: [[0.5, 0, 0.3], [0.5, 0, -0.1]]\n",
           "trajectories:\n  - {waypoints: [[0.5, 0, 0.3], [0.5, 0, -0.1]]}\n",
           "grid: {lower: [-0.5, -0.5, -0.3], upper: [0.5, 0.5, 0.5], spacing: 0.1}\n",
       }) {
    SCOPED_TRACE(text);
    const std::string message = refusal(text);
    expectOneLineNamingFile(message, "broken.yaml");
    EXPECT_NE(message.find("below the table top"), std::string::npos) << message;
  }
  // On the table top is allowed.
  const Scene scene = loadSceneFile(write("on_table.yaml", "training_areas:\n  - {centre: [0.5, 0.3, 0]}\n"));
  EXPECT_DOUBLE_EQ(scene.training_areas.at(0).p_WA.z(), 0.0);
}

TEST_F(SceneFileTest, RefusesMissingAndBrokenMeshFilesNamingTheLine) {
  const std::string message = refusal("obstacles:\n  - {shape: mesh, file: meshes/nowhere.stl}\n");
  expectOneLineNamingFile(message, "broken.yaml:2");
  EXPECT_NE(message.find("nowhere.stl"), std::string::npos) << message;
  fs::create_directories(dir_ / "folder.stl");
  const std::string folder = refusal("obstacles:\n  - {shape: mesh, file: folder.stl}\n");
  expectOneLineNamingFile(folder, "broken.yaml");
  EXPECT_NE(folder.find("'folder.stl' is a folder, not a mesh file"), std::string::npos) << folder;
  // A mesh that cannot be read is reported at the scene line that names it, with the mesh's reason.
  write("meshes/readme.stl", "These meshes are exported from the fixture's CAD model in millimetres.\n");
  const std::string broken = refusal("name: cell\nobstacles:\n  - {shape: mesh, file: meshes/readme.stl}\n");
  expectOneLineNamingFile(broken, "broken.yaml:3");
  EXPECT_NE(broken.find("text but not an ASCII STL"), std::string::npos) << broken;
}

TEST_F(SceneFileTest, RefusesEmptyAndBinaryFiles) {
  expectOneLineNamingFile(refusal(""), "broken.yaml");
  expectOneLineNamingFile(refusal("# only a comment\n"), "broken.yaml");
  expectOneLineNamingFile(refusal("just a string\n"), "broken.yaml");
  expectOneLineNamingFile(refusal("- a\n- list\n"), "broken.yaml");
  expectOneLineNamingFile(refusal("name: a\n---\nname: b\n"), "broken.yaml");
  std::string garbage(4096, '\0');
  std::mt19937 rng(3);
  for (auto& c : garbage) c = static_cast<char>(rng() & 0xFFU);
  const std::string message = refusal(garbage, "garbage.yaml");
  expectOneLineNamingFile(message, "garbage.yaml");
  EXPECT_NE(message.find("not a text file"), std::string::npos) << message;
  expectOneLineNamingFile(refusal("name: \xC3\x28\n"), "broken.yaml");  // invalid UTF-8
}

// A hang would show as the CTest timeout; how fast the refusal is belongs to a benchmark.
TEST_F(SceneFileTest, RefusesHugeCountsAndAliasBombsBeforeExpandingThem) {
  std::string many = "obstacles:\n";
  for (int i = 0; i < 100001; ++i) many += "- {shape: sphere, radius: 1}\n";
  const std::string message = refusal(many);
  expectOneLineNamingFile(message, "broken.yaml");
  EXPECT_NE(message.find("too many"), std::string::npos) << message;

  // 100 000 obstacles is the limit, not a refusal.
  many = "obstacles:\n";
  for (int i = 0; i < 100000; ++i) many += "- {shape: sphere, radius: 1}\n";
  EXPECT_EQ(loadSceneFile(write("many.yaml", many)).obstacles.size(), 100000U);

  std::string boxes = "grid:\n  exclude:\n";
  for (int i = 0; i < 1001; ++i) boxes += "  - {lower: [0, 0, 0], upper: [1, 1, 1]}\n";
  const std::string boxes_message = refusal(boxes);
  expectOneLineNamingFile(boxes_message, "broken.yaml");
  EXPECT_NE(boxes_message.find("too many"), std::string::npos) << boxes_message;

  // Aliases repeat one list of 10 001 waypoints in 10 000 trajectories: 400 kB of text that
  // would expand to 10^8 waypoints.
  std::string bomb = "trajectories:\n  - {name: t0, waypoints: &p [";
  for (int i = 0; i < 10000; ++i) bomb += "[0, 0, 0], ";
  bomb += "[0, 0, 0]]}\n";
  for (int i = 1; i < 10000; ++i) bomb += "  - {name: t" + std::to_string(i) + ", waypoints: *p}\n";
  const std::string bomb_message = refusal(bomb);
  expectOneLineNamingFile(bomb_message, "broken.yaml");
  EXPECT_NE(bomb_message.find("waypoints"), std::string::npos) << bomb_message;
  // More YAML values than any scene needs are refused while parsing, before they take memory.
  std::string values = "targets: [";
  values.reserve(6'100'000);
  for (int i = 0; i < 3'000'000; ++i) values += "0,";
  values += "0]\n";
  const std::string values_message = refusal(values);
  expectOneLineNamingFile(values_message, "broken.yaml:1");
  EXPECT_NE(values_message.find("YAML values"), std::string::npos) << values_message;
}

TEST_F(SceneFileTest, RefusesDeeplyNestedInputWithoutCrashing) {
  const std::string open(100000, '[');
  expectOneLineNamingFile(refusal("targets: " + open + "\n"), "broken.yaml");
  expectOneLineNamingFile(refusal("targets: " + open + std::string(100000, ']') + "\n"), "broken.yaml");
  std::string maps;
  for (int i = 0; i < 20000; ++i) maps += "{a: ";
  expectOneLineNamingFile(refusal("grid: " + maps + "\n"), "broken.yaml");
}

TEST_F(SceneFileTest, RefusesFilesLargerThan16Megabytes) {
  const fs::path file = dir_ / "large.yaml";
  { std::ofstream(file) << "name: large\n"; }
  fs::resize_file(file, 16U * 1024U * 1024U + 1U);  // sparse: costs no disk space
  try {
    loadSceneFile(file);
    ADD_FAILURE() << "a 16 MB + 1 byte file was accepted";
  } catch (const InputError& error) {
    expectOneLineNamingFile(error.what(), "large.yaml");
    EXPECT_NE(std::string(error.what()).find("16 MB"), std::string::npos) << error.what();
  }
}

TEST_F(SceneFileTest, RefusesMissingFilesAndUnknownSceneNames) {
  EXPECT_THROW(loadSceneFile(dir_ / "absent.yaml"), InputError);
  EXPECT_THROW(loadSceneFile(dir_), InputError);
  try {
    loadScene("setup_Z");
    ADD_FAILURE() << "an unknown scene name was accepted";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("setup_Z"), std::string::npos);
    EXPECT_NE(message.find("setup_A"), std::string::npos) << "the message lists the built-in scenes";
  }
}

TEST_F(SceneFileTest, AFolderOrABrokenLinkGivenForASceneIsNamedAsSuch) {
  const auto messageFor = [](const fs::path& path) {
    try {
      loadScene(path.string());
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(messageFor(dir_).find("nor a readable scene file (it is a folder)"), std::string::npos) << messageFor(dir_);
  EXPECT_NE(messageFor(dir_ / "absent.yaml").find("(no such file)"), std::string::npos) << messageFor(dir_ / "absent.yaml");
  fs::create_symlink(dir_ / "moved.yaml", dir_ / "link.yaml");
  EXPECT_NE(messageFor(dir_ / "link.yaml").find("(a broken symbolic link)"), std::string::npos) << messageFor(dir_ / "link.yaml");
}

// ---------------------------------------------------------------------------------------------
// Built-in scenes

TEST(BuiltinScenes, AllLoadUnderTheirNames) {
  for (const auto& name : builtinSceneNames()) {
    SCOPED_TRACE(name);
    const Scene scene = loadScene(name);
    EXPECT_EQ(scene.name, name);
    EXPECT_FALSE(scene.description.empty());
    EXPECT_TRUE(fs::equivalent(scene.source, resourceDir() / "scenes" / (name + ".yaml")));
    // Writing and reading back a shipped scene loses nothing.
    expectScenesEqual(scene, parseScene(sceneToYaml(scene), scene.source.parent_path(), name));
  }
}

TEST(BuiltinScenes, NoNameAndEmptyAreTheSameEmptyScene) {
  const Scene none = loadScene("");
  const Scene empty = loadScene("empty");
  EXPECT_TRUE(none.source.empty());
  expectScenesEqual(none, empty);
  EXPECT_TRUE(empty.obstacles.empty());
  EXPECT_TRUE(empty.table);
  EXPECT_TRUE(empty.training_areas.empty());
}

// What the thesis fixes about each setup (Sect. 3.3, 4.3, 8.2, App. B).
TEST(BuiltinScenes, HoldWhatTheThesisStates) {
  for (const char* name : {"setup_A", "setup_B", "setup_C", "setup_D"}) {
    SCOPED_TRACE(name);
    const Scene scene = loadScene(name);
    ASSERT_GE(scene.training_areas.size(), 2U);
    // Left and right training areas about 0.74 m apart (Sect. 3.3.1).
    EXPECT_NEAR((scene.training_areas[0].p_WA - scene.training_areas[1].p_WA).norm(), 0.74, 0.03);
    // Tab. 3.2: 100 straight trajectories, 25 left, 25 right, 50 in the interpolation area, each
    // inside the area it evaluates.
    std::map<std::string, int> per_group;
    const Area* interpolation = nullptr;
    for (const auto& area : scene.working_areas) {
      if (area.name == "interpolation") interpolation = &area;
    }
    ASSERT_NE(interpolation, nullptr);
    for (const auto& trajectory : scene.trajectories) {
      ++per_group[trajectory.group];
      EXPECT_EQ(trajectory.waypoints.size(), 2U);
      const Area& area = trajectory.group == "left"    ? scene.training_areas[0]
                         : trajectory.group == "right" ? scene.training_areas[1]
                                                       : *interpolation;
      for (const auto& p : trajectory.waypoints) EXPECT_TRUE(area.contains(p)) << trajectory.name;
    }
    EXPECT_EQ(scene.trajectories.size(), 100U);
    EXPECT_EQ(per_group["left"], 25);
    EXPECT_EQ(per_group["right"], 25);
    EXPECT_EQ(per_group["interpolation"], 50);
  }
  // D* adds a third area in the former interpolation area.
  const Scene d = loadScene("setup_D");
  ASSERT_EQ(d.training_areas.size(), 3U);
  EXPECT_TRUE(d.working_areas.front().contains(d.training_areas[2].p_WA));

  const Scene one = loadScene("setup_I");
  const Scene two = loadScene("setup_II");
  EXPECT_EQ(one.training_areas.size(), 12U);  // sweeps 1, 2, 4, 6, 12 (Tab. 3.3)
  EXPECT_EQ(two.training_areas.size(), 21U);  // sweeps 1, 2, 4, 6, 21
  for (const Scene* scene : {&one, &two}) {
    ASSERT_TRUE(scene->grid.has_value());
    EXPECT_TRUE(scene->grid->lower.isApprox(Eigen::Vector3d(-0.9, -0.55, 0.05)));
    EXPECT_TRUE(scene->grid->upper.isApprox(Eigen::Vector3d(0.0, 0.55, 0.8)));
    EXPECT_DOUBLE_EQ(scene->grid->tolerance, 0.01);
  }
  // Setup I: one 0.2 x 0.2 x 0.8 m box and a board at z = 0.55 m.
  int tall_boxes = 0;
  bool board = false;
  for (const auto& o : one.obstacles) {
    if (o.size.isApprox(Eigen::Vector3d(0.2, 0.2, 0.8))) ++tall_boxes;
    if (std::abs(o.X_WO.translation().z() - 0.55) < 0.011 && o.size.z() < 0.05) board = true;
  }
  EXPECT_EQ(tall_boxes, 1);
  EXPECT_TRUE(board);
  // Setup II: two such boxes, one on each side, leaving about 5 cm beside the elbow housing
  // (radius 0.065 m) on each side.
  ASSERT_EQ(two.obstacles.size(), 2U);
  double gap = 0.0;
  for (const auto& o : two.obstacles) {
    EXPECT_TRUE(o.size.isApprox(Eigen::Vector3d(0.2, 0.2, 0.8)));
    gap += std::abs(o.X_WO.translation().y()) - 0.5 * o.size.y();
  }
  EXPECT_LT(two.obstacles[0].X_WO.translation().y() * two.obstacles[1].X_WO.translation().y(), 0.0);
  EXPECT_NEAR(gap - 2 * 0.065, 2 * 0.05, 0.02);

  const Scene harting = loadScene("harting");
  EXPECT_EQ(harting.training_areas.size(), 2U);
  const auto parcours = std::find_if(harting.trajectories.begin(), harting.trajectories.end(),
                                     [](const Trajectory& t) { return t.name == "parcours"; });
  ASSERT_NE(parcours, harting.trajectories.end());
  EXPECT_GE(parcours->waypoints.size(), 3U);

  const Scene arm9 = loadScene("arm9_areas");
  EXPECT_EQ(arm9.robot, "arm9");
  ASSERT_EQ(arm9.working_areas.size(), 3U);
  EXPECT_EQ(arm9.working_areas[0].name, "A1");
  EXPECT_EQ(arm9.working_areas[1].name, "A2");
  EXPECT_EQ(arm9.working_areas[2].name, "A3");
  EXPECT_EQ(arm9.training_areas.size(), 8U);  // K = 8 (Sect. 8.3)
}

// A grid point meant to lie on an excluded box's face is computed as lower + spacing * i and
// lands there only up to rounding (x = -0.6 + 6 * 0.1 = 1.1e-16, not 0): it is still excluded.
TEST(EvaluationGrid, ExcludedBoxesHoldTheGridPointsOnTheirFacesDespiteRounding) {
  EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.6, -0.6, 0.05);
  grid.upper = Eigen::Vector3d(0.6, 0.6, 1.0);
  grid.spacing = 0.1;
  grid.excluded.emplace_back(Eigen::Vector3d(-0.6, -0.6, 0.05), Eigen::Vector3d(0.0, 0.0, 1.0));
  int excluded = 0;
  for (const Eigen::Vector3d& p : grid.points()) {
    const bool inside = p.x() < 0.05 && p.y() < 0.05;  // half a spacing past the faces
    EXPECT_EQ(grid.excludes(p), inside) << p.transpose();
    excluded += inside ? 1 : 0;
  }
  EXPECT_EQ(excluded, 7 * 7 * 10);
  EXPECT_FALSE(grid.excludes(Eigen::Vector3d(1e-6, -0.3, 0.5)));  // a micrometre outside is outside
}

TEST(EvaluationGrid, SaysHowLargeAGridTooLargeToEvaluateWouldBe) {
  EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-2, -2, 0);
  grid.upper = Eigen::Vector3d(2, 2, 2);
  grid.spacing = 0.1;
  EXPECT_DOUBLE_EQ(grid.pointCount(), 41.0 * 41.0 * 21.0);
  EXPECT_EQ(grid.sizeProblem(), "");
  grid.spacing = 0.01;
  EXPECT_DOUBLE_EQ(grid.pointCount(), 401.0 * 401.0 * 201.0);
  EXPECT_EQ(grid.sizeProblem(), "the grid would have 3.23e+07 points (at most 5000000)");
}

// Setup II's listed postures keep to the one redundancy family the thesis' tutor used there
// (Sect. 4.2.1, Fig. 4.5), so that a learner interpolates between areas instead of averaging IK
// families: the elbow (q4) and wrist (q6) bent one way everywhere, q1 ~ 0 in front of the boxes
// (the upper arm between them), q3 of opposite sign to y, and each right area the mirror image of
// its left twin (q1, q3, q5, q7 negated).
TEST(BuiltinScenes, SetupIIPosturesKeepToOneRedundancyFamily) {
  const Scene scene = loadScene("setup_II");
  int with_posture = 0;
  for (const auto& area : scene.training_areas) {
    SCOPED_TRACE(area.name);
    if (!area.posture) continue;
    ++with_posture;
    const Eigen::VectorXd& q = *area.posture;
    ASSERT_EQ(q.size(), 7);
    EXPECT_LT(q[3], -0.3);
    EXPECT_GT(q[5], 0.3);
    const Eigen::Vector3d& c = area.p_WA;
    if (c.x() < -0.3) {
      EXPECT_LT(std::abs(q[0]), 0.1);
      if (std::abs(c.y()) > 0.05) {
        EXPECT_LT(q[2] * c.y(), 0.0);
      }
    }
    if (c.y() < -0.05) {
      const auto twin = std::find_if(scene.training_areas.begin(), scene.training_areas.end(), [&](const Area& other) {
        return other.p_WA.isApprox(Eigen::Vector3d(c.x(), -c.y(), c.z()));
      });
      ASSERT_NE(twin, scene.training_areas.end());
      if (!twin->posture) continue;
      Eigen::VectorXd mirrored = *twin->posture;
      for (const int j : {0, 2, 4, 6}) mirrored[j] = -mirrored[j];
      EXPECT_TRUE(q.isApprox(mirrored, 1e-9)) << q.transpose() << " vs the mirrored " << mirrored.transpose();
    }
  }
  EXPECT_GE(with_posture, 19);
}

// Loads a built-in robot; skips the calling test while its meshes have not been generated.
std::optional<RobotModel> loadRobotOrNull(const std::string& robot, std::string& why) {
  try {
    return RobotModel::fromUrdfFile(resolveRobotPath(robot));
  } catch (const InputError& error) {
    why = error.what();
    if (why.find("mesh") == std::string::npos) throw;
    return std::nullopt;
  }
}

// Setup I's listed postures keep to one redundancy family as the thesis' tutor did there
// (Sect. 4.2.1, Fig. 4.4: q2 near pi/2): the upper arm about level, so the elbow stays under the
// board, with q3, q4 < 0 and q6 > 0 everywhere. Only the area beside the box's back face is out
// of the level arm's way and reached leaning back (q2 < 0) with the same signs.
TEST(BuiltinScenes, SetupIPosturesKeepToOneRedundancyFamily) {
  const Scene scene = loadScene("setup_I");
  std::string why;
  const auto model = loadRobotOrNull(scene.robot, why);
  if (!model) GTEST_SKIP() << "robot meshes not generated yet: " << why;
  Kinematics kinematics(*model);
  const auto board = std::find_if(scene.obstacles.begin(), scene.obstacles.end(), [](const Obstacle& o) { return o.name == "board"; });
  ASSERT_NE(board, scene.obstacles.end());
  const double board_underside = board->X_WO.translation().z() - 0.01;
  int level = 0;
  for (const auto& area : scene.training_areas) {
    SCOPED_TRACE(area.name);
    ASSERT_TRUE(area.posture.has_value());
    const Eigen::VectorXd& q = *area.posture;
    ASSERT_EQ(q.size(), 7);
    EXPECT_LT(q[2], 0.0);
    EXPECT_LT(q[3], -0.3);
    EXPECT_GT(q[5], 0.3);
    if (q[1] < 0.0) continue;  // leaning back around the box
    ++level;
    EXPECT_GE(q[1], 1.0);
    EXPECT_LE(q[1], 1.7);
    kinematics.update(q);
    // Body 4 is the forearm; its origin is the elbow.
    EXPECT_LT(kinematics.X_WB(4).translation().z(), board_underside - 0.04);
  }
  EXPECT_GE(level, 11);
}

// Points along the kinematic skeleton (joint origins joined by straight lines, up to the tip)
// at most 1 cm apart. The links' surfaces lie at least 4.5 cm (the hand's radius) around it.
std::vector<Eigen::Vector3d> skeleton(const Kinematics& kinematics, int first_body) {
  std::vector<Eigen::Vector3d> corners;
  for (int b = first_body; b <= kinematics.model().dof(); ++b) corners.push_back(kinematics.X_WB(b).translation());
  corners.push_back(kinematics.p_WT());
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i + 1 < corners.size(); ++i) {
    const int steps = std::max(1, static_cast<int>(std::ceil((corners[i + 1] - corners[i]).norm() / 0.01)));
    for (int k = 0; k <= steps; ++k) points.push_back(corners[i] + (corners[i + 1] - corners[i]) * (static_cast<double>(k) / steps));
  }
  return points;
}

// A posture must lie within the URDF's software limits (the ones controllers keep to, inside the
// hardware limits) and keep the arm's axis 3 cm clear of every obstacle and above the table
// (z = 0), beyond the shoulder.
void expectPostureClear(const RobotModel& model, const Scene& scene, const Eigen::VectorXd& q,
                        const std::string& what) {
  ASSERT_EQ(q.size(), model.dof()) << what;
  EXPECT_TRUE((q.array() >= model.softLowerLimits().array()).all() &&
              (q.array() <= model.softUpperLimits().array()).all())
      << what << ": outside the joint limits: " << q.transpose();
  Kinematics kinematics(model);
  kinematics.update(q);
  for (const auto& p : skeleton(kinematics, 2)) {
    EXPECT_GT(p.z(), 0.03) << what << " reaches into the table at " << p.transpose();
    for (const auto& obstacle : scene.obstacles) {
      EXPECT_FALSE(obstacleContains(obstacle, p, 0.03)) << what << " runs into " << obstacle.name << " at " << p.transpose();
    }
  }
}

TEST(BuiltinScenes, AreGeometricallySensibleForTheirRobot) {
  for (const auto& name : builtinSceneNames()) {
    SCOPED_TRACE(name);
    const Scene scene = loadScene(name);
    std::string why;
    const auto model = loadRobotOrNull(scene.robot, why);
    if (!model) GTEST_SKIP() << "robot meshes not generated yet: " << why;
    Kinematics kinematics(*model);
    kinematics.update(Eigen::VectorXd::Zero(model->dof()));
    // Joint 2 (the shoulder) is the first joint off the vertical axis; the arm's reach is the
    // stretched length from there to the tip, which q = 0 (straight up) realizes for the LWR
    // IV and its 9-DoF variant.
    const Eigen::Vector3d p_WShoulder = kinematics.X_WB(2).translation();
    const double reach = (kinematics.p_WT() - p_WShoulder).norm();
    ASSERT_GT(reach, 0.5);

    // No obstacle touches the robot's base: a 9 cm cylinder (base radius 8 cm plus collision
    // margin) up to the shoulder.
    for (double z = 0.0; z <= p_WShoulder.z(); z += 0.01) {
      for (const auto& obstacle : scene.obstacles) {
        EXPECT_FALSE(obstacleContains(obstacle, Eigen::Vector3d(0, 0, z), 0.09)) << obstacle.name << " at the base";
      }
    }
    // Every area centre lies outside every obstacle and within reach, with some room.
    for (const auto* areas : {&scene.training_areas, &scene.working_areas}) {
      for (const auto& area : *areas) {
        for (const auto& obstacle : scene.obstacles) {
          EXPECT_FALSE(obstacleContains(obstacle, area.p_WA, 0.03)) << area.name << " inside " << obstacle.name;
        }
        EXPECT_LT((area.p_WA - p_WShoulder).norm(), reach - 0.05) << area.name << " out of reach";
        EXPECT_GT(area.p_WA.z(), 0.0) << area.name << " below the table";
        if (area.posture) {
          expectPostureClear(*model, scene, *area.posture, area.name + "'s posture");
          // The suggested posture puts the flange into its area.
          kinematics.update(*area.posture);
          EXPECT_LE((kinematics.p_WT() - area.p_WA).norm(), area.radius) << area.name;
        }
      }
    }
    if (scene.home_posture) expectPostureClear(*model, scene, *scene.home_posture, "home posture");
    for (const auto& trajectory : scene.trajectories) {
      for (const auto& p : trajectory.waypoints) {
        EXPECT_LT((p - p_WShoulder).norm(), reach - 0.05) << trajectory.name;
        for (const auto& obstacle : scene.obstacles) {
          EXPECT_FALSE(obstacleContains(obstacle, p, 0.02)) << trajectory.name << " runs into " << obstacle.name;
        }
      }
    }
  }
}

TEST(ScenePostures, ARobotOptionWinsOverTheScenesRobotAndPosturesMustHaveItsJointCount) {
  Scene scene;
  scene.name = "cell";
  scene.robot = "arm9";
  EXPECT_EQ(robotFor("", scene), "arm9");
  EXPECT_EQ(robotFor("lwr4", scene), "lwr4");
  scene.robot.clear();
  EXPECT_EQ(robotFor("", scene), "lwr4");

  scene.robot = "arm9";
  scene.home_posture = Eigen::VectorXd::Zero(9);
  Area area;
  area.name = "left";
  area.posture = Eigen::VectorXd::Zero(9);
  scene.training_areas.push_back(area);
  EXPECT_NO_THROW(checkPosturesFit(scene, 9, "arm9"));
  struct Mismatch {
    std::string what;
    int dof;
    std::function<void(Scene&)> change;
  };
  for (const Mismatch& mismatch : std::vector<Mismatch>{
           {"home_posture has 9 joint values, the robot 'r' has 7 joints", 7, [](Scene&) {}},
           {"training area 'left' posture has 7 joint values", 9,
            [](Scene& s) { s.training_areas[0].posture = Eigen::VectorXd::Zero(7); }},
           {"working area 'far' posture has 8 joint values", 9,
            [](Scene& s) {
              Area far;
              far.name = "far";
              far.posture = Eigen::VectorXd::Zero(8);
              s.working_areas.push_back(far);
            }},
       }) {
    Scene changed = scene;
    mismatch.change(changed);
    try {
      checkPosturesFit(changed, mismatch.dof, "r");
      ADD_FAILURE() << "accepted: " << mismatch.what;
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(mismatch.what), std::string::npos) << message;
      EXPECT_NE(message.find("scene 'cell'"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  // A scene without postures fits any robot.
  EXPECT_NO_THROW(checkPosturesFit(Scene{}, 7, "lwr4"));
}

TEST(ScenePostures, MustLieWithinTheRobotsJointLimits) {
  const RobotModel lwr4 = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  for (const std::string& name : builtinSceneNames()) {
    const Scene scene = loadScene(name);
    if (robotFor("", scene) == "lwr4") {
      EXPECT_NO_THROW(checkPosturesFit(scene, lwr4, "lwr4")) << name;
    }
  }
  Scene scene;
  scene.name = "cell";
  scene.home_posture = lwr4.midPosture();
  (*scene.home_posture)[6] = 1e300;
  try {
    checkPosturesFit(scene, lwr4, "lwr4");
    ADD_FAILURE() << "accepted a home posture of 1e300 rad";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("scene 'cell': home_posture: joint 7 (A7) at 1e+300 lies outside its limits [-2.967, 2.967]"),
              std::string::npos)
        << message;
  }
  scene.home_posture = lwr4.midPosture();
  Area area;
  area.name = "shelf";
  area.posture = lwr4.midPosture();
  (*area.posture)[1] = -2.2;  // A2 ends at 2.094 rad
  scene.training_areas.push_back(area);
  EXPECT_THROW(checkPosturesFit(scene, lwr4, "lwr4"), InputError);
  scene.training_areas[0].posture = lwr4.midPosture();
  Kinematics kinematics(lwr4);
  kinematics.update(lwr4.midPosture());
  scene.training_areas[0].p_WA = kinematics.p_WT() + Eigen::Vector3d(0.0, 0.0, 0.05);
  scene.training_areas[0].radius = 0.08;
  EXPECT_NO_THROW(checkPosturesFit(scene, lwr4, "lwr4"));
  // A posture that holds the tip 0.3 m from its area is a slip of the scene's author.
  scene.training_areas[0].p_WA = kinematics.p_WT() + Eigen::Vector3d(0.3, 0.0, 0.0);
  try {
    checkPosturesFit(scene, lwr4, "lwr4");
    ADD_FAILURE() << "accepted a posture 0.3 m off its area";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("training area 'shelf' posture puts the tip 0.300 m from the area's centre"),
              std::string::npos)
        << error.what();
  }
  // Read from a file, the refusal names the file and the posture's line, as the reader's do.
  scene.source = "/cells/shelf.yaml";
  scene.training_areas[0].posture_line = 12;
  try {
    checkPosturesFit(scene, lwr4, "lwr4");
    ADD_FAILURE() << "accepted a posture 0.3 m off its area";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("/cells/shelf.yaml:12: training area 'shelf' posture puts the tip", 0), 0U) << error.what();
  }
}

// The example a reader of docs/SCENES.md copies first: its area posture had put the tip 0.32 m
// from its area, and every program refused the file.
TEST_F(SceneFileTest, TheExampleInTheDocsLoadsAndItsPosturesFitTheRobot) {
  std::ifstream in(fs::path(FLEXIROB_TEST_DATA_DIR) / ".." / ".." / "docs" / "SCENES.md");
  ASSERT_TRUE(in) << "docs/SCENES.md";
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string opening = "## Example\n\n```yaml\n";
  const std::size_t begin = doc.find(opening);
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = doc.find("\n```", begin + opening.size());
  ASSERT_NE(end, std::string::npos);
  write("meshes/fixture.stl", kOneTriangleStl);
  const Scene scene = loadSceneFile(write("example.yaml", doc.substr(begin + opening.size(), end - begin - opening.size() + 1)));
  EXPECT_EQ(scene.name, "shelf_cell");
  ASSERT_EQ(scene.training_areas.size(), 2U);
  ASSERT_TRUE(scene.training_areas[1].posture.has_value());
  const RobotModel lwr4 = RobotModel::fromUrdfFile(resolveRobotPath(scene.robot));
  EXPECT_NO_THROW(checkPosturesFit(scene, lwr4, scene.robot));
}

TEST_F(SceneFileTest, KnowsTheLinesItsPosturesAreWrittenOn) {
  const Scene scene = loadSceneFile(write("lines.yaml", "name: lines\nhome_posture: [0, 0.5, 0, -1, 0, 0.5, 0]\ntraining_areas:\n"
                                                       "  - name: a\n    centre: [-0.5, 0, 0.3]\n    posture: [0, 1, 0, -1, 0, 0.5, 0]\n"));
  EXPECT_EQ(scene.home_posture_line, 2);
  ASSERT_EQ(scene.training_areas.size(), 1U);
  EXPECT_EQ(scene.training_areas[0].posture_line, 6);
}

// `unit: deg` turns every value of a posture into radians, and a slide's value is a length: a
// rail at 0.2 m had become 3.5 mm without a word. Such a posture is refused on a robot with a
// slide, naming it; in radians and metres it is taken.
TEST_F(SceneFileTest, RefusesAPostureInDegreesOnARobotWithASlide) {
  const RobotModel rail = RobotModel::fromUrdfString(
      "<robot name='rail'><link name='base'/>"
      "<joint name='carriage' type='prismatic'><parent link='base'/><child link='cart'/><axis xyz='0 1 0'/>"
      "<limit lower='-0.5' upper='0.5' velocity='1' effort='100'/></joint>"
      "<link name='cart'><inertial><mass value='5'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial></link>"
      "<joint name='shoulder' type='revolute'><parent link='cart'/><child link='arm'/><origin xyz='0 0 0.1'/><axis xyz='0 1 0'/>"
      "<limit lower='-2' upper='2' velocity='1' effort='100'/></joint>"
      "<link name='arm'><inertial><origin xyz='0 0 0.3'/><mass value='2'/>"
      "<inertia ixx='0.01' ixy='0' ixz='0' iyy='0.01' iyz='0' izz='0.01'/></inertial></link></robot>",
      ".");
  const Scene in_degrees = loadSceneFile(write("rail.yaml", "name: rail\nhome_posture: {unit: deg, values: [0.2, 30]}\n"));
  try {
    checkPosturesFit(in_degrees, rail, "rail");
    ADD_FAILURE() << "took a slide's 0.2 as degrees";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("rail.yaml:2: home_posture is written in degrees, but joint 'carriage' slides"),
              std::string::npos)
        << error.what();
  }
  const Scene area_in_degrees = loadSceneFile(write(
      "rail_area.yaml", "name: rail\ntraining_areas:\n  - {name: a, centre: [0.3, 0.2, 0.1], posture: {unit: deg, values: [0.2, 90]}}\n"));
  try {
    checkPosturesFit(area_in_degrees, rail, "rail");
    ADD_FAILURE() << "took an area posture's slide in degrees";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("training area 'a' posture is written in degrees"), std::string::npos) << error.what();
  }
  const Scene in_radians = loadSceneFile(write("rail_rad.yaml", "name: rail\nhome_posture: [0.2, 0.5]\n"));
  EXPECT_NO_THROW(checkPosturesFit(in_radians, rail, "rail"));
  EXPECT_DOUBLE_EQ((*in_radians.home_posture)[0], 0.2);
  // A robot that only turns takes degrees.
  const RobotModel lwr4 = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const Scene lwr_in_degrees =
      loadSceneFile(write("lwr.yaml", "name: cell\nhome_posture: {unit: deg, values: [0, 34.4, 0, -91.7, 0, 51.6, 0]}\n"));
  EXPECT_NO_THROW(checkPosturesFit(lwr_in_degrees, lwr4, "lwr4"));
}

}  // namespace
}  // namespace flexirob::robot
