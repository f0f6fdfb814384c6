#pragma once
// Digests of the mesh files a robot and a scene read. A session stores its robot's URDF and its
// scene's text, not their meshes: it records a digest of each, so that a mesh changed after
// teaching is noticed when the session is evaluated, planned, exported or drawn again.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {

/// Part ("link 'l3' collision 1", "obstacle 'crate'") -> digest of the bytes of its mesh file
/// (64-bit FNV-1a, hexadecimal; "unreadable" for a file that does not read).
using MeshDigests = std::map<std::string, std::string>;

/// Part (as MeshDigests names it) -> the mesh file it reads, for every mesh of `model` and `scene`.
std::map<std::string, std::filesystem::path> meshFiles(const robot::RobotModel& model, const robot::Scene& scene);

MeshDigests meshDigests(const robot::RobotModel& model, const robot::Scene& scene);

/// One line per part, "<digest> <part>", as SessionMetadata::mesh_digests holds them.
std::string meshDigestsText(const MeshDigests& digests);
/// The lines of meshDigestsText; a line that is not one is skipped (a session edited by hand
/// loses only the check).
MeshDigests parseMeshDigests(const std::string& text);

/// The parts both know whose meshes differ, as "part (file)" for a note. Parts only one knows
/// are left out: a robot or scene changed in its structure is noted by its text already.
std::vector<std::string> meshesChanged(const MeshDigests& recorded, const robot::RobotModel& model, const robot::Scene& scene);

}  // namespace flexirob::app
