#include "robot/mesh_solid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <utility>

namespace flexirob::robot {
namespace {

// A point this close to the surface lies on it: the winding number jumps there and its value is
// noise, so the boundary is decided by distance, as a box's boundary counts as inside.
constexpr double kOnSurface = 1e-9;  // [m]

using Triangle = std::array<std::uint32_t, 3>;

bool hasDirectedEdge(const Triangle& t, std::uint32_t from, std::uint32_t to) {
  for (int i = 0; i < 3; ++i) {
    if (t[i] == from && t[(i + 1) % 3] == to) return true;
  }
  return false;
}

Triangle flipped(const Triangle& t) { return {t[0], t[2], t[1]}; }

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32U) | std::max(a, b);
}

// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denominator = va + vb + vc;
  if (!(std::abs(denominator) > 0.0)) return a;  // a degenerate sliver: its corner is close enough
  return a + (vb / denominator) * ab + (vc / denominator) * ac;
}

// Vertices merged by `key(index)` into their mean; the triangles that keep three distinct
// corners, each wound way once (clustering folds neighbouring triangles onto each other). Two
// that wind opposite ways stay: a sheet's two faces, or a wall thinner than a cell folded flat,
// cancel in the winding number as before.
template <typename Key>
void weldVertices(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& indices,
                  const Key& key, std::vector<Eigen::Vector3d>& positions, std::vector<Triangle>& triangles) {
  std::map<std::array<std::int64_t, 3>, std::uint32_t> welded_index;
  std::vector<std::uint32_t> weld(points.size());
  std::vector<int> members;
  positions.clear();
  for (std::size_t v = 0; v < points.size(); ++v) {
    const auto [it, inserted] = welded_index.try_emplace(key(v), static_cast<std::uint32_t>(positions.size()));
    if (inserted) {
      positions.push_back(Eigen::Vector3d::Zero());
      members.push_back(0);
    }
    positions[it->second] += points[v];
    ++members[it->second];
    weld[v] = it->second;
  }
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] /= members[i];
  triangles.clear();
  triangles.reserve(indices.size() / 3);
  std::map<std::array<std::uint32_t, 3>, bool> seen;
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const Triangle triangle{weld[indices[t]], weld[indices[t + 1]], weld[indices[t + 2]]};
    if (triangle[0] == triangle[1] || triangle[1] == triangle[2] || triangle[2] == triangle[0]) continue;
    // The same triangle from its smallest corner on, its winding kept.
    const auto first = static_cast<std::size_t>(std::min_element(triangle.begin(), triangle.end()) - triangle.begin());
    const std::array<std::uint32_t, 3> corners{triangle[first], triangle[(first + 1) % 3], triangle[(first + 2) % 3]};
    if (!seen.emplace(corners, true).second) continue;
    triangles.push_back(triangle);
  }
}

}  // namespace

MeshSolid::MeshSolid(const TriangleMesh& mesh, const Eigen::Vector3d& scale, std::size_t max_triangles) : scale_(scale) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3f& p : mesh.vertices) points.push_back(scale.cwiseProduct(p.cast<double>()));
  // The loader keeps one vertex per corner normal, so the corners of a box are several vertices:
  // weld them by position to see which triangles share an edge.
  std::vector<Eigen::Vector3d> positions;
  std::vector<Triangle> triangles;
  weldVertices(
      points, mesh.indices,
      [&mesh](std::size_t v) {
        // The file's float coordinates, bit for bit: equal corners weld, nothing else does.
        std::array<std::int64_t, 3> key{};
        for (int a = 0; a < 3; ++a) {
          const float value = mesh.vertices[v][a] == 0.0F ? 0.0F : mesh.vertices[v][a];  // -0 and +0 are one corner
          std::int32_t bits = 0;
          static_assert(sizeof(bits) == sizeof(value));
          std::memcpy(&bits, &value, sizeof(bits));
          key[static_cast<std::size_t>(a)] = bits;
        }
        return key;
      },
      positions, triangles);
  source_triangles_ = triangles.size();
  constexpr double kFirstCell = 0.002, kLargestCell = 0.02;  // [m]
  for (double cell = kFirstCell; triangles.size() > max_triangles && cell <= kLargestCell * 1.0001; cell *= 1.25) {
    weldVertices(
        points, mesh.indices,
        [cell, &points](std::size_t v) {
          const Eigen::Vector3d& p = points[v];
          return std::array<std::int64_t, 3>{std::llround(std::floor(p.x() / cell)), std::llround(std::floor(p.y() / cell)),
                                             std::llround(std::floor(p.z() / cell))};
        },
        positions, triangles);
    deviation_ = cell * std::sqrt(3.0);
  }

  // Edges sorted by their (undirected) vertex pair: the triangles of one run share that edge.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
  edges.reserve(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    for (int i = 0; i < 3; ++i) edges.emplace_back(edgeKey(triangles[t][i], triangles[t][(i + 1) % 3]), t);
  }
  std::sort(edges.begin(), edges.end());
  const auto neighboursAcross = [&edges](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t key = edgeKey(a, b);
    const auto first = std::lower_bound(edges.begin(), edges.end(), std::make_pair(key, std::uint32_t{0}));
    auto last = first;
    while (last != edges.end() && last->first == key) ++last;
    return std::make_pair(first, last);
  };

  // Walk each connected piece from one triangle, turning every neighbour to run a shared edge
  // the other way (as two faces of one consistently wound surface do). First only across an
  // edge two triangles share: where more meet (parts of an assembly touching along an edge, a
  // wall flush on a plate's rim), which of them belong to one surface is not known, and agreeing
  // with the wrong one turned a part inside out. Each part that comes out mostly closed is a
  // piece of its own, judged below.
  constexpr std::uint32_t kUnvisited = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> piece(triangles.size(), kUnvisited);
  std::vector<std::uint32_t> queue;
  std::uint32_t piece_count = 0;
  const auto walk = [&](std::uint32_t seed, bool across_shared_edges_only, const std::vector<bool>& walkable) {
    piece[seed] = piece_count;
    queue.assign(1, seed);
    while (!queue.empty()) {
      const std::uint32_t t = queue.back();
      queue.pop_back();
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t from = triangles[t][i], to = triangles[t][(i + 1) % 3];
        const auto [first, last] = neighboursAcross(from, to);
        if (across_shared_edges_only && last - first != 2) continue;
        for (auto it = first; it != last; ++it) {
          const std::uint32_t n = it->second;
          if (piece[n] != kUnvisited || !walkable[n]) continue;
          if (hasDirectedEdge(triangles[n], from, to)) triangles[n] = flipped(triangles[n]);
          piece[n] = piece_count;
          queue.push_back(n);
        }
      }
    }
    ++piece_count;
  };
  const std::vector<bool> every_triangle(triangles.size(), true);
  for (std::uint32_t seed = 0; seed < triangles.size(); ++seed) {
    if (piece[seed] == kUnvisited) walk(seed, true, every_triangle);
  }
  // A piece whose edges are mostly shared within it encloses something. The rest (a lone
  // triangle, a face written twice with both windings as "two-sided" exports do, the faces two
  // parts share) has no volume of its own to tell its outside by: those triangles are walked
  // again across any edge, among themselves, once their copies are sorted out (below).
  std::vector<int> piece_triangles(piece_count, 0), piece_edges_within(piece_count, 0), piece_edges(piece_count, 0);
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    ++piece_triangles[piece[t]];
    for (int i = 0; i < 3; ++i) {
      const auto [first, last] = neighboursAcross(triangles[t][i], triangles[t][(i + 1) % 3]);
      const bool within = last - first == 2 && piece[first->second] == piece[(first + 1)->second];
      // An edge within the piece is seen from both its triangles: each sees half of it.
      piece_edges[piece[t]] += within ? 1 : 2;
      piece_edges_within[piece[t]] += within ? 1 : 0;
    }
  }
  std::vector<bool> without_volume(triangles.size(), false);
  bool any_without_volume = false;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const std::uint32_t p = piece[t];
    without_volume[t] = piece_triangles[p] < 4 || 2 * piece_edges_within[p] < piece_edges[p];
    any_without_volume = any_without_volume || without_volume[t];
  }
  // A face written twice (same corners) counts once: between two parts (a block standing on
  // another, each exported closed) the two copies face away from each other and cancel, so
  // both go; elsewhere (a two-sided export) one stays, to be turned as the rest.
  std::vector<bool> dropped(triangles.size(), false);
  if (any_without_volume) {
    std::map<std::array<std::uint32_t, 3>, std::vector<std::uint32_t>> copies;
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      if (!without_volume[t]) continue;
      std::array<std::uint32_t, 3> corners = triangles[t];
      std::sort(corners.begin(), corners.end());
      copies[corners].push_back(t);
    }
    const auto touchesAPart = [&](std::uint32_t t) {
      for (int i = 0; i < 3; ++i) {
        const auto [first, last] = neighboursAcross(triangles[t][i], triangles[t][(i + 1) % 3]);
        for (auto it = first; it != last; ++it) {
          if (!without_volume[it->second]) return true;
        }
      }
      return false;
    };
    for (const auto& [corners, same] : copies) {
      if (same.size() < 2) continue;
      const bool between_parts = same.size() == 2 && !hasDirectedEdge(triangles[same[1]], triangles[same[0]][0], triangles[same[0]][1]) &&
                                 touchesAPart(same[0]);
      for (std::size_t k = between_parts ? 0 : 1; k < same.size(); ++k) dropped[same[k]] = true;
    }
    std::vector<bool> walkable(triangles.size(), false);
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      walkable[t] = without_volume[t] && !dropped[t];
      if (without_volume[t]) piece[t] = kUnvisited;
    }
    for (std::uint32_t seed = 0; seed < triangles.size(); ++seed) {
      if (walkable[seed] && piece[seed] == kUnvisited) walk(seed, false, walkable);
    }
  }

  // Each piece faces outwards if the volume it encloses is positive (divergence theorem, taken
  // about the piece's own centre so that an open piece is judged by its own shape).
  std::vector<Eigen::AlignedBox3d> piece_bounds(piece_count);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (dropped[t]) continue;
    for (const std::uint32_t v : triangles[t]) piece_bounds[piece[t]].extend(positions[v]);
  }
  std::vector<double> piece_volume(piece_count, 0.0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (dropped[t]) continue;
    const Eigen::Vector3d centre = piece_bounds[piece[t]].center();
    const Eigen::Vector3d a = positions[triangles[t][0]] - centre;
    const Eigen::Vector3d b = positions[triangles[t][1]] - centre;
    const Eigen::Vector3d c = positions[triangles[t][2]] - centre;
    piece_volume[piece[t]] += a.dot(b.cross(c));
  }
  triangles_.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (dropped[t]) continue;
    const Triangle triangle = piece_volume[piece[t]] < 0.0 ? flipped(triangles[t]) : triangles[t];
    triangles_.push_back({positions[triangle[0]], positions[triangle[1]], positions[triangle[2]]});
    for (const std::uint32_t v : triangle) bounds_.extend(positions[v]);
  }
}

double MeshSolid::windingNumber(const Eigen::Vector3d& p) const {
  // Solid angle of each triangle seen from p (Van Oosterom and Strackee 1983), signed positive
  // for a triangle facing away from p.
  double solid_angle = 0.0;
  for (const auto& triangle : triangles_) {
    const Eigen::Vector3d a = triangle[0] - p, b = triangle[1] - p, c = triangle[2] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    solid_angle += 2.0 * std::atan2(numerator, denominator);
  }
  return solid_angle / (4.0 * std::numbers::pi);
}

double MeshSolid::distanceToSurface(const Eigen::Vector3d& p) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (const auto& triangle : triangles_) {
    nearest = std::min(nearest, (closestPointOnTriangle(p, triangle[0], triangle[1], triangle[2]) - p).squaredNorm());
  }
  return std::sqrt(nearest);
}

bool MeshSolid::contains(const Eigen::Vector3d& p, double margin) const {
  if (triangles_.empty()) return false;
  const double reach = std::max(margin, 0.0) + kOnSurface;
  // Most points of an evaluation grid lie far from any one obstacle: the box settles them.
  if (bounds_.exteriorDistance(p) > reach) return false;
  if (windingNumber(p) >= 0.5) return true;
  return distanceToSurface(p) <= reach;
}

namespace {
struct SolidCacheEntry {
  std::shared_ptr<const TriangleMesh> mesh;  // held so that its address names this mesh only
  Eigen::Vector3d scale;
  std::shared_ptr<const MeshSolid> solid;
};
constexpr std::size_t kMaxCachedSolids = 256;  // as the mesh cache
std::mutex solid_cache_mutex;
std::vector<SolidCacheEntry> solid_cache;
}  // namespace

std::shared_ptr<const MeshSolid> loadMeshSolidCached(const std::filesystem::path& file, const Eigen::Vector3d& scale) {
  // The mesh cache notices a changed file and then hands out a new mesh: key on that mesh.
  std::shared_ptr<const TriangleMesh> mesh = loadMeshCached(file);
  {
    const std::lock_guard lock(solid_cache_mutex);
    for (const auto& entry : solid_cache) {
      if (entry.mesh == mesh && entry.scale == scale) return entry.solid;
    }
  }
  auto solid = std::make_shared<const MeshSolid>(*mesh, scale);
  const std::lock_guard lock(solid_cache_mutex);
  if (solid_cache.size() >= kMaxCachedSolids) solid_cache.clear();
  solid_cache.push_back(SolidCacheEntry{std::move(mesh), scale, solid});
  return solid;
}

}  // namespace flexirob::robot
