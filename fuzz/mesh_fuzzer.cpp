// Fuzz target: mesh files (STL, binary or ASCII, and OBJ; the first byte picks the extension)
// through loadMesh: size limits, sub-mesh merging, normals. Anything unreadable must end in an
// InputError; an accepted mesh must be consistent (indices in range, one unit normal per vertex).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "robot/errors.hpp"
#include "robot/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static flexirob::fuzz::InputFile stl(".stl");
  static flexirob::fuzz::InputFile obj(".obj");
  flexirob::fuzz::InputFile& file = (data[0] & 1U) != 0 ? obj : stl;
  const auto& path = file.write(data + 1, size - 1);
  flexirob::robot::MeshLimits limits;
  limits.max_file_bytes = 1 << 20;
  limits.max_vertices = 100'000;
  try {
    const auto mesh = flexirob::robot::loadMesh(path, limits);
    if (mesh.indices.size() % 3 != 0) flexirob::fuzz::invariantBroken("index count not a multiple of 3");
    if (mesh.normals.size() != mesh.vertices.size()) flexirob::fuzz::invariantBroken("normals != vertices");
    if (mesh.vertices.size() > limits.max_vertices) flexirob::fuzz::invariantBroken("vertex limit exceeded");
    for (const auto index : mesh.indices) {
      if (index >= mesh.vertices.size()) flexirob::fuzz::invariantBroken("index out of range");
    }
  } catch (const flexirob::InputError&) {
  }
  return 0;
}
