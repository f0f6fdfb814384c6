// A third-party robot description (tests/data/third_party/iiwa_like_description: the KUKA LBR
// iiwa 14 R820 kinematics written ROS-package style, with package:// URIs, DAE/OBJ/STL meshes,
// fixed joints and axes that are not all z) loads and works like ours; its broken variants fail
// with a one-line InputError.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include <unistd.h>

#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/mesh.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::robot {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

const fs::path kPackage = fs::path(FLEXIROB_TEST_DATA_DIR) / "third_party" / "iiwa_like_description";
const fs::path kArm = kPackage / "urdf" / "arm.urdf";

const RobotModel& arm() {
  static const RobotModel model = RobotModel::fromUrdfFile(kArm);
  return model;
}

// Standard DH link transform T = Rz(theta) Tz(d) Rx(alpha) (a = 0 for this arm).
Eigen::Isometry3d dh(double theta, double d, double alpha) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.rotate(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
  T.translate(Eigen::Vector3d(0, 0, d));
  T.rotate(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()));
  return T;
}

// The published LBR iiwa 14 R820 chain, written independently of the URDF: the mount pose of
// the file's world_to_base joint, the DH table (d = 0.36, 0, 0.42, 0, 0.4, 0, 0.126 m;
// alpha = -pi/2, pi/2, pi/2, -pi/2, -pi/2, pi/2, 0), then tool0, which is DH frame 7 turned by
// +90 degrees about z (the file yaws its link frames from joint 3 on by that much).
Eigen::Isometry3d referenceToolPose(const Eigen::VectorXd& q) {
  constexpr std::array<double, 7> d{0.36, 0, 0.42, 0, 0.4, 0, 0.126};
  constexpr std::array<double, 7> alpha{-kPi / 2, kPi / 2, kPi / 2, -kPi / 2, -kPi / 2, kPi / 2, 0};
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translate(Eigen::Vector3d(0.25, -0.1, 0.02));
  X.rotate(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  for (std::size_t i = 0; i < 7; ++i) X = X * dh(q[static_cast<Eigen::Index>(i)], d[i], alpha[i]);
  return X * Eigen::Isometry3d(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
}

Eigen::VectorXd randomPosture(const RobotModel& model, std::mt19937& rng) {
  Eigen::VectorXd q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    std::uniform_real_distribution<double> uniform(model.lowerLimits()[i], model.upperLimits()[i]);
    q[i] = uniform(rng);
  }
  return q;
}

double signedVolume(const TriangleMesh& mesh) {
  double volume = 0.0;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const Eigen::Vector3d a = mesh.vertices[mesh.indices[t]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[mesh.indices[t + 1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[mesh.indices[t + 2]].cast<double>();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

// Volume of the 24-gon prism the fixture's cylinders are made of.
double prismVolume(double radius, double height, int sides) {
  return 0.5 * sides * radius * radius * std::sin(2 * kPi / sides) * height;
}

void expectOneLineInputError(const std::function<void()>& action, const std::string& fragment) {
  try {
    action();
    ADD_FAILURE() << "expected InputError containing '" << fragment << "'";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got " << e.what();
  }
}

TEST(ThirdPartyUrdf, LoadsWithToolZeroAsDefaultTipAndFoldsFixedLinks) {
  const RobotModel& model = arm();
  EXPECT_EQ(model.name(), "iiwa_like");
  EXPECT_EQ(model.dof(), 7);
  EXPECT_EQ(model.baseLink(), "world");
  EXPECT_EQ(model.tipLink(), "tool0");
  EXPECT_EQ(model.joints().front().name, "iiwa_joint_1");
  EXPECT_EQ(model.joints().back().name, "iiwa_joint_7");
  // Limits as published: +-170, 120, 170, 120, 170, 120, 175 deg; 85 ... 135 deg/s.
  const std::array<double, 7> limit_deg{170, 120, 170, 120, 170, 120, 175};
  const std::array<double, 7> velocity_deg{85, 85, 100, 75, 130, 135, 135};
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_NEAR(model.upperLimits()[static_cast<Eigen::Index>(i)], limit_deg[i] * kPi / 180, 1e-5);
    EXPECT_NEAR(model.lowerLimits()[static_cast<Eigen::Index>(i)], -limit_deg[i] * kPi / 180, 1e-5);
    EXPECT_NEAR(model.velocityLimits()[static_cast<Eigen::Index>(i)], velocity_deg[i] * kPi / 180, 1e-5);
  }
  // The mount link is folded into the root body, the camera bracket into link 3, tool0 into link 7.
  const auto& bodies = model.bodies();
  EXPECT_EQ(bodies[0].folded_links, std::vector<std::string>{"iiwa_link_0"});
  EXPECT_EQ(bodies[3].folded_links, std::vector<std::string>{"camera_link"});
  EXPECT_EQ(bodies[7].folded_links, std::vector<std::string>{"tool0"});
  // The camera box keeps its pose relative to link 3.
  bool camera_found = false;
  for (const auto& visual : bodies[3].visuals) {
    if (visual.source_link != "camera_link") continue;
    camera_found = true;
    EXPECT_EQ(visual.kind, Geometry::Kind::kBox);
    EXPECT_LT((visual.X_BG.translation() - Eigen::Vector3d(0.08, 0, 0.1)).norm(), 1e-12);
  }
  EXPECT_TRUE(camera_found);
  // The base's geometry moved with the mount joint: in the root frame it sits at the mount.
  ASSERT_FALSE(bodies[0].visuals.empty());
  EXPECT_LT((bodies[0].visuals[0].X_BG.translation() - Eigen::Vector3d(0.25, -0.1, 0.02)).norm(), 1e-12);
}

TEST(ThirdPartyUrdf, ForwardKinematicsMatchesThePublishedDhChain) {
  const RobotModel& model = arm();
  // Straight up: tool0 at the mount plus 0.36 + 0.42 + 0.4 + 0.126 m.
  const Eigen::Isometry3d X_up = tipPose(model, Eigen::VectorXd::Zero(7));
  EXPECT_LT((X_up.translation() - Eigen::Vector3d(0.25, -0.1, 0.02 + 1.306)).norm(), 1e-12);
  std::mt19937 rng(2024);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::VectorXd q = randomPosture(model, rng);
    const Eigen::Isometry3d X_WT = tipPose(model, q);
    const Eigen::Isometry3d X_ref = referenceToolPose(q);
    ASSERT_LT((X_WT.translation() - X_ref.translation()).norm(), 1e-9) << "q = " << q.transpose();
    ASSERT_LT((X_WT.linear() - X_ref.linear()).norm(), 1e-9) << "q = " << q.transpose();
  }
}

TEST(ThirdPartyUrdf, TipJacobianMatchesDifferencesOfTheDhChain) {
  const RobotModel& model = arm();
  Kinematics kinematics(model);
  std::mt19937 rng(11);
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd q = randomPosture(model, rng);
    kinematics.update(q);
    Matrix6Xd J(6, 7);
    kinematics.tipJacobian(J);
    for (int j = 0; j < 7; ++j) {
      Eigen::VectorXd qp = q, qm = q;
      qp[j] += h;
      qm[j] -= h;
      const Eigen::Isometry3d Xp = referenceToolPose(qp), Xm = referenceToolPose(qm);
      const Eigen::Vector3d v = (Xp.translation() - Xm.translation()) / (2 * h);
      // Angular velocity from the rotation difference: R' R^T is skew(omega).
      const Eigen::Matrix3d dR = (Xp.linear() - Xm.linear()) / (2 * h) * referenceToolPose(q).linear().transpose();
      const Eigen::Vector3d w(dR(2, 1), dR(0, 2), dR(1, 0));
      EXPECT_LT((J.col(j).head<3>() - v).norm(), 1e-6) << "joint " << j;
      EXPECT_LT((J.col(j).tail<3>() - w).norm(), 1e-6) << "joint " << j;
    }
  }
}

TEST(ThirdPartyUrdf, ResolvesPackageAndRelativeMeshUris) {
  const RobotModel& model = arm();
  const fs::path segment = fs::weakly_canonical(kPackage / "meshes" / "visual" / "segment.dae");
  // Link 1 names it as package://iiwa_like_description/..., link 2 as ../meshes/...
  EXPECT_EQ(model.bodies()[1].visuals.at(0).mesh_file, segment);
  EXPECT_EQ(model.bodies()[2].visuals.at(0).mesh_file, segment);
  const Geometry& collision = model.bodies()[1].collisions.at(0);
  EXPECT_EQ(collision.mesh_file, fs::weakly_canonical(kPackage / "meshes" / "collision" / "segment_mm.stl"));
  EXPECT_TRUE(collision.mesh_scale.isApprox(Eigen::Vector3d::Constant(0.001)));
  // Every mesh the description names loads.
  for (const auto& body : model.bodies()) {
    for (const auto* list : {&body.visuals, &body.collisions}) {
      for (const auto& geometry : *list) {
        if (geometry.kind != Geometry::Kind::kMesh) continue;
        EXPECT_NO_THROW(loadMeshCached(geometry.mesh_file)) << geometry.mesh_file;
      }
    }
  }
}

TEST(ThirdPartyUrdf, ResolvesPackageUrisThroughRosPackagePathWhenTheUrdfLivesElsewhere) {
  // A URDF generated outside its package (as xacro output often is) finds the package through
  // ROS_PACKAGE_PATH, and only through it.
  const fs::path dir = fs::temp_directory_path() / ("flexirob_third_party_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::copy_file(kArm, dir / "arm.urdf", fs::copy_options::overwrite_existing);
  const char* previous = std::getenv("ROS_PACKAGE_PATH");
  const std::string saved = previous != nullptr ? previous : "";
  ::unsetenv("ROS_PACKAGE_PATH");
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(dir / "arm.urdf"); }, "not found");
  ::setenv("ROS_PACKAGE_PATH", ("/nonexistent:" + kPackage.parent_path().string()).c_str(), 1);
  {
    // Link 2's relative URI cannot resolve from there: name the package instead.
    std::string xml(static_cast<std::size_t>(fs::file_size(kArm)), '\0');
    std::ifstream(kArm, std::ios::binary).read(xml.data(), static_cast<std::streamsize>(xml.size()));
    const std::string relative = "../meshes/visual/segment.dae";
    xml.replace(xml.find(relative), relative.size(), "package://iiwa_like_description/meshes/visual/segment.dae");
    std::ofstream(dir / "arm.urdf") << xml;
  }
  const RobotModel model = RobotModel::fromUrdfFile(dir / "arm.urdf");
  EXPECT_EQ(model.bodies()[1].visuals.at(0).mesh_file, fs::weakly_canonical(kPackage / "meshes" / "visual" / "segment.dae"));
  if (previous != nullptr) {
    ::setenv("ROS_PACKAGE_PATH", saved.c_str(), 1);
  } else {
    ::unsetenv("ROS_PACKAGE_PATH");
  }
  fs::remove_all(dir);
}

TEST(ThirdPartyUrdf, LoadsColladaObjAndStlMeshesInMetres) {
  const fs::path visual = kPackage / "meshes" / "visual";
  const fs::path collision = kPackage / "meshes" / "collision";
  // COLLADA in millimetres (unit 0.001), z up, moved up 78.75 mm by its node: radius 0.11 m,
  // standing on z = 0 up to 0.1575 m.
  const TriangleMesh base = loadMesh(visual / "base.dae");
  EXPECT_NEAR(base.bounds().max().x(), 0.11, 1e-6);
  EXPECT_NEAR(base.bounds().min().z(), 0.0, 1e-6);
  EXPECT_NEAR(base.bounds().max().z(), 0.1575, 1e-6);
  EXPECT_NEAR(signedVolume(base), prismVolume(0.11, 0.1575, 24), 1e-6);
  // Two sub-meshes under two nodes, merged: 0..0.2 m, twice the triangles of one part.
  const TriangleMesh segment = loadMesh(visual / "segment.dae");
  EXPECT_EQ(segment.triangleCount(), 2U * 96U);
  EXPECT_NEAR(segment.bounds().min().z(), 0.0, 1e-6);
  EXPECT_NEAR(segment.bounds().max().z(), 0.2, 1e-6);
  EXPECT_NEAR(signedVolume(segment), prismVolume(0.065, 0.2, 24), 1e-6);
  // OBJ in metres with quads (triangulated), and the same shape as ASCII STL.
  const TriangleMesh wrist_obj = loadMesh(visual / "wrist.obj");
  const TriangleMesh wrist_stl = loadMesh(collision / "wrist.stl");
  EXPECT_EQ(wrist_obj.triangleCount(), 96U);
  EXPECT_EQ(wrist_stl.triangleCount(), 96U);
  EXPECT_NEAR(signedVolume(wrist_obj), prismVolume(0.05, 0.081, 24), 1e-8);
  EXPECT_NEAR(signedVolume(wrist_stl), prismVolume(0.05, 0.081, 24), 1e-8);
  // Binary STL in millimetres: the loader keeps the file's numbers, the URDF's scale makes metres.
  const TriangleMesh segment_mm = loadMesh(collision / "segment_mm.stl");
  EXPECT_NEAR(segment_mm.bounds().max().z(), 200.0, 1e-3);
  const TriangleMesh segment_m = transformedMesh(segment_mm, Eigen::Isometry3d::Identity(), Eigen::Vector3d::Constant(0.001));
  EXPECT_NEAR(segment_m.bounds().max().z(), 0.2, 1e-6);
  EXPECT_NEAR(signedVolume(segment_m), prismVolume(0.065, 0.2, 12), 1e-7);
}

TEST(ThirdPartyUrdf, BrokenVariantsFailWithOneLineInputError) {
  const fs::path broken = kPackage / "urdf" / "broken";
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "malformed.urdf"); }, "invalid URDF");
  // The file that did not read is named (a scene's `robot:` may point anywhere).
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "malformed.urdf"); }, "broken/malformed.urdf: invalid URDF");
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "missing_link.urdf"); }, "iiwa_link_2");
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "missing_mesh.urdf"); }, "link_1_missing.dae' not found");
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "floating_joint.urdf"); }, "floating");
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(broken / "two_chains.urdf"); }, "not a serial chain");
  // The truncated mesh is found (the description is fine); loading it is what fails.
  const RobotModel truncated = RobotModel::fromUrdfFile(broken / "truncated_mesh.urdf");
  expectOneLineInputError([&] { loadMesh(truncated.bodies()[1].collisions.at(0).mesh_file); }, "truncated");
}

TEST(ThirdPartyUrdf, NamedTipSelectsOneChainOrAShorterArm) {
  const RobotModel left = RobotModel::fromUrdfFile(kPackage / "urdf" / "broken" / "two_chains.urdf", "left_link_2");
  EXPECT_EQ(left.dof(), 2);
  EXPECT_EQ(left.joints().front().name, "left_joint_1");
  const RobotModel to_link4 = RobotModel::fromUrdfFile(kArm, "iiwa_link_4");
  EXPECT_EQ(to_link4.dof(), 4);
  // Link 4's frame sits at the elbow, A4, 0.36 + 0.42 m above the mount when straight up.
  EXPECT_LT((tipPose(to_link4, Eigen::VectorXd::Zero(4)).translation() - Eigen::Vector3d(0.25, -0.1, 0.02 + 0.78)).norm(), 1e-12);
  expectOneLineInputError([&] { RobotModel::fromUrdfFile(kArm, "no_such_link"); }, "no_such_link");
}

}  // namespace
}  // namespace flexirob::robot
