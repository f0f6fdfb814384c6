#include "ui/mouse_perturbation.hpp"

#include <osg/Geode>
#include <osg/Material>
#include <osg/Shape>
#include <osg/ShapeDrawable>
#include <cmath>
#include <vector>

#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "ui/live_teaching.hpp"

namespace flexirob::ui {

ForceArrow::ForceArrow() : transform_(new osg::MatrixTransform) {
  // A unit arrow along +z from the origin: shaft 0.8, head 0.2; scaled to the force's length.
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  geode->addDrawable(new osg::ShapeDrawable(new osg::Cylinder(osg::Vec3(0.0F, 0.0F, 0.4F), 0.025F, 0.8F)));
  geode->addDrawable(new osg::ShapeDrawable(new osg::Cone(osg::Vec3(0.0F, 0.0F, 0.8F), 0.07F, 0.2F)));
  osg::ref_ptr<osg::Material> material = new osg::Material;
  const osg::Vec4 colour(0.95F, 0.35F, 0.05F, 1.0F);
  material->setDiffuse(osg::Material::FRONT_AND_BACK, colour);
  material->setAmbient(osg::Material::FRONT_AND_BACK, colour * 0.6F);
  material->setEmission(osg::Material::FRONT_AND_BACK, colour * 0.3F);
  geode->getOrCreateStateSet()->setAttributeAndModes(material.get());
  // Scaling the unit arrow must not darken it.
  geode->getOrCreateStateSet()->setMode(GL_NORMALIZE, osg::StateAttribute::ON);
  transform_->addChild(geode.get());
  transform_->setNodeMask(0);
}

void ForceArrow::show(const Eigen::Vector3d& p_W, const Eigen::Vector3d& F_W) {
  const double newtons = F_W.norm();
  if (!(newtons / scale_.force() >= 0.5) || !p_W.allFinite()) {
    hide();
    return;
  }
  const double length = this->length(F_W);
  const osg::Vec3d direction(F_W.x() / newtons, F_W.y() / newtons, F_W.z() / newtons);
  osg::Matrixd rotation;
  rotation.makeRotate(osg::Vec3d(0.0, 0.0, 1.0), direction);
  // The shaft's thickness grows slowly with the length so that short arrows stay visible.
  const double width = std::max(0.4, std::min(1.0, length / (0.3 * scale_.length))) * 0.5 * scale_.length;
  transform_->setMatrix(osg::Matrixd::scale(width, width, length) * rotation *
                        osg::Matrixd::translate(p_W.x(), p_W.y(), p_W.z()));
  transform_->setNodeMask(~0U);
}

double ForceArrow::length(const Eigen::Vector3d& F_W) const {
  return F_W.norm() / scale_.force() * kMetresPerNewton * scale_.length;
}

void ForceArrow::hide() { transform_->setNodeMask(0); }

bool ForceArrow::visible() const { return transform_->getNodeMask() != 0; }

MousePerturbation::MousePerturbation(OsgView& view, render::World& world, std::function<LiveTeaching*()> live,
                                     std::function<const robot::Kinematics*()> kinematics)
    : view_(&view), world_(&world), live_(std::move(live)), kinematics_(std::move(kinematics)) {}

bool MousePerturbation::press(const QPointF& position) {
  LiveTeaching* live = live_();
  const robot::Kinematics* kinematics = kinematics_();
  render::RobotGraph* graph = world_->robot();
  if (live == nullptr || kinematics == nullptr || graph == nullptr) return false;
  std::vector<osg::Node*> bodies;
  for (int i = 0; i < graph->bodyCount(); ++i) bodies.push_back(graph->body(i));
  Eigen::Vector3d p_W;
  const int body = view_->pick(position, bodies, p_W);
  if (body < 1) return false;  // the base is bolted down: orbit instead
  body_ = body;
  p_B_ = kinematics->X_WB(body).inverse() * p_W;
  plane_point_W_ = p_W;
  plane_normal_W_ = view_->viewDirection();
  target_W_ = p_W;
  live->grab(body_, p_B_, target_W_, kStiffness);
  return true;
}

void MousePerturbation::move(const QPointF& position) {
  LiveTeaching* live = live_();
  if (body_ < 1 || live == nullptr) return;
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
  view_->ray(position, origin, direction);
  const double along = direction.dot(plane_normal_W_);
  if (std::abs(along) < 1e-6) return;  // the ray runs in the plane
  const double t = (plane_point_W_ - origin).dot(plane_normal_W_) / along;
  if (t <= 0.0) return;
  target_W_ = origin + t * direction;
  live->grab(body_, p_B_, target_W_, kStiffness);
}

void MousePerturbation::release() {
  if (LiveTeaching* live = live_(); live != nullptr && body_ > 0) live->release();
  body_ = -1;
}

}  // namespace flexirob::ui
