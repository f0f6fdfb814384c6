// Mesh loading (robot/mesh.hpp) and the generated LWR IV meshes: closed outward surfaces in
// metres, placed by forward kinematics so that the links of both arms join up at every joint.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/mesh.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::robot {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshDir = fs::path(FLEXIROB_TEST_RESOURCE_DIR) / "robots" / "lwr4" / "meshes";

// Signed volume by the divergence theorem: positive iff the closed surface faces outwards.
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

// Edges keyed by quantised positions (0.01 mm), so vertices split at creases still match.
using PositionKey = std::array<long, 3>;
PositionKey keyOf(const Eigen::Vector3f& p) {
  const Eigen::Vector3d q = p.cast<double>() * 1e5;
  return {std::lround(q.x()), std::lround(q.y()), std::lround(q.z())};
}

// Closed and consistently wound: every directed edge appears once and its reverse once.
int countBadEdges(const TriangleMesh& mesh) {
  std::map<std::pair<PositionKey, PositionKey>, int> directed;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const auto a = keyOf(mesh.vertices[mesh.indices[t + static_cast<std::size_t>(e)]]);
      const auto b = keyOf(mesh.vertices[mesh.indices[t + static_cast<std::size_t>((e + 1) % 3)]]);
      ++directed[{a, b}];
    }
  }
  int bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad;
  }
  return bad;
}

// Generalised winding number of a closed surface around p (Van Oosterom-Strackee solid angles):
// for a union of overlapping closed components it counts the components that contain p.
double windingNumber(const std::vector<Eigen::Vector3d>& triangles_W, const Eigen::Vector3d& p) {
  double total = 0.0;
  for (std::size_t t = 0; t + 2 < triangles_W.size(); t += 3) {
    const Eigen::Vector3d a = triangles_W[t] - p, b = triangles_W[t + 1] - p, c = triangles_W[t + 2] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * std::numbers::pi);
}

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double s = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (p - (a + s * ab)).norm();
}

Eigen::VectorXd randomPosture(const RobotModel& model, std::mt19937& rng) {
  Eigen::VectorXd q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    std::uniform_real_distribution<double> uniform(model.softLowerLimits()[i], model.softUpperLimits()[i]);
    q[i] = uniform(rng);
  }
  return q;
}

TEST(GeneratedLwrMeshes, AreClosedOutwardFacingAndWithinTriangleBudgets) {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kMeshDir)) {
    if (entry.path().extension() != ".stl") continue;
    ++files;
    SCOPED_TRACE(entry.path().filename().string());
    const TriangleMesh mesh = loadMesh(entry.path());
    ASSERT_FALSE(mesh.empty());
    EXPECT_EQ(countBadEdges(mesh), 0);
    EXPECT_GT(signedVolume(mesh), 0.0);
    ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
    const bool collision = entry.path().filename().string().find("_collision") != std::string::npos;
    EXPECT_LE(mesh.triangleCount(), collision ? 500U : 5000U);
    // Vertex normals agree with the winding: each face's normal points the way its corners' do.
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      const auto& a = mesh.vertices[mesh.indices[t]];
      const auto& b = mesh.vertices[mesh.indices[t + 1]];
      const auto& c = mesh.vertices[mesh.indices[t + 2]];
      const Eigen::Vector3f face = (b - a).cross(c - a);
      const Eigen::Vector3f corners =
          mesh.normals[mesh.indices[t]] + mesh.normals[mesh.indices[t + 1]] + mesh.normals[mesh.indices[t + 2]];
      ASSERT_GT(face.dot(corners), 0.0F) << "triangle " << t / 3;
    }
  }
  // 8 bodies x (shell, collision), 7 rings, the flange.
  EXPECT_EQ(files, 8 * 2 + 7 + 1);
}

TEST(GeneratedLwrMeshes, FlangeIsAMetreScaleDiscOfTheIsoFlangeSize) {
  const TriangleMesh flange = loadMesh(kMeshDir / "flange.stl");
  const Eigen::AlignedBox3f box = flange.bounds();
  // ISO 9409-1-A50: 63 mm diameter; the mounting face is the flange frame's z = 0.
  EXPECT_NEAR(box.max().x(), 0.0315, 1e-4);
  EXPECT_NEAR(box.max().z(), 0.0, 1e-6);
  // Volume of a disc of radius 31.5 mm and 8 mm thickness, up to the rounded rim and the
  // 64-gon (about 1 %).
  const double disc = std::numbers::pi * 0.0315 * 0.0315 * 0.008;
  EXPECT_NEAR(signedVolume(flange) / disc, 1.0, 0.02);
}

// The visual meshes of one body in the world: triangle corners (3 per triangle) and vertices.
struct PosedBody {
  std::vector<Eigen::Vector3d> corners;
  std::vector<Eigen::Vector3d> vertices;
};

std::vector<PosedBody> posedVisuals(const RobotModel& model, const Kinematics& kinematics) {
  std::vector<PosedBody> bodies;
  for (int b = 0; b <= model.dof(); ++b) {
    PosedBody body;
    for (const Geometry& visual : model.bodies()[static_cast<std::size_t>(b)].visuals) {
      if (visual.kind != Geometry::Kind::kMesh) continue;
      const auto mesh = loadMeshCached(visual.mesh_file);
      const Eigen::Isometry3d X_WG = kinematics.X_WB(b) * visual.X_BG;
      auto pose = [&](const Eigen::Vector3f& p_G) { return Eigen::Vector3d(X_WG * p_G.cast<double>().cwiseProduct(visual.mesh_scale)); };
      for (const auto index : mesh->indices) body.corners.push_back(pose(mesh->vertices[index]));
      for (const auto& v : mesh->vertices) body.vertices.push_back(pose(v));
    }
    bodies.push_back(std::move(body));
  }
  return bodies;
}

// The arm's centre line: the distinct joint centres from the mount to the flange.
std::vector<Eigen::Vector3d> centreLine(const RobotModel& model, const Kinematics& kinematics) {
  std::vector<Eigen::Vector3d> points;
  for (int b = 1; b <= model.dof(); ++b) points.push_back(kinematics.X_WB(b).translation());
  points.push_back(kinematics.X_WT().translation());
  points.erase(std::unique(points.begin(), points.end(),
                           [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).norm() < 1e-9; }),
               points.end());
  return points;
}

void expectArmJoinsUp(const RobotModel& model, const Eigen::VectorXd& q) {
  Kinematics kinematics(model);
  kinematics.update(q);
  const auto bodies = posedVisuals(model, kinematics);
  const auto line = centreLine(model, kinematics);
  // Mount, shoulder, elbow(s), wrist, flange: one bone more than the transverse joints.
  ASSERT_EQ(static_cast<int>(line.size()), (model.dof() + 3) / 2);

  // Every body hugs its own bone: bodies 2k and 2k+1 share bone k (between the transverse
  // joints), body 1 is the bone from the mount to the shoulder. A link built along the wrong
  // axis or direction lies a whole segment away from it.
  for (int b = 1; b <= model.dof(); ++b) {
    const auto bone = static_cast<std::size_t>(b / 2);
    double worst = 0.0;
    for (const auto& p : bodies[static_cast<std::size_t>(b)].vertices) {
      worst = std::max(worst, distanceToSegment(p, line[bone], line[bone + 1]));
    }
    EXPECT_LT(worst, 0.095) << "body " << b << " strays from its bone";
    EXPECT_FALSE(bodies[static_cast<std::size_t>(b)].vertices.empty());
  }
  // The base stands on the mounting plane around A1.
  for (const auto& p : bodies[0].vertices) {
    EXPECT_LT(p.head<2>().norm(), 0.09);
    EXPECT_GE(p.z(), -1e-6);
  }

  // No gap anywhere: every point of the centre line, from the mount to the flange, lies inside
  // the union of the visual meshes (sampled every 5 mm) of the bodies around that bone.
  for (std::size_t k = 0; k + 1 < line.size(); ++k) {
    std::vector<Eigen::Vector3d> near;
    const int first = std::max(0, 2 * static_cast<int>(k) - 1);
    const int last = std::min(model.dof(), 2 * static_cast<int>(k) + 2);
    for (int b = first; b <= last; ++b) {
      const auto& corners = bodies[static_cast<std::size_t>(b)].corners;
      near.insert(near.end(), corners.begin(), corners.end());
    }
    const double length = (line[k + 1] - line[k]).norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(length / 0.005)));
    for (int s = 0; s <= steps; ++s) {
      const Eigen::Vector3d p = line[k] + (line[k + 1] - line[k]) * (static_cast<double>(s) / steps);
      // The mount and the flange face lie on the surface itself; test just inside.
      const Eigen::Vector3d inside = p + (k == 0 && s == 0 ? 0.001 : 0.0) * Eigen::Vector3d::UnitZ() -
                                     (k + 2 == line.size() && s == steps ? 0.001 : 0.0) * (line[k + 1] - line[k]).normalized();
      ASSERT_GT(windingNumber(near, inside), 0.5) << "gap on bone " << k << " at " << p.transpose();
    }
  }

  // Adjacent bodies touch at their joint: some vertex pair within 1 cm.
  for (int b = 0; b < model.dof(); ++b) {
    double nearest = 1e9;
    for (const auto& p : bodies[static_cast<std::size_t>(b)].vertices) {
      for (const auto& c : bodies[static_cast<std::size_t>(b + 1)].vertices) nearest = std::min(nearest, (p - c).squaredNorm());
    }
    EXPECT_LT(std::sqrt(nearest), 0.01) << "bodies " << b << " and " << b + 1 << " do not meet";
  }
}

TEST(GeneratedLwrMeshes, LinksJoinUpAtEveryJointStraightUpAndInRandomPostures) {
  for (const std::string robot : {"lwr4", "arm9"}) {
    SCOPED_TRACE(robot);
    const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath(robot));
    std::mt19937 rng(7);
    expectArmJoinsUp(model, Eigen::VectorXd::Zero(model.dof()));
    for (int trial = 0; trial < 4; ++trial) {
      const Eigen::VectorXd q = randomPosture(model, rng);
      SCOPED_TRACE(::testing::Message() << "q = " << q.transpose());
      expectArmJoinsUp(model, q);
    }
  }
}

TEST(GeneratedLwrMeshes, StraightUpArmSpansMountToFlangeOnTheVerticalAxis) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  Kinematics kinematics(model);
  kinematics.update(Eigen::VectorXd::Zero(model.dof()));
  Eigen::AlignedBox3d box;
  for (const auto& body : posedVisuals(model, kinematics)) {
    for (const auto& p : body.vertices) box.extend(p);
  }
  EXPECT_NEAR(box.min().z(), 0.0, 1e-6);
  EXPECT_NEAR(box.max().z(), 0.3105 + 0.4 + 0.39 + 0.078, 1e-6);
  EXPECT_LT(box.max().head<2>().norm(), 0.13);  // nothing sticks out sideways (base 0.086 m)
}

// ---- Loader behaviour -----------------------------------------------------------------------

fs::path scratchDir() {
  const fs::path dir = fs::temp_directory_path() / ("flexirob_mesh_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

void expectOneLineInputError(const std::function<void()>& action, const std::string& fragment) {
  try {
    action();
    ADD_FAILURE() << "expected InputError containing '" << fragment << "'";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(MeshLoader, RefusesMissingEmptyAndGarbageFiles) {
  const fs::path dir = scratchDir();
  expectOneLineInputError([&] { loadMesh(dir / "nope.stl"); }, "not found");
  std::ofstream(dir / "empty.obj").close();
  expectOneLineInputError([&] { loadMesh(dir / "empty.obj"); }, "empty");
  std::ofstream(dir / "garbage.dae") << "<COLLADA><this is not";
  expectOneLineInputError([&] { loadMesh(dir / "garbage.dae"); }, "garbage.dae");
  std::ofstream(dir / "noise.stl", std::ios::binary) << std::string(300, '\x7f');
  expectOneLineInputError([&] { loadMesh(dir / "noise.stl"); }, "truncated or corrupt");
  // Text that is no ASCII STL, long and short, is called what it is, not a truncated binary.
  std::ofstream(dir / "readme.stl") << "This folder holds the gripper meshes; export them as binary STL in metres.\n"
                                    << std::string(100, '-') << "\n";
  expectOneLineInputError([&] { loadMesh(dir / "readme.stl"); }, "text but not an ASCII STL");
  std::ofstream(dir / "short.stl") << "v 0 0 0\n";
  expectOneLineInputError([&] { loadMesh(dir / "short.stl"); }, "text but not an ASCII STL");
  // An ASCII STL without a facet, short and long: no triangles, said so.
  std::ofstream(dir / "hollow.stl") << "solid x\nendsolid x\n";
  expectOneLineInputError([&] { loadMesh(dir / "hollow.stl"); }, "contains no triangles (an ASCII STL without a facet)");
  std::ofstream(dir / "hollow_long.stl") << "solid facets_removed\n" << std::string(200000, ' ') << "\nendsolid\n";
  expectOneLineInputError([&] { loadMesh(dir / "hollow_long.stl"); }, "contains no triangles");
  fs::remove_all(dir);
}

TEST(MeshLoader, RefusesTruncatedBinaryStlBeforeReadingIt) {
  const fs::path dir = scratchDir();
  const fs::path source = kMeshDir / "link3_collision.stl";
  std::string bytes(static_cast<std::size_t>(fs::file_size(source)), '\0');
  std::ifstream(source, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::ofstream(dir / "cut.stl", std::ios::binary) << bytes.substr(0, bytes.size() - 30);
  expectOneLineInputError([&] { loadMesh(dir / "cut.stl"); }, "truncated");
  // A header that declares a billion triangles in a small file is caught the same way.
  bytes[80] = bytes[81] = bytes[82] = '\0';
  bytes[83] = '\x40';
  std::ofstream(dir / "huge_count.stl", std::ios::binary) << bytes;
  expectOneLineInputError([&] { loadMesh(dir / "huge_count.stl"); }, "truncated or corrupt");
  fs::remove_all(dir);
}

TEST(MeshLoader, EnforcesFileSizeAndVertexLimits) {
  expectOneLineInputError([&] { loadMesh(kMeshDir / "link2_shell.stl", MeshLimits{1000, 10'000'000}); }, "larger than");
  expectOneLineInputError([&] { loadMesh(kMeshDir / "link2_shell.stl", MeshLimits{256ULL << 20, 300}); }, "limit");
  // Non-STL formats are counted after import, with every node instance included.
  const fs::path dir = scratchDir();
  {
    std::ofstream obj(dir / "quad.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
  }
  EXPECT_EQ(loadMesh(dir / "quad.obj").triangleCount(), 2U);
  expectOneLineInputError([&] { loadMesh(dir / "quad.obj", MeshLimits{256ULL << 20, 3}); }, "more than the limit");
  fs::remove_all(dir);
}

TEST(MeshLoader, RefusesHeadersThatDeclareAbsurdCountsWithoutAllocating) {
  const fs::path dir = scratchDir();
  {
    std::ofstream ply(dir / "huge.ply", std::ios::binary);
    ply << "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\nproperty float x\n"
           "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
           "end_header\n"
        << std::string(64, '\0');
  }
  expectOneLineInputError([&] { loadMesh(dir / "huge.ply"); }, "declares 3000000000 vertex elements");
  // A COLLADA array that claims more values than it holds is refused by the parser.
  std::string dae = "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" "
                    "version=\"1.4.1\"><library_geometries><geometry id=\"g\"><mesh><source id=\"p\">"
                    "<float_array id=\"a\" count=\"3000000000\">0 0 0 1 0 0 0 1 0</float_array></source>"
                    "</mesh></geometry></library_geometries></COLLADA>";
  std::ofstream(dir / "huge.dae") << dae;
  expectOneLineInputError([&] { loadMesh(dir / "huge.dae"); }, "huge.dae");
  fs::remove_all(dir);
}

// One triangle copied 30 000 times: assimp's joining of identical vertices compares every
// copy with every other (minutes for 10^5 copies, hours for 10^6); refused at once, by name.
TEST(MeshLoader, RefusesAFileOfOneFaceCopiedOverAndOverWithoutJoiningIt) {
  const fs::path dir = scratchDir();
  {
    std::ofstream stl(dir / "copies.stl", std::ios::binary);
    stl << std::string(80, '\0');
    const std::uint32_t count = 30000;
    stl.write(reinterpret_cast<const char*>(&count), 4);
    const float facet[12] = {0, 0, 1, 0, 0, 0, 0.01F, 0, 0, 0, 0.01F, 0};
    for (std::uint32_t t = 0; t < count; ++t) {
      stl.write(reinterpret_cast<const char*>(facet), sizeof facet);
      stl.write("\0\0", 2);
    }
  }
  expectOneLineInputError([&] { loadMesh(dir / "copies.stl"); }, "has 30000 corners at the one point (0, 0, 0)");
  // A face written twice stays a mesh (SCENES.md: it counts once).
  {
    std::ofstream obj(dir / "twice.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\nf 3 1 4\n";
  }
  EXPECT_EQ(loadMesh(dir / "twice.obj").triangleCount(), 5U);
  fs::remove_all(dir);
}

TEST(MeshLoader, CachesByPathUntilTheFileChanges) {
  clearMeshCache();
  const fs::path dir = scratchDir();
  fs::copy_file(kMeshDir / "flange.stl", dir / "part.stl");
  const auto first = loadMeshCached(dir / "part.stl");
  const auto again = loadMeshCached(dir / "sub" / ".." / "part.stl");
  EXPECT_EQ(first.get(), again.get());
  fs::copy_file(kMeshDir / "link7_collision.stl", dir / "part.stl", fs::copy_options::overwrite_existing);
  fs::last_write_time(dir / "part.stl", fs::last_write_time(dir / "part.stl") + std::chrono::seconds(5));
  const auto changed = loadMeshCached(dir / "part.stl");
  EXPECT_NE(changed.get(), first.get());
  EXPECT_NE(changed->triangleCount(), first->triangleCount());
  fs::remove_all(dir);
}

TEST(MeshLoader, TransformedMeshScalesThenPosesAndKeepsMirroredMeshesOutward) {
  const TriangleMesh flange = loadMesh(kMeshDir / "flange.stl");
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.1, -0.2, 0.3);
  const Eigen::Vector3d scale(2.0, 3.0, -0.5);  // mirrors
  const TriangleMesh moved = transformedMesh(flange, X, scale);
  ASSERT_EQ(moved.vertices.size(), flange.vertices.size());
  for (std::size_t i = 0; i < flange.vertices.size(); i += 37) {
    const Eigen::Vector3d expected = X * flange.vertices[i].cast<double>().cwiseProduct(scale);
    EXPECT_LT((moved.vertices[i].cast<double>() - expected).norm(), 1e-6);
    EXPECT_NEAR(moved.normals[i].norm(), 1.0F, 1e-5F);
  }
  // Volume scales by |det| and stays positive (outward) despite the mirror.
  EXPECT_NEAR(signedVolume(moved) / signedVolume(flange), 3.0, 1e-3);
  EXPECT_EQ(countBadEdges(moved), 0);
}

}  // namespace
}  // namespace flexirob::robot
