#pragma once
// Runs the real flexirob-cli binary and captures what a calling program would see.
#include <algorithm>
#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace flexirob::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
  nlohmann::json json() const { return nlohmann::json::parse(out); }
};

/// Runs `flexirob-cli <arguments>` through the shell; arguments are passed as written.
inline CliResult runCliBinary(const std::string& arguments) {
  char err_template[] = "/tmp/flexirob-cli-stderr-XXXXXX";
  const int err_fd = mkstemp(err_template);
  if (err_fd >= 0) close(err_fd);
  const std::string err_file = err_template;
  // Whatever the calling shell sets: progress on stderr is asked for by the tests that want it.
  const std::string command = "env -u FLEXIROB_PROGRESS " + std::string(FLEXIROB_CLI_EXECUTABLE) + " " + arguments + " 2>" + err_file;
  CliResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  std::size_t read = 0;
  while ((read = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.out.append(buffer.data(), read);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (FILE* err = std::fopen(err_file.c_str(), "r")) {
    while ((read = std::fread(buffer.data(), 1, buffer.size(), err)) > 0) result.err.append(buffer.data(), read);
    std::fclose(err);
  }
  std::remove(err_file.c_str());
  return result;
}

/// A scratch folder of this test process for `suite`, created on first use and removed with
/// everything in it when the process ends (ctest runs every test in a process of its own, and
/// hundreds of folders were left in /tmp per run).
inline std::filesystem::path scratchDir(const std::string& suite) {
  struct RemovedAtExit {
    std::filesystem::path path;
    ~RemovedAtExit() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static std::vector<RemovedAtExit> folders;
  const auto dir = std::filesystem::temp_directory_path() / ("flexirob-" + suite + "-" + std::to_string(::getpid()));
  if (std::none_of(folders.begin(), folders.end(), [&](const RemovedAtExit& folder) { return folder.path == dir; })) {
    folders.push_back({dir});
  }
  std::filesystem::create_directories(dir);
  return dir;
}

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << text;
}

}  // namespace flexirob::testing
