#pragma once
// A triangle mesh read as a solid: which points lie inside it, and how far a point is from its
// surface. Evaluations and the simulated tutor ask this of mesh obstacles for every grid point
// (robot/scene.hpp, obstacleContains); the simulator's collision engine does not need it.
//
// "Inside" is decided by the generalized winding number w(p) (Jacobson et al. 2013, "Robust
// inside-outside segmentation using generalized winding numbers"): the solid angle the surface
// subtends at p over 4π. For a closed surface it is 1 inside and 0 outside, without the edge
// and vertex cases of ray casting; for a surface with small holes or gaps it varies smoothly and
// still reads about 1 deep inside and about 0 far outside. A point counts as inside when
// w(p) ≥ 0.5, or when it lies on the surface (within 1e-9 m).
//
// The winding number needs triangles that face one way. Meshes exported with mixed winding are
// common, so the constructor turns the triangles of each connected piece to agree with their
// neighbours, and each piece to face outwards (positive enclosed volume). A sealed cavity is
// therefore counted as inside: a robot cannot get there anyway.
//
// A mesh of more than kMaxSolidTriangles triangles (a scan, a finely tessellated CAD export) is
// simplified first by vertex clustering: vertices within one cell of a grid merge into their
// mean, triangles that collapse go. The cell grows from 2 mm until the count fits, up to 1 cm;
// the surface then moves at most a cell's diagonal (deviation()). The collision model uses the
// same triangles (robot/collision.cpp), so that each test and each clearance query of the tutor
// costs what a modest mesh costs, and the two agree on where the surface is.
//
// Units: metres, in the mesh's own frame (an obstacle's frame O) after scaling.
#include <Eigen/Geometry>
#include <array>
#include <filesystem>
#include <memory>
#include <vector>

#include "robot/mesh.hpp"

namespace flexirob::robot {

/// More triangles than this are simplified (see above).
inline constexpr std::size_t kMaxSolidTriangles = 5000;

class MeshSolid {
 public:
  /// The solid bounded by `mesh` scaled per axis by `scale` (> 0, as a scene's mesh `scale`),
  /// simplified when it has more than `max_triangles` triangles.
  explicit MeshSolid(const TriangleMesh& mesh, const Eigen::Vector3d& scale = Eigen::Vector3d::Ones(),
                     std::size_t max_triangles = kMaxSolidTriangles);

  /// Generalized winding number at p [m, mesh frame]: 1 inside a closed surface, 0 outside.
  double windingNumber(const Eigen::Vector3d& p) const;
  /// Distance [m] from p to the nearest point of the surface (not signed).
  double distanceToSurface(const Eigen::Vector3d& p) const;
  /// True if p lies inside, on the surface, or within `margin` [m] of the surface.
  bool contains(const Eigen::Vector3d& p, double margin = 0.0) const;

  /// Bounds of the scaled vertices.
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }
  std::size_t triangleCount() const { return triangles_.size(); }
  /// The scale it was built with.
  const Eigen::Vector3d& scale() const { return scale_; }
  /// The triangles, facing outwards [m, mesh frame after scaling].
  const std::vector<std::array<Eigen::Vector3d, 3>>& triangles() const { return triangles_; }
  /// Triangles of the mesh it was built from (after dropping degenerate ones).
  std::size_t sourceTriangleCount() const { return source_triangles_; }
  /// How far the simplification may have moved the surface [m]; 0 when it kept the mesh.
  double deviation() const { return deviation_; }

 private:
  std::vector<std::array<Eigen::Vector3d, 3>> triangles_;  ///< consistently facing outwards
  Eigen::AlignedBox3d bounds_;
  Eigen::Vector3d scale_;
  std::size_t source_triangles_ = 0;
  double deviation_ = 0.0;
};

/// The solid of a mesh file at a scale, built once per unchanged file (loadMeshCached's rule)
/// and scale, and shared. Thread-safe. Throws InputError as loadMesh.
std::shared_ptr<const MeshSolid> loadMeshSolidCached(const std::filesystem::path& file, const Eigen::Vector3d& scale);

}  // namespace flexirob::robot
