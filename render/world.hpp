#pragma once
// Everything a 3D view shows, as one OpenSceneGraph tree: lights fixed in the world, a ground
// grid with the world axes, the robot (RobotGraph) and the scene (obstacles, training and
// working areas, targets, trajectories). Shared by the offscreen renderer and the GUI's view.
#include <osg/Group>
#include <osg/ref_ptr>

#include <Eigen/Core>
#include <memory>
#include <optional>

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
  static Eigen::Vector4f trajectory() { return {0.55F, 0.15F, 0.65F, 1.0F}; }
};

/// The obstacles, areas, targets and trajectories of a scene (world frame). Throws InputError
/// if an obstacle mesh cannot be read.
osg::ref_ptr<osg::Node> makeSceneNode(const robot::Scene& scene);

/// A square grid on z = 0 of the given half extent and line spacing [m], every fifth line
/// darker, with the world axes (x red, y green, z blue) at the origin.
osg::ref_ptr<osg::Node> makeGroundGrid(double half_extent = 1.5, double spacing = 0.1);

class World {
 public:
  World();
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  osg::Group* root() const { return root_.get(); }

  /// Replaces the robot (nullptr-safe: the view shows no robot until the first call).
  void setRobot(const robot::RobotModel& model);
  RobotGraph* robot() const { return robot_.get(); }
  /// Replaces the scene.
  void setScene(const robot::Scene& scene);
  void setGridVisible(bool visible);
  /// The overlay layers (render/overlays.hpp), drawn with the robot and the scene; not part of
  /// contentBound() or defaultCamera(), so a large confidence slice does not move the camera.
  Overlays& overlays() { return *overlays_; }

  /// Bounding sphere (centre in W, radius in m) of the robot and the scene, grid excluded.
  std::pair<Eigen::Vector3d, double> contentBound() const;
  /// Axis-aligned bounding box (lower, upper corners in W, m) of the robot and the scene, grid
  /// excluded; nothing when there is neither.
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> contentBox() const;
  /// A camera that shows the robot and the scene from the front-left, slightly above.
  CameraPose defaultCamera(double aspect) const;

 private:
  osg::ref_ptr<osg::Group> root_;
  osg::ref_ptr<osg::Group> content_;  // robot and scene: what the default camera frames
  osg::ref_ptr<osg::Node> grid_;
  osg::ref_ptr<osg::Node> scene_node_;
  std::unique_ptr<RobotGraph> robot_;
  std::unique_ptr<Overlays> overlays_;
};

}  // namespace flexirob::render
