// The command-line contract of `robot info` and `fk` (DESIGN section 6), exercised through the
// real binary as other programs use it.
#include <gtest/gtest.h>

#include <fstream>

#include <Eigen/Geometry>
#include <numbers>
#include <unistd.h>
#include <filesystem>

#include "cli_test_support.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"

namespace flexirob {
namespace {

using testing::runCliBinary;

TEST(RobotCli, InfoListsJointsWithLimitsAndTheUrdfItRead) {
  const auto result = runCliBinary("robot info --robot lwr4");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json["name"], "lwr4");
  EXPECT_EQ(json["dof"], 7);
  EXPECT_EQ(json["base_link"], "base_link");
  EXPECT_EQ(json["tip_link"], "flange");
  EXPECT_NE(json["urdf"].get<std::string>().find("lwr4.urdf"), std::string::npos);
  ASSERT_EQ(json["joints"].size(), 7U);
  EXPECT_EQ(json["joints"][0]["name"], "A1");
  EXPECT_NEAR(json["joints"][1]["upper"].get<double>(), 120.0 * std::numbers::pi / 180.0, 1e-6);
  EXPECT_NEAR(json["joints"][4]["velocity"].get<double>(), 204.0 * std::numbers::pi / 180.0, 1e-6);
}

TEST(RobotCli, FkPrintsPoseAndAWorldAlignedJacobianOfTheTip) {
  const auto result = runCliBinary("fk --robot arm9 --q 0.1,-0.4,0.3,1.1,-0.2,0.5,0.7,-0.9,0.2");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  Eigen::VectorXd q(9);
  q << 0.1, -0.4, 0.3, 1.1, -0.2, 0.5, 0.7, -0.9, 0.2;
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(json["position"][i].get<double>(), kinematics.p_WT()[i], 1e-12);
  const Eigen::Quaterniond expected(kinematics.X_WT().linear());
  const Eigen::Quaterniond printed(json["quaternion"][0].get<double>(), json["quaternion"][1].get<double>(),
                                   json["quaternion"][2].get<double>(), json["quaternion"][3].get<double>());
  EXPECT_NEAR(std::abs(expected.dot(printed)), 1.0, 1e-12) << "[w,x,y,z] order";
  EXPECT_GE(json["quaternion"][0].get<double>(), 0.0);
  ASSERT_EQ(json["jacobian"].size(), 6U);
  ASSERT_EQ(json["jacobian"][0].size(), 9U);
  robot::Matrix6Xd J;
  kinematics.tipJacobian(J);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(json["jacobian"][r][c].get<double>(), J(r, c), 1e-12);
  }
}

// bench prints its suite entries with the fields PERFORMANCE.md names, counters too where a
// case has none, and says nothing on a stderr that is no terminal.
TEST(RobotCli, BenchEntriesHaveTheDocumentedFieldsAndNoProgressGoesToAFile) {
  const auto result = runCliBinary("bench --filter kinematics/fk_jacobian/arm9 --repetitions 2 --min-time 0.001");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.err.empty()) << result.err;
  const auto entries = result.json().at("benchmarks");
  ASSERT_EQ(entries.size(), 1U);
  for (const char* field : {"name", "median_us", "mean_us", "min_us", "max_us", "repetitions", "iterations", "counters"}) {
    EXPECT_TRUE(entries[0].contains(field)) << field << " in " << entries[0].dump();
  }
  EXPECT_TRUE(entries[0].at("counters").is_object());
  EXPECT_EQ(entries[0].at("repetitions"), 2);
  EXPECT_LE(entries[0].at("min_us").get<double>(), entries[0].at("median_us").get<double>());
}

TEST(RobotCli, AcceptsNegativeFirstJointValue) {
  const auto result = runCliBinary("fk --robot lwr4 --q -0.5,0.3,0,0,0,0,0");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(result.json()["beyond_limits"].empty());
  EXPECT_TRUE(result.err.empty()) << result.err;
}

// An arm whose mid-range posture hangs its forearm into the table: without --scene, reach starts
// where it starts in the empty scene (the nearest free posture), not in the table.
TEST(RobotCli, ReachWithoutASceneIsReachInTheEmptyScene) {
  const std::filesystem::path urdf = std::filesystem::temp_directory_path() / ("flexirob-reach-hanging-" + std::to_string(::getpid()) + ".urdf");
  testing::writeText(urdf, R"(<robot name="hanging"><link name="base"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
      <limit lower="1.0" upper="3.0" velocity="2" effort="100"/></joint>
    <link name="upper"><collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.03" length="0.4"/></geometry></collision></link>
    <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
      <limit lower="-0.5" upper="0.5" velocity="2" effort="100"/></joint>
    <link name="fore"><collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.03" length="0.3"/></geometry></collision></link>
    <joint name="j3" type="revolute"><parent link="fore"/><child link="hand"/><origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>
      <limit lower="-1" upper="1" velocity="2" effort="100"/></joint>
    <link name="hand"/></robot>)");
  const std::string target = " --target 0.6,0,0.45";
  const auto without = runCliBinary("reach --robot " + urdf.string() + target);
  const auto empty = runCliBinary("reach --robot " + urdf.string() + " --scene empty" + target);
  ASSERT_EQ(without.exit_code, empty.exit_code) << without.err << empty.err;
  const auto a = without.json(), b = empty.json();
  EXPECT_EQ(a.at("collisions"), b.at("collisions"));
  EXPECT_EQ(a.at("collisions"), 0) << without.out;
  EXPECT_EQ(a.at("q"), b.at("q"));
  std::filesystem::remove(urdf);
}

// -500,200,300 was meant in millimetres: "unreachable", 615 m short, had said nothing more.
TEST(RobotCli, ReachSaysATargetHundredsOfReachesAwayMayBeInMillimetres) {
  const auto millimetres = runCliBinary("reach --robot lwr4 --target -500,200,300 --max-time 5");
  ASSERT_EQ(millimetres.exit_code, 0) << millimetres.err;
  EXPECT_EQ(millimetres.json().at("status"), "unreachable");
  EXPECT_NE(millimetres.err.find("note: the target lies 616 m from the arm's shoulder"), std::string::npos) << millimetres.err;
  EXPECT_NE(millimetres.err.find("--target is read in metres (millimetres?)"), std::string::npos) << millimetres.err;
  // Out of reach, but in metres: nothing about units.
  const auto metres = runCliBinary("reach --robot lwr4 --target -1.5,0,0.3 --max-time 5");
  ASSERT_EQ(metres.exit_code, 0) << metres.err;
  EXPECT_EQ(metres.err.find("millimetres"), std::string::npos) << metres.err;
}

// reach drives the tip straight through what lies in the way (it plans nothing): a target below
// a slab is reached, but not as `eval reachable` counts it, and reach says so.
TEST(RobotCli, ReachSaysWhenTheTargetWasReachedOnlyThroughAContact) {
  const std::filesystem::path scene =
      std::filesystem::temp_directory_path() / ("flexirob-reach-slab-" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(scene) << "name: slab\nobstacles:\n  - {name: slab, shape: box, size: [0.3, 0.6, 0.04], position: [0.5, 0, 0.5]}\n";
  const std::string target = " --robot lwr4 --target 0.5,0,0.3 --scene ";
  const auto through = runCliBinary("reach" + target + scene.string());
  const auto free = runCliBinary("reach" + target + "empty");
  ASSERT_EQ(through.exit_code, 0) << through.err;
  ASSERT_EQ(free.exit_code, 0) << free.err;
  EXPECT_TRUE(through.json().at("reached").get<bool>());
  EXPECT_GT(through.json().at("collisions").get<int>(), 0);
  EXPECT_FALSE(through.json().at("reached_without_contact").get<bool>());
  EXPECT_NE(through.err.find("note: reached, but not free of contacts on the way: "), std::string::npos) << through.err;
  EXPECT_NE(through.err.find(" on slab"), std::string::npos) << through.err;
  EXPECT_TRUE(free.json().at("reached_without_contact").get<bool>());
  EXPECT_EQ(free.err.find("not free of contacts"), std::string::npos) << free.err;
  EXPECT_TRUE(through.json().at("inside_obstacle").is_null());
  // A target inside the slab: reached, and said to lie in it, as `eval` says of scene targets.
  const auto inside = runCliBinary("reach --robot lwr4 --target 0.5,0,0.5 --scene " + scene.string());
  ASSERT_EQ(inside.exit_code, 0) << inside.err;
  EXPECT_EQ(inside.json().at("inside_obstacle"), "slab");
  EXPECT_NE(inside.err.find("note: the target lies inside obstacle 'slab'"), std::string::npos) << inside.err;
  EXPECT_TRUE(free.json().at("inside_obstacle").is_null());
  std::filesystem::remove(scene);
}

// A 5 kg forearm held out level pulls about 10 Nm on its shoulder: with 2 Nm of effort the
// arm cannot hold itself, and reach says so beside its status; with 200 Nm it is silent.
TEST(RobotCli, ReachSaysWhenTheJointsCannotHoldTheArmUp) {
  const auto write_arm = [](double effort) {
    const std::filesystem::path urdf = std::filesystem::temp_directory_path() /
                                       ("flexirob-reach-weak-" + std::to_string(::getpid()) + "-" + std::to_string(static_cast<int>(effort)) + ".urdf");
    const std::string limit = "velocity=\"2\" effort=\"" + std::to_string(effort) + "\"";
    testing::writeText(urdf, R"(<robot name="weak"><link name="base"/>
      <joint name="j1" type="revolute"><parent link="base"/><child link="post"/><origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
        <limit lower="-3" upper="3" )" + limit + R"(/></joint>
      <link name="post"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="shoulder" type="revolute"><parent link="post"/><child link="fore"/><axis xyz="0 1 0"/>
        <limit lower="-2.5" upper="2.5" )" + limit + R"(/></joint>
      <link name="fore"><inertial><origin xyz="0 0 0.2"/><mass value="5"/><inertia ixx="0.07" iyy="0.07" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="elbow" type="revolute"><parent link="fore"/><child link="hand"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
        <limit lower="-2.5" upper="2.5" )" + limit + R"(/></joint>
      <link name="hand"><inertial><origin xyz="0 0 0.1"/><mass value="0.5"/><inertia ixx="0.002" iyy="0.002" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
      </robot>)");
    return urdf;
  };
  const std::filesystem::path weak = write_arm(2.0), strong = write_arm(200.0);
  const std::string target = " --target 0.45,0,0.45 --max-time 3 --scene empty";
  const auto sagging = runCliBinary("reach --robot " + weak.string() + target);
  const auto holding = runCliBinary("reach --robot " + strong.string() + target);
  ASSERT_EQ(sagging.exit_code, 0) << sagging.err;
  ASSERT_EQ(holding.exit_code, 0) << holding.err;
  const std::string overload = sagging.json().at("gravity_overload");
  EXPECT_NE(overload.find("joint 'shoulder' to hold"), std::string::npos) << overload;
  EXPECT_NE(sagging.err.find("warning: the joints cannot hold the arm up"), std::string::npos) << sagging.err;
  EXPECT_EQ(holding.json().at("gravity_overload"), "");
  EXPECT_EQ(holding.err.find("cannot hold"), std::string::npos) << holding.err;
  std::filesystem::remove(weak);
  std::filesystem::remove(strong);
}

TEST(RobotCli, FkNamesJointsBeyondTheirLimitsAndStillGivesThePose) {
  // A2 of the LWR IV stops at 120 deg = 2.094 rad; A4 at -120 deg.
  const auto result = runCliBinary("fk --robot lwr4 --q 0,2.5,0,-2.2,0,0,0");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  ASSERT_EQ(json["beyond_limits"].size(), 2U);
  EXPECT_EQ(json["beyond_limits"][0]["joint"], "A2");
  EXPECT_DOUBLE_EQ(json["beyond_limits"][0]["value"].get<double>(), 2.5);
  EXPECT_NEAR(json["beyond_limits"][0]["upper"].get<double>(), 120.0 * std::numbers::pi / 180.0, 1e-6);
  EXPECT_EQ(json["beyond_limits"][1]["joint"], "A4");
  Eigen::VectorXd q(7);
  q << 0, 2.5, 0, -2.2, 0, 0, 0;
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(json["position"][i].get<double>(), kinematics.p_WT()[i], 1e-12);
  ASSERT_FALSE(result.err.empty());
  EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "one line: " << result.err;
  EXPECT_NE(result.err.find("A2"), std::string::npos) << result.err;
}

struct BadInvocation {
  const char* arguments;
  const char* fragment;
};

void PrintTo(const BadInvocation& invocation, std::ostream* out) { *out << invocation.arguments; }

class CliRefuses : public ::testing::TestWithParam<BadInvocation> {};

TEST_P(CliRefuses, WithExitCode2AndOneLine) {
  const auto result = runCliBinary(GetParam().arguments);
  EXPECT_EQ(result.exit_code, 2) << result.out;
  EXPECT_TRUE(result.out.empty()) << "nothing on stdout: " << result.out;
  ASSERT_FALSE(result.err.empty());
  EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "one line: " << result.err;
  EXPECT_NE(result.err.find(GetParam().fragment), std::string::npos) << result.err;
}

INSTANTIATE_TEST_SUITE_P(
    BadInput, CliRefuses,
    ::testing::Values(BadInvocation{"fk --robot lwr4 --q 1,2,3", "expected 7 values, got 3"},
                      BadInvocation{"fk --robot lwr4 --q 1,2,3,4,5,6,nan", "not a finite number"},
                      BadInvocation{"fk --robot lwr4 --q 1,,3,4,5,6,7", "empty entry"},
                      BadInvocation{"fk --robot lwr4 --q 1,2,3,4,5,6,7,8", "expected 7 values, got 8"},
                      BadInvocation{"fk --robot lwr4 --q 1e999,0,0,0,0,0,0", "not a finite number"},
                      BadInvocation{"fk --robot lwr4 --q abc", "not a finite number"},
                      BadInvocation{"fk --robot /nonexistent.urdf --q 0", "nor a readable URDF file (no such file)"},
                      // A folder given for the URDF in it is named as a folder.
                      BadInvocation{"fk --robot / --q 0", "nor a readable URDF file (it is a folder)"},
                      BadInvocation{"render --scene / --out /dev/null", "nor a readable scene file (it is a folder)"},
                      BadInvocation{"fk --robot /etc/hostname --q 0", "invalid URDF"},
                      BadInvocation{"robot info --robot lwr4 --tip nowhere", "tip link 'nowhere'"},
                      BadInvocation{"fk --robot lwr4", "--q is required"},
                      // A command mistyped is named, with the one meant and the commands there are.
                      BadInvocation{"no-such-command", "unknown command 'no-such-command'; the commands are robot, fk,"},
                      BadInvocation{"eval reachabel --session s.flexirob", "eval: unknown command 'reachabel' (did you mean reachable?)"},
                      BadInvocation{"learn", "learn: a command is needed (fit, predict)"},
                      BadInvocation{"eval --session s.flexirob", "eval: a command is needed (reachable, scene-model, trajectories)"},
                      // A slip in an option's name: the option meant is named.
                      BadInvocation{"teach --area 2 --out x.db", "(--area: did you mean --areas?)"},
                      BadInvocation{"reach --robot lwr4 --taget=0,0,1", "(--taget: did you mean --target?)"}),
    [](const ::testing::TestParamInfo<BadInvocation>& param_info) { return "Case" + std::to_string(param_info.index); });

}  // namespace
}  // namespace flexirob
