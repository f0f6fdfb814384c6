// Meshes read as solids (robot/mesh_solid.hpp): the generalized winding number, the inside
// test and the distance to the surface, against boxes and prisms whose answers are known.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "robot/mesh.hpp"
#include "robot/mesh_solid.hpp"

namespace flexirob::robot {
namespace {

namespace fs = std::filesystem;

// A closed right prism over a counter-clockwise polygon (seen from +z) between z = 0 and
// z = height, every triangle counter-clockwise seen from outside. The caps are fans from the
// first corner, so the polygon must be star-shaped around it.
TriangleMesh prism(const std::vector<Eigen::Vector2f>& polygon, float height) {
  TriangleMesh mesh;
  const auto n = static_cast<std::uint32_t>(polygon.size());
  for (const auto& p : polygon) mesh.vertices.emplace_back(p.x(), p.y(), 0.0F);
  for (const auto& p : polygon) mesh.vertices.emplace_back(p.x(), p.y(), height);
  mesh.normals.assign(mesh.vertices.size(), Eigen::Vector3f::UnitZ());
  for (std::uint32_t i = 1; i + 1 < n; ++i) {
    mesh.indices.insert(mesh.indices.end(), {0, i + 1, i});          // bottom, facing -z
    mesh.indices.insert(mesh.indices.end(), {n, n + i, n + i + 1});  // top, facing +z
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    mesh.indices.insert(mesh.indices.end(), {i, j, n + j});
    mesh.indices.insert(mesh.indices.end(), {i, n + j, n + i});
  }
  return mesh;
}

// The unit cube [0, 1]^3.
TriangleMesh unitCube() { return prism({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, 1.0F); }

// An L: the square [0, 2] x [0, 2] without its notch [1, 2] x [1, 2], 1 high.
TriangleMesh lShape() { return prism({{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}, 1.0F); }

TEST(MeshSolid, UnitCubeWindsOnceAroundItsInsideAndNotAroundItsOutside) {
  const MeshSolid cube(unitCube());
  EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(0.5, 0.5, 0.5)), 1.0, 1e-12);
  EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(0.01, 0.99, 0.02)), 1.0, 1e-9);
  EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(1.5, 0.5, 0.5)), 0.0, 1e-12);
  EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(-3.0, 7.0, 0.5)), 0.0, 1e-12);
  EXPECT_TRUE(cube.contains(Eigen::Vector3d(0.5, 0.5, 0.5)));
  EXPECT_TRUE(cube.contains(Eigen::Vector3d(0.999, 0.001, 0.999)));
  // Just outside each face, and beyond an edge and a corner (where a ray would graze).
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(1.001, 0.5, 0.5), Eigen::Vector3d(-0.001, 0.5, 0.5),
                                   Eigen::Vector3d(0.5, 1.001, 0.5), Eigen::Vector3d(0.5, -0.001, 0.5),
                                   Eigen::Vector3d(0.5, 0.5, 1.001), Eigen::Vector3d(0.5, 0.5, -0.001),
                                   Eigen::Vector3d(1.001, 1.001, 0.5), Eigen::Vector3d(1.001, 1.001, 1.001)}) {
    EXPECT_FALSE(cube.contains(p)) << p.transpose();
  }
}

TEST(MeshSolid, DistanceToTheSurfaceIsThatToTheNearestFaceEdgeOrCorner) {
  const MeshSolid cube(unitCube());
  EXPECT_NEAR(cube.distanceToSurface(Eigen::Vector3d(1.5, 0.5, 0.5)), 0.5, 1e-12);           // face
  EXPECT_NEAR(cube.distanceToSurface(Eigen::Vector3d(1.3, 1.4, 0.5)), 0.5, 1e-12);           // edge
  EXPECT_NEAR(cube.distanceToSurface(Eigen::Vector3d(-0.2, -0.3, 1.6)), std::sqrt(0.49), 1e-12);  // corner
  EXPECT_NEAR(cube.distanceToSurface(Eigen::Vector3d(0.5, 0.5, 0.4)), 0.4, 1e-12);           // inside
}

TEST(MeshSolid, CountsTheSurfaceAndPointsWithinTheMarginAsInside) {
  const MeshSolid cube(unitCube());
  EXPECT_TRUE(cube.contains(Eigen::Vector3d(1.0, 0.5, 0.5)));  // on a face
  EXPECT_TRUE(cube.contains(Eigen::Vector3d(1.0, 1.0, 1.0)));  // on a corner
  const Eigen::Vector3d beside(1.05, 0.5, 0.5);
  EXPECT_FALSE(cube.contains(beside, 0.04));
  EXPECT_TRUE(cube.contains(beside, 0.06));
  const Eigen::Vector3d beyond_edge(1.03, 1.04, 0.5);  // 0.05 m from the edge
  EXPECT_FALSE(cube.contains(beyond_edge, 0.049));
  EXPECT_TRUE(cube.contains(beyond_edge, 0.051));
}

TEST(MeshSolid, LShapeLeavesItsNotchOutside) {
  const MeshSolid l_shape(lShape());
  EXPECT_TRUE(l_shape.contains(Eigen::Vector3d(0.5, 0.5, 0.5)));
  EXPECT_TRUE(l_shape.contains(Eigen::Vector3d(1.5, 0.5, 0.5)));
  EXPECT_TRUE(l_shape.contains(Eigen::Vector3d(0.5, 1.5, 0.5)));
  EXPECT_TRUE(l_shape.contains(Eigen::Vector3d(0.99, 0.99, 0.5)));  // at the inner corner
  const Eigen::Vector3d notch(1.5, 1.5, 0.5);  // inside the bounding box, outside the L
  EXPECT_NEAR(l_shape.windingNumber(notch), 0.0, 1e-12);
  EXPECT_FALSE(l_shape.contains(notch));
  EXPECT_FALSE(l_shape.contains(Eigen::Vector3d(1.01, 1.01, 0.5)));
  EXPECT_NEAR(l_shape.distanceToSurface(notch), 0.5, 1e-12);
  EXPECT_FALSE(l_shape.contains(notch, 0.49));
  EXPECT_TRUE(l_shape.contains(notch, 0.51));
}

TEST(MeshSolid, TurnsTrianglesOutwardsWhateverWayTheFileWindsThem) {
  TriangleMesh inward = unitCube();
  for (std::size_t t = 0; t < inward.indices.size(); t += 3) std::swap(inward.indices[t + 1], inward.indices[t + 2]);
  TriangleMesh mixed = unitCube();
  for (std::size_t t = 0; t < mixed.indices.size(); t += 6) std::swap(mixed.indices[t + 1], mixed.indices[t + 2]);
  for (const TriangleMesh& mesh : {inward, mixed}) {
    const MeshSolid cube(mesh);
    EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(0.5, 0.5, 0.5)), 1.0, 1e-12);
    EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(0.2, 0.9, 0.3)), 1.0, 1e-12);
    EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(1.5, 0.5, 0.5)), 0.0, 1e-12);
  }
}

// A closed box [lower, upper] appended to `mesh`, wound outwards or (inward) the other way.
void appendBox(TriangleMesh& mesh, const Eigen::Vector3f& lower, const Eigen::Vector3f& upper, bool inward = false) {
  const Eigen::Vector3f size = upper - lower;
  TriangleMesh box = prism({{0, 0}, {size.x(), 0}, {size.x(), size.y()}, {0, size.y()}}, size.z());
  const auto offset = static_cast<std::uint32_t>(mesh.vertices.size());
  for (const Eigen::Vector3f& v : box.vertices) mesh.vertices.push_back(v + lower);
  mesh.normals.insert(mesh.normals.end(), box.normals.begin(), box.normals.end());
  for (std::size_t t = 0; t < box.indices.size(); t += 3) {
    mesh.indices.push_back(offset + box.indices[t]);
    mesh.indices.push_back(offset + box.indices[t + (inward ? 2 : 1)]);
    mesh.indices.push_back(offset + box.indices[t + (inward ? 1 : 2)]);
  }
}

// A CAD export of a fixture: a plate and two walls, each a closed box, the walls standing flush
// on the plate's edges. Four faces meet at each such edge; turning the triangles to agree across
// it had turned a whole wall inside out, and its inside read as outside.
TEST(MeshSolid, PartsThatTouchAlongAnEdgeAreEachInside) {
  for (const bool second_wall_inward : {false, true}) {
    TriangleMesh fixture;
    appendBox(fixture, {0.0F, 0.0F, 0.0F}, {0.3F, 0.3F, 0.02F});
    appendBox(fixture, {0.0F, 0.0F, 0.02F}, {0.3F, 0.03F, 0.27F});
    appendBox(fixture, {0.0F, 0.27F, 0.02F}, {0.3F, 0.3F, 0.27F}, second_wall_inward);
    const MeshSolid solid(fixture);
    for (const Eigen::Vector3d& inside : {Eigen::Vector3d(0.15, 0.15, 0.01), Eigen::Vector3d(0.15, 0.015, 0.15),
                                          Eigen::Vector3d(0.15, 0.285, 0.15), Eigen::Vector3d(0.29, 0.29, 0.01)}) {
      EXPECT_NEAR(solid.windingNumber(inside), 1.0, 1e-9) << inside.transpose() << (second_wall_inward ? " (wall wound inwards)" : "");
      EXPECT_TRUE(solid.contains(inside)) << inside.transpose();
    }
    for (const Eigen::Vector3d& outside : {Eigen::Vector3d(0.15, 0.15, 0.15), Eigen::Vector3d(0.15, -0.05, 0.15),
                                           Eigen::Vector3d(0.15, 0.35, 0.15), Eigen::Vector3d(0.15, 0.15, -0.05)}) {
      EXPECT_NEAR(solid.windingNumber(outside), 0.0, 1e-9) << outside.transpose();
      EXPECT_FALSE(solid.contains(outside)) << outside.transpose();
    }
  }
}

// `mesh` turned by `rotation` about the origin (vertices in float, as a file holds them).
TriangleMesh rotated(TriangleMesh mesh, const Eigen::Matrix3d& rotation) {
  for (Eigen::Vector3f& v : mesh.vertices) v = (rotation * v.cast<double>()).cast<float>();
  return mesh;
}

Eigen::Matrix3d someRotation() {
  return (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())).toRotationMatrix();
}

// Whether `solid` holds exactly the points of `inside` and none of `outside`, each turned by
// `rotation`; winding numbers to 1e-5 (float corners).
void expectHolds(const MeshSolid& solid, const Eigen::Matrix3d& rotation, const std::vector<Eigen::Vector3d>& inside,
                 const std::vector<Eigen::Vector3d>& outside, double inside_winding, const std::string& what) {
  for (const Eigen::Vector3d& p : inside) {
    EXPECT_NEAR(solid.windingNumber(rotation * p), inside_winding, 1e-5) << what << " at " << p.transpose();
    EXPECT_TRUE(solid.contains(rotation * p)) << what << " at " << p.transpose();
  }
  for (const Eigen::Vector3d& p : outside) {
    EXPECT_NEAR(solid.windingNumber(rotation * p), 0.0, 1e-5) << what << " at " << p.transpose();
    EXPECT_FALSE(solid.contains(rotation * p)) << what << " at " << p.transpose();
  }
}

// A "two-sided" export writes every face twice, once each way round: no edge joins just two
// triangles. Its inside is still inside, however the mesh lies in space.
TEST(MeshSolid, ATwoSidedExportHoldsItsInsideHoweverItIsTurned) {
  TriangleMesh two_sided = unitCube();
  const std::size_t count = two_sided.indices.size();
  for (std::size_t t = 0; t < count; t += 3) {
    two_sided.indices.insert(two_sided.indices.end(), {two_sided.indices[t], two_sided.indices[t + 2], two_sided.indices[t + 1]});
  }
  for (const Eigen::Matrix3d& rotation : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), someRotation()}) {
    const MeshSolid solid(rotated(two_sided, rotation));
    // A face written twice counts once.
    expectHolds(solid, rotation, {{0.5, 0.5, 0.5}, {0.1, 0.9, 0.2}}, {{1.5, 0.5, 0.5}, {0.5, -0.3, 0.5}}, 1.0, "two-sided cube");
  }
}

// Parts exported as closed bodies of their own that share a face (a block standing on another,
// the shared face written once per part), and parts touching along an edge, turned in space.
TEST(MeshSolid, PartsSharingAFaceOrAnEdgeAreInsideHoweverTheyAreTurned) {
  TriangleMesh stacked;
  appendBox(stacked, {0.0F, 0.0F, 0.0F}, {1.0F, 1.0F, 0.5F});
  appendBox(stacked, {0.0F, 0.0F, 0.5F}, {1.0F, 1.0F, 1.0F});
  TriangleMesh fixture;
  appendBox(fixture, {0.0F, 0.0F, 0.0F}, {0.3F, 0.3F, 0.02F});
  appendBox(fixture, {0.0F, 0.0F, 0.02F}, {0.3F, 0.03F, 0.27F});
  appendBox(fixture, {0.0F, 0.27F, 0.02F}, {0.3F, 0.3F, 0.27F}, true);
  for (const Eigen::Matrix3d& rotation : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), someRotation()}) {
    expectHolds(MeshSolid(rotated(stacked, rotation)), rotation, {{0.5, 0.5, 0.25}, {0.5, 0.5, 0.45}, {0.5, 0.5, 0.55}, {0.2, 0.8, 0.9}},
                {{0.5, 0.5, 1.2}, {1.3, 0.5, 0.5}, {0.5, 0.5, -0.2}}, 1.0, "stacked blocks");
    expectHolds(MeshSolid(rotated(fixture, rotation)), rotation, {{0.15, 0.15, 0.01}, {0.15, 0.015, 0.15}, {0.15, 0.285, 0.15}},
                {{0.15, 0.15, 0.15}, {0.15, -0.05, 0.15}, {0.15, 0.35, 0.15}}, 1.0, "fixture");
  }
}

TEST(MeshSolid, WeldsCornersThatTheLoaderKeptApartPerFace) {
  // One vertex per triangle corner, as the loader leaves a box with flat faces; the second
  // face winds the other way, so only welding lets the triangles agree.
  const TriangleMesh shared = unitCube();
  TriangleMesh split;
  for (std::size_t t = 0; t < shared.indices.size(); ++t) {
    split.vertices.push_back(shared.vertices[shared.indices[t]]);
    split.indices.push_back(static_cast<std::uint32_t>(t));
  }
  split.normals.assign(split.vertices.size(), Eigen::Vector3f::UnitZ());
  std::swap(split.indices[4], split.indices[5]);
  const MeshSolid cube(split);
  EXPECT_EQ(cube.triangleCount(), 12U);
  EXPECT_NEAR(cube.windingNumber(Eigen::Vector3d(0.5, 0.5, 0.5)), 1.0, 1e-12);
}

TEST(MeshSolid, ScalesEachAxisBeforeTesting) {
  const MeshSolid box(unitCube(), Eigen::Vector3d(2.0, 0.5, 3.0));
  EXPECT_TRUE(box.contains(Eigen::Vector3d(1.9, 0.45, 2.9)));
  EXPECT_FALSE(box.contains(Eigen::Vector3d(1.9, 0.55, 1.0)));
  EXPECT_FALSE(box.contains(Eigen::Vector3d(2.1, 0.25, 1.0)));
  EXPECT_NEAR(box.distanceToSurface(Eigen::Vector3d(1.0, 0.25, 4.0)), 1.0, 1e-12);
  EXPECT_TRUE(box.bounds().isApprox(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(2.0, 0.5, 3.0))));
}

TEST(MeshSolid, OpenBoxHoldsWhatItMostlySurroundsAndASheetHoldsNothing) {
  // The cube without its top (the two triangles facing +z): at the centre five of six faces
  // surround the point, each a sixth of the full solid angle.
  TriangleMesh open = unitCube();
  for (std::size_t t = 0; t < open.indices.size(); t += 3) {
    const bool top = open.vertices[open.indices[t]].z() == 1.0F && open.vertices[open.indices[t + 1]].z() == 1.0F &&
                     open.vertices[open.indices[t + 2]].z() == 1.0F;
    if (top) {
      open.indices.erase(open.indices.begin() + static_cast<std::ptrdiff_t>(t), open.indices.begin() + static_cast<std::ptrdiff_t>(t + 3));
      t -= 3;
    }
  }
  ASSERT_EQ(open.triangleCount(), 10U);
  const MeshSolid box(open);
  EXPECT_NEAR(box.windingNumber(Eigen::Vector3d(0.5, 0.5, 0.5)), 5.0 / 6.0, 1e-12);
  EXPECT_TRUE(box.contains(Eigen::Vector3d(0.5, 0.5, 0.5)));
  EXPECT_TRUE(box.contains(Eigen::Vector3d(0.5, 0.5, 0.1)));
  // The opening reads about as if it were closed: just below it the walls still surround more
  // than half the view, just above it less.
  EXPECT_TRUE(box.contains(Eigen::Vector3d(0.5, 0.5, 0.99)));
  EXPECT_FALSE(box.contains(Eigen::Vector3d(0.5, 0.5, 1.01)));
  EXPECT_FALSE(box.contains(Eigen::Vector3d(0.5, 0.5, 1.5)));
  TriangleMesh sheet;
  sheet.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  sheet.normals.assign(4, Eigen::Vector3f::UnitZ());
  sheet.indices = {0, 1, 2, 0, 2, 3};
  const MeshSolid plate(sheet);
  EXPECT_FALSE(plate.contains(Eigen::Vector3d(0.5, 0.5, 0.01)));
  EXPECT_FALSE(plate.contains(Eigen::Vector3d(0.5, 0.5, -0.01)));
  EXPECT_TRUE(plate.contains(Eigen::Vector3d(0.5, 0.5, 0.0)));
  EXPECT_TRUE(plate.contains(Eigen::Vector3d(0.5, 0.5, 0.01), 0.02));
}

// A UV sphere of `radius` about the origin, rings x segments quads (the poles as fans), facing
// outwards: the fine tessellation of a scan or a CAD export.
TriangleMesh uvSphere(double radius, std::uint32_t rings, std::uint32_t segments) {
  TriangleMesh mesh;
  for (std::uint32_t i = 0; i <= rings; ++i) {
    const double polar = std::numbers::pi * i / rings;
    for (std::uint32_t j = 0; j < segments; ++j) {
      const double azimuth = 2.0 * std::numbers::pi * j / segments;
      mesh.vertices.emplace_back(Eigen::Vector3d(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                                                 std::cos(polar)).cast<float>() * static_cast<float>(radius));
    }
  }
  mesh.normals = mesh.vertices;
  const auto at = [segments](std::uint32_t i, std::uint32_t j) { return i * segments + j % segments; };
  for (std::uint32_t i = 0; i < rings; ++i) {
    for (std::uint32_t j = 0; j < segments; ++j) {
      if (i > 0) mesh.indices.insert(mesh.indices.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
      if (i + 1 < rings) mesh.indices.insert(mesh.indices.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return mesh;
}

TEST(MeshSolid, AFinelyTessellatedMeshIsSimplifiedWithinTheDeviationItReports) {
  constexpr double kRadius = 0.1;
  const TriangleMesh fine = uvSphere(kRadius, 200, 200);
  ASSERT_GT(fine.triangleCount(), 30000U);
  const MeshSolid solid(fine);
  EXPECT_EQ(solid.sourceTriangleCount(), fine.triangleCount());
  EXPECT_LE(solid.triangles().size(), kMaxSolidTriangles);
  EXPECT_GT(solid.triangles().size(), kMaxSolidTriangles / 4) << "no coarser than it needs to be";
  ASSERT_GT(solid.deviation(), 0.0);
  EXPECT_LE(solid.deviation(), 0.035);
  // Every corner of the simplified surface lies within the deviation of the true sphere.
  double farthest = 0.0;
  for (const auto& triangle : solid.triangles()) {
    for (const Eigen::Vector3d& corner : triangle) farthest = std::max(farthest, std::abs(corner.norm() - kRadius));
  }
  EXPECT_LE(farthest, solid.deviation());
  // Inside and outside hold beyond the deviation, in every direction.
  for (const Eigen::Vector3d& direction : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 1),
                                           Eigen::Vector3d(1, 1, 1).normalized(), Eigen::Vector3d(-1, 2, -3).normalized()}) {
    EXPECT_TRUE(solid.contains((kRadius - solid.deviation() - 1e-3) * direction)) << direction.transpose();
    EXPECT_FALSE(solid.contains((kRadius + solid.deviation() + 1e-3) * direction)) << direction.transpose();
  }
  EXPECT_TRUE(solid.contains(Eigen::Vector3d::Zero()));
}

TEST(MeshSolid, AModestMeshIsKeptAsItIs) {
  const TriangleMesh coarse = uvSphere(0.1, 20, 20);
  const MeshSolid solid(coarse);
  EXPECT_EQ(solid.triangles().size(), coarse.triangleCount());
  EXPECT_EQ(solid.sourceTriangleCount(), coarse.triangleCount());
  EXPECT_DOUBLE_EQ(solid.deviation(), 0.0);
}

TEST(MeshSolid, IsBuiltOncePerFileAndScale) {
  const fs::path file = fs::temp_directory_path() / ("flexirob_mesh_solid_test_" + std::to_string(::getpid()) + ".obj");
  {
    std::ofstream out(file);
    const TriangleMesh cube = unitCube();
    for (const auto& v : cube.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    for (std::size_t t = 0; t < cube.indices.size(); t += 3) {
      out << "f " << cube.indices[t] + 1 << ' ' << cube.indices[t + 1] + 1 << ' ' << cube.indices[t + 2] + 1 << '\n';
    }
  }
  const auto once = loadMeshSolidCached(file, Eigen::Vector3d::Ones());
  EXPECT_EQ(loadMeshSolidCached(file, Eigen::Vector3d::Ones()), once);
  const auto doubled = loadMeshSolidCached(file, Eigen::Vector3d::Constant(2.0));
  EXPECT_NE(doubled, once);
  EXPECT_TRUE(doubled->contains(Eigen::Vector3d(1.5, 1.5, 1.5)));
  EXPECT_FALSE(once->contains(Eigen::Vector3d(1.5, 1.5, 1.5)));
  fs::remove(file);
}

}  // namespace
}  // namespace flexirob::robot
