#include "app/mesh_digest.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace flexirob::app {
namespace {

std::string fileDigest(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "unreadable";
  std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a offset basis
  std::array<char, 65536> buffer{};
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      hash ^= static_cast<std::uint8_t>(buffer[static_cast<std::size_t>(i)]);
      hash *= 0x100000001b3ULL;  // FNV prime
    }
  }
  if (in.bad()) return "unreadable";
  std::array<char, 17> text{};
  std::snprintf(text.data(), text.size(), "%016llx", static_cast<unsigned long long>(hash));
  return text.data();
}

// A part's name on one line: a name from a file may hold a line break.
std::string oneLine(std::string name) {
  for (char& c : name) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return name;
}

}  // namespace

std::map<std::string, std::filesystem::path> meshFiles(const robot::RobotModel& model, const robot::Scene& scene) {
  std::map<std::string, std::filesystem::path> files;
  for (const robot::Body& body : model.bodies()) {
    for (const auto& [kind, geometries] : {std::pair<const char*, const std::vector<robot::Geometry>*>{"visual", &body.visuals},
                                           {"collision", &body.collisions}}) {
      for (std::size_t i = 0; i < geometries->size(); ++i) {
        const robot::Geometry& geometry = (*geometries)[i];
        if (geometry.mesh_file.empty()) continue;
        files.emplace(oneLine("link '" + body.name + "' " + kind + " " + std::to_string(i)), geometry.mesh_file);
      }
    }
  }
  for (std::size_t i = 0; i < scene.obstacles.size(); ++i) {
    const robot::Obstacle& obstacle = scene.obstacles[i];
    if (obstacle.mesh_file.empty()) continue;
    // Names are not required to differ: the second of a name is told apart by its place.
    std::string part = oneLine("obstacle '" + obstacle.name + "'");
    if (files.count(part) != 0) part += " #" + std::to_string(i + 1);
    files.emplace(part, obstacle.mesh_file);
  }
  return files;
}

namespace {

// The digest of each part's mesh; a mesh several parts share is read once.
MeshDigests digestsOf(const std::map<std::string, std::filesystem::path>& files) {
  MeshDigests digests;
  std::map<std::filesystem::path, std::string> by_file;
  for (const auto& [part, file] : files) {
    auto found = by_file.find(file);
    if (found == by_file.end()) found = by_file.emplace(file, fileDigest(file)).first;
    digests.emplace(part, found->second);
  }
  return digests;
}

}  // namespace

MeshDigests meshDigests(const robot::RobotModel& model, const robot::Scene& scene) { return digestsOf(meshFiles(model, scene)); }

std::string meshDigestsText(const MeshDigests& digests) {
  std::string text;
  for (const auto& [part, digest] : digests) text += digest + " " + part + "\n";
  return text;
}

MeshDigests parseMeshDigests(const std::string& text) {
  MeshDigests digests;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t space = line.find(' ');
    if (space == std::string::npos || space == 0 || space + 1 >= line.size()) continue;
    digests[line.substr(space + 1)] = line.substr(0, space);
  }
  return digests;
}

std::vector<std::string> meshesChanged(const MeshDigests& recorded, const robot::RobotModel& model, const robot::Scene& scene) {
  std::vector<std::string> changed;
  if (recorded.empty()) return changed;
  const auto files = meshFiles(model, scene);
  const MeshDigests now = digestsOf(files);
  for (const auto& [part, digest] : now) {
    const auto then = recorded.find(part);
    if (then != recorded.end() && then->second != digest) changed.push_back(part + " (" + files.at(part).string() + ")");
  }
  return changed;
}

}  // namespace flexirob::app
