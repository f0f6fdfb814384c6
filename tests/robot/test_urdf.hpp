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

/// A kinematics-only 3-joint arm: no link says what it weighs. Link l1 spans 0.4 m, l2 only
/// 4 cm, l3 0.3 m to the tool; every joint turns within +-2 rad.
/// The first two joints of the small arms below: from link `base` about z at 0.1 m, to link
/// `l2` about y 0.4 m higher, both within +-2 rad. Without mass.
inline std::string twoMasslessJointsToL2() {
  return R"(
    <link name="base"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/>
      <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="2" effort="100"/></joint>
    <link name="l1"/>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.4"/>
      <axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="2" effort="100"/></joint>
    <link name="l2"/>)";
}

inline std::string masslessArm() {
  return R"(<robot name="bare">)" + twoMasslessJointsToL2() + R"(
    <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.04"/>
      <axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="2" effort="100"/></joint>
    <link name="l3"/>
    <joint name="tip" type="fixed"><parent link="l3"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
    <link name="tool"/>
  </robot>)";
}

inline std::string resourcePath(const std::string& relative) {
  return std::string(FLEXIROB_TEST_RESOURCE_DIR) + "/" + relative;
}

}  // namespace flexirob::testing
