#pragma once
// Helpers for robot tests: small URDFs written inline into a fresh temporary folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace flexirob::testing {

/// A temporary folder removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    static std::mt19937_64 engine{std::random_device{}()};
    path_ = std::filesystem::temp_directory_path() / ("flexirob-test-" + std::to_string(engine()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path write(const std::string& relative, const std::string& text) const {
    const auto file = path_ / relative;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

 private:
  std::filesystem::path path_;
};

inline std::string resourcePath(const std::string& relative) {
  return std::string(FLEXIROB_TEST_RESOURCE_DIR) + "/" + relative;
}

}  // namespace flexirob::testing
