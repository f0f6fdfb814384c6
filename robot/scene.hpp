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
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace flexirob::robot {

class MeshSolid;
class RobotModel;

struct Obstacle {
  enum class Shape { kBox, kCylinder, kSphere, kMesh };
  std::string name;
  Shape shape = Shape::kBox;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();  ///< pose of the shape's centre
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: edge lengths; cylinder: (radius, length, 0) along z; sphere: (radius, 0, 0)
  std::filesystem::path mesh_file;                 ///< resolved path (meshes only)
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  /// The solid of mesh_file at mesh_scale (meshes only), built once by the scene reader so that
  /// point tests do not reload the file. May be empty (an obstacle built in code): the point
  /// tests then fetch it from a cache. Code that changes mesh_file or mesh_scale resets it.
  std::shared_ptr<const MeshSolid> mesh_solid;
  Eigen::Vector4f rgba{0.55F, 0.6F, 0.65F, 1.0F};
};

/// A region where the tutor demonstrates a redundancy resolution (Sect. 3.1, 4.1), or where
/// the robot is meant to work.
struct Area {
  std::string name;
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero();  ///< centre [m]
  double radius = 0.05;                            ///< extent of the area as drawn and framed [m] (the tutor sizes its helix itself)
  std::optional<Eigen::VectorXd> posture;          ///< suggested q_fixed [rad], if the scene gives one
  /// Edge lengths [m] of the axis-aligned box around p_WA that bounds the area (as drawn, and
  /// for the check of its posture); unset: the ball of `radius` around p_WA.
  std::optional<Eigen::Vector3d> box;
  bool posture_in_degrees = false;  ///< `posture` was written {unit: deg} (refused on a robot with a slide)
  int posture_line = 0;             ///< line of `posture` in the scene file (1-based; 0: not read from a file)
  /// True if p_W (world frame, metres) lies in the box, or in the ball if there is no box;
  /// the boundary counts as inside.
  bool contains(const Eigen::Vector3d& p_W) const;
};

/// An axis-aligned evaluation grid (Sect. 3.3.2: G = [-0.9, 0] x [-0.55, 0.55] x [0.05, 0.8] m).
struct EvaluationGrid {
  Eigen::Vector3d lower = Eigen::Vector3d(-0.9, -0.55, 0.05);
  Eigen::Vector3d upper = Eigen::Vector3d(0.0, 0.55, 0.8);
  double spacing = 0.05;  ///< [m]
  double tolerance = 0.01;  ///< a target counts as reached within this distance [m] (Sect. 3.3.2)
  /// Boxes whose points are not targets although the arm could get there: parts of the
  /// workspace a scene's author rules out, as Sect. 3.3.2 drops the points above setup I's board
  /// from T_I. Boundaries count as inside (within 1e-9 m: points() puts a point meant to lie on
  /// a boundary there only up to rounding).
  std::vector<Eigen::AlignedBox3d> excluded;
  /// Whether p_W lies in one of the excluded boxes.
  bool excludes(const Eigen::Vector3d& p_W) const;
  /// Points lower + spacing * (i, j, k) inside [lower, upper] (upper inclusive up to 1e-9 m),
  /// x fastest.
  std::vector<Eigen::Vector3d> points() const;
  /// Number of points() per axis.
  Eigen::Vector3i counts() const;
  /// Number of points(), as a real number: a grid a user asks for may exceed every integer type.
  double pointCount() const;
  /// Why the grid is too large to evaluate (more than kMaxGridPoints points), for a one-line
  /// error, or empty if it is not.
  std::string sizeProblem() const;
};

/// Largest evaluation grid a scene or an evaluation may ask for: 5e6 points hold 120 MB of
/// positions and take hours to evaluate.
inline constexpr double kMaxGridPoints = 5.0e6;

/// A target trajectory in task space: waypoints joined by straight segments.
struct Trajectory {
  std::string name;
  std::string group;  ///< evaluation group, e.g. "left", "right", "interpolation" (Tab. 3.2); may be empty
  std::vector<Eigen::Vector3d> waypoints;  ///< [m], at least one
};

struct Scene {
  std::string name;
  std::string description;
  std::filesystem::path source;       ///< file it was read from (empty for scenes built in code)
  std::string robot = "lwr4";         ///< robot the scene was made for
  /// Why `robot` names no robot ("<file>:<line>: robot: ..."), empty when it does. A scene
  /// from elsewhere may name a URDF file this machine lacks: it still reads, and robotFor()
  /// refuses it only where no other robot is given.
  std::string robot_unreadable;
  std::optional<Eigen::VectorXd> home_posture;  ///< start posture [rad]
  bool home_posture_in_degrees = false;         ///< written {unit: deg} (refused on a robot with a slide)
  std::vector<Obstacle> obstacles;
  /// The table top z = 0 the robot stands on is an obstacle below every link but the base (and
  /// links within 1 cm of it at the reference posture): the thesis' q2 ≫ π/2 "would result in
  /// collisions with the table surface" (Sect. 4.2.1). Off for a robot that hangs or stands on
  /// a pedestal.
  bool table = true;
  std::vector<Area> training_areas;
  std::vector<Area> working_areas;    ///< where programming is meant to happen: drawn, not taught or evaluated
  std::optional<EvaluationGrid> grid;
  std::vector<Eigen::Vector3d> targets;
  std::vector<Trajectory> trajectories;
  std::map<std::string, double> parameters;  ///< overrides of declared parameters, by name
  int home_posture_line = 0;                 ///< line of `home_posture` in the file (1-based; 0: not from a file)
  std::vector<std::string> ignored_parameters;  ///< names no component declares, left out (SceneText::kSessionCopy)
};

/// True if p_W (world frame, metres) lies inside the obstacle or within `margin` [m] of its
/// surface; the surface counts as inside. A mesh's inside is that of robot/mesh_solid.hpp
/// (generalized winding number ≥ 0.5, in the obstacle's frame with its scale). Throws
/// InputError if a mesh obstacle built in code names a file that cannot be loaded.
bool obstacleContains(const Obstacle& obstacle, const Eigen::Vector3d& p_W, double margin = 0.0);

/// The solid of a mesh obstacle (mesh_solid when it matches the obstacle's file and scale, else
/// from the cache): what the point tests and the collision model use. Throws InputError if the
/// file cannot be loaded.
std::shared_ptr<const MeshSolid> meshSolidOf(const Obstacle& obstacle);

/// The first of the scene's obstacles that contains p_W within `margin` [m] (as obstacleContains),
/// or nullptr when p_W lies in free space.
const Obstacle* obstacleAt(const Scene& scene, const Eigen::Vector3d& p_W, double margin = 0.0);

/// The robot to use with `scene`: `robot_option` when the user gave one (non-empty), else the
/// robot the scene was made for.
std::string robotFor(const std::string& robot_option, const Scene& scene);

/// Throws InputError (one line, naming the scene and the posture) when a posture of the scene
/// (home, training or working area) does not have `dof` values: postures are joint vectors of
/// the robot the scene was made for, and one of another robot is a mistake, not a suggestion.
void checkPosturesFit(const Scene& scene, int dof, const std::string& robot_name);
/// As above, and every such posture must lie within the robot's hardware joint limits (the
/// simulation cannot start from one outside them, and the tutor would teach it as given), and an
/// area's posture must put the tip (the model's) within the area, 1 cm of slack beyond it.
void checkPosturesFit(const Scene& scene, const RobotModel& model, const std::string& robot_name);

/// Built-in scene names: empty, setup_A .. setup_D, setup_I, setup_II, harting, arm9_areas.
const std::vector<std::string>& builtinSceneNames();

/// Reads a scene file. Throws InputError with a one-line reason (file, and where possible the
/// line) for malformed YAML, unknown keys, wrong types, non-finite numbers, missing meshes.
Scene loadSceneFile(const std::filesystem::path& file);

/// Whose text the reader reads. A file being written: a parameter name no component declares is
/// refused, and `robot:` must name a built-in robot or an existing URDF. A copy a session stored,
/// which must still read: such a name is left out and listed in Scene::ignored_parameters (stored
/// before names were checked), and `robot:` may name a file gone since (the session stores the
/// URDF too).
enum class SceneText { kFile, kSessionCopy };

/// Parses scene text as loadSceneFile does; relative mesh and robot paths are resolved against
/// base_dir, and errors name `origin` (e.g. a file name) instead of a file.
Scene parseScene(const std::string& yaml_text, const std::filesystem::path& base_dir,
                 const std::string& origin, SceneText source = SceneText::kFile);

/// The scene as scene-file text that parseScene reads back to an equal scene (numbers with 17
/// significant digits, rotations as quaternions, mesh and robot paths as stored).
std::string sceneToYaml(const Scene& scene);

/// Where a scene came from, for messages: its file, else "scene 'name'".
std::string sceneOrigin(const Scene& scene);

/// A built-in name (see builtinSceneNames) or a path to a scene file; "" or "empty" is the
/// empty scene.
Scene loadScene(const std::string& name_or_path);

/// What a user should know about how the scene is modelled, one line each: mesh obstacles whose
/// triangles were simplified for the collision model and the point tests (MeshSolid), with the
/// largest deviation. Empty for most scenes.
std::vector<std::string> sceneNotes(const Scene& scene);

}  // namespace flexirob::robot
