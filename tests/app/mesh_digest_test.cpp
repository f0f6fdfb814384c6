#include "app/mesh_digest.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "robot/resources.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

class MeshDigestTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flexirob-mesh-digest-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    fs::copy(resolveRobotPath("lwr4").parent_path(), dir_ / "lwr4", fs::copy_options::recursive);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const fs::path& file, const std::string& bytes) { std::ofstream(file, std::ios::binary) << bytes; }
  robot::Obstacle meshObstacle(const std::string& name, const fs::path& file) {
    robot::Obstacle obstacle;
    obstacle.name = name;
    obstacle.shape = robot::Obstacle::Shape::kMesh;
    obstacle.mesh_file = file;
    return obstacle;
  }
  fs::path dir_;
};

TEST_F(MeshDigestTest, EachMeshIsDigestedByItsBytesWithFnv1a) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(dir_ / "lwr4" / "lwr4.urdf");
  robot::Scene scene;
  write(dir_ / "a.bin", "a");
  write(dir_ / "empty.bin", "");
  scene.obstacles = {meshObstacle("crate", dir_ / "a.bin"), meshObstacle("crate", dir_ / "empty.bin")};
  const MeshDigests digests = meshDigests(model, scene);
  // FNV-1a's published 64-bit vectors: "a" and the empty input (the offset basis).
  EXPECT_EQ(digests.at("obstacle 'crate'"), "af63dc4c8601ec8c");
  EXPECT_EQ(digests.at("obstacle 'crate' #2"), "cbf29ce484222325");
  int link_meshes = 0;
  for (const robot::Body& body : model.bodies()) {
    for (const auto* geometries : {&body.visuals, &body.collisions}) {
      for (const robot::Geometry& geometry : *geometries) link_meshes += geometry.mesh_file.empty() ? 0 : 1;
    }
  }
  EXPECT_GT(link_meshes, 0);
  EXPECT_EQ(static_cast<int>(digests.size()), link_meshes + 2);
  EXPECT_EQ(parseMeshDigests(meshDigestsText(digests)), digests);
}

TEST_F(MeshDigestTest, AMeshChangedOrGoneSinceIsNamedAndNothingElse) {
  const fs::path urdf = dir_ / "lwr4" / "lwr4.urdf";
  robot::Scene scene;
  write(dir_ / "crate.stl", "the crate as taught");
  scene.obstacles = {meshObstacle("crate", dir_ / "crate.stl")};
  const robot::RobotModel taught = robot::RobotModel::fromUrdfFile(urdf);
  const std::string recorded = meshDigestsText(meshDigests(taught, scene));
  EXPECT_TRUE(meshesChanged(parseMeshDigests(recorded), taught, scene).empty());
  // Another link's mesh copied over link 1's, and the crate's file rewritten.
  fs::copy_file(dir_ / "lwr4" / "meshes" / "link2_collision.stl", dir_ / "lwr4" / "meshes" / "link1_collision.stl",
                fs::copy_options::overwrite_existing);
  write(dir_ / "crate.stl", "the crate moved");
  const robot::RobotModel now = robot::RobotModel::fromUrdfFile(urdf);
  const auto changed = meshesChanged(parseMeshDigests(recorded), now, scene);
  ASSERT_EQ(changed.size(), 2U);
  EXPECT_EQ(changed[0].rfind("link 'link1' collision 0 (", 0), 0U) << changed[0];
  EXPECT_EQ(changed[1], "obstacle 'crate' (" + (dir_ / "crate.stl").string() + ")");
  // Gone: unreadable, which differs too.
  fs::remove(dir_ / "crate.stl");
  EXPECT_EQ(meshesChanged(parseMeshDigests(recorded), now, scene).size(), 2U);
  // A session that recorded no digests (older files) is not checked; lines that are no digest
  // are passed over.
  EXPECT_TRUE(meshesChanged({}, now, scene).empty());
  EXPECT_EQ(parseMeshDigests("nonsense\n\n 'x'\nabc \n").size(), 0U);
}

}  // namespace
}  // namespace flexirob::app
