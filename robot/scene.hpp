#pragma once
// A scene: the obstacles around the robot, the training and working areas a tutor uses, and
// what evaluations aim at (grid, targets, trajectories), plus parameter overrides.
//
// Only the simulator, the simulated tutor, evaluations and the renderer read the obstacle
// geometry; controllers, learners and the planner never do (the method is model-free).
// Frames: everything is given in the world frame W = the robot's mounting point, z up; metres.
// The file format (YAML) is documented in docs/SCENES.md.
#include <Eigen/Geometry>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace flexirob::robot {

struct Obstacle {
  enum class Shape { kBox, kCylinder, kSphere, kMesh };
  std::string name;
  Shape shape = Shape::kBox;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();  ///< pose of the shape's centre
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: edge lengths; cylinder: (radius, length, 0) along z; sphere: (radius, 0, 0)
  std::filesystem::path mesh_file;                 ///< resolved path (meshes only)
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  Eigen::Vector4f rgba{0.55F, 0.6F, 0.65F, 1.0F};
};

/// A region where the tutor demonstrates a redundancy resolution (Sect. 3.1, 4.1).
struct Area {
  std::string name;
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero();  ///< centre [m]
  double radius = 0.05;                            ///< extent of the demonstrated motion [m]
  std::optional<Eigen::VectorXd> posture;          ///< suggested q_fixed [rad], if the scene gives one
};

/// An axis-aligned evaluation grid (Sect. 3.3.2: G = [-0.9, 0] x [-0.55, 0.55] x [0.05, 0.8] m).
struct EvaluationGrid {
  Eigen::Vector3d lower = Eigen::Vector3d(-0.9, -0.55, 0.05);
  Eigen::Vector3d upper = Eigen::Vector3d(0.0, 0.55, 0.8);
  double spacing = 0.05;  ///< [m]
  std::vector<Eigen::Vector3d> points() const;
};

/// A target trajectory in task space: waypoints joined by straight segments.
struct Trajectory {
  std::string name;
  std::vector<Eigen::Vector3d> waypoints;
};

struct Scene {
  std::string name;
  std::string description;
  std::filesystem::path source;       ///< file it was read from (empty for scenes built in code)
  std::string robot = "lwr4";         ///< robot the scene was made for
  std::optional<Eigen::VectorXd> home_posture;  ///< start posture [rad]
  std::vector<Obstacle> obstacles;
  std::vector<Area> training_areas;
  std::vector<Area> working_areas;    ///< where programming / evaluation happens
  std::optional<EvaluationGrid> grid;
  std::vector<Eigen::Vector3d> targets;
  std::vector<Trajectory> trajectories;
  std::map<std::string, double> parameters;  ///< overrides of declared parameters, by name
};

/// Built-in scene names: empty, setup_A .. setup_D, setup_I, setup_II, harting, arm9_areas.
const std::vector<std::string>& builtinSceneNames();

/// Reads a scene file. Throws InputError with a one-line reason (file, and where possible the
/// line) for malformed YAML, unknown keys, wrong types, non-finite numbers, missing meshes.
Scene loadSceneFile(const std::filesystem::path& file);

/// A built-in name (see builtinSceneNames) or a path to a scene file; "" or "empty" is the
/// empty scene.
Scene loadScene(const std::string& name_or_path);

}  // namespace flexirob::robot
