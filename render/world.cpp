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

#include "render/shapes.hpp"

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
  // World axes at the mounting point, 0.25 m long.
  osg::ref_ptr<osg::Geode> axes = new osg::Geode();
  const float length = 0.25F;
  const float lift = 0.002F;  // just above the floor
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
}

void World::setScene(const robot::Scene& scene) {
  osg::ref_ptr<osg::Node> node = makeSceneNode(scene);
  if (scene_node_) content_->removeChild(scene_node_);
  content_->addChild(node);
  scene_node_ = node;
}

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

CameraPose World::defaultCamera(double aspect) const {
  osg::ComputeBoundsVisitor visitor;
  content_->accept(visitor);
  const osg::BoundingBox& box = visitor.getBoundingBox();
  if (!box.valid()) return frameSphere(Eigen::Vector3d(0.0, 0.0, 0.5), 1.0, aspect);
  return frameBox(Eigen::Vector3d(box.xMin(), box.yMin(), box.zMin()),
                  Eigen::Vector3d(box.xMax(), box.yMax(), box.zMax()), aspect);
}

}  // namespace flexirob::render
