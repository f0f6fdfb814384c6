// Offscreen rendering: things appear where the camera projection of the kinematics says.
#include <gtest/gtest.h>
#include <osg/Matrixd>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "render/camera.hpp"
#include "render/offscreen.hpp"
#include "render/world.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/mesh.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::render {
namespace {

constexpr int kWidth = 480;
constexpr int kHeight = 360;

std::array<float, 4> background() {
  const Eigen::Vector4f c = Palette::background();
  return {c[0], c[1], c[2], c[3]};
}

// Centroid (pixel centres) and count of the pixels that differ between two renders.
struct ChangedPixels {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  int count = 0;
};

ChangedPixels diff(const Image& a, const Image& b) {
  ChangedPixels result;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const auto pa = a.pixel(x, y);
      const auto pb = b.pixel(x, y);
      int difference = 0;
      for (int c = 0; c < 3; ++c) difference += std::abs(int{pa[c]} - int{pb[c]});
      if (difference <= 6) continue;
      result.centroid += Eigen::Vector2d(x + 0.5, y + 0.5);
      ++result.count;
    }
  }
  if (result.count > 0) result.centroid /= result.count;
  return result;
}

// A two-joint pointer whose tip link is a red sphere centred on the tip frame, clear of the
// links (nothing cuts into its outline): the centroid of its pixels is (up to perspective, well
// below a pixel here) the projection of the tip.
constexpr const char* kPointerUrdf = R"(<?xml version="1.0"?>
<robot name="pointer">
  <material name="grey"><color rgba="0.5 0.5 0.55 1"/></material>
  <material name="red"><color rgba="0.9 0.05 0.05 1"/></material>
  <link name="base"><visual><geometry><box size="0.12 0.12 0.05"/></geometry><material name="grey"/></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="10"/></joint>
  <link name="upper"><visual><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.02" length="0.4"/></geometry>
    <material name="grey"/></visual></link>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="lower"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" velocity="1" effort="10"/></joint>
  <link name="lower"><visual><origin xyz="0 0 0.125"/><geometry><cylinder radius="0.015" length="0.25"/></geometry>
    <material name="grey"/></visual></link>
  <joint name="tip_joint" type="fixed"><parent link="lower"/><child link="tip"/><origin xyz="0 0 0.3"/></joint>
  <link name="tip"><visual><geometry><sphere radius="0.03"/></geometry><material name="red"/></visual></link>
</robot>)";

TEST(OffscreenRender, SphereTipAppearsAtTheProjectionOfItsForwardKinematics) {
  const auto model = robot::RobotModel::fromUrdfString(kPointerUrdf, std::filesystem::temp_directory_path());
  ASSERT_EQ(model.tipLink(), "tip");
  World world;
  world.setRobot(model);
  world.setGridVisible(false);
  OffscreenRenderer renderer(kWidth, kHeight);
  robot::Kinematics kinematics(model);
  const CameraPose camera = parseCamera("-1.3,-0.9,0.9,0,0,0.35");
  std::mt19937 engine(7);
  std::uniform_real_distribution<double> joint1(-1.2, 1.2);
  std::uniform_real_distribution<double> joint2(-1.8, 1.8);
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::Vector2d q(joint1(engine), joint2(engine));
    kinematics.update(q);
    world.robot()->setPosture(kinematics);
    ASSERT_EQ(world.robot()->setLinkVisible("tip", true), 1);
    const Image shown = renderer.render(world.root(), camera, background());
    world.robot()->setLinkVisible("tip", false);
    const Image hidden = renderer.render(world.root(), camera, background());
    const ChangedPixels tip = diff(shown, hidden);
    const auto expected = projectToPixel(camera, kWidth, kHeight, kinematics.p_WT());
    ASSERT_TRUE(expected.has_value());
    ASSERT_GT(tip.count, 30) << "the tip sphere should cover some pixels at q = " << q.transpose();
    EXPECT_LT((tip.centroid - *expected).norm(), 1.0)
        << "q = " << q.transpose() << ": rendered " << tip.centroid.transpose() << ", projected "
        << expected->transpose();
  }
}

TEST(OffscreenRender, LwrFlangeAppearsAtTheProjectionOfItsForwardKinematics) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  ASSERT_EQ(model.tipLink(), "flange");
  World world;
  world.setRobot(model);
  OffscreenRenderer renderer(kWidth, kHeight);
  robot::Kinematics kinematics(model);
  // The flange is a disc behind the tip frame's origin, along -z of the tip frame: expect the
  // centre of its visible face, i.e. the centre of the mesh's bounds.
  const robot::TriangleMesh flange = robot::loadMesh(model.bodies().back().visuals.back().mesh_file);
  const Eigen::Vector3d p_TF = flange.bounds().center().cast<double>();
  const Eigen::Vector3d p_WCenter(-0.3, 0.0, 0.55);
  CameraPose camera;
  camera.center_W = p_WCenter;
  camera.eye_W = p_WCenter + Eigen::Vector3d(-1.6, -1.0, 0.9);
  // Random postures (fixed seed) with the flange facing the camera, so that its whole disc is
  // in sight.
  std::mt19937 engine(11);
  std::vector<Eigen::VectorXd> postures;
  while (postures.size() < 3) {
    Eigen::VectorXd q = model.midPosture();
    for (int j = 0; j < model.dof(); ++j) {
      const auto& limits = model.joints()[static_cast<std::size_t>(j)].limits;
      q[j] = std::uniform_real_distribution<double>(0.6 * limits.soft_lower, 0.6 * limits.soft_upper)(engine);
    }
    kinematics.update(q);
    const Eigen::Vector3d towards_eye = (camera.eye_W - kinematics.p_WT()).normalized();
    if (kinematics.X_WT().linear().col(2).dot(towards_eye) > 0.6 && kinematics.p_WT().z() > 0.2) postures.push_back(q);
  }
  for (const Eigen::VectorXd& q : postures) {
    kinematics.update(q);
    world.robot()->setPosture(kinematics);
    const Eigen::Vector3d p_WF = kinematics.X_WT() * p_TF;
    world.robot()->setLinkVisible("flange", true);
    const Image shown = renderer.render(world.root(), camera, background());
    ASSERT_EQ(world.robot()->setLinkVisible("flange", false), 1);
    const Image hidden = renderer.render(world.root(), camera, background());
    const ChangedPixels changed = diff(shown, hidden);
    const auto expected = projectToPixel(camera, kWidth, kHeight, p_WF);
    ASSERT_TRUE(expected.has_value());
    ASSERT_GT(changed.count, 40) << "the flange should be visible at q = " << q.transpose();
    // About 3 mm per pixel here; the disc's visible face may be cut a little by link 7's ring
    // (measured offsets stay below 0.3 pixels).
    EXPECT_LT((changed.centroid - *expected).norm(), 1.5)
        << "q = " << q.transpose() << ": rendered " << changed.centroid.transpose() << ", projected "
        << expected->transpose();
  }
}

TEST(OffscreenRender, PostureChangeMovesTheRenderedArm) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  World world;
  world.setRobot(model);
  OffscreenRenderer renderer(kWidth, kHeight);
  robot::Kinematics kinematics(model);
  const CameraPose camera = world.defaultCamera(static_cast<double>(kWidth) / kHeight);
  kinematics.update(model.midPosture());
  world.robot()->setPosture(kinematics);
  const Image before = renderer.render(world.root(), camera, background());
  Eigen::VectorXd q = model.midPosture();
  q[1] += 0.8;
  kinematics.update(q);
  world.robot()->setPosture(kinematics);
  const Image after = renderer.render(world.root(), camera, background());
  EXPECT_GT(diff(before, after).count, 2000);
  // Rendering the same posture again gives the same picture (no state leaks between frames).
  const Image again = renderer.render(world.root(), camera, background());
  EXPECT_EQ(diff(after, again).count, 0);
}

TEST(OffscreenRender, ObstacleShowsInItsSceneColourWhereProjected) {
  World world;
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "blue_box";
  box.size = Eigen::Vector3d(0.2, 0.2, 0.8);
  box.X_WO.translation() = Eigen::Vector3d(-0.4, 0.4, 0.4);
  box.rgba = Eigen::Vector4f(0.1F, 0.2F, 0.9F, 1.0F);
  scene.obstacles.push_back(box);
  robot::Area area;
  area.name = "A";
  area.p_WA = Eigen::Vector3d(-0.5, -0.3, 0.4);
  area.radius = 0.1;
  scene.training_areas.push_back(area);
  world.setScene(scene);
  OffscreenRenderer renderer(kWidth, kHeight);
  const CameraPose camera = world.defaultCamera(static_cast<double>(kWidth) / kHeight);
  const Image image = renderer.render(world.root(), camera, background());
  const Eigen::Vector2d box_pixel = *projectToPixel(camera, kWidth, kHeight, box.X_WO.translation());
  const auto box_color = image.pixel(static_cast<int>(box_pixel.x()), static_cast<int>(box_pixel.y()));
  EXPECT_GT(box_color[2], box_color[0] + 60) << "expected the box's blue";
  EXPECT_GT(box_color[2], box_color[1] + 40) << "expected the box's blue";
  // The translucent training area tints the background towards its green.
  const Eigen::Vector2d area_pixel = *projectToPixel(camera, kWidth, kHeight, area.p_WA);
  const auto area_color = image.pixel(static_cast<int>(area_pixel.x()), static_cast<int>(area_pixel.y()));
  EXPECT_GT(area_color[1], area_color[0] + 20) << "expected the area's green tint";
  EXPECT_GT(area_color[1], area_color[2]) << "expected the area's green tint";
  // Translucent shapes blend their colour but leave the picture opaque.
  for (std::size_t i = 3; i < image.rgba.size(); i += 4) ASSERT_EQ(image.rgba[i], 255) << "pixel " << i / 4;
}

TEST(Camera, ProjectionAgreesWithOpenSceneGraphMatrices) {
  const CameraPose camera = parseCamera("-2.1,-1.3,1.4,-0.2,0.1,0.45,40");
  const int width = 640;
  const int height = 400;
  const osg::Matrixd view = osg::Matrixd::lookAt(osg::Vec3d(-2.1, -1.3, 1.4), osg::Vec3d(-0.2, 0.1, 0.45),
                                                 osg::Vec3d(0, 0, 1));
  const osg::Matrixd projection = osg::Matrixd::perspective(40.0, static_cast<double>(width) / height, 0.1, 50.0);
  std::mt19937 engine(3);
  std::uniform_real_distribution<double> coordinate(-0.8, 0.8);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d p_W(coordinate(engine), coordinate(engine), 0.5 + coordinate(engine));
    const osg::Vec3d ndc = osg::Vec3d(p_W.x(), p_W.y(), p_W.z()) * view * projection;
    const Eigen::Vector2d osg_pixel((ndc.x() + 1.0) * 0.5 * width, (1.0 - ndc.y()) * 0.5 * height);
    const auto pixel = projectToPixel(camera, width, height, p_W);
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR(pixel->x(), osg_pixel.x(), 1e-6);
    EXPECT_NEAR(pixel->y(), osg_pixel.y(), 1e-6);
  }
  EXPECT_FALSE(projectToPixel(camera, width, height, Eigen::Vector3d(-4.0, -2.5, 2.0)).has_value())
      << "a point behind the eye has no pixel";
}

TEST(Camera, DefaultCameraFramesTheWholeArm) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  World world;
  world.setRobot(model);
  const double aspect = 4.0 / 3.0;
  const CameraPose camera = world.defaultCamera(aspect);
  robot::Kinematics kinematics(model);
  kinematics.update(model.midPosture());
  // Eye in front (-x), left (-y) and above the centre it looks at.
  EXPECT_LT(camera.eye_W.x(), camera.center_W.x());
  EXPECT_LT(camera.eye_W.y(), camera.center_W.y());
  EXPECT_GT(camera.eye_W.z(), camera.center_W.z());
  for (int body = 0; body < static_cast<int>(model.bodies().size()); ++body) {
    const auto pixel = projectToPixel(camera, 400, 300, kinematics.X_WB(body).translation());
    ASSERT_TRUE(pixel.has_value());
    EXPECT_GT(pixel->x(), 0.0);
    EXPECT_LT(pixel->x(), 400.0);
    EXPECT_GT(pixel->y(), 0.0);
    EXPECT_LT(pixel->y(), 300.0);
  }
}

TEST(Camera, RefusesMalformedCameraText) {
  EXPECT_THROW(parseCamera("1,2,3"), InputError);
  EXPECT_THROW(parseCamera("1,2,3,4,5,x"), InputError);
  EXPECT_THROW(parseCamera("1,2,3,1,2,3"), InputError);
  EXPECT_THROW(parseCamera("0,0,2,0,0,0,200"), InputError);
  EXPECT_THROW(parseCamera("0,0,nan,0,0,0"), InputError);
  EXPECT_NO_THROW(parseCamera("0,0,2,0,0,0"));  // looking straight down is allowed
}

TEST(OffscreenRender, RefusesImpossibleImageSizes) {
  EXPECT_THROW(OffscreenRenderer(0, 10), InputError);
  EXPECT_THROW(OffscreenRenderer(10, 100000), InputError);
  EXPECT_THROW(OffscreenRenderer(10, 10, 9), InputError);
}

TEST(OffscreenRender, SupersamplingKeepsThingsInPlace) {
  const auto model = robot::RobotModel::fromUrdfString(kPointerUrdf, std::filesystem::temp_directory_path());
  World world;
  world.setRobot(model);
  world.setGridVisible(false);
  const CameraPose camera = parseCamera("-1.3,-0.9,0.9,0,0,0.35");
  OffscreenRenderer plain(kWidth, kHeight, 1);
  OffscreenRenderer smooth(kWidth, kHeight, 3);
  const Image a = plain.render(world.root(), camera, background());
  const Image b = smooth.render(world.root(), camera, background());
  world.robot()->setLinkVisible("tip", false);
  const ChangedPixels tip_plain = diff(a, plain.render(world.root(), camera, background()));
  const ChangedPixels tip_smooth = diff(b, smooth.render(world.root(), camera, background()));
  ASSERT_GT(tip_plain.count, 30);
  EXPECT_LT((tip_plain.centroid - tip_smooth.centroid).norm(), 0.5);
}

TEST(Png, WritesTheImageLosslessly) {
  Image image;
  image.width = 7;
  image.height = 5;
  for (int i = 0; i < image.width * image.height * 4; ++i) image.rgba.push_back(static_cast<std::uint8_t>((i * 37) % 256));
  const std::string bytes = encodePng(image);
  ASSERT_GT(bytes.size(), 33U);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto u32 = [&](std::size_t at) {
    return (std::uint32_t{static_cast<unsigned char>(bytes[at])} << 24) |
           (std::uint32_t{static_cast<unsigned char>(bytes[at + 1])} << 16) |
           (std::uint32_t{static_cast<unsigned char>(bytes[at + 2])} << 8) | std::uint32_t{static_cast<unsigned char>(bytes[at + 3])};
  };
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  EXPECT_EQ(u32(16), 7U);
  EXPECT_EQ(u32(20), 5U);
  // Inflate the IDAT chunk and compare every scanline (filter byte 0, then RGBA).
  const std::size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  const std::uint32_t length = u32(idat - 4);
  std::vector<unsigned char> raw(static_cast<std::size_t>(image.height) * (image.width * 4 + 1));
  uLongf raw_size = raw.size();
  ASSERT_EQ(uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(bytes.data() + idat + 4), length), Z_OK);
  ASSERT_EQ(raw_size, raw.size());
  for (int y = 0; y < image.height; ++y) {
    EXPECT_EQ(raw[static_cast<std::size_t>(y) * (image.width * 4 + 1)], 0);
    for (int i = 0; i < image.width * 4; ++i) {
      ASSERT_EQ(raw[static_cast<std::size_t>(y) * (image.width * 4 + 1) + 1 + static_cast<std::size_t>(i)],
                image.rgba[static_cast<std::size_t>(y * image.width * 4 + i)]);
    }
  }
  image.rgba.pop_back();
  EXPECT_THROW(encodePng(image), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::render
