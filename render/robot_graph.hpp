#pragma once
// The robot as a scene graph: one osg::MatrixTransform per body, holding that body's visual
// shapes (meshes through assimp, or URDF primitives) with their URDF material colours. A link
// without visuals is drawn with its collision shapes, and a body with no shapes at all with the
// capsule the collision world gives it, so that every arm the simulation moves can be seen. The
// posture comes from robot::Kinematics; this class computes no kinematics itself.
#include <osg/Group>
#include <osg/MatrixTransform>
#include <osg/ref_ptr>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::render {

class RobotGraph {
 public:
  /// Colour of the stand-ins drawn for links without visuals (collision shapes or capsules).
  static Eigen::Vector4f standInColor() { return {0.55F, 0.58F, 0.64F, 1.0F}; }

  /// Builds the visual shapes (or stand-ins) of every body. Throws InputError if a mesh cannot
  /// be read.
  explicit RobotGraph(const robot::RobotModel& model);

  osg::Group* root() const { return root_.get(); }
  int bodyCount() const { return static_cast<int>(bodies_.size()); }
  /// Transform of body i (0 = base); its matrix is X_WB(i).
  osg::MatrixTransform* body(int i) const { return bodies_.at(static_cast<std::size_t>(i)).get(); }

  /// Moves every body to the poses of an updated Kinematics of the same model.
  void setPosture(const robot::Kinematics& kinematics);

  /// Shows or hides the visuals declared on one URDF link (a chain link or one folded into a
  /// body, such as the flange). Returns how many visuals were affected.
  int setLinkVisible(const std::string& urdf_link, bool visible);
  /// Overrides the colour of the visuals of one URDF link (e.g. highlighting); returns how many.
  int setLinkColor(const std::string& urdf_link, const Eigen::Vector4f& rgba);
  /// Restores the URDF colours of every visual.
  void resetColors();

 private:
  struct Visual {
    osg::ref_ptr<osg::Node> node;
    std::string link;
    Eigen::Vector4f rgba;
  };
  osg::ref_ptr<osg::Group> root_;
  std::vector<osg::ref_ptr<osg::MatrixTransform>> bodies_;
  std::vector<Visual> visuals_;
};

}  // namespace flexirob::render
