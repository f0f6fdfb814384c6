// What the default view frames and from where: the robot and its surroundings, not a far or
// huge obstacle, and a side from which the arm is seen.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <osg/ComputeBoundsVisitor>
#include <osg/NodeVisitor>
#include <filesystem>
#include <string>

#include "render/camera.hpp"
#include "render/offscreen.hpp"
#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kAspect = static_cast<double>(kWidth) / kHeight;

std::array<float, 4> background() {
  const Eigen::Vector4f c = Palette::background();
  return {c[0], c[1], c[2], c[3]};
}

robot::Obstacle box(const std::string& name, const Eigen::Vector3d& size, const Eigen::Vector3d& p_W) {
  robot::Obstacle obstacle;
  obstacle.name = name;
  obstacle.size = size;
  obstacle.X_WO.translation() = p_W;
  obstacle.rgba = Eigen::Vector4f(0.25F, 0.27F, 0.30F, 1.0F);
  return obstacle;
}

// The LWR IV reaching forward and down (-x), as in the thesis' setups.
Eigen::VectorXd reachingForward() {
  Eigen::VectorXd q(7);
  q << 0.0, 0.6, 0.0, -1.6, 0.0, 0.9, 0.0;
  return q;
}

struct Lwr4InScene {
  robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  World world;
  explicit Lwr4InScene(const robot::Scene& scene, const Eigen::VectorXd& q = reachingForward()) {
    world.setRobot(model);
    world.setScene(scene);
    robot::Kinematics kinematics(model);
    kinematics.update(q);
    world.robot()->setPosture(kinematics);
  }
};

// How many pixels of the picture are the robot's: those that change when it is left out.
int visibleRobotPixels(World& world, const CameraPose& camera) {
  OffscreenRenderer renderer(kWidth, kHeight, 1);
  const Image with = renderer.render(world.root(), camera, background());
  world.robot()->root()->setNodeMask(0U);
  const Image without = renderer.render(world.root(), camera, background());
  world.robot()->root()->setNodeMask(~0U);
  int count = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      int difference = 0;
      for (int c = 0; c < 3; ++c) difference += std::abs(int{with.pixel(x, y)[c]} - int{without.pixel(x, y)[c]});
      count += difference > 12 ? 1 : 0;
    }
  }
  return count;
}

// An arm of three joints whose links add up to `reach` [m] (a fifth, two fifths, two fifths).
robot::RobotModel armOfReach(double reach) {
  std::string urdf = "<robot name=\"scaled\"><link name=\"base\"/>";
  const double parts[] = {0.2, 0.4, 0.4};
  std::string parent = "base";
  for (int j = 0; j < 3; ++j) {
    const std::string child = "l" + std::to_string(j + 1);
    urdf += "<joint name=\"j" + std::to_string(j + 1) + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" +
            child + "\"/><origin xyz=\"0 0 " + std::to_string(parts[j] * reach) + "\"/><axis xyz=\"0 1 0\"/>" +
            "<limit lower=\"-2\" upper=\"2\" velocity=\"1\" effort=\"10\"/></joint><link name=\"" + child + "\"/>";
    parent = child;
  }
  return robot::RobotModel::fromUrdfString(urdf + "</robot>", ".");
}

// Half the width of the ground grid in the world's picture, and whether it is drawn.
std::pair<double, bool> groundGridHalfWidth(World& world) {
  struct FindGrid : osg::NodeVisitor {
    FindGrid() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) { setNodeMaskOverride(~0U); }
    void apply(osg::Node& node) override {
      if (node.getName() == "ground_grid") found = &node;
      traverse(node);
    }
    osg::Node* found = nullptr;
  } finder;
  world.root()->accept(finder);
  if (finder.found == nullptr) return {0.0, false};
  osg::ComputeBoundsVisitor bounds;
  finder.found->accept(bounds);
  bool drawn = true;
  for (const osg::Node* node = finder.found; node != nullptr; node = node->getNumParents() > 0 ? node->getParent(0) : nullptr) {
    drawn = drawn && node->getNodeMask() != 0U;
  }
  return {0.5 * static_cast<double>(bounds.getBoundingBox().xMax() - bounds.getBoundingBox().xMin()), drawn};
}

// A 20 cm arm on 10 cm squares, or a 4 m arm on a grid smaller than its reach, hides its size;
// the LWR IV keeps the grid of the thesis' pictures (0.1 m squares, 1.5 m out).
// View names are the robot's sides (it works towards -x, so its left is -y): `left` had looked
// from +y while `front-left` looked from -y.
TEST(Framing, ViewNamesAreTheRobotsSides) {
  Eigen::Vector3d direction;
  Eigen::Vector3d up;
  for (const char* name : {"front-left", "front-left-low", "back-left", "left"}) {
    namedView(name, direction, up);
    EXPECT_LT(direction.y(), 0.0) << name << " looks from the robot's left, -y";
  }
  for (const char* name : {"front-right", "back-right", "right"}) {
    namedView(name, direction, up);
    EXPECT_GT(direction.y(), 0.0) << name << " looks from the robot's right, +y";
  }
  for (const char* name : {"front-left", "front-right", "front", "left", "right"}) {
    namedView(name, direction, up);
    EXPECT_LT(direction.x(), 0.0) << name << " looks from the front, -x, or beside it";
  }
}

TEST(Framing, TheGroundGridIsDrawnAtTheArmsScale) {
  const robot::RobotModel lwr4 = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const GroundGridSize thesis = groundGridSize(reachSphere(lwr4).second);
  EXPECT_DOUBLE_EQ(thesis.spacing, 0.1);
  EXPECT_NEAR(thesis.half_extent, 1.5, 1e-12);
  for (const double reach : {0.2, 4.0}) {
    const robot::RobotModel arm = armOfReach(reach);
    EXPECT_NEAR(reachSphere(arm).second, reach, 1e-6);
    const GroundGridSize size = groundGridSize(reach);
    // Ten to a hundred squares across the reach, out to the next darker line beyond 1.25 times it.
    EXPECT_GE(reach / size.spacing, 10.0 - 1e-9) << reach;
    EXPECT_LT(reach / size.spacing, 100.0) << reach;
    EXPECT_GE(size.half_extent, 1.25 * reach - 1e-9) << reach;
    EXPECT_LT(size.half_extent, 1.25 * reach + 5.0 * size.spacing) << reach;
    World world;
    world.setGridVisible(false);
    world.setRobot(arm);
    const auto [half_width, drawn] = groundGridHalfWidth(world);
    EXPECT_NEAR(half_width, size.half_extent, 1e-5) << reach;
    EXPECT_FALSE(drawn) << reach << ": a hidden grid stays hidden with the new robot";
  }
  // Goal markers and the like, sized in metres for the LWR IV, shrink with a smaller robot.
  EXPECT_EQ(robotSizeScale(lwr4), 1.0);
  EXPECT_EQ(robotSizeScale(robot::RobotModel::fromUrdfFile(resolveRobotPath("arm9"))), 1.0);
  EXPECT_NEAR(robotSizeScale(armOfReach(0.2)), 0.2 / 1.15, 1e-9);
  World world;
  world.setRobot(lwr4);
  const auto [half_width, drawn] = groundGridHalfWidth(world);
  EXPECT_NEAR(half_width, 1.5, 1e-5);
  EXPECT_TRUE(drawn);
}

TEST(Framing, ClipsABoxToThePartInsideASphere) {
  const Eigen::Vector3d center = Eigen::Vector3d::Zero();
  // Inside: unchanged.
  const Box inside(Eigen::Vector3d(-0.2, -0.1, 0.0), Eigen::Vector3d(0.3, 0.2, 0.5));
  const auto kept = clipBoxToSphere(inside, center, 1.0);
  ASSERT_TRUE(kept);
  EXPECT_TRUE(kept->first.isApprox(inside.first));
  EXPECT_TRUE(kept->second.isApprox(inside.second));
  // Far away: nothing.
  EXPECT_FALSE(clipBoxToSphere(Box(Eigen::Vector3d(-250, 350, 0), Eigen::Vector3d(250, 850, 10)), center, 2.0));
  // A ceiling slab at z = 0.6..0.7 over a unit sphere: the circle the sphere cuts at z = 0.6.
  const auto slab = clipBoxToSphere(Box(Eigen::Vector3d(-3, -3, 0.6), Eigen::Vector3d(3, 3, 0.7)), center, 1.0);
  ASSERT_TRUE(slab);
  EXPECT_NEAR(slab->second.x(), 0.8, 1e-12);
  EXPECT_NEAR(slab->first.y(), -0.8, 1e-12);
  EXPECT_NEAR(slab->first.z(), 0.6, 1e-12);
  EXPECT_NEAR(slab->second.z(), 0.7, 1e-12);
}

TEST(Framing, AFarHugeObstacleLeavesTheViewAsWithoutIt) {
  robot::Scene near_only;
  near_only.obstacles.push_back(box("near", Eigen::Vector3d(0.2, 0.2, 0.3), Eigen::Vector3d(-0.5, 0.3, 0.15)));
  robot::Scene with_far = near_only;
  // A building wall 600 m away (hold-out scene far_box.yaml).
  with_far.obstacles.push_back(box("far", Eigen::Vector3d(500, 500, 10), Eigen::Vector3d(0, 600, 5)));
  Lwr4InScene plain(near_only);
  Lwr4InScene far(with_far);
  const CameraPose expected = plain.world.defaultCamera(kAspect);
  const CameraPose camera = far.world.defaultCamera(kAspect);
  EXPECT_LT((camera.eye_W - expected.eye_W).norm(), 1e-6) << camera.eye_W.transpose();
  EXPECT_LT((camera.center_W - expected.center_W).norm(), 1e-6) << camera.center_W.transpose();
  // The arm fills a good part of the picture's height, not a speck.
  robot::Kinematics kinematics(far.model);
  kinematics.update(reachingForward());
  double top = kHeight;
  double bottom = 0.0;
  for (int body = 0; body < static_cast<int>(far.model.bodies().size()); ++body) {
    const auto pixel = projectToPixel(camera, kWidth, kHeight, kinematics.X_WB(body).translation());
    ASSERT_TRUE(pixel);
    top = std::min(top, pixel->y());
    bottom = std::max(bottom, pixel->y());
  }
  EXPECT_GT(bottom - top, 0.3 * kHeight);
}

TEST(Framing, BuiltInScenesKeepTheirFramingAndTheFrontLeftView) {
  for (const std::string& name : robot::builtinSceneNames()) {
    const robot::Scene scene = robot::loadScene(name);
    const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot::robotFor("", scene)));
    World world;
    world.setRobot(model);
    world.setScene(scene);
    robot::Kinematics kinematics(model);
    kinematics.update(scene.home_posture && scene.home_posture->size() == model.dof() ? *scene.home_posture
                                                                                       : model.midPosture());
    world.robot()->setPosture(kinematics);
    // Every obstacle of the thesis' setups lies within the robot's reach: framed whole.
    const auto whole = world.contentBox();
    const auto focus = world.focusBox();
    ASSERT_TRUE(whole && focus) << name;
    EXPECT_TRUE(focus->first.isApprox(whole->first)) << name << ": " << focus->first.transpose();
    EXPECT_TRUE(focus->second.isApprox(whole->second)) << name << ": " << focus->second.transpose();
    const ViewChoice choice = world.chooseView(*focus, kAspect, defaultViewOrder());
    EXPECT_EQ(choice.view, "front-left") << name << " hides " << choice.hidden_fraction << " of the arm";
  }
}

TEST(Framing, ACeilingOverTheRobotDoesNotHideTheArm) {
  robot::Scene scene;
  // Hold-out scene ceiling.yaml: a 6 x 6 m slab at 1.35..1.45 m.
  scene.obstacles.push_back(box("ceiling", Eigen::Vector3d(6, 6, 0.1), Eigen::Vector3d(0, 0, 1.4)));
  Lwr4InScene setup(scene);
  const CameraPose camera = setup.world.defaultCamera(kAspect);
  EXPECT_LT(camera.eye_W.z(), 1.35) << "the eye should stay under the ceiling";
  EXPECT_GT(visibleRobotPixels(setup.world, camera), 400);
}

TEST(Framing, AWallBetweenTheFrontAndTheRobotDoesNotHideTheArm) {
  robot::Scene scene;
  // A shelf's back wall in front of the robot (hold-out scene ur5b_shelf.yaml, wider).
  scene.obstacles.push_back(box("wall", Eigen::Vector3d(0.04, 3.0, 1.6), Eigen::Vector3d(-0.85, 0, 0.8)));
  Lwr4InScene setup(scene);
  const CameraPose camera = setup.world.defaultCamera(kAspect);
  EXPECT_GT(camera.eye_W.x(), -0.85) << "the eye should be on the robot's side of the wall";
  EXPECT_GT(visibleRobotPixels(setup.world, camera), 400);
}

TEST(Framing, ANamedViewIsKeptAndTheObstaclesInTheWayTurnSeeThrough) {
  robot::Scene scene;
  scene.obstacles.push_back(box("wall", Eigen::Vector3d(0.04, 3.0, 1.6), Eigen::Vector3d(-0.85, 0, 0.8)));
  scene.obstacles.push_back(box("aside", Eigen::Vector3d(0.2, 0.2, 0.3), Eigen::Vector3d(0.4, 0.6, 0.15)));
  Lwr4InScene setup(scene);
  const ViewChoice choice = setup.world.chooseView(*setup.world.focusBox(), kAspect, {"front-left"});
  EXPECT_EQ(choice.view, "front-left");
  EXPECT_GT(choice.hidden_fraction, 0.8);
  EXPECT_EQ(visibleRobotPixels(setup.world, choice.camera), 0) << "the wall hides the arm";
  EXPECT_EQ(setup.world.revealRobot(choice.camera), std::vector<std::string>{"wall"});
  EXPECT_GT(visibleRobotPixels(setup.world, choice.camera), 400);
}

// A dome of 2 m radius over the robot: every point of the arm is inside it, hidden from every
// side. The picture had shown a grey ball and called the arm seen (hidden fraction 0).
TEST(Framing, AnObstacleEnclosingTheWholeRobotTurnsSeeThrough) {
  robot::Scene scene;
  robot::Obstacle dome;
  dome.name = "dome";
  dome.shape = robot::Obstacle::Shape::kSphere;
  dome.size = Eigen::Vector3d(2.0, 0.0, 0.0);
  dome.rgba = Eigen::Vector4f(0.25F, 0.27F, 0.30F, 1.0F);
  scene.obstacles.push_back(dome);
  Lwr4InScene setup(scene);
  const ViewChoice choice = setup.world.chooseView(*setup.world.focusBox(), kAspect, defaultViewOrder());
  EXPECT_GT(choice.hidden_fraction, 0.9);
  EXPECT_EQ(visibleRobotPixels(setup.world, choice.camera), 0) << "the dome hides the arm";
  EXPECT_EQ(setup.world.revealRobot(choice.camera), std::vector<std::string>{"dome"});
  // Framed with the whole dome, the arm is small, but in sight.
  EXPECT_GT(visibleRobotPixels(setup.world, choice.camera), 100);
}

}  // namespace
}  // namespace flexirob::render
