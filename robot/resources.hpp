#pragma once
// Locating the data files the product ships (robots, scenes, meshes) at run time.
#include <filesystem>
#include <string>
#include <vector>

namespace flexirob {

/// The resources folder: $FLEXIROB_RESOURCES if set, else ../share/flexirob/resources next to
/// the running executable, else the source tree the build came from. Throws InputError if none
/// of them exists.
std::filesystem::path resourceDir();

/// Built-in robot names ("lwr4", "arm9") in the order they are offered to users.
const std::vector<std::string>& builtinRobotNames();

/// Resolves a robot argument: a built-in name maps to its URDF under resources/robots, anything
/// else is taken as a path to a URDF file. Throws InputError if the file does not exist.
std::filesystem::path resolveRobotPath(const std::string& robot_argument);

/// Why `path` cannot be read as a file ("no such file", "it is a folder", ...), or an empty
/// string when it can: an error naming a path says which of these it met.
std::string unreadableFileReason(const std::filesystem::path& path);

/// How a session refers to a robot or scene argument so that it still resolves from another
/// working directory: a built-in name as it is, a file as its absolute path. Empty stays empty.
std::string portableReference(const std::string& argument, const std::vector<std::string>& builtin_names);

}  // namespace flexirob
