#include "render/robot_graph.hpp"

#include <osg/Geode>
#include <osg/ShapeDrawable>

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>

#include "render/shapes.hpp"
#include "robot/collision.hpp"

namespace flexirob::render {

namespace {

const std::string& linkOf(const robot::Geometry& geometry, const robot::Body& body) {
  return geometry.source_link.empty() ? body.name : geometry.source_link;
}

// The collision world's capsule of a body (robot::linkCapsule), in the body's frame.
osg::ref_ptr<osg::Node> makeCapsule(const robot::LinkCapsule& capsule, const Eigen::Vector4f& rgba) {
  const Eigen::Vector3d axis = capsule.b_B - capsule.a_B;
  osg::ref_ptr<osg::Shape> shape;
  if (axis.norm() < 1e-6) {
    shape = new osg::Sphere(toOsg(capsule.a_B), static_cast<float>(capsule.radius));
  } else {
    osg::ref_ptr<osg::Capsule> segment = new osg::Capsule(toOsg(0.5 * (capsule.a_B + capsule.b_B)),
                                                          static_cast<float>(capsule.radius), static_cast<float>(axis.norm()));
    const Eigen::Quaterniond z_to_axis = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis.normalized());
    segment->setRotation(osg::Quat(z_to_axis.x(), z_to_axis.y(), z_to_axis.z(), z_to_axis.w()));
    shape = segment;
  }
  osg::ref_ptr<osg::ShapeDrawable> drawable = new osg::ShapeDrawable(shape.get());
  drawable->setColor(toOsgColor(rgba));
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  geode->addDrawable(drawable);
  applyColor(*geode, rgba);
  return geode;
}

}  // namespace

RobotGraph::RobotGraph(const robot::RobotModel& model) : root_(new osg::Group) {
  root_->setName("robot:" + model.name());
  for (std::size_t b = 0; b < model.bodies().size(); ++b) {
    const robot::Body& body = model.bodies()[b];
    osg::ref_ptr<osg::MatrixTransform> transform = new osg::MatrixTransform();
    transform->setName(body.name);
    const auto add = [&](const osg::ref_ptr<osg::Node>& node, const std::string& link, const Eigen::Vector4f& rgba) {
      transform->addChild(node);
      visuals_.push_back({node, link, rgba});
    };
    for (const robot::Geometry& geometry : body.visuals) add(makeVisual(geometry), linkOf(geometry, body), geometry.rgba);
    // Links the URDF gives no visual are drawn as the simulation sees them (their collision
    // shapes): an arm described for collision checking only would otherwise be invisible.
    for (const robot::Geometry& geometry : body.collisions) {
      const std::string& link = linkOf(geometry, body);
      const bool drawn = std::any_of(body.visuals.begin(), body.visuals.end(),
                                     [&](const robot::Geometry& visual) { return linkOf(visual, body) == link; });
      if (drawn) continue;
      robot::Geometry stand_in = geometry;
      stand_in.rgba = standInColor();
      add(makeVisual(stand_in), link, stand_in.rgba);
    }
    if (body.visuals.empty() && body.collisions.empty()) {
      add(makeCapsule(robot::linkCapsule(model, static_cast<int>(b)), standInColor()), body.name, standInColor());
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
