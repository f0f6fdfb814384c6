#include "robot/mesh.hpp"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <system_error>
#include <unordered_map>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace fs = std::filesystem;

Eigen::AlignedBox3f TriangleMesh::bounds() const {
  Eigen::AlignedBox3f box;
  for (const auto& v : vertices) box.extend(v);
  return box;
}

namespace {

std::string oneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  return text;
}

std::string lowerExtension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// Whether an ASCII STL declares any facet ("facet normal ..."): one without ("solid x" and
// "endsolid x" alone) made the importer say "Mesh with invalid primitive type", which names
// neither the file's fault nor the fix.
bool asciiStlHasAFacet(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string word = "facet";
  std::string window;
  std::array<char, 65536> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    // The end of the chunk before, so that a keyword across two chunks is found.
    window = window.substr(window.size() > word.size() ? window.size() - word.size() : 0) +
             std::string(chunk.data(), static_cast<std::size_t>(in.gcount()));
    // The keyword, followed by a blank: not "facets" in the solid's name.
    for (std::size_t at = window.find(word); at != std::string::npos; at = window.find(word, at + 1)) {
      const std::size_t after = at + word.size();
      if (after < window.size() && (window[after] == ' ' || window[after] == '\t')) return true;
    }
  }
  return false;
}

// STL needs a look before assimp: a binary STL declares its triangle count in the header, so a
// truncated file or an absurd count is caught without reading (or allocating) anything more.
// ASCII STL (starts with "solid" and is text) carries no count and is bounded by the file size.

void precheckStl(const fs::path& file, std::uintmax_t file_bytes, const MeshLimits& limits) {
  std::ifstream in(file, std::ios::binary);
  std::array<char, 84> head{};
  in.read(head.data(), head.size());
  const auto got = static_cast<std::size_t>(in.gcount());
  const bool starts_solid = got >= 5 && std::memcmp(head.data(), "solid", 5) == 0;
  const bool printable = got > 0 && std::all_of(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(got), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return std::isprint(u) != 0 || std::isspace(u) != 0;
  });
  // Text that is not an ASCII STL (a README or an OBJ saved as .stl) would otherwise be read as
  // a binary header declaring a count made of letters, and called truncated.
  const auto notAnStl = [&file] {
    return InputError("mesh '" + file.string() + "' is text but not an ASCII STL (which begins with \"solid\")");
  };
  const auto checkAscii = [&file] {
    if (!asciiStlHasAFacet(file)) throw InputError("mesh '" + file.string() + "' contains no triangles (an ASCII STL without a facet)");
  };
  if (got < 84) {
    if (starts_solid) return checkAscii();  // a tiny ASCII STL
    if (printable) throw notAnStl();
    throw InputError("mesh '" + file.string() + "' is truncated (shorter than a binary STL header)");
  }
  std::uint32_t count = 0;
  std::memcpy(&count, head.data() + 80, sizeof count);  // little-endian on every platform we build for
  const std::uintmax_t expected = 84 + 50ULL * count;
  if (expected == file_bytes) {
    if (3ULL * count > limits.max_vertices) {
      throw InputError("mesh '" + file.string() + "' has " + std::to_string(count) +
                       " triangles, more than the limit of " + std::to_string(limits.max_vertices / 3));
    }
    return;
  }
  // Not a consistent binary STL: accept it only as text.
  if (starts_solid && printable) return checkAscii();
  if (printable) throw notAnStl();
  throw InputError("mesh '" + file.string() + "' is truncated or corrupt: the binary STL header declares " +
                   std::to_string(count) + " triangles (" + std::to_string(expected) + " bytes), the file has " +
                   std::to_string(file_bytes) + " bytes");
}

// A PLY header declares its element counts up front; absurd ones are refused before assimp
// reserves memory for them.
void precheckPly(const fs::path& file, const MeshLimits& limits) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  for (int lines = 0; lines < 1000 && std::getline(in, line); ++lines) {
    if (line.rfind("end_header", 0) == 0) return;
    std::istringstream words(line);
    std::string keyword, element;
    std::uintmax_t count = 0;
    if (words >> keyword >> element >> count && keyword == "element" && (element == "vertex" || element == "face") &&
        count > limits.max_vertices) {
      throw InputError("mesh '" + file.string() + "' declares " + std::to_string(count) + " " + element +
                       " elements, more than the limit of " + std::to_string(limits.max_vertices));
    }
  }
}

// Vertices the merged mesh will hold: every mesh counted once per node that instances it.
std::uintmax_t countInstancedVertices(const aiScene& scene, const aiNode& node, int depth) {
  if (depth > 256) throw InputError("mesh node hierarchy deeper than 256 levels");
  std::uintmax_t count = 0;
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    if (node.mMeshes[i] < scene.mNumMeshes) count += scene.mMeshes[node.mMeshes[i]]->mNumVertices;
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) count += countInstancedVertices(scene, *node.mChildren[c], depth + 1);
  return count;
}

Eigen::Matrix4f toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4f out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return out;
}

// Appends the triangles of every mesh under `node`, posed by the accumulated node transform.
void appendNode(const aiScene& scene, const aiNode& node, const Eigen::Matrix4f& X_parent, TriangleMesh& out) {
  const Eigen::Matrix4f X = X_parent * toEigen(node.mTransformation);
  const Eigen::Matrix3f linear = X.topLeftCorner<3, 3>();
  const Eigen::Matrix3f normal_map = linear.inverse().transpose();
  const bool mirrored = linear.determinant() < 0.0F;
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    if (node.mMeshes[i] >= scene.mNumMeshes) continue;
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[i]];
    if ((mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
    const auto offset = static_cast<std::uint32_t>(out.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      out.vertices.emplace_back(linear * Eigen::Vector3f(p.x, p.y, p.z) + X.topRightCorner<3, 1>());
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      if (mesh.mNormals != nullptr) {
        const aiVector3D& m = mesh.mNormals[v];
        n = normal_map * Eigen::Vector3f(m.x, m.y, m.z);
      }
      const float length = n.norm();
      out.normals.push_back(length > 1e-12F && std::isfinite(length) ? Eigen::Vector3f(n / length) : Eigen::Vector3f::Zero());
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      const std::array<unsigned, 3> idx{face.mIndices[0], mirrored ? face.mIndices[2] : face.mIndices[1],
                                        mirrored ? face.mIndices[1] : face.mIndices[2]};
      if (std::any_of(idx.begin(), idx.end(), [&](unsigned k) { return k >= mesh.mNumVertices; })) continue;
      for (const unsigned k : idx) out.indices.push_back(offset + k);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) appendNode(scene, *node.mChildren[c], X, out);
}

// Normals the file did not provide (zero entries): area-weighted face normals per vertex.
void fillMissingNormals(TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> sum(mesh.vertices.size(), Eigen::Vector3f::Zero());
  bool missing = false;
  for (const auto& n : mesh.normals) missing = missing || n.isZero();
  if (!missing) return;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const auto a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    const Eigen::Vector3f face = (mesh.vertices[b] - mesh.vertices[a]).cross(mesh.vertices[c] - mesh.vertices[a]);
    sum[a] += face;
    sum[b] += face;
    sum[c] += face;
  }
  for (std::size_t v = 0; v < mesh.normals.size(); ++v) {
    if (mesh.normals[v].isZero() && sum[v].norm() > 0.0F) mesh.normals[v] = sum[v].normalized();
  }
}

// assimp joins identical vertices and smooths normals mesh by mesh, comparing each vertex with
// every other of its mesh at its position: about the sum of k^2 over the positions k vertices
// of one mesh share. Real meshes meet a few dozen triangles at a corner (a finely divided
// cone's tip a few thousand), a few 10^7 comparisons for millions of triangles; one face copied
// 200 000 times (a broken or hostile export) needs 4 * 10^10, hours. Counted on the file as
// read, before any post-processing.
constexpr double kMaxCornerComparisons = 2e8;

void refuseStackedCorners(const aiScene& scene, const fs::path& file) {
  struct PositionHash {
    std::size_t operator()(const std::array<float, 3>& p) const {
      std::size_t h = 0;
      for (const float c : p) {
        std::uint32_t bits = 0;
        std::memcpy(&bits, &c, sizeof bits);
        h = h * 1000003U ^ bits;
      }
      return h;
    }
  };
  std::unordered_map<std::array<float, 3>, std::uint32_t, PositionHash> sharing;
  double comparisons = 0.0;
  std::uint32_t most = 0;
  std::array<float, 3> most_at{};
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    sharing.clear();
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      // +0.0f: -0 and 0 are one position.
      const std::array<float, 3> p{mesh.mVertices[v].x + 0.0F, mesh.mVertices[v].y + 0.0F, mesh.mVertices[v].z + 0.0F};
      const std::uint32_t k = ++sharing[p];
      comparisons += 2.0 * k - 1.0;  // k^2 - (k - 1)^2
      if (k > most) {
        most = k;
        most_at = p;
      }
    }
  }
  if (comparisons <= kMaxCornerComparisons) return;
  std::ostringstream message;
  message << "mesh '" << file.string() << "' has " << most << " corners at the one point (" << most_at[0] << ", " << most_at[1]
          << ", " << most_at[2] << "): copies of the same faces, which would take hours to join; export it without them";
  throw InputError(message.str());
}

}  // namespace

TriangleMesh loadMesh(const fs::path& file, const MeshLimits& limits) {
  std::error_code error;
  if (!fs::is_regular_file(file, error)) throw InputError("mesh file '" + file.string() + "' not found");
  const std::uintmax_t bytes = fs::file_size(file, error);
  if (error) throw InputError("cannot read mesh file '" + file.string() + "'");
  if (bytes > limits.max_file_bytes) {
    throw InputError("mesh file '" + file.string() + "' is larger than " +
                     std::to_string(limits.max_file_bytes / (1024 * 1024)) + " MB");
  }
  if (bytes == 0) throw InputError("mesh file '" + file.string() + "' is empty");
  const std::string ext = lowerExtension(file);
  if (ext == ".stl") precheckStl(file, bytes, limits);
  if (ext == ".ply") precheckPly(file, limits);

  Assimp::Importer importer;
  // Points and lines are not surfaces; STL facet normals are flat, so smooth ones are
  // generated instead, keeping edges sharper than 60 degrees (cylinder caps, rims) as creases.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, 60.0F);
  // URDF meshes are authored in the link frame: keep COLLADA's coordinates as written (its
  // <unit> is still applied).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_GenSmoothNormals |
                   aiProcess_SortByPType | aiProcess_FindDegenerates | aiProcess_FindInvalidData;
  if (ext == ".stl") flags |= aiProcess_ForceGenNormals;
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  if (scene == nullptr) {
    throw InputError("cannot load mesh '" + file.string() + "': " + oneLine(importer.GetErrorString()));
  }
  refuseStackedCorners(*scene, file);
  scene = importer.ApplyPostProcessing(flags);
  if (scene == nullptr) {
    // A failing step leaves no error string behind (assimp swallows what it threw).
    const std::string reason = oneLine(importer.GetErrorString());
    throw InputError("cannot load mesh '" + file.string() + "': " + (reason.empty() ? "its triangles could not be prepared" : reason));
  }
  if (scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    throw InputError("cannot load mesh '" + file.string() + "': incomplete scene");
  }
  const std::uintmax_t vertex_count = countInstancedVertices(*scene, *scene->mRootNode, 0);
  if (vertex_count > limits.max_vertices) {
    throw InputError("mesh '" + file.string() + "' has " + std::to_string(vertex_count) +
                     " vertices, more than the limit of " + std::to_string(limits.max_vertices));
  }
  TriangleMesh mesh;
  mesh.vertices.reserve(static_cast<std::size_t>(vertex_count));
  mesh.normals.reserve(static_cast<std::size_t>(vertex_count));
  appendNode(*scene, *scene->mRootNode, Eigen::Matrix4f::Identity(), mesh);
  if (mesh.empty()) throw InputError("mesh '" + file.string() + "' contains no triangles");
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) throw InputError("mesh '" + file.string() + "' has non-finite vertex coordinates");
  }
  fillMissingNormals(mesh);
  return mesh;
}

namespace {
struct CacheEntry {
  std::uintmax_t bytes = 0;
  fs::file_time_type modified;
  std::shared_ptr<const TriangleMesh> mesh;
};
// Robots and scenes reference a few dozen files; the cap only bounds memory in long sessions
// that load many different scenes.
constexpr std::size_t kMaxCachedMeshes = 256;
std::mutex cache_mutex;
std::map<fs::path, CacheEntry> cache;
}  // namespace

std::shared_ptr<const TriangleMesh> loadMeshCached(const fs::path& file) {
  std::error_code error;
  fs::path key = fs::absolute(file, error);
  if (!error) key = fs::weakly_canonical(key, error);
  if (error || !fs::is_regular_file(key, error)) throw InputError("mesh file '" + file.string() + "' not found");
  const std::uintmax_t bytes = fs::file_size(key, error);
  if (error) throw InputError("cannot read mesh file '" + file.string() + "'");
  const fs::file_time_type modified = fs::last_write_time(key, error);
  if (error) throw InputError("cannot read mesh file '" + file.string() + "'");
  {
    const std::lock_guard lock(cache_mutex);
    if (const auto it = cache.find(key); it != cache.end() && it->second.bytes == bytes && it->second.modified == modified) {
      return it->second.mesh;
    }
  }
  // Load outside the lock: two threads may load the same file once each, which is harmless.
  auto mesh = std::make_shared<const TriangleMesh>(loadMesh(key));
  const std::lock_guard lock(cache_mutex);
  if (cache.size() >= kMaxCachedMeshes) cache.clear();
  cache[key] = CacheEntry{bytes, modified, mesh};
  return mesh;
}

void clearMeshCache() {
  const std::lock_guard lock(cache_mutex);
  cache.clear();
}

TriangleMesh transformedMesh(const TriangleMesh& mesh, const Eigen::Isometry3d& X, const Eigen::Vector3d& scale) {
  const Eigen::Matrix3f linear = (X.linear() * scale.asDiagonal()).cast<float>();
  const Eigen::Vector3f translation = X.translation().cast<float>();
  const Eigen::Matrix3f normal_map = (X.linear() * scale.cwiseInverse().asDiagonal()).cast<float>();
  TriangleMesh out;
  out.vertices.reserve(mesh.vertices.size());
  out.normals.reserve(mesh.normals.size());
  for (const auto& v : mesh.vertices) out.vertices.emplace_back(linear * v + translation);
  for (const auto& n : mesh.normals) {
    const Eigen::Vector3f m = normal_map * n;
    const float length = m.norm();
    out.normals.push_back(length > 0.0F && std::isfinite(length) ? Eigen::Vector3f(m / length) : Eigen::Vector3f::Zero());
  }
  out.indices = mesh.indices;
  if (scale.prod() < 0.0) {
    for (std::size_t t = 0; t + 2 < out.indices.size(); t += 3) std::swap(out.indices[t + 1], out.indices[t + 2]);
  }
  return out;
}

}  // namespace flexirob::robot
