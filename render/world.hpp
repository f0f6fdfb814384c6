#pragma once
// Everything a 3D view shows, as one OpenSceneGraph tree: lights fixed in the world, a ground
// grid with the world axes, the robot (RobotGraph) and the scene (obstacles, training and
// working areas, targets, trajectories). Shared by the offscreen renderer and the GUI's view.
#include <osg/Group>
#include <osg/ref_ptr>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "render/camera.hpp"
#include "render/overlays.hpp"
#include "render/robot_graph.hpp"
#include "robot/scene.hpp"

namespace flexirob::render {

/// Colours of the scene's parts (RGBA, 0..1).
struct Palette {
  static Eigen::Vector4f background() { return {0.86F, 0.89F, 0.93F, 1.0F}; }
  static Eigen::Vector4f trainingArea() { return {0.15F, 0.65F, 0.25F, 0.30F}; }
  static Eigen::Vector4f workingArea() { return {0.20F, 0.45F, 0.90F, 0.22F}; }
  static Eigen::Vector4f target() { return {0.10F, 0.10F, 0.12F, 1.0F}; }
  /// The scene's evaluation trajectories: the target trajectories' near-black
  /// (OverlayPalette::targetTrajectory), apart from every area's samples (a purple had read as
  /// the first area's).
  static Eigen::Vector4f trajectory() { return {0.10F, 0.10F, 0.12F, 1.0F}; }
};

/// The obstacles, areas, targets and trajectories of a scene (world frame). Throws InputError
/// if an obstacle mesh cannot be read.
osg::ref_ptr<osg::Node> makeSceneNode(const robot::Scene& scene);

/// An axis-aligned box: lower and upper corners in W [m].
using Box = std::pair<Eigen::Vector3d, Eigen::Vector3d>;

/// The sphere (centre in W, radius in m) holding everything the robot can reach: around its base
/// frame's origin, with the lengths from joint to joint and to the tip (and prismatic travel)
/// added up.
std::pair<Eigen::Vector3d, double> reachSphere(const robot::RobotModel& model);

/// What sizes drawn in metres for the LWR IV (goal markers) are multiplied by for a robot: its
/// reachSphere() radius over the LWR IV's (1.18 m, a little less), at most 1.
double robotSizeScale(const robot::RobotModel& model);

/// The bounding box of the part of `box` inside the sphere (centre, radius); nothing when they
/// do not meet. Exact for the intersection of the box with the sphere, computed per axis.
std::optional<Box> clipBoxToSphere(const Box& box, const Eigen::Vector3d& center_W, double radius);

/// A viewpoint chosen by World::chooseView: its camera, the name of its side (namedView) and the
/// fraction of the robot and its areas that opaque obstacles hide from it (0..1, see
/// World::hiddenFraction).
struct ViewChoice {
  CameraPose camera;
  std::string view;
  double hidden_fraction = 0.0;
};

/// The sides World::defaultCamera tries, best first: the front-left, lower under a ceiling, from
/// behind past a wall in front, then the other sides.
const std::vector<std::string>& defaultViewOrder();

/// A view hiding at most this fraction of the robot and its areas counts as seeing them. From
/// the front-left, the thesis' setups hide at most 3 % (a board or pillar covers a link, the arm
/// around it stays in sight); a shelf's back wall hides 20 %, a ceiling 100 %.
inline constexpr double kAcceptableHiddenFraction = 0.15;

/// A square grid on z = 0 of the given half extent and line spacing [m], every fifth line
/// darker, with the world axes (x red, y green, z blue) at the origin, a sixth of the half
/// extent long.
osg::ref_ptr<osg::Node> makeGroundGrid(double half_extent = 1.5, double spacing = 0.1);

/// The ground grid's size for an arm of the given reach [m]: lines a decade below a tenth of the
/// reach apart (0.1 m for the LWR IV, 1 cm for a 20 cm arm), reaching at least 1.25 times the
/// reach out, to the next darker line (1.5 m for the LWR IV).
struct GroundGridSize {
  double half_extent;
  double spacing;
};
GroundGridSize groundGridSize(double reach);

class World {
 public:
  World();
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  osg::Group* root() const { return root_.get(); }

  /// Replaces the robot (nullptr-safe: the view shows no robot until the first call) and focuses
  /// the default framing on its reach (setFocusSphere).
  void setRobot(const robot::RobotModel& model);
  RobotGraph* robot() const { return robot_.get(); }
  /// Replaces the scene.
  void setScene(const robot::Scene& scene);
  void setGridVisible(bool visible);
  /// The overlay layers (render/overlays.hpp), drawn with the robot and the scene; not part of
  /// contentBound() or defaultCamera(), so a large confidence slice does not move the camera.
  Overlays& overlays() { return *overlays_; }

  /// Limits what focusBox() takes of the obstacles to this sphere (centre in W, radius in m);
  /// setRobot() sets the robot's reachSphere() grown by a margin. Without a focus sphere every
  /// obstacle is framed whole.
  void setFocusSphere(const Eigen::Vector3d& center_W, double radius);

  /// Bounding sphere (centre in W, radius in m) of the robot and the scene, grid excluded.
  std::pair<Eigen::Vector3d, double> contentBound() const;
  /// Axis-aligned bounding box (lower, upper corners in W, m) of the robot and the scene, grid
  /// excluded; nothing when there is neither.
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> contentBox() const;
  /// What a picture of the robot is about: the robot, the scene's areas, targets and
  /// trajectories, and of each obstacle only the part inside the focus sphere, so that a huge or
  /// far obstacle does not shrink the robot to a speck. Nothing when there is nothing to frame.
  std::optional<Box> focusBox() const;
  /// Frames `box` (aspect = width / height, margin a fraction of the image) from the first of
  /// `views` (namedView names) from which opaque obstacles hide at most kAcceptableHiddenFraction
  /// of the robot, else from the one hiding least. Throws InputError for an unknown name.
  ViewChoice chooseView(const Box& box, double aspect, const std::vector<std::string>& views,
                        double margin = 0.05) const;
  /// Fraction (0..1) of the robot and its areas that opaque obstacles hide from the camera's eye:
  /// 24 points evenly along the robot's chain of joints (weight 0.7, or 1 without areas) and the
  /// centres of the scene's training and working areas (0.3). A point counts as hidden when it
  /// and four points around it (8 % of the reach across the line of sight) are all hidden, so a
  /// pillar in front of a link does not count but a wall does. Points enclosed by obstacles
  /// (hidden from every side) do not count. 0 without a robot.
  double hiddenFraction(const CameraPose& camera) const;
  /// If obstacles hide more than kAcceptableHiddenFraction of the robot from the camera, draws
  /// every opaque obstacle that hides part of it see-through; returns the names of those.
  /// setScene() draws them opaque again.
  std::vector<std::string> revealRobot(const CameraPose& camera);
  /// A camera that shows focusBox() from the front-left, slightly above, or from the first side
  /// of defaultViewOrder() from which obstacles do not hide the robot.
  CameraPose defaultCamera(double aspect) const;

 private:
  osg::ref_ptr<osg::Group> root_;
  osg::ref_ptr<osg::Group> content_;  // robot and scene: what the default camera frames
  osg::ref_ptr<osg::Node> grid_;
  osg::ref_ptr<osg::Group> scene_node_;
  struct ObstacleNode {
    osg::ref_ptr<osg::Node> node;   // placed in W: what the camera sees and rays hit
    osg::ref_ptr<osg::Node> shape;  // carries the colour
    std::string name;
    Eigen::Vector4f rgba;
  };
  struct SamplePoint {
    Eigen::Vector3d p_W;
    double weight;  // the weights of all points add up to 1
    bool is_area;
  };
  // Share of the areas' centres in the hidden fraction, where the scene has areas.
  static constexpr double kAreaShare = 0.3;
  std::vector<Eigen::Vector3d> robotSamplePoints() const;
  // Whether opaque obstacle k lies on the line of sight from the eye to p_W.
  bool obstacleHides(std::size_t k, const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const;
  // The first opaque obstacle hiding p_W from the eye, if any (index into obstacles_).
  std::optional<std::size_t> hidingObstacle(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const;
  // The robot's and the areas' points that some view may see, weighted.
  std::vector<SamplePoint> visibleSamplePoints() const;
  // Whether obstacles hide p_W and the points around it (surroundings_radius_ across the line of
  // sight) from the eye.
  bool hiddenWithSurroundings(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const;
  double hiddenWeight(const std::vector<SamplePoint>& points, const Eigen::Vector3d& eye_W) const;

  std::vector<ObstacleNode> obstacles_;
  std::vector<Eigen::Vector3d> area_centers_;
  double surroundings_radius_ = 0.1;  // [m], 8 % of the robot's reach
  std::optional<std::pair<Eigen::Vector3d, double>> focus_sphere_;
  std::unique_ptr<RobotGraph> robot_;
  std::unique_ptr<Overlays> overlays_;
};

}  // namespace flexirob::render
