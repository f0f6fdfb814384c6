#include "render/world.hpp"

#include <osg/ComputeBoundsVisitor>
#include <osg/Depth>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/LightModel>
#include <osg/LightSource>
#include <osg/LineWidth>
#include <osg/MatrixTransform>
#include <osg/PolygonOffset>
#include <osgUtil/IntersectionVisitor>
#include <osgUtil/LineSegmentIntersector>

#include <algorithm>
#include <cmath>

#include "render/shapes.hpp"
#include "robot/errors.hpp"

namespace flexirob::render {

namespace {

osg::ref_ptr<osg::LightSource> makeDirectionalLight(int number, const osg::Vec3& towards_light,
                                                    float diffuse, float specular) {
  osg::ref_ptr<osg::Light> light = new osg::Light(number);
  osg::Vec3 direction = towards_light;
  direction.normalize();
  light->setPosition(osg::Vec4(direction, 0.0F));  // w = 0: a directional light
  light->setAmbient(osg::Vec4(0.0F, 0.0F, 0.0F, 1.0F));
  light->setDiffuse(osg::Vec4(diffuse, diffuse, diffuse, 1.0F));
  light->setSpecular(osg::Vec4(specular, specular, specular, 1.0F));
  osg::ref_ptr<osg::LightSource> source = new osg::LightSource();
  source->setLight(light);
  source->setReferenceFrame(osg::LightSource::ABSOLUTE_RF);
  return source;
}

// Translucent shapes are drawn after the opaque ones and do not hide what lies behind them.
void makeTranslucent(osg::Node& node) {
  osg::StateSet* state = node.getOrCreateStateSet();
  state->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false));
  state->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
}

osg::ref_ptr<osg::Node> placed(const Eigen::Isometry3d& X, osg::Node* child) {
  osg::ref_ptr<osg::MatrixTransform> transform = new osg::MatrixTransform(toOsgMatrix(X));
  transform->addChild(child);
  return transform;
}

osg::ref_ptr<osg::Node> makeAreaNode(const robot::Area& area, const Eigen::Vector4f& rgba) {
  osg::ref_ptr<osg::Geode> shape =
      area.box ? makePrimitive(PrimitiveShape::kBox, *area.box, rgba)
               : makePrimitive(PrimitiveShape::kSphere, Eigen::Vector3d(area.radius, 0, 0), rgba);
  makeTranslucent(*shape);
  osg::ref_ptr<osg::Node> node = placed(Eigen::Isometry3d(Eigen::Translation3d(area.p_WA)), shape.get());
  node->setName("area:" + area.name);
  return node;
}

osg::ref_ptr<osg::Geometry> makeLines(const std::vector<osg::Vec3>& points, GLenum mode, const osg::Vec4& color) {
  osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry();
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array(points.begin(), points.end());
  osg::ref_ptr<osg::Vec4Array> colors = new osg::Vec4Array();
  colors->push_back(color);
  geometry->setVertexArray(vertices);
  geometry->setColorArray(colors, osg::Array::BIND_OVERALL);
  geometry->addPrimitiveSet(new osg::DrawArrays(mode, 0, static_cast<int>(points.size())));
  return geometry;
}

}  // namespace

std::pair<Eigen::Vector3d, double> reachSphere(const robot::RobotModel& model) {
  double reach = model.X_LastBodyTip().translation().norm();
  for (const robot::Joint& joint : model.joints()) {
    reach += joint.X_PJ.translation().norm();
    if (joint.type == robot::JointType::kPrismatic) {
      const double travel = std::max(std::abs(joint.limits.lower), std::abs(joint.limits.upper));
      if (std::isfinite(travel)) reach += travel;
    }
  }
  return {Eigen::Vector3d::Zero(), reach};
}

double robotSizeScale(const robot::RobotModel& model) {
  constexpr double kLwrReach = 1.15;  // [m] the LWR IV's reachSphere() radius, 1.18 m, a little less
  const double reach = reachSphere(model).second;
  return reach > 0.0 && std::isfinite(reach) ? std::min(1.0, reach / kLwrReach) : 1.0;
}

std::optional<Box> clipBoxToSphere(const Box& box, const Eigen::Vector3d& center_W, double radius) {
  Box clipped = box;
  for (int axis = 0; axis < 3; ++axis) {
    // Along this axis the box meets the sphere where the sphere's cross-section still reaches
    // the box's extent in the two other axes.
    double across_squared = 0.0;
    for (int other = 0; other < 3; ++other) {
      if (other == axis) continue;
      const double nearest = std::clamp(center_W[other], box.first[other], box.second[other]);
      across_squared += (nearest - center_W[other]) * (nearest - center_W[other]);
    }
    if (across_squared > radius * radius) return std::nullopt;
    const double half_chord = std::sqrt(radius * radius - across_squared);
    clipped.first[axis] = std::max(box.first[axis], center_W[axis] - half_chord);
    clipped.second[axis] = std::min(box.second[axis], center_W[axis] + half_chord);
    if (clipped.first[axis] > clipped.second[axis]) return std::nullopt;
  }
  return clipped;
}

const std::vector<std::string>& defaultViewOrder() {
  static const std::vector<std::string> views{"front-left", "front-left-low", "back-left", "front-right", "back-right",
                                              "left",       "right",          "front",     "back"};
  return views;
}

osg::ref_ptr<osg::Node> makeSceneNode(const robot::Scene& scene) {
  osg::ref_ptr<osg::Group> group = new osg::Group();
  group->setName("scene:" + scene.name);
  for (const robot::Obstacle& obstacle : scene.obstacles) {
    osg::ref_ptr<osg::Geode> shape;
    switch (obstacle.shape) {
      case robot::Obstacle::Shape::kBox:
        shape = makePrimitive(PrimitiveShape::kBox, obstacle.size, obstacle.rgba);
        break;
      case robot::Obstacle::Shape::kCylinder:
        shape = makePrimitive(PrimitiveShape::kCylinder, obstacle.size, obstacle.rgba);
        break;
      case robot::Obstacle::Shape::kSphere:
        shape = makePrimitive(PrimitiveShape::kSphere, obstacle.size, obstacle.rgba);
        break;
      case robot::Obstacle::Shape::kMesh:
        shape = makeMesh(obstacle.mesh_file, obstacle.mesh_scale, obstacle.rgba);
        break;
    }
    if (obstacle.rgba[3] < 0.999F) makeTranslucent(*shape);
    osg::ref_ptr<osg::Node> node = placed(obstacle.X_WO, shape.get());
    node->setName("obstacle:" + obstacle.name);
    group->addChild(node);
  }
  for (const robot::Area& area : scene.training_areas) group->addChild(makeAreaNode(area, Palette::trainingArea()));
  for (const robot::Area& area : scene.working_areas) group->addChild(makeAreaNode(area, Palette::workingArea()));
  for (const Eigen::Vector3d& target : scene.targets) {
    osg::ref_ptr<osg::Geode> dot = makePrimitive(PrimitiveShape::kSphere, Eigen::Vector3d(0.008, 0, 0), Palette::target());
    group->addChild(placed(Eigen::Isometry3d(Eigen::Translation3d(target)), dot.get()));
  }
  if (!scene.trajectories.empty()) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode();
    for (const robot::Trajectory& trajectory : scene.trajectories) {
      std::vector<osg::Vec3> points;
      for (const Eigen::Vector3d& p : trajectory.waypoints) points.emplace_back(toOsg(p));
      if (points.size() >= 2) geode->addDrawable(makeLines(points, GL_LINE_STRIP, toOsgColor(Palette::trajectory())));
    }
    osg::StateSet* state = geode->getOrCreateStateSet();
    state->setMode(GL_LIGHTING, osg::StateAttribute::OFF | osg::StateAttribute::PROTECTED);
    state->setAttributeAndModes(new osg::LineWidth(2.5F));
    group->addChild(geode);
  }
  return group;
}

osg::ref_ptr<osg::Node> makeGroundGrid(double half_extent, double spacing) {
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  geode->setName("ground_grid");
  const int lines_per_side = static_cast<int>(std::round(half_extent / spacing));
  const auto extent = static_cast<float>(lines_per_side * spacing);
  std::vector<osg::Vec3> minor;
  std::vector<osg::Vec3> major;
  for (int i = -lines_per_side; i <= lines_per_side; ++i) {
    const auto s = static_cast<float>(i * spacing);
    auto& target = (i % 5 == 0) ? major : minor;
    target.emplace_back(s, -extent, 0.0F);
    target.emplace_back(s, extent, 0.0F);
    target.emplace_back(-extent, s, 0.0F);
    target.emplace_back(extent, s, 0.0F);
  }
  geode->addDrawable(makeLines(minor, GL_LINES, osg::Vec4(0.62F, 0.65F, 0.70F, 1.0F)));
  geode->addDrawable(makeLines(major, GL_LINES, osg::Vec4(0.45F, 0.48F, 0.53F, 1.0F)));
  // A floor under the lines, pushed back in depth so the lines stay on top of it.
  osg::ref_ptr<osg::Geometry> floor = new osg::Geometry();
  osg::ref_ptr<osg::Vec3Array> corners = new osg::Vec3Array();
  corners->push_back(osg::Vec3(-extent, -extent, 0.0F));
  corners->push_back(osg::Vec3(extent, -extent, 0.0F));
  corners->push_back(osg::Vec3(extent, extent, 0.0F));
  corners->push_back(osg::Vec3(-extent, extent, 0.0F));
  osg::ref_ptr<osg::Vec4Array> floor_color = new osg::Vec4Array();
  floor_color->push_back(osg::Vec4(0.93F, 0.94F, 0.95F, 1.0F));
  floor->setVertexArray(corners);
  floor->setColorArray(floor_color, osg::Array::BIND_OVERALL);
  floor->addPrimitiveSet(new osg::DrawArrays(GL_QUADS, 0, 4));
  floor->getOrCreateStateSet()->setAttributeAndModes(new osg::PolygonOffset(1.0F, 1.0F));
  geode->addDrawable(floor);
  // World axes at the mounting point: 0.25 m long on the LWR IV's grid.
  osg::ref_ptr<osg::Geode> axes = new osg::Geode();
  const float length = extent / 6.0F;
  const float lift = 0.02F * static_cast<float>(spacing);  // just above the floor
  axes->addDrawable(makeLines({{0, 0, lift}, {length, 0, lift}}, GL_LINES, osg::Vec4(0.85F, 0.1F, 0.1F, 1)));
  axes->addDrawable(makeLines({{0, 0, lift}, {0, length, lift}}, GL_LINES, osg::Vec4(0.1F, 0.65F, 0.1F, 1)));
  axes->addDrawable(makeLines({{0, 0, lift}, {0, 0, length}}, GL_LINES, osg::Vec4(0.1F, 0.2F, 0.9F, 1)));
  axes->getOrCreateStateSet()->setAttributeAndModes(new osg::LineWidth(3.0F));
  osg::ref_ptr<osg::Group> group = new osg::Group();
  group->addChild(geode);
  group->addChild(axes);
  osg::StateSet* state = group->getOrCreateStateSet();
  state->setMode(GL_LIGHTING, osg::StateAttribute::OFF | osg::StateAttribute::PROTECTED);
  return group;
}

GroundGridSize groundGridSize(double reach) {
  if (!(reach > 0.0) || !std::isfinite(reach)) return {1.5, 0.1};
  const double spacing = std::pow(10.0, std::floor(std::log10(reach / 10.0)));
  const double major = 5.0 * spacing;
  // A hair below the multiple, so that a reach whose 1.25 times lands on a line is not pushed
  // a whole major step out by rounding.
  return {major * std::ceil(1.25 * reach / major - 1e-9), spacing};
}

World::World()
    : root_(new osg::Group), content_(new osg::Group), grid_(makeGroundGrid()), overlays_(std::make_unique<Overlays>()) {
  root_->setName("world");
  // A key light from the front-left above, a weaker fill from the right and a rim light from
  // behind: rounded shells show their curvature from any default viewpoint.
  root_->addChild(makeDirectionalLight(0, osg::Vec3(-0.8F, -0.6F, 1.0F), 0.75F, 0.6F));
  root_->addChild(makeDirectionalLight(1, osg::Vec3(0.5F, 1.0F, 0.35F), 0.35F, 0.1F));
  root_->addChild(makeDirectionalLight(2, osg::Vec3(1.0F, -0.3F, -0.2F), 0.2F, 0.0F));
  osg::StateSet* state = root_->getOrCreateStateSet();
  state->setMode(GL_LIGHTING, osg::StateAttribute::ON);
  for (int i = 0; i < 3; ++i) state->setMode(GL_LIGHT0 + static_cast<GLenum>(i), osg::StateAttribute::ON);
  osg::ref_ptr<osg::LightModel> light_model = new osg::LightModel();
  light_model->setAmbientIntensity(osg::Vec4(0.35F, 0.35F, 0.37F, 1.0F));
  light_model->setTwoSided(true);
  light_model->setLocalViewer(true);
  light_model->setColorControl(osg::LightModel::SEPARATE_SPECULAR_COLOR);
  state->setAttributeAndModes(light_model);
  state->setMode(GL_NORMALIZE, osg::StateAttribute::ON);
  root_->addChild(grid_);
  root_->addChild(content_);
  root_->addChild(overlays_->root());
}

World::~World() = default;

void World::setRobot(const robot::RobotModel& model) {
  auto graph = std::make_unique<RobotGraph>(model);
  if (robot_) content_->removeChild(robot_->root());
  content_->addChild(graph->root());
  robot_ = std::move(graph);
  // A quarter of the reach and 0.25 m beyond it: obstacles the arm can touch are framed whole,
  // with some of their surroundings.
  const auto [center_W, reach] = reachSphere(model);
  setFocusSphere(center_W, 1.25 * reach + 0.25);
  // The grid at the arm's scale: a 20 cm arm on 10 cm squares, or a 3 m arm on a grid smaller
  // than its reach, hides the size it has.
  const GroundGridSize size = groundGridSize(reach);
  osg::ref_ptr<osg::Node> grid = makeGroundGrid(size.half_extent, size.spacing);
  grid->setNodeMask(grid_->getNodeMask());
  root_->replaceChild(grid_, grid);
  grid_ = grid;
  surroundings_radius_ = 0.08 * reach;
}

void World::setScene(const robot::Scene& scene) {
  osg::ref_ptr<osg::Group> node = makeSceneNode(scene)->asGroup();
  if (scene_node_) content_->removeChild(scene_node_);
  content_->addChild(node);
  scene_node_ = node;
  area_centers_.clear();
  for (const robot::Area& area : scene.training_areas) area_centers_.push_back(area.p_WA);
  for (const robot::Area& area : scene.working_areas) area_centers_.push_back(area.p_WA);
  // makeSceneNode places the obstacles first, in the scene's order.
  obstacles_.clear();
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    osg::Group* placed_shape = node->getChild(static_cast<unsigned>(k))->asGroup();
    if (placed_shape == nullptr || placed_shape->getNumChildren() == 0) continue;
    obstacles_.push_back({placed_shape, placed_shape->getChild(0), scene.obstacles[k].name, scene.obstacles[k].rgba});
  }
}

void World::setFocusSphere(const Eigen::Vector3d& center_W, double radius) { focus_sphere_ = {center_W, radius}; }

void World::setGridVisible(bool visible) { grid_->setNodeMask(visible ? ~0U : 0U); }

std::pair<Eigen::Vector3d, double> World::contentBound() const {
  // Tight box bounds rather than OSG's conservative bounding spheres.
  osg::ComputeBoundsVisitor visitor;
  content_->accept(visitor);
  const osg::BoundingBox& box = visitor.getBoundingBox();
  if (!box.valid()) return {Eigen::Vector3d(0.0, 0.0, 0.5), 1.0};
  const osg::Vec3 c = box.center();
  return {Eigen::Vector3f(c.x(), c.y(), c.z()).cast<double>(), static_cast<double>(std::max(0.1F, box.radius()))};
}

std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> World::contentBox() const {
  osg::ComputeBoundsVisitor visitor;
  content_->accept(visitor);
  const osg::BoundingBox& box = visitor.getBoundingBox();
  if (!box.valid()) return std::nullopt;
  return std::make_pair(Eigen::Vector3f(box.xMin(), box.yMin(), box.zMin()).cast<double>(),
                        Eigen::Vector3f(box.xMax(), box.yMax(), box.zMax()).cast<double>());
}

namespace {

std::optional<Box> boundsOf(osg::Node& node) {
  osg::ComputeBoundsVisitor visitor;
  node.accept(visitor);
  const osg::BoundingBox& box = visitor.getBoundingBox();
  if (!box.valid()) return std::nullopt;
  return Box(Eigen::Vector3f(box.xMin(), box.yMin(), box.zMin()).cast<double>(),
             Eigen::Vector3f(box.xMax(), box.yMax(), box.zMax()).cast<double>());
}

void grow(std::optional<Box>& box, const std::optional<Box>& part) {
  if (!part) return;
  if (!box) {
    box = part;
    return;
  }
  box->first = box->first.cwiseMin(part->first);
  box->second = box->second.cwiseMax(part->second);
}

bool isOpaque(const Eigen::Vector4f& rgba) { return rgba[3] >= 0.999F; }

}  // namespace

std::optional<Box> World::focusBox() const {
  std::optional<Box> box;
  if (robot_) grow(box, boundsOf(*robot_->root()));
  if (scene_node_) {
    for (unsigned i = 0; i < scene_node_->getNumChildren(); ++i) {
      // Obstacles are framed below, clipped.
      if (scene_node_->getChild(i)->getName().rfind("obstacle:", 0) != 0) grow(box, boundsOf(*scene_node_->getChild(i)));
    }
  }
  for (const ObstacleNode& obstacle : obstacles_) {
    const std::optional<Box> bounds = boundsOf(*obstacle.node);
    if (bounds && focus_sphere_) {
      grow(box, clipBoxToSphere(*bounds, focus_sphere_->first, focus_sphere_->second));
    } else {
      grow(box, bounds);
    }
  }
  return box;
}

std::vector<Eigen::Vector3d> World::robotSamplePoints() const {
  std::vector<Eigen::Vector3d> points;
  if (!robot_ || robot_->root()->getNodeMask() == 0U) return points;
  // Evenly along the chain of joints, then the last link's centre (towards the tool): each part
  // of the arm counts by its length, not by how many joints crowd into it (the LWR's shoulder
  // holds three).
  std::vector<Eigen::Vector3d> chain;
  for (int i = 0; i < robot_->bodyCount(); ++i) {
    const osg::Vec3d origin = robot_->body(i)->getMatrix().getTrans();
    chain.emplace_back(origin.x(), origin.y(), origin.z());
  }
  if (const std::optional<Box> bounds = boundsOf(*robot_->body(robot_->bodyCount() - 1))) {
    chain.push_back(0.5 * (bounds->first + bounds->second));
  }
  double length = 0.0;
  for (std::size_t i = 1; i < chain.size(); ++i) length += (chain[i] - chain[i - 1]).norm();
  if (length < 1e-6) return {chain.front()};
  constexpr int kSamples = 24;
  std::size_t segment = 1;
  double walked = 0.0;  // chain length before `segment`
  for (int n = 0; n < kSamples; ++n) {
    const double at = length * (n + 0.5) / kSamples;
    while (segment + 1 < chain.size() && walked + (chain[segment] - chain[segment - 1]).norm() < at) {
      walked += (chain[segment] - chain[segment - 1]).norm();
      ++segment;
    }
    const double piece = (chain[segment] - chain[segment - 1]).norm();
    const double along = piece > 1e-9 ? std::clamp((at - walked) / piece, 0.0, 1.0) : 0.0;
    points.push_back(chain[segment - 1] + along * (chain[segment] - chain[segment - 1]));
  }
  return points;
}

bool World::obstacleHides(std::size_t k, const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const {
  if (!isOpaque(obstacles_[k].rgba)) return false;
  // Stop just short of the point: an obstacle the robot rests on does not hide it.
  const Eigen::Vector3d towards = p_W - eye_W;
  if (towards.norm() < 1e-6) return false;
  const Eigen::Vector3d end_W = p_W - 0.005 * towards.normalized();
  osg::ref_ptr<osgUtil::LineSegmentIntersector> ray = new osgUtil::LineSegmentIntersector(toOsg(eye_W), toOsg(end_W));
  osgUtil::IntersectionVisitor visitor(ray.get());
  obstacles_[k].node->accept(visitor);
  return ray->containsIntersections();
}

std::optional<std::size_t> World::hidingObstacle(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const {
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    if (obstacleHides(k, eye_W, p_W)) return k;
  }
  return std::nullopt;
}

std::vector<World::SamplePoint> World::visibleSamplePoints() const {
  // A point inside an obstacle (or closed in by obstacles) is hidden from every side: no view
  // can do better there, so it does not take part in choosing one.
  const auto enclosed = [&](const Eigen::Vector3d& p_W) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        if (!hidingObstacle(p_W + sign * 1e3 * Eigen::Vector3d::Unit(axis), p_W)) return false;
      }
    }
    return true;
  };
  const std::vector<Eigen::Vector3d> robot_points = robotSamplePoints();
  std::vector<Eigen::Vector3d> arm;
  for (const Eigen::Vector3d& p_W : robot_points) {
    if (!enclosed(p_W)) arm.push_back(p_W);
  }
  // A robot closed in whole (a dome over it, a box around the cell) is hidden from every side
  // by what encloses it: its points count, so that the hiding obstacles are drawn see-through
  // instead of the arm counting as seen.
  if (arm.empty()) arm = robot_points;
  std::vector<Eigen::Vector3d> areas;
  for (const Eigen::Vector3d& p_W : area_centers_) {
    if (!enclosed(p_W)) areas.push_back(p_W);
  }
  // The arm counts most; where the scene has areas, seeing where the arm is to work counts too
  // (a shelf's back wall hides the areas between its boards more than the arm in front).
  const double area_share = arm.empty() ? 1.0 : areas.empty() ? 0.0 : kAreaShare;
  std::vector<SamplePoint> points;
  for (const Eigen::Vector3d& p_W : arm) points.push_back({p_W, (1.0 - area_share) / static_cast<double>(arm.size()), false});
  for (const Eigen::Vector3d& p_W : areas) points.push_back({p_W, area_share / static_cast<double>(areas.size()), true});
  return points;
}

bool World::hiddenWithSurroundings(const Eigen::Vector3d& eye_W, const Eigen::Vector3d& p_W) const {
  if (!hidingObstacle(eye_W, p_W)) return false;
  // A pillar or a board edge may cover a link and leave the arm around it in sight; a wall or a
  // ceiling hides the point and its surroundings too.
  const Eigen::Vector3d forward = (p_W - eye_W).normalized();
  Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
  if (right.norm() < 1e-6) right = forward.cross(Eigen::Vector3d::UnitX());
  right.normalize();
  const Eigen::Vector3d up = right.cross(forward);
  for (const Eigen::Vector3d& offset : {right, Eigen::Vector3d(-right), up, Eigen::Vector3d(-up)}) {
    if (!hidingObstacle(eye_W, p_W + surroundings_radius_ * offset)) return false;
  }
  return true;
}

double World::hiddenWeight(const std::vector<SamplePoint>& points, const Eigen::Vector3d& eye_W) const {
  double hidden = 0.0;
  for (const SamplePoint& point : points) {
    if (hiddenWithSurroundings(eye_W, point.p_W)) hidden += point.weight;
  }
  return hidden;
}

double World::hiddenFraction(const CameraPose& camera) const { return hiddenWeight(visibleSamplePoints(), camera.eye_W); }

ViewChoice World::chooseView(const Box& box, double aspect, const std::vector<std::string>& views, double margin) const {
  const std::vector<SamplePoint> points = visibleSamplePoints();
  std::optional<ViewChoice> best;
  for (const std::string& view : views) {
    Eigen::Vector3d direction_W, up_W;
    namedView(view, direction_W, up_W);
    ViewChoice choice;
    choice.view = view;
    choice.camera = frameBoxFrom(box.first, box.second, aspect, direction_W, up_W, margin);
    choice.hidden_fraction = hiddenWeight(points, choice.camera.eye_W);
    if (choice.hidden_fraction <= kAcceptableHiddenFraction) return choice;
    if (!best || choice.hidden_fraction < best->hidden_fraction) best = choice;
  }
  if (!best) throw InputError("no view to choose from");
  return *best;
}

std::vector<std::string> World::revealRobot(const CameraPose& camera) {
  std::vector<std::string> revealed;
  const std::vector<SamplePoint> points = visibleSamplePoints();
  if (hiddenWeight(points, camera.eye_W) <= kAcceptableHiddenFraction) return revealed;
  // Every opaque obstacle on the way counts, not only the first: the one behind would hide the
  // point as soon as the first turns see-through.
  std::vector<bool> hides(obstacles_.size(), false);
  for (const SamplePoint& point : points) {
    for (std::size_t k = 0; k < obstacles_.size(); ++k) hides[k] = hides[k] || obstacleHides(k, camera.eye_W, point.p_W);
  }
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    if (!hides[k]) continue;
    ObstacleNode& obstacle = obstacles_[k];
    // Faint enough that the arm behind reads clearly, solid enough that the obstacle's extent
    // still shows.
    Eigen::Vector4f see_through = obstacle.rgba;
    see_through[3] = 0.25F;
    applyColor(*obstacle.shape, see_through);
    makeTranslucent(*obstacle.shape);
    obstacle.rgba = see_through;
    revealed.push_back(obstacle.name);
  }
  return revealed;
}

CameraPose World::defaultCamera(double aspect) const {
  const std::optional<Box> box = focusBox();
  if (!box) return frameSphere(Eigen::Vector3d(0.0, 0.0, 0.5), 1.0, aspect);
  return chooseView(*box, aspect, defaultViewOrder()).camera;
}

}  // namespace flexirob::render
