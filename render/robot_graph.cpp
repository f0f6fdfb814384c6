#include "render/robot_graph.hpp"

#include <stdexcept>

#include "render/shapes.hpp"

namespace flexirob::render {

RobotGraph::RobotGraph(const robot::RobotModel& model) : root_(new osg::Group) {
  root_->setName("robot:" + model.name());
  for (const robot::Body& body : model.bodies()) {
    osg::ref_ptr<osg::MatrixTransform> transform = new osg::MatrixTransform();
    transform->setName(body.name);
    for (const robot::Geometry& geometry : body.visuals) {
      osg::ref_ptr<osg::Node> node = makeVisual(geometry);
      transform->addChild(node);
      visuals_.push_back({node, geometry.source_link.empty() ? body.name : geometry.source_link, geometry.rgba});
    }
    root_->addChild(transform);
    bodies_.push_back(transform);
  }
  // Until a posture is set, show the robot at its safe default posture.
  robot::Kinematics kinematics(model);
  kinematics.update(model.midPosture());
  setPosture(kinematics);
}

void RobotGraph::setPosture(const robot::Kinematics& kinematics) {
  if (kinematics.model().bodies().size() != bodies_.size()) {
    throw std::invalid_argument("RobotGraph::setPosture: expected a model with " + std::to_string(bodies_.size()) +
                                " bodies, got " + std::to_string(kinematics.model().bodies().size()));
  }
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    bodies_[i]->setMatrix(toOsgMatrix(kinematics.X_WB(static_cast<int>(i))));
  }
}

int RobotGraph::setLinkVisible(const std::string& urdf_link, bool visible) {
  int count = 0;
  for (Visual& visual : visuals_) {
    if (visual.link != urdf_link) continue;
    visual.node->setNodeMask(visible ? ~0U : 0U);
    ++count;
  }
  return count;
}

int RobotGraph::setLinkColor(const std::string& urdf_link, const Eigen::Vector4f& rgba) {
  int count = 0;
  for (Visual& visual : visuals_) {
    if (visual.link != urdf_link) continue;
    applyColor(*visual.node, rgba);
    ++count;
  }
  return count;
}

void RobotGraph::resetColors() {
  for (Visual& visual : visuals_) applyColor(*visual.node, visual.rgba);
}

}  // namespace flexirob::render
