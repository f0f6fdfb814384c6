#include "robot/robot_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "test_urdf.hpp"

namespace flexirob::robot {
namespace {

using flexirob::testing::TempDir;
constexpr double kDeg = std::numbers::pi / 180.0;

std::string twoJointArm(const std::string& extra_links = "", const std::string& tail_joint_type = "revolute") {
  return R"(<?xml version="1.0"?>
<robot name="two">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="2" effort="10"/></joint>
  <link name="l1"><inertial><origin xyz="0 0 0.25"/><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type=")" + tail_joint_type + R"("><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="3" effort="5"/></joint>
  <link name="l2"/>
  <joint name="tool_joint" type="fixed"><parent link="l2"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
  <link name="tool"><inertial><origin xyz="0 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
)" + extra_links + "</robot>\n";
}

TEST(RobotModel, ReadsTheLwr4JointsAndLimitsFromItsUrdf) {
  const auto model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  ASSERT_EQ(model.dof(), 7);
  EXPECT_EQ(model.baseLink(), "base_link");
  EXPECT_EQ(model.tipLink(), "flange");
  const double hardware[7] = {170, 120, 170, 120, 170, 120, 170};
  const double velocity[7] = {110, 110, 128, 128, 204, 184, 184};
  const double effort[7] = {176, 176, 100, 100, 100, 38, 38};
  for (int j = 0; j < 7; ++j) {
    const auto& limits = model.joints()[static_cast<std::size_t>(j)].limits;
    EXPECT_NEAR(limits.upper, hardware[j] * kDeg, 1e-5) << "joint " << j;
    EXPECT_NEAR(limits.lower, -hardware[j] * kDeg, 1e-5) << "joint " << j;
    EXPECT_LT(limits.soft_upper, limits.upper) << "software limits are tighter";
    EXPECT_GT(limits.soft_lower, limits.lower);
    EXPECT_NEAR(limits.velocity, velocity[j] * kDeg, 1e-5);
    EXPECT_DOUBLE_EQ(limits.effort, effort[j]);
  }
  // The thesis' prototype kept A6 within +-115 deg.
  EXPECT_NEAR(model.joints()[5].limits.soft_upper, 115 * kDeg, 1e-5);
}

TEST(RobotModel, Arm9DuplicatesTheA3A4SegmentOfTheLwr4) {
  const auto lwr = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const auto arm9 = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  ASSERT_EQ(arm9.dof(), 9);
  // Chain order A1 A2 A3 A4 A3' A4' A5 A6 A7: each joint copies the limits of its original.
  const int original[9] = {0, 1, 2, 3, 2, 3, 4, 5, 6};
  for (int j = 0; j < 9; ++j) {
    EXPECT_DOUBLE_EQ(arm9.joints()[static_cast<std::size_t>(j)].limits.upper,
                     lwr.joints()[static_cast<std::size_t>(original[j])].limits.upper);
    EXPECT_DOUBLE_EQ(arm9.bodies()[static_cast<std::size_t>(j + 1)].mass,
                     lwr.bodies()[static_cast<std::size_t>(original[j] + 1)].mass);
  }
}

TEST(RobotModel, EveryLinkOfOurRobotsHasVisualAndCollisionGeometry) {
  for (const auto& name : builtinRobotNames()) {
    const auto model = RobotModel::fromUrdfFile(resolveRobotPath(name));
    for (const auto& body : model.bodies()) {
      EXPECT_FALSE(body.visuals.empty()) << name << ": " << body.name;
      EXPECT_FALSE(body.collisions.empty()) << name << ": " << body.name;
      for (const auto& visual : body.visuals) {
        EXPECT_TRUE(std::filesystem::is_regular_file(visual.mesh_file)) << visual.mesh_file;
      }
    }
    double mass = 0;
    for (const auto& body : model.bodies()) mass += body.mass;
    EXPECT_GT(mass, 10.0) << name;
  }
}

TEST(RobotModel, FoldsFixedJointsIntoTheirMovableParent) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfFile(dir.write("two.urdf", twoJointArm()));
  ASSERT_EQ(model.dof(), 2);
  EXPECT_EQ(model.tipLink(), "tool") << "default tip is the end of the longest chain, past fixed joints";
  EXPECT_TRUE(model.X_LastBodyTip().translation().isApprox(Eigen::Vector3d(0.3, 0, 0)));
  // The tool's 1 kg at (0.3, 0, 0) is the last body's whole mass.
  EXPECT_DOUBLE_EQ(model.bodies()[2].mass, 1.0);
  EXPECT_TRUE(model.bodies()[2].p_BCom.isApprox(Eigen::Vector3d(0.3, 0, 0)));
  EXPECT_EQ(model.bodies()[2].folded_links, std::vector<std::string>{"tool"});
}

TEST(RobotModel, CombinesInertiaOfFoldedLinksWithTheParallelAxisTheorem) {
  TempDir dir;
  // Two point-like masses of 1 kg, 0.2 m apart along x, folded into one body.
  const std::string urdf = R"(<robot name="fold">
    <link name="base"/>
    <joint name="j" type="continuous"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/></joint>
    <link name="a"><inertial><origin xyz="-0.1 0 0"/><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
    <joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.1 0 0"/></joint>
    <link name="b"><inertial><origin xyz="0 0 0"/><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  </robot>)";
  const auto model = RobotModel::fromUrdfString(urdf, dir.path());
  const Body& body = model.bodies()[1];
  EXPECT_DOUBLE_EQ(body.mass, 2.0);
  EXPECT_NEAR(body.p_BCom.norm(), 0.0, 1e-12);
  // Two 1 kg points at +-0.1 m along x: Iyy = Izz = 2 * 1 * 0.01, Ixx = 0.
  EXPECT_NEAR(body.I_BCom(0, 0), 0.0, 1e-12);
  EXPECT_NEAR(body.I_BCom(1, 1), 0.02, 1e-12);
  EXPECT_NEAR(body.I_BCom(2, 2), 0.02, 1e-12);
  EXPECT_TRUE(std::isinf(model.joints()[0].limits.upper)) << "continuous joints are unbounded";
}

TEST(RobotModel, AMovingLinkWithoutMassWeighsTheAssumedMassAtTheMiddleOfItsLink) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfString(flexirob::testing::masslessArm(), dir.path());
  ASSERT_EQ(model.bodies().size(), 4U);
  EXPECT_FALSE(model.bodies()[0].inertia_assumed) << "the base does not move";
  for (std::size_t b = 1; b < 4; ++b) {
    EXPECT_TRUE(model.bodies()[b].inertia_assumed) << b;
    EXPECT_DOUBLE_EQ(model.bodies()[b].mass, kAssumedMass) << b;
  }
  // l1 spans 0.4 m to the next joint: centre at 0.2 m, a sphere of radius 0.2 m.
  EXPECT_TRUE(model.bodies()[1].p_BCom.isApprox(Eigen::Vector3d(0.0, 0.0, 0.2)));
  EXPECT_TRUE(model.bodies()[1].I_BCom.isApprox(0.4 * kAssumedMass * 0.04 * Eigen::Matrix3d::Identity()));
  // l2 is 4 cm short: the sphere keeps its least radius.
  EXPECT_TRUE(model.bodies()[2].p_BCom.isApprox(Eigen::Vector3d(0.0, 0.0, 0.02)));
  EXPECT_TRUE(model.bodies()[2].I_BCom.isApprox(
      0.4 * kAssumedMass * kAssumedMinRadius * kAssumedMinRadius * Eigen::Matrix3d::Identity()));
  // The last link ends at the tip.
  EXPECT_TRUE(model.bodies()[3].p_BCom.isApprox(Eigen::Vector3d(0.15, 0.0, 0.0)));
  // A body that weighs something keeps its own inertia.
  const auto two = RobotModel::fromUrdfFile(dir.write("two.urdf", twoJointArm()));
  EXPECT_FALSE(two.bodies()[1].inertia_assumed);
  EXPECT_DOUBLE_EQ(two.bodies()[1].mass, 2.0);
}

TEST(RobotModel, GivesAnUnboundedJointOneTurnToDrawPosturesFrom) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfFile(dir.write("c.urdf", twoJointArm("", "continuous")));
  ASSERT_TRUE(std::isinf(model.softUpperLimits()[1]));
  const Eigen::VectorXd lower = model.sampleLowerLimits();
  const Eigen::VectorXd upper = model.sampleUpperLimits();
  EXPECT_DOUBLE_EQ(lower[0], model.softLowerLimits()[0]) << "a bounded joint keeps its limits";
  EXPECT_DOUBLE_EQ(upper[0], model.softUpperLimits()[0]);
  EXPECT_DOUBLE_EQ(lower[1], -std::numbers::pi);
  EXPECT_DOUBLE_EQ(upper[1], std::numbers::pi);
  EXPECT_DOUBLE_EQ(model.midPosture()[1], 0.0) << "the default posture of an unbounded joint";
}

TEST(RobotModel, PosturesDifferByTheShorterWayRoundOnAnUnboundedJointOnly) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfFile(dir.write("c.urdf", twoJointArm("", "continuous")));
  const Eigen::Vector2d to(0.5, 0.3 + 4.0 * std::numbers::pi), from(0.2, 0.1);
  const Eigen::VectorXd difference = model.postureDifference(to, from);
  EXPECT_NEAR(difference[0], 0.3, 1e-12) << "a bounded joint: the plain difference";
  EXPECT_NEAR(difference[1], 0.2, 1e-9) << "two turns are no difference";
  // Past half a turn the other way round is shorter.
  EXPECT_NEAR(model.postureDifference(Eigen::Vector2d(0.0, 3.0), Eigen::Vector2d(0.0, -3.0))[1], 6.0 - 2.0 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(model.postureDifference(Eigen::Vector2d(3.0, 0.0), Eigen::Vector2d(-3.0, 0.0))[0], 6.0, 1e-12);
}

TEST(RobotModel, AJointWithoutAVelocityLimitGetsTheDocumentedOneInsteadOfStandingStill) {
  TempDir dir;
  std::string urdf = twoJointArm();
  const std::string given = R"(velocity="3")";
  urdf.replace(urdf.find(given), given.size(), R"(velocity="0")");
  const auto model = RobotModel::fromUrdfFile(dir.write("zero.urdf", urdf));
  EXPECT_TRUE(model.joints()[0].limits.velocity_from_urdf);
  EXPECT_DOUBLE_EQ(model.velocityLimits()[0], 2.0);
  EXPECT_FALSE(model.joints()[1].limits.velocity_from_urdf);
  EXPECT_DOUBLE_EQ(model.velocityLimits()[1], kUnspecifiedVelocityLimit);
  ASSERT_EQ(model.notes().size(), 1U);
  EXPECT_NE(model.notes()[0].find("joint 'j2' gives <limit velocity=\"0\">: read as not given, 1 rad/s"), std::string::npos)
      << model.notes()[0];
}

// A URDF written for kinematics often gives effort="0"; read as no limit, which is said.
TEST(RobotModel, SaysWhichJointsGiveAZeroEffortLimit) {
  std::string urdf = twoJointArm();
  for (const std::string given : {R"(effort="10")", R"(effort="5")"}) urdf.replace(urdf.find(given), given.size(), R"(effort="0")");
  const RobotModel model = RobotModel::fromUrdfString(urdf, ".");
  EXPECT_DOUBLE_EQ(model.joints()[0].limits.effort, 0.0);
  ASSERT_EQ(model.notes().size(), 1U);
  EXPECT_NE(model.notes()[0].find("joints 'j1', 'j2' give <limit effort=\"0\">: read as no effort limit"), std::string::npos)
      << model.notes()[0];
  EXPECT_TRUE(RobotModel::fromUrdfString(twoJointArm(), ".").notes().empty());
}

// mass="0" on one link of an arm whose other links weigh something is a slip, not a choice: the
// simulated 1 kg is said. A URDF with no masses at all gets the assumed masses without a word.
TEST(RobotModel, SaysWhichBodiesGetTheAssumedMassWhenOthersGiveTheirs) {
  std::string urdf = twoJointArm();
  const std::string given = R"(<mass value="2"/>)";
  urdf.replace(urdf.find(given), given.size(), R"(<mass value="0"/>)");
  const RobotModel model = RobotModel::fromUrdfString(urdf, ".");
  ASSERT_EQ(model.notes().size(), 1U);
  EXPECT_NE(model.notes()[0].find("moving body 'l1' gives no mass"), std::string::npos) << model.notes()[0];
  EXPECT_NE(model.notes()[0].find("simulated as 1 kg"), std::string::npos) << model.notes()[0];
  EXPECT_TRUE(model.bodies()[1].inertia_assumed);
  EXPECT_DOUBLE_EQ(model.bodies()[1].mass, kAssumedMass);
  EXPECT_TRUE(RobotModel::fromUrdfString(twoJointArm(), ".").notes().empty());
}

// A joint locked by its limits stays in the posture vector, and the model says it never moves.
TEST(RobotModel, SaysWhichJointsEqualLimitsLockInPlace) {
  std::string urdf = twoJointArm();
  const std::string given = R"(lower="-2" upper="2")";
  urdf.replace(urdf.find(given), given.size(), R"(lower="0.25" upper="0.25")");
  const RobotModel model = RobotModel::fromUrdfString(urdf, ".");
  ASSERT_EQ(model.dof(), 2);
  EXPECT_DOUBLE_EQ(model.midPosture()[1], 0.25);
  ASSERT_EQ(model.notes().size(), 1U);
  EXPECT_NE(model.notes()[0].find("equal lower and upper limits lock joint 'j2' at 0.25 in place"), std::string::npos)
      << model.notes()[0];
}

// lower="-110" upper="110" was meant in degrees; read as radians the joint turns 35 times round.
TEST(RobotModel, SaysWhichRevoluteLimitsLookWrittenInDegrees) {
  std::string urdf = twoJointArm();
  const std::string given = R"(lower="-2" upper="2")";
  urdf.replace(urdf.find(given), given.size(), R"(lower="-110" upper="110")");
  const RobotModel degrees = RobotModel::fromUrdfString(urdf, ".");
  ASSERT_EQ(degrees.notes().size(), 1U);
  EXPECT_EQ(degrees.notes()[0], "revolute joint limits beyond two turns either way, 'j2' [-110, 110] rad: URDF limits are radians (written in degrees?)");
  // A multi-turn wrist of two turns each way is a real joint.
  std::string two_turns = twoJointArm();
  two_turns.replace(two_turns.find(given), given.size(), R"(lower="-12.566" upper="12.566")");
  EXPECT_TRUE(RobotModel::fromUrdfString(two_turns, ".").notes().empty());
}

// Principal moments of a solid body satisfy the triangle inequality (I1 + I2 >= I3) and are
// not negative; Bullet takes them as given, so a set that breaks either is said.
TEST(RobotModel, SaysWhichLinkHasAnInertiaNoSolidBodyHas) {
  const std::string thin_rod = R"(ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.01")";
  for (const auto& [inertia, reason] : std::vector<std::pair<std::string, std::string>>{
           {R"(ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.3")", "the largest above the sum of the other two"},
           {R"(ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="-0.01")", "one below zero"},
           // Diagonal moments that look fine, products that make one principal moment negative.
           {R"(ixx="0.1" ixy="0.2" ixz="0" iyy="0.1" iyz="0" izz="0.1")", "one below zero"}}) {
    std::string urdf = twoJointArm();
    urdf.replace(urdf.find(thin_rod), thin_rod.size(), inertia);
    const RobotModel model = RobotModel::fromUrdfString(urdf, ".");
    ASSERT_EQ(model.notes().size(), 1U) << inertia;
    EXPECT_NE(model.notes()[0].find("link 'l1' has an inertia no solid body has"), std::string::npos) << model.notes()[0];
    EXPECT_NE(model.notes()[0].find(reason), std::string::npos) << model.notes()[0];
  }
  // A thin rod (I3 near 0, I1 = I2) and a flat plate (I1 + I2 = I3 exactly) are solid bodies.
  for (const std::string inertia : {R"(ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0")",
                                    R"(ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3")"}) {
    std::string urdf = twoJointArm();
    urdf.replace(urdf.find(thin_rod), thin_rod.size(), inertia);
    EXPECT_TRUE(RobotModel::fromUrdfString(urdf, ".").notes().empty()) << inertia;
  }
}

TEST(RobotModel, AcceptsAnExplicitTipInsideTheChain) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfFile(dir.write("two.urdf", twoJointArm()), "l1");
  EXPECT_EQ(model.dof(), 1);
  EXPECT_EQ(model.tipLink(), "l1");
}

TEST(RobotModel, LinksOffTheChainMoveWithTheLinkTheyHangFromTheirJointHeldStill) {
  TempDir dir;
  // A finger on a prismatic joint whose range [0.02, 0.04] m excludes 0: held at 0.02.
  const std::string finger = R"(
  <joint name="finger_joint" type="prismatic"><parent link="l2"/><child link="finger"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 2"/><limit lower="0.02" upper="0.04" velocity="1" effort="1"/></joint>
  <link name="finger">
    <inertial><origin xyz="0 0 0"/><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><geometry><box size="0.01 0.02 0.03"/></geometry></collision>
  </link>
)";
  const auto model = RobotModel::fromUrdfFile(dir.write("finger.urdf", twoJointArm(finger)), "tool");
  ASSERT_EQ(model.dof(), 2);
  const Body& hand = model.bodies()[2];
  EXPECT_EQ(hand.held_links, std::vector<std::string>{"finger"});
  EXPECT_DOUBLE_EQ(hand.mass, 1.5);
  // Tool (1 kg at x = 0.3) and finger (0.5 kg at (0.1, 0, 0.02)).
  EXPECT_TRUE(hand.p_BCom.isApprox(Eigen::Vector3d(0.35 / 1.5, 0.0, 0.01 / 1.5))) << hand.p_BCom.transpose();
  ASSERT_EQ(hand.collisions.size(), 1U);
  EXPECT_TRUE(hand.collisions[0].X_BG.translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.02)));

  // A tip inside the chain: the links past it ride on its body, the joint between held at 0.
  const auto short_arm = RobotModel::fromUrdfFile(dir.write("finger.urdf", twoJointArm(finger)), "l1");
  ASSERT_EQ(short_arm.dof(), 1);
  const Body& last = short_arm.bodies()[1];
  EXPECT_EQ(last.held_links, (std::vector<std::string>{"l2", "finger"}));
  EXPECT_DOUBLE_EQ(last.mass, 3.5);
  ASSERT_EQ(last.collisions.size(), 1U);
  EXPECT_TRUE(last.collisions[0].X_BG.translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.52)));
}

TEST(RobotModel, SupportsPrismaticJoints) {
  TempDir dir;
  const auto model = RobotModel::fromUrdfFile(dir.write("p.urdf", twoJointArm("", "prismatic")));
  ASSERT_EQ(model.joints()[1].type, JointType::kPrismatic);
  Eigen::VectorXd q(2);
  q << 0.0, 0.25;
  // The prismatic axis is y in l1's frame: the tool moves 0.25 m along world y.
  EXPECT_TRUE(tipPose(model, q).translation().isApprox(Eigen::Vector3d(0.3, 0.25, 0.6)));
}

TEST(RobotModel, ReadsSoftLimitsFromTheSafetyController) {
  TempDir dir;
  const std::string urdf = R"(<robot name="soft"><link name="base"/>
    <joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
      <limit lower="-2" upper="2" velocity="1" effort="1"/>
      <safety_controller soft_lower_limit="-1.5" soft_upper_limit="3" k_position="1" k_velocity="1"/></joint>
    <link name="a"/></robot>)";
  const auto model = RobotModel::fromUrdfString(urdf, dir.path());
  EXPECT_DOUBLE_EQ(model.joints()[0].limits.soft_lower, -1.5);
  EXPECT_DOUBLE_EQ(model.joints()[0].limits.soft_upper, 2.0) << "never wider than the hardware limit";
  EXPECT_DOUBLE_EQ(model.midPosture()[0], 0.25);
}

// Every malformed description is refused with a one-line InputError naming the problem.
struct BrokenUrdf {
  const char* label;
  std::string xml;
  std::string tip;
  const char* expected_fragment;
};

void PrintTo(const BrokenUrdf& broken, std::ostream* out) { *out << broken.label; }

class RefusesBrokenUrdf : public ::testing::TestWithParam<BrokenUrdf> {};

TEST_P(RefusesBrokenUrdf, WithAOneLineReason) {
  TempDir dir;
  const auto& broken = GetParam();
  try {
    RobotModel::fromUrdfFile(dir.write("broken.urdf", broken.xml), broken.tip);
    FAIL() << "accepted " << broken.label;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(broken.expected_fragment), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, RefusesBrokenUrdf,
    ::testing::Values(
        BrokenUrdf{"malformed XML", "<robot name='x'><link name='a'>", "", "invalid URDF"},
        BrokenUrdf{"not XML", std::string("\x00\x01\x02garbage", 10), "", "invalid URDF"},
        BrokenUrdf{"empty file", "", "", "invalid URDF"},
        BrokenUrdf{"plain text", "this is a robot\n", "", "no XML element in the file"},
        BrokenUrdf{"a link a kilometre off",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<origin xyz='0 0 1000'/><axis xyz='0 0 1'/></joint><link name='b'/></robot>",
                   "", "joint 'j': origin 1000 m from its parent link, beyond 100 m"},
        BrokenUrdf{"a link in millimetres",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<origin xyz='0 0 310'/><axis xyz='0 0 1'/></joint><link name='b'/></robot>",
                   "", "(a URDF is in metres)"},
        BrokenUrdf{"revolute limits of 1e300 rad",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/><limit lower='-1e300' upper='1e300' velocity='1' effort='1'/></joint><link name='b'/></robot>",
                   "", "beyond ±1000 rad; a joint that turns without end is of type 'continuous'"},
        BrokenUrdf{"a slide a kilometre long",
                   "<robot name='x'><link name='a'/><joint name='j' type='prismatic'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/><limit lower='0' upper='1000' velocity='1' effort='1'/></joint><link name='b'/></robot>",
                   "", "limits [0, 1000] beyond ±100 m"},
        BrokenUrdf{"missing tip link", twoJointArm(), "nonexistent", "tip link 'nonexistent'"},
        BrokenUrdf{"a mesh scaled flat",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/></joint><link name='b'><visual><geometry><mesh filename='b.stl' scale='0 0.001 0.001'/>"
                   "</geometry></visual></link></robot>",
                   "", "link 'b': mesh 'b.stl' has a scale with a zero component"},
        BrokenUrdf{"joint to a missing link",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
                   "<child link='ghost'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' velocity='1' effort='1'/></joint></robot>",
                   "", "invalid URDF"},
        BrokenUrdf{"software limits above the hardware range",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
                   "<child link='b'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' velocity='1' effort='1'/>"
                   "<safety_controller soft_lower_limit='1.5' soft_upper_limit='3' k_velocity='1'/></joint><link name='b'/></robot>",
                   "", "soft limits lie outside"},
        BrokenUrdf{"software limits below the hardware range",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
                   "<child link='b'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' velocity='1' effort='1'/>"
                   "<safety_controller soft_lower_limit='-3' soft_upper_limit='-2' k_velocity='1'/></joint><link name='b'/></robot>",
                   "", "soft limits lie outside"},
        BrokenUrdf{"software limits the wrong way round",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
                   "<child link='b'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' velocity='1' effort='1'/>"
                   "<safety_controller soft_lower_limit='0.5' soft_upper_limit='-0.5' k_velocity='1'/></joint><link name='b'/></robot>",
                   "", "soft_lower_limit lies above soft_upper_limit"},
        BrokenUrdf{"floating joint on the chain",
                   "<robot name='x'><link name='a'/><joint name='free' type='floating'><parent link='a'/>"
                   "<child link='b'/></joint><link name='b'/></robot>",
                   "b", "floating joints are not supported"},
        BrokenUrdf{"planar joint on the chain",
                   "<robot name='x'><link name='a'/><joint name='p' type='planar'><parent link='a'/>"
                   "<child link='b'/><axis xyz='0 0 1'/></joint><link name='b'/></robot>",
                   "b", "planar joints are not supported"},
        BrokenUrdf{"two equally long chains",
                   "<robot name='x'><link name='a'/>"
                   "<joint name='l' type='continuous'><parent link='a'/><child link='left'/><axis xyz='0 0 1'/></joint><link name='left'/>"
                   "<joint name='r' type='continuous'><parent link='a'/><child link='right'/><axis xyz='0 0 1'/></joint><link name='right'/>"
                   "</robot>",
                   "", "not a serial chain"},
        BrokenUrdf{"missing mesh file",
                   twoJointArm("<link name='deco'><visual><geometry><mesh filename='package://nowhere/m.stl'/></geometry></visual></link>"
                               "<joint name='d' type='fixed'><parent link='tool'/><child link='deco'/></joint>"),
                   "", "mesh file 'package://nowhere/m.stl' not found (looked for its package folder among the URDF's parent folders and in $ROS_PACKAGE_PATH"},
        BrokenUrdf{"missing mesh file beside the URDF",
                   twoJointArm("<link name='deco'><visual><geometry><mesh filename='meshes/m.stl'/></geometry></visual></link>"
                               "<joint name='d' type='fixed'><parent link='tool'/><child link='deco'/></joint>"),
                   "", "mesh file 'meshes/m.stl' not found (relative to the URDF's folder /"},
        BrokenUrdf{"no movable joint",
                   "<robot name='x'><link name='a'/><joint name='f' type='fixed'><parent link='a'/><child link='b'/></joint><link name='b'/></robot>",
                   "", "no movable joint"},
        BrokenUrdf{"revolute joint without limits",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/></joint><link name='b'/></robot>",
                   "", "invalid URDF"},
        BrokenUrdf{"inverted limits",
                   "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/><limit lower='1' upper='-1' velocity='1' effort='1'/></joint><link name='b'/></robot>",
                   "", "lower <= upper"},
        BrokenUrdf{"non-finite origin",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<origin xyz='nan 0 0'/><axis xyz='0 0 1'/></joint><link name='b'/></robot>",
                   "", "invalid URDF"},
        BrokenUrdf{"negative mass",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 1'/></joint><link name='b'><inertial><mass value='-2'/>"
                   "<inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link></robot>",
                   "", "mass must be"},
        BrokenUrdf{"zero axis",
                   "<robot name='x'><link name='a'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/>"
                   "<axis xyz='0 0 0'/></joint><link name='b'/></robot>",
                   "", "axis"}),
    [](const ::testing::TestParamInfo<BrokenUrdf>& param_info) {
      std::string name = param_info.param.label;
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

// A recording reviewed where the robot's mesh folder is not: the arm without that mesh, and why.
TEST(RobotModel, LeavesOutAMissingMeshWhenAskedAndNamesIt) {
  TempDir dir;
  const std::string xml = twoJointArm(
      "<link name='deco'><visual><geometry><mesh filename='meshes/gone.stl'/></geometry></visual>"
      "<visual><geometry><box size='0.1 0.1 0.1'/></geometry></visual>"
      "<collision><geometry><mesh filename='meshes/gone.stl'/></geometry></collision></link>"
      "<joint name='d' type='fixed'><parent link='tool'/><child link='deco'/></joint>");
  EXPECT_THROW(RobotModel::fromUrdfString(xml, dir.path()), InputError);
  std::vector<std::string> left_out;
  const RobotModel model = RobotModel::fromUrdfString(xml, dir.path(), "", &left_out);
  ASSERT_EQ(left_out.size(), 2U);  // the visual and the collision element
  EXPECT_NE(left_out[0].find("mesh file 'meshes/gone.stl' not found"), std::string::npos) << left_out[0];
  const Body& last = model.bodies().back();
  bool box = false;
  for (const Geometry& visual : last.visuals) {
    EXPECT_NE(visual.kind, Geometry::Kind::kMesh);
    box = box || visual.kind == Geometry::Kind::kBox;
  }
  EXPECT_TRUE(box) << "the link's other geometry stays";
  // Anything else that is wrong still refuses the URDF.
  EXPECT_THROW(RobotModel::fromUrdfString("<robot name='x'><link name='a'>", dir.path(), "", &left_out), InputError);
}

TEST(RobotModel, ResolvesPackageAndRelativeMeshUris) {
  TempDir dir;
  dir.write("my_robot/meshes/part.stl", "solid x\nendsolid x\n");
  dir.write("my_robot/urdf/local.stl", "solid x\nendsolid x\n");
  const auto urdf = dir.write(
      "my_robot/urdf/robot.urdf",
      twoJointArm("<link name='deco'><visual><geometry><mesh filename='package://my_robot/meshes/part.stl'/></geometry></visual>"
                  "<collision><geometry><mesh filename='local.stl' scale='0.001 0.001 0.001'/></geometry></collision></link>"
                  "<joint name='d' type='fixed'><parent link='tool'/><child link='deco'/><origin xyz='0 0 0.1'/></joint>"));
  const auto model = RobotModel::fromUrdfFile(urdf);
  const Body& last = model.bodies().back();
  ASSERT_EQ(last.visuals.size(), 1U);
  EXPECT_EQ(last.visuals[0].mesh_file.filename(), "part.stl");
  EXPECT_EQ(last.visuals[0].source_link, "deco");
  // deco hangs 0.1 m above the tool, which is 0.3 m along x of l2.
  EXPECT_TRUE(last.visuals[0].X_BG.translation().isApprox(Eigen::Vector3d(0.3, 0, 0.1)));
  ASSERT_EQ(last.collisions.size(), 1U);
  EXPECT_EQ(last.collisions[0].mesh_file.filename(), "local.stl");
  EXPECT_DOUBLE_EQ(last.collisions[0].mesh_scale.x(), 0.001);
}

// file:// URIs as exporters write them (RFC 8089): absolute, with the host 'localhost', with a
// space as %20, and (not in the RFC, but written) relative to the URDF's folder.
TEST(RobotModel, ResolvesFileUrisWithAHostEscapesOrARelativePath) {
  TempDir dir;
  const auto part = dir.write("my robot/meshes/part.stl", "solid x\nendsolid x\n");
  const std::string absolute = part.string();
  std::string escaped;
  for (const char c : absolute) escaped += c == ' ' ? std::string("%20") : std::string(1, c);
  for (const std::string& uri : {"file://" + absolute, "file://" + escaped, "file://localhost" + escaped, std::string("file://meshes/part.stl")}) {
    const auto urdf = dir.write("my robot/robot.urdf", twoJointArm("<link name='deco'><visual><geometry><mesh filename='" + uri +
                                                                    "'/></geometry></visual></link><joint name='d' type='fixed'>"
                                                                    "<parent link='tool'/><child link='deco'/></joint>"));
    const auto model = RobotModel::fromUrdfFile(urdf);
    ASSERT_EQ(model.bodies().back().visuals.size(), 1U) << uri;
    EXPECT_TRUE(std::filesystem::equivalent(model.bodies().back().visuals[0].mesh_file, part)) << uri;
  }
  // An escaped NUL would end the path where the system reads it: part.stl%00.dae opening part.stl.
  const auto nul = dir.write("my robot/nul.urdf", twoJointArm("<link name='deco'><visual><geometry><mesh filename='file://" + escaped +
                                                               "%00.dae'/></geometry></visual></link><joint name='d' type='fixed'>"
                                                               "<parent link='tool'/><child link='deco'/></joint>"));
  try {
    RobotModel::fromUrdfFile(nul);
    FAIL() << "a URI escaping a NUL was read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("escapes a control byte"), std::string::npos) << error.what();
  }
  // Another machine's file cannot be read; the message says how to name one on this machine.
  const auto remote = dir.write("my robot/remote.urdf", twoJointArm("<link name='deco'><visual><geometry><mesh filename='file://cadserver/parts/part.stl"
                                                                     "'/></geometry></visual></link><joint name='d' type='fixed'>"
                                                                     "<parent link='tool'/><child link='deco'/></joint>"));
  try {
    RobotModel::fromUrdfFile(remote);
    FAIL() << "a file on another host was read";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("if 'cadserver' is a host name"), std::string::npos) << message;
    EXPECT_NE(message.find("file:///path"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(RobotModel, RefusesANonexistentFileAndUnknownRobotName) {
  EXPECT_THROW(RobotModel::fromUrdfFile("/nonexistent/robot.urdf"), InputError);
  EXPECT_THROW(resolveRobotPath("not_a_robot"), InputError);
}

TEST(RobotModel, ChecksPostureSizeAndFiniteness) {
  const auto model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  EXPECT_THROW(model.checkPosture(Eigen::VectorXd::Zero(6)), InputError);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  EXPECT_NO_THROW(model.checkPosture(q));
  q[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(model.checkPosture(q), InputError);
}

// A 2-joint arm whose hand carries two fingers: the left one slides, the right one slides as its
// mimic (or is fixed), with a fingertip link on the right where `tip_on_right`.
std::string armWithAGripper(bool right_finger_moves, bool tip_on_right) {
  std::string urdf = R"(<robot name="gripper_arm">)" + flexirob::testing::twoMasslessJointsToL2() + R"(
    <joint name="hand_mount" type="fixed"><parent link="l2"/><child link="hand"/><origin xyz="0.3 0 0"/></joint>
    <link name="hand"/>
    <joint name="left_finger" type="prismatic"><parent link="hand"/><child link="finger_l"/><origin xyz="0.05 0.02 0"/>
      <axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.1" effort="20"/></joint>
    <link name="finger_l"/>)";
  urdf += right_finger_moves ? R"(
    <joint name="right_finger" type="prismatic"><parent link="hand"/><child link="finger_r"/><origin xyz="0.05 -0.02 0"/>
      <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" velocity="0.1" effort="20"/><mimic joint="left_finger"/></joint>)"
                             : R"(
    <joint name="right_finger" type="fixed"><parent link="hand"/><child link="finger_r"/><origin xyz="0.05 -0.02 0"/></joint>)";
  urdf += R"(
    <link name="finger_r"/>)";
  if (tip_on_right) {
    urdf += R"(
    <joint name="right_tip" type="fixed"><parent link="finger_r"/><child link="fingertip_r"/><origin xyz="0.02 0 0"/></joint>
    <link name="fingertip_r"/>)";
  }
  return urdf + "\n  </robot>";
}

// Most arms' descriptions carry a gripper. Where the longest chain ends in its one moving finger,
// the slide becomes the arm's last joint; it is said, with the tip that ends the arm before it.
TEST(RobotModel, SaysWhenTheDefaultTipIsPastAGrippersSlide) {
  const RobotModel one_finger = RobotModel::fromUrdfString(armWithAGripper(false, false), ".");
  EXPECT_EQ(one_finger.tipLink(), "finger_l");
  EXPECT_EQ(one_finger.dof(), 3);
  ASSERT_EQ(one_finger.notes().size(), 1U);
  EXPECT_NE(one_finger.notes()[0].find("past the slide 'left_finger' where 'hand' branches"), std::string::npos) << one_finger.notes()[0];
  EXPECT_NE(one_finger.notes()[0].find("--tip hand"), std::string::npos) << one_finger.notes()[0];
  // Named, the tip is the user's choice; an arm without a gripper has nothing to say.
  EXPECT_TRUE(RobotModel::fromUrdfString(armWithAGripper(false, false), ".", "finger_l").notes().empty());
  EXPECT_EQ(RobotModel::fromUrdfString(armWithAGripper(false, false), ".", "hand").dof(), 2);
  EXPECT_TRUE(RobotModel::fromUrdfString(flexirob::testing::masslessArm(), ".").notes().empty());
}

// The usual gripper: two fingers of one joint each, equally long. Every command had refused the
// arm ("not a serial chain") unless told --tip; the tip is the hand they branch from, said.
TEST(RobotModel, TakesTheHandTwoEquallyLongFingersBranchFromAsTheTip) {
  std::string two_fingers = armWithAGripper(true, false);
  const std::string mimic = R"(<mimic joint="left_finger"/>)";
  for (const bool mimicked : {true, false}) {
    std::string urdf = two_fingers;
    if (!mimicked) urdf.erase(urdf.find(mimic), mimic.size());
    const RobotModel model = RobotModel::fromUrdfString(urdf, ".");
    EXPECT_EQ(model.tipLink(), "hand") << mimicked;
    EXPECT_EQ(model.dof(), 2);
    ASSERT_EQ(model.notes().size(), 1U);
    EXPECT_NE(model.notes()[0].find("the longest chains end in 'finger_l', 'finger_r', which branch at 'hand'"), std::string::npos)
        << model.notes()[0];
  }
  // Named, a finger is the tip.
  EXPECT_EQ(RobotModel::fromUrdfString(armWithAGripper(true, false), ".", "finger_l").dof(), 3);
}

// A cell's URDF mounting the arm on a stand from a bare `world` root: the arm stands that high
// over every scene's table top, which was drawn without a word.
TEST(RobotModel, SaysWhenTheRootHoldsTheArmAboveTheTableTop) {
  const auto mounted = [](const std::string& xyz) {
    return std::string("<robot name='cell'><link name='world'/><joint name='mount' type='fixed'><parent link='world'/>"
                       "<child link='base'/><origin xyz='") + xyz + "'/></joint>"
                       "<link name='base'><visual><geometry><cylinder radius='0.1' length='0.1'/></geometry></visual>"
                       "<collision><geometry><cylinder radius='0.1' length='0.1'/></geometry></collision></link>"
                       "<joint name='j1' type='revolute'><parent link='base'/><child link='l1'/><origin xyz='0 0 0.1'/>"
                       "<axis xyz='0 0 1'/><limit lower='-1' upper='1' velocity='1' effort='10'/></joint>"
                       "<link name='l1'><collision><geometry><box size='0.1 0.1 0.3'/></geometry></collision></link></robot>";
  };
  const RobotModel raised = RobotModel::fromUrdfString(mounted("0.1 0 0.8"), ".");
  ASSERT_EQ(raised.notes().size(), 1U);
  EXPECT_NE(raised.notes()[0].find("the URDF's root 'world' holds 'base' 0.80 m above its origin"), std::string::npos) << raised.notes()[0];
  // On the table top (and 2 cm of a base plate's thickness) there is nothing to say.
  EXPECT_TRUE(RobotModel::fromUrdfString(mounted("0.3 0 0"), ".").notes().empty());
  EXPECT_TRUE(RobotModel::fromUrdfString(mounted("0 0 0.02"), ".").notes().empty());
  EXPECT_TRUE(RobotModel::fromUrdfFile(resolveRobotPath("arm9")).notes().empty());
}

// A link drawn but without a collision element touches through a capsule all the same.
TEST(RobotModel, SaysWhichDrawnLinkHasNoCollisionElement) {
  const std::string drawn_only = twoJointArm(
      "<link name='cover'><visual><geometry><box size='0.1 0.1 0.1'/></geometry></visual></link>"
      "<joint name='c' type='fixed'><parent link='tool'/><child link='cover'/></joint>");
  const RobotModel model = RobotModel::fromUrdfString(drawn_only, ".");
  const std::string last = model.bodies().back().name;
  ASSERT_TRUE(model.bodies().back().collisions.empty());
  ASSERT_EQ(model.notes().size(), 1U);
  EXPECT_EQ(model.notes()[0], "link 'cover' has a visual but no collision element: a capsule along '" + last +
                                  "' stands in for it in contacts and clearances");
  EXPECT_TRUE(RobotModel::fromUrdfFile(resolveRobotPath("lwr4")).notes().empty());
}

TEST(RobotModel, RefusesAMimicFingerOnTheChainNamingATipBeforeIt) {
  try {
    RobotModel::fromUrdfString(armWithAGripper(true, true), ".");
    FAIL() << "a mimic joint on the chain was accepted";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("joint 'right_finger': mimic joints are not supported on the chain to the tip 'fingertip_r'"), std::string::npos)
        << message;
    EXPECT_NE(message.find("--tip hand"), std::string::npos) << message;
  }
  EXPECT_EQ(RobotModel::fromUrdfString(armWithAGripper(true, true), ".", "hand").dof(), 2);
}

}  // namespace
}  // namespace flexirob::robot
