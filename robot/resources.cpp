#include "robot/resources.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <system_error>

#include <unistd.h>

#include "robot/errors.hpp"

#ifndef FLEXIROB_SOURCE_RESOURCE_DIR
#define FLEXIROB_SOURCE_RESOURCE_DIR ""
#endif

namespace flexirob {
namespace fs = std::filesystem;

namespace {
fs::path executableDir() {
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::path{} : exe.parent_path();
}
}  // namespace

fs::path resourceDir() {
  if (const char* env = std::getenv("FLEXIROB_RESOURCES"); env != nullptr && *env != '\0') {
    if (fs::is_directory(env)) return fs::path(env);
    throw InputError("FLEXIROB_RESOURCES points to '" + std::string(env) + "', which is not a folder");
  }
  const fs::path exe_dir = executableDir();
  if (!exe_dir.empty()) {
    const fs::path installed = exe_dir / ".." / "share" / "flexirob" / "resources";
    if (fs::is_directory(installed)) return fs::weakly_canonical(installed);
  }
  const fs::path source_tree(FLEXIROB_SOURCE_RESOURCE_DIR);
  if (!source_tree.empty() && fs::is_directory(source_tree)) return source_tree;
  throw InputError("cannot find the resources folder; set FLEXIROB_RESOURCES");
}

const std::vector<std::string>& builtinRobotNames() {
  static const std::vector<std::string> names{"lwr4", "arm9"};
  return names;
}

fs::path resolveRobotPath(const std::string& robot_argument) {
  if (robot_argument.empty()) throw InputError("expected a robot name or URDF path, got an empty string");
  for (const auto& name : builtinRobotNames()) {
    if (robot_argument == name) return resourceDir() / "robots" / name / (name + ".urdf");
  }
  const fs::path path(robot_argument);
  if (const std::string reason = unreadableFileReason(path); !reason.empty()) {
    std::string known;
    for (const auto& name : builtinRobotNames()) known += (known.empty() ? "" : ", ") + name;
    throw InputError("robot '" + printable(robot_argument, 200) + "' is neither a built-in robot (" + known +
                     ") nor a readable URDF file (" + reason + ")");
  }
  return path;
}

std::string unreadableFileReason(const fs::path& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  // A folder on the way that cannot be searched, a name too long: not a missing file.
  if (error && error != std::errc::no_such_file_or_directory && error != std::errc::not_a_directory) {
    return "cannot read it: " + error.message();
  }
  if (!fs::exists(status)) return fs::is_symlink(fs::symlink_status(path, error)) ? "a broken symbolic link" : "no such file";
  if (fs::is_directory(status)) return "it is a folder";
  if (!fs::is_regular_file(status)) return "it is not a regular file";
  if (::access(path.c_str(), R_OK) != 0) return "cannot read it: " + std::string(std::strerror(errno));
  return {};
}

std::string portableReference(const std::string& argument, const std::vector<std::string>& builtin_names) {
  if (argument.empty() || std::find(builtin_names.begin(), builtin_names.end(), argument) != builtin_names.end()) {
    return argument;
  }
  std::error_code error;
  const fs::path absolute = fs::absolute(argument, error);
  return error ? argument : absolute.lexically_normal().string();
}

}  // namespace flexirob
