// Every link of the robot drawn, whether the URDF gives it visuals, only collision shapes or
// nothing: an arm the simulation moves is never invisible.
#include <gtest/gtest.h>
#include <osg/ComputeBoundsVisitor>

#include <Eigen/Core>
#include <filesystem>
#include <string>

#include "render/offscreen.hpp"
#include "render/robot_graph.hpp"
#include "render/world.hpp"
#include "robot/collision.hpp"
#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kAspect = static_cast<double>(kWidth) / kHeight;

// How many pixels of the picture are the robot's: those that change when it is left out.
int visibleRobotPixels(World& world, const CameraPose& camera) {
  const Eigen::Vector4f c = Palette::background();
  OffscreenRenderer renderer(kWidth, kHeight, 1);
  const Image with = renderer.render(world.root(), camera, {c[0], c[1], c[2], c[3]});
  world.robot()->root()->setNodeMask(0U);
  const Image without = renderer.render(world.root(), camera, {c[0], c[1], c[2], c[3]});
  world.robot()->root()->setNodeMask(~0U);
  int count = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      int difference = 0;
      for (int k = 0; k < 3; ++k) difference += std::abs(int{with.pixel(x, y)[k]} - int{without.pixel(x, y)[k]});
      count += difference > 12 ? 1 : 0;
    }
  }
  return count;
}

// Two links on a base; `link_geometry` goes into each moving link (collision only, or nothing).
std::string armWith(const std::string& link_geometry) {
  return R"(<?xml version="1.0"?>
<robot name="bare">
  <link name="base">)" + link_geometry + R"(</link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="10"/></joint>
  <link name="upper">)" + link_geometry + R"(</link>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="lower"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" velocity="1" effort="10"/></joint>
  <link name="lower">)" + link_geometry + R"(</link>
  <joint name="tip_joint" type="fixed"><parent link="lower"/><child link="tip"/><origin xyz="0 0 0.4"/></joint>
  <link name="tip"/>
</robot>)";
}

constexpr const char* kCollisionOnly =
    R"(<collision><origin xyz="0 0 0.2"/><geometry><box size="0.08 0.08 0.4"/></geometry></collision>)";

Box bodyBounds(const RobotGraph& graph, int body) {
  osg::ComputeBoundsVisitor visitor;
  graph.body(body)->accept(visitor);
  const osg::BoundingBox& bounds = visitor.getBoundingBox();
  return {Eigen::Vector3d(bounds.xMin(), bounds.yMin(), bounds.zMin()), Eigen::Vector3d(bounds.xMax(), bounds.yMax(), bounds.zMax())};
}

TEST(RobotGraph, LinksWithOnlyCollisionShapesAreDrawnWithThem) {
  const auto model = robot::RobotModel::fromUrdfString(armWith(kCollisionOnly), std::filesystem::temp_directory_path());
  World world;
  world.setRobot(model);
  robot::Kinematics kinematics(model);
  kinematics.update(Eigen::Vector2d(0.0, 1.0));
  world.robot()->setPosture(kinematics);
  // The lower link's box, 0.08 x 0.08 x 0.4 m from its joint along its z axis.
  const Box lower = bodyBounds(*world.robot(), 2);
  const Eigen::Vector3d p_WMiddle = kinematics.X_WB(2) * Eigen::Vector3d(0, 0, 0.2);
  EXPECT_LT((0.5 * (lower.first + lower.second) - p_WMiddle).norm(), 1e-5);
  EXPECT_GT(visibleRobotPixels(world, world.defaultCamera(kAspect)), 2000);
}

TEST(RobotGraph, LinksWithVisualsDrawOnlyTheirVisuals) {
  const std::string both = std::string(R"(<visual><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.01" length="0.4"/></geometry></visual>)") +
                           kCollisionOnly;
  const auto model = robot::RobotModel::fromUrdfString(armWith(both), std::filesystem::temp_directory_path());
  const RobotGraph graph(model);
  const Box upper = bodyBounds(graph, 1);
  // The thin visual's width, not the 8 cm collision box's.
  EXPECT_NEAR(upper.second.x() - upper.first.x(), 0.02, 1e-3);
}

TEST(RobotGraph, BodiesWithoutAnyShapeGetTheCollisionWorldsCapsule) {
  const auto model = robot::RobotModel::fromUrdfString(armWith(""), std::filesystem::temp_directory_path());
  World world;
  world.setRobot(model);
  robot::Kinematics kinematics(model);
  kinematics.update(Eigen::Vector2d(0.0, 0.0));
  world.robot()->setPosture(kinematics);
  for (int body = 0; body < 3; ++body) {
    const robot::LinkCapsule capsule = robot::linkCapsule(model, body);
    ASSERT_GT(capsule.radius, 0.0);
    // Straight up, each capsule spans its segment along z, grown by its radius all round.
    const Box bounds = bodyBounds(*world.robot(), body);
    const Eigen::Vector3d a_W = kinematics.X_WB(body) * capsule.a_B;
    const Eigen::Vector3d b_W = kinematics.X_WB(body) * capsule.b_B;
    EXPECT_NEAR(bounds.first.z(), std::min(a_W.z(), b_W.z()) - capsule.radius, 2e-3) << body;
    EXPECT_NEAR(bounds.second.z(), std::max(a_W.z(), b_W.z()) + capsule.radius, 2e-3) << body;
    EXPECT_NEAR(bounds.second.x(), capsule.radius, 2e-3) << body;
  }
  EXPECT_GT(visibleRobotPixels(world, world.defaultCamera(kAspect)), 1000);
}

}  // namespace
}  // namespace flexirob::render
