#pragma once
// Triangle meshes of robot links and obstacles, loaded from any format assimp reads (STL, DAE,
// OBJ, ...). Used for visuals (render/) and for collision shapes (the Bullet simulation).
//
// Units: metres. A file's own unit is applied (a COLLADA <unit meter="0.001"/> yields metres);
// a URDF <mesh scale> is the caller's to apply (transformedMesh). Coordinates are those of the
// file's root frame with every node transform applied; COLLADA's <up_axis> is not turned into
// assimp's y-up convention, as URDF meshes are authored in the link frame.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

namespace flexirob::robot {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;  ///< [m]
  std::vector<Eigen::Vector3f> normals;   ///< unit vertex normals, one per vertex
  std::vector<std::uint32_t> indices;     ///< 3 per triangle, counter-clockwise seen from outside

  std::size_t triangleCount() const { return indices.size() / 3; }
  bool empty() const { return indices.empty(); }
  /// Axis-aligned bounds of the vertices (empty box for an empty mesh).
  Eigen::AlignedBox3f bounds() const;
};

/// Hard limits checked before and while loading, so that absurd files are refused with an
/// InputError instead of exhausting memory.
struct MeshLimits {
  std::uintmax_t max_file_bytes = 256ULL * 1024 * 1024;
  std::size_t max_vertices = 10'000'000;  ///< after merging all sub-meshes and node instances
};

/// Loads every triangle of a mesh file into one mesh (all sub-meshes merged, node transforms
/// and the file's unit applied; points and lines dropped). Vertex normals come from the file
/// when it has them, else smoothed ones with edges sharper than 60 degrees kept as creases.
/// Throws InputError with a one-line reason for missing, unreadable, truncated, empty or too
/// large files.
TriangleMesh loadMesh(const std::filesystem::path& file, const MeshLimits& limits = {});

/// As loadMesh, but repeated loads of the same unchanged file (same canonical path, size and
/// modification time) share one immutable copy. Thread-safe.
std::shared_ptr<const TriangleMesh> loadMeshCached(const std::filesystem::path& file);

/// Drops every cached mesh (e.g. after regenerating files in tests).
void clearMeshCache();

/// The mesh scaled per axis by `scale` (the URDF <mesh scale>), then posed by X (e.g. a
/// geometry's X_BG): p' = X * (scale .* p). Normals follow; a mirroring scale (odd number of
/// negative factors) reverses the winding so that triangles still face outwards.
TriangleMesh transformedMesh(const TriangleMesh& mesh, const Eigen::Isometry3d& X,
                             const Eigen::Vector3d& scale = Eigen::Vector3d::Ones());

}  // namespace flexirob::robot
