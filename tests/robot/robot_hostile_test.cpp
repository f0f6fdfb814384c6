// Absurd robot descriptions, meshes and scenes: each is refused with an InputError carrying a
// one-line reason, before any large allocation and without deep recursion (docs/RELIABILITY.md).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "robot/errors.hpp"
#include "robot/mesh.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {
namespace {

namespace fs = std::filesystem;

const fs::path kResources(FLEXIROB_TEST_RESOURCE_DIR);

/// A scratch directory removed with the test.
class ScratchDir {
 public:
  ScratchDir() : path_(fs::temp_directory_path() / ("flexirob-hostile-" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

/// The message of the InputError `action` throws ("" if it throws none; other exceptions escape).
template <class Action>
std::string inputErrorOf(Action action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string nestedUrdf(int depth) {
  std::string xml = "<robot name=\"deep\"><link name=\"base\">";
  for (int i = 0; i < depth; ++i) xml += "<visual>";
  for (int i = 0; i < depth; ++i) xml += "</visual>";
  return xml + "</link></robot>";
}

TEST(HostileUrdf, DeeplyNestedXmlIsRefusedBeforeTheXmlParserRecurses) {
  // 300000 nested elements overflowed the stack of urdfdom's XML parser (a crash, found by hand
  // and kept in fuzz/regressions/urdf/).
  const std::string message = inputErrorOf([] { RobotModel::fromUrdfString(nestedUrdf(300000), kResources); });
  EXPECT_NE(message.find("nested deeper than 100"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(HostileUrdf, NestingInsideCommentsCdataAndAttributesIsNotCounted) {
  // A real robot with a comment, a CDATA section and '>' / '<'-free attribute text full of
  // angle-like characters still loads: the depth scan skips them.
  std::string comment = "<!--";
  for (int i = 0; i < 1000; ++i) comment += "<a>";
  comment += "-->";
  const std::string xml = "<?xml version=\"1.0\"?>" + comment +
                          "<robot name=\"ok\"><link name=\"base\"/><link name=\"l1\"/>"
                          "<joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/><child link=\"l1\"/>"
                          "<axis xyz=\"0 0 1\"/></joint></robot>";
  const RobotModel model = RobotModel::fromUrdfString(xml, kResources);
  EXPECT_EQ(model.dof(), 1);
}

TEST(HostileUrdf, AMalformedTagIsLocatedByItsLine) {
  // urdfdom's XML errors ("Error reading Attributes") name no place: the line of the first tag
  // whose attributes do not read is added. Well-formed tags around it (self-closing, single
  // quotes, spaces about '=') are not taken for it.
  const std::string head = "<robot name='r'>\n<link name = \"base\"/>\n<link name=\"l1\" />\n";
  const std::string joint_text = "<joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/><child link=\"l1\"/></joint>\n";
  const std::string broken = head + "<joint name=\"a \"quoted\" name\" type=\"continuous\"><parent link=\"base\"/><child link=\"l1\"/></joint>\n</robot>";
  const std::string message = inputErrorOf([&broken] { RobotModel::fromUrdfString(broken, kResources); });
  EXPECT_NE(message.find("invalid URDF"), std::string::npos) << message;
  EXPECT_NE(message.find("the first malformed tag is on line 4"), std::string::npos) << message;
  // A document urdfdom refuses for what it means, not how it is written, gets no line.
  const std::string unknown_parent = head + "<joint name=\"j1\" type=\"continuous\"><parent link=\"nowhere\"/><child link=\"l1\"/></joint>\n</robot>";
  const std::string meaning = inputErrorOf([&unknown_parent] { RobotModel::fromUrdfString(unknown_parent, kResources); });
  EXPECT_FALSE(meaning.empty());
  EXPECT_EQ(meaning.find("malformed tag"), std::string::npos) << meaning;
  EXPECT_EQ(RobotModel::fromUrdfString(head + joint_text + "</robot>", kResources).dof(), 1);
}

// (A million-joint URDF is refused by its size: tests/cli/hostile_cli_test.cpp.)
TEST(HostileUrdf, MoreLinksThanTheLimitUnderTheSizeLimitAreRefusedByCount) {
  std::ostringstream xml;
  xml << "<robot name=\"many\"><link name=\"l0\"/>";
  for (int i = 1; i <= 10'001; ++i) {
    xml << "<link name=\"l" << i << "\"/><joint name=\"j" << i << "\" type=\"continuous\"><parent link=\"l" << i - 1
        << "\"/><child link=\"l" << i << "\"/></joint>";
  }
  xml << "</robot>";
  const std::string message = inputErrorOf([&xml] { RobotModel::fromUrdfString(xml.str(), kResources); });
  EXPECT_NE(message.find("more than 10000 links"), std::string::npos) << message;
}

std::string joint(const std::string& name, const std::string& parent, const std::string& child) {
  return "<joint name=\"" + name + "\" type=\"continuous\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><axis xyz=\"0 0 1\"/></joint>";
}

TEST(HostileUrdf, JointCyclesAreRefusedInsteadOfLoopingForever) {
  // Found by fuzz/urdf_fuzzer.cpp (fuzz/regressions/urdf/joint_cycle_hang.urdf): a joint whose
  // parent is its own child made the search for the default tip walk up the chain forever.
  const std::string links = "<link name=\"base\"/><link name=\"a\"/><link name=\"b\"/><link name=\"tip\"/>";
  const std::string self_loop = "<robot name=\"r\">" + links + joint("j0", "base", "b") + joint("j1", "a", "a") +
                                joint("j2", "a", "tip") + "</robot>";
  const std::string two_cycle = "<robot name=\"r\">" + links + joint("j1", "a", "b") + joint("j2", "b", "a") +
                                joint("j3", "a", "tip") + "</robot>";
  for (const std::string& xml : {self_loop, two_cycle}) {
    const std::string message = inputErrorOf([&xml] { RobotModel::fromUrdfString(xml, kResources); });
    EXPECT_FALSE(message.empty()) << xml;
  }
  const std::string message = inputErrorOf([&two_cycle] { RobotModel::fromUrdfString(two_cycle, kResources); });
  EXPECT_NE(message.find("form a cycle"), std::string::npos) << message;
}

TEST(HostileUrdf, ALinkThatIsTheChildOfTwoJointsIsRefused) {
  const std::string xml = "<robot name=\"r\"><link name=\"base\"/><link name=\"a\"/><link name=\"b\"/>" +
                          joint("j1", "base", "a") + joint("j2", "base", "b") + joint("j3", "b", "a") + "</robot>";
  const std::string message = inputErrorOf([&xml] { RobotModel::fromUrdfString(xml, kResources); });
  EXPECT_NE(message.find("child of more than one joint"), std::string::npos) << message;
}

TEST(HostileUrdf, NonFiniteOriginsAxesAndLimitsAreRefused) {
  const auto urdf = [](const std::string& joint_body) {
    return "<robot name=\"n\"><link name=\"base\"/><link name=\"l1\"/><joint name=\"j1\" type=\"revolute\">"
           "<parent link=\"base\"/><child link=\"l1\"/>" +
           joint_body + "</joint></robot>";
  };
  const std::string limit = "<limit lower=\"-1\" upper=\"1\" velocity=\"1\" effort=\"1\"/>";
  for (const std::string& body : {"<origin xyz=\"nan 0 0\"/><axis xyz=\"0 0 1\"/>" + limit,
                                  "<origin xyz=\"0 0 0\" rpy=\"0 inf 0\"/><axis xyz=\"0 0 1\"/>" + limit,
                                  "<axis xyz=\"0 0 nan\"/>" + limit, "<axis xyz=\"0 0 0\"/>" + limit,
                                  std::string("<axis xyz=\"0 0 1\"/><limit lower=\"-inf\" upper=\"nan\" velocity=\"1\" effort=\"1\"/>")}) {
    const std::string message = inputErrorOf([&] { RobotModel::fromUrdfString(urdf(body), kResources); });
    EXPECT_FALSE(message.empty()) << "accepted: " << body;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(HostileMesh, TwoGigabyteMeshIsRefusedBeforeLoading) {
  ScratchDir dir;
  const fs::path file = dir / "huge.stl";
  { std::ofstream(file) << "solid huge\n"; }
  fs::resize_file(file, 2ULL * 1024 * 1024 * 1024);  // sparse: no disk space, no time
  const std::string message = inputErrorOf([&file] { loadMesh(file); });
  EXPECT_NE(message.find("larger than 256 MB"), std::string::npos) << message;
}

TEST(HostileMesh, VertexLimitIsEnforcedWhileLoading) {
  ScratchDir dir;
  const fs::path file = dir / "many.stl";
  {
    std::ofstream out(file);
    out << "solid many\n";
    for (int i = 0; i < 2000; ++i) {
      out << "facet normal 0 0 1\nouter loop\nvertex " << i << " 0 0\nvertex " << i + 1 << " 0 0\nvertex " << i
          << " 1 0\nendloop\nendfacet\n";
    }
    out << "endsolid many\n";
  }
  MeshLimits limits;
  limits.max_vertices = 1000;
  const std::string message = inputErrorOf([&] { loadMesh(file, limits); });
  EXPECT_FALSE(message.empty());
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST(HostileScene, NonFinitePosesAndSizesAreRefusedNamingTheField) {
  const std::string base = "name: hostile\nobstacles:\n  - name: box\n    shape: box\n";
  for (const std::string& body :
       {base + "    size: [0.1, 0.1, 0.1]\n    position: [.nan, 0, 0]\n",
        base + "    size: [0.1, 0.1, 0.1]\n    position: [0, 0, 1e999]\n",
        base + "    size: [0.1, .inf, 0.1]\n    position: [0, 0, 0]\n",
        base + "    size: [0.1, 0.1, 0.1]\n    position: [0, 0, 0]\n    rotation: {quaternion: [.nan, 0, 0, 1]}\n",
        std::string("name: hostile\nhome_posture: [0, 0, .nan, 0, 0, 0, 0]\n"),
        std::string("name: hostile\ntargets:\n  - [0.4, -.inf, 0.5]\n")}) {
    const std::string message = inputErrorOf([&] { parseScene(body, kResources / "scenes", "hostile.yaml"); });
    EXPECT_FALSE(message.empty()) << "accepted:\n" << body;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(HostileScene, DeeplyNestedYamlIsRefused) {
  const std::string yaml = "name: deep\nobstacles: " + std::string(100000, '[') + std::string(100000, ']') + "\n";
  const std::string message = inputErrorOf([&] { parseScene(yaml, kResources / "scenes", "deep.yaml"); });
  EXPECT_FALSE(message.empty());
}

TEST(HostileScene, SceneMeshOfTwoGigabytesIsRefusedWhenTheSceneIsRead) {
  ScratchDir dir;
  const fs::path mesh = dir / "huge.stl";
  { std::ofstream(mesh) << "solid huge\n"; }
  fs::resize_file(mesh, 2ULL * 1024 * 1024 * 1024);
  const std::string yaml = "name: big\nobstacles:\n  - name: m\n    shape: mesh\n    file: " + mesh.string() +
                           "\n    position: [0.5, 0, 0]\n";
  // Either the scene reader refuses it, or the first mesh load does; never a 2 GB read.
  std::string message = inputErrorOf([&] {
    const Scene scene = parseScene(yaml, dir / "", "big.yaml");
    for (const auto& obstacle : scene.obstacles) {
      if (!obstacle.mesh_file.empty()) loadMesh(obstacle.mesh_file);
    }
  });
  EXPECT_NE(message.find("larger than"), std::string::npos) << message;
}

}  // namespace
}  // namespace flexirob::robot
