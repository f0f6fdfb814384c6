// Kinematic evaluations: motions with the hierarchical controller and a learned map, the
// reachable-workspace count and the explored fraction.
#include <gtest/gtest.h>

#include <sstream>

#include <numbers>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "app/evaluation.hpp"
#include "tests/common/scene_objects.hpp"
#include "learning/elm.hpp"
#include "planning/itm.hpp"
#include "robot/collision.hpp"
#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/sim/reach.hpp"

namespace flexirob::app {
namespace {

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

Eigen::VectorXd ready() {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  q[1] = 0.6;
  q[3] = -1.6;
  q[5] = 0.9;
  return q;
}

// A map that gives (about) the ready posture everywhere: an ELM fitted on it at a few points.
std::unique_ptr<learning::Learner> constantMap() {
  learning::TrainingSet data;
  data.X.resize(3, 8);
  data.Y.resize(7, 8);
  for (int l = 0; l < 8; ++l) {
    data.X.col(l) = Eigen::Vector3d(-0.5 + 0.1 * (l % 2), -0.3 + 0.2 * ((l / 2) % 2), 0.2 + 0.2 * (l / 4));
    data.Y.col(l) = ready();
  }
  auto elm = std::make_unique<learning::Elm>(3, 7);
  elm->fit(data);
  return elm;
}

struct Parameters {
  Parameters() : declarations(robot::reachParameters()), parameters(declarations) {}
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
};

// A posture that does not fit the arm costs only itself: the others stay, and each left out
// is named once.
TEST(Evaluation, FittingASceneToARobotLeavesOutOnlyThePosturesThatDoNotFit) {
  robot::Scene scene = robot::loadScene("setup_I");
  ASSERT_TRUE(scene.home_posture.has_value());
  ASSERT_GE(scene.training_areas.size(), 2U);
  ASSERT_TRUE(scene.training_areas[0].posture.has_value());
  Eigen::VectorXd beyond = *scene.training_areas[1].posture;
  beyond[1] = 3.0;  // A2 beyond its 2.09 rad
  scene.training_areas[1].posture = beyond;
  scene.training_areas[2].posture = Eigen::VectorXd::Zero(6);  // a posture of a six-joint arm
  const FittedScene fitted = fitSceneToRobot(scene, lwr4());
  ASSERT_TRUE(fitted.scene.home_posture.has_value());
  EXPECT_TRUE(fitted.scene.home_posture->isApprox(*scene.home_posture));
  ASSERT_TRUE(fitted.scene.training_areas[0].posture.has_value());
  EXPECT_TRUE(fitted.scene.training_areas[0].posture->isApprox(*scene.training_areas[0].posture));
  EXPECT_FALSE(fitted.scene.training_areas[1].posture.has_value());
  EXPECT_FALSE(fitted.scene.training_areas[2].posture.has_value());
  ASSERT_EQ(fitted.left_out.size(), 2U);
  EXPECT_EQ(fitted.other_joint_count, 1);
  EXPECT_NE(fitted.left_out[0].find("1 posture has 6 joint values, the robot 'lwr4' has 7 joints"), std::string::npos) << fitted.left_out[0];
  EXPECT_NE(fitted.left_out[1].find("outside its limits"), std::string::npos) << fitted.left_out[1];
  EXPECT_TRUE(fitSceneToRobot(robot::loadScene("setup_I"), lwr4()).left_out.empty());
  // Every posture of another arm: one line, not one per posture.
  scene.home_posture = Eigen::VectorXd::Zero(6);
  scene.training_areas[0].posture = Eigen::VectorXd::Zero(6);
  const FittedScene other_arm = fitSceneToRobot(scene, lwr4());
  EXPECT_EQ(other_arm.other_joint_count, 3);
  ASSERT_EQ(other_arm.left_out.size(), 2U);
  EXPECT_NE(other_arm.left_out[0].find("3 postures have 6 joint values"), std::string::npos) << other_arm.left_out[0];
  EXPECT_FALSE(other_arm.scene.home_posture.has_value());
  scene.home_posture = Eigen::VectorXd::Zero(9);
  EXPECT_NE(fitSceneToRobot(scene, lwr4()).left_out[0].find("3 postures have 6 or 9 joint values"), std::string::npos);
}

TEST(Evaluation, AStartPostureThatTouchesSomethingGivesWayToTheNearestFreeOne) {
  // The LWR IV's limits are symmetric: the middle is the arm upright, its flange 1.18 m up.
  const Eigen::VectorXd mid = lwr4().midPosture();
  robot::Scene open_scene;
  EXPECT_TRUE(homePosture(lwr4(), open_scene).isApprox(mid));
  robot::Scene scene_with_home;
  scene_with_home.home_posture = ready();
  EXPECT_TRUE(homePosture(lwr4(), scene_with_home).isApprox(ready()));

  // A ceiling 1 m up: upright, the arm is in it.
  robot::Scene ceiling;
  robot::Obstacle slab;
  slab.name = "ceiling";
  slab.shape = robot::Obstacle::Shape::kBox;
  slab.X_WO.translation() = Eigen::Vector3d(0.0, 0.0, 1.05);
  slab.size = Eigen::Vector3d(3.0, 3.0, 0.1);
  ceiling.obstacles.push_back(slab);
  robot::CollisionWorld world(lwr4(), ceiling);
  world.update(mid);
  ASSERT_FALSE(world.contacts().empty());
  const Eigen::VectorXd home = homePosture(lwr4(), ceiling);
  world.update(home);
  EXPECT_TRUE(world.contacts().empty());
  EXPECT_GE(world.clearance(0.05).distance, 0.05);
  EXPECT_GE(world.selfClearance(3, 0.05), 0.0);
  for (int j = 0; j < 7; ++j) {
    EXPECT_GE(home[j], lwr4().sampleLowerLimits()[j]);
    EXPECT_LE(home[j], lwr4().sampleUpperLimits()[j]);
  }
  // Near the middle: bent little more than needed to stay 5 cm under the ceiling (A2 alone
  // would need about 0.7 rad), not the nearest of postures drawn anywhere in the limits, which
  // lies over 2 rad away.
  EXPECT_LT((home - mid).norm(), 1.5);
}

TEST(Evaluation, TheArmsRoomIsWithinReachAndOffTheColumnAroundItsFirstAxis) {
  // LWR IV: the column stands on the origin; the shoulder is body 2's origin.
  const ArmReach lwr = armReach(lwr4());
  EXPECT_NEAR(std::abs(lwr.base_axis.z()), 1.0, 1e-12);
  EXPECT_NEAR(lwr.base_point.head<2>().norm(), 0.0, 1e-12);
  robot::Kinematics kinematics(lwr4());
  kinematics.update(Eigen::VectorXd::Zero(7));
  EXPECT_TRUE(lwr.shoulder.isApprox(kinematics.X_WB(2).translation()));
  EXPECT_NEAR(lwr.reach, (kinematics.p_WT() - lwr.shoulder).norm(), 1e-12) << "stretched upright, the tip is farthest";
  EXPECT_FALSE(lwr.roomFor(Eigen::Vector3d(0.1, 0.05, 0.5), 0.05)) << "inside the column";
  EXPECT_TRUE(lwr.roomFor(Eigen::Vector3d(-0.5, 0.1, 0.4), 0.05));
  EXPECT_FALSE(lwr.roomFor(lwr.shoulder + Eigen::Vector3d(0.0, lwr.reach - 0.04, 0.0), 0.05)) << "beyond reach - margin";

  // An arm lying on its side 0.5 m up: its column runs along world x, not z.
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="lying">
  <link name="world"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/><origin xyz="0 0 0.5" rpy="0 1.5707963267948966 0"/></joint>
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l1"/>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <link name="l2"/>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <link name="l3"/>
  <joint name="tool" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0 0 0.3"/></joint>
  <link name="tip"/>
</robot>
)";
  const auto lying_model = robot::RobotModel::fromUrdfString(urdf, ".");
  const ArmReach lying = armReach(lying_model);
  EXPECT_NEAR(std::abs(lying.base_axis.x()), 1.0, 1e-12);
  EXPECT_TRUE(lying.shoulder.isApprox(Eigen::Vector3d(0.1, 0.0, 0.5), 1e-12));
  EXPECT_NEAR(lying.reach, 0.8, 1e-12);
  EXPECT_DOUBLE_EQ(lying.base_radius, 0.2);
  EXPECT_FALSE(lying.roomFor(Eigen::Vector3d(0.3, 0.0, 0.55), 0.05)) << "5 cm off its axis, though 0.3 m off world z";
  EXPECT_TRUE(lying.roomFor(Eigen::Vector3d(0.3, 0.0, 1.0), 0.05));

  // The same arm with every joint about y: it swings from its first joint, through its base.
  std::string planar_urdf = urdf;
  const std::string first_axis = R"(<axis xyz="0 0 1"/>)";
  planar_urdf.replace(planar_urdf.find(first_axis), first_axis.size(), R"(<axis xyz="0 1 0"/>)");
  const auto planar_model = robot::RobotModel::fromUrdfString(planar_urdf, ".");
  const ArmReach planar = armReach(planar_model);
  EXPECT_TRUE(planar.shoulder.isApprox(Eigen::Vector3d(0.0, 0.0, 0.5), 1e-12));
  EXPECT_NEAR(planar.reach, 0.9, 1e-12);
  EXPECT_DOUBLE_EQ(planar.base_radius, 0.0);
  EXPECT_TRUE(planar.roomFor(Eigen::Vector3d(0.0, 0.0, 1.34), 0.05)) << "0.84 m out along its first link";

  // The lying arm with its forearm folded back 2.5 rad at zero, 0.45 m from the shoulder to the
  // tip: the elbow's limit (-2) undoes all but 0.5 rad of the fold, the tighter limit -1 all but
  // 1.5 rad; the reach is the law of cosines' distance of the two links' ends then.
  std::string folded_urdf = urdf;
  const std::string elbow = R"(<origin xyz="0 0 0.5"/>)";
  folded_urdf.replace(folded_urdf.find(elbow), elbow.size(), R"(<origin xyz="0 0 0.5" rpy="0 2.5 0"/>)");
  const ArmReach folded = armReach(robot::RobotModel::fromUrdfString(folded_urdf, "."));
  const auto stretched = [](double fold) { return std::sqrt(0.5 * 0.5 + 0.3 * 0.3 + 2.0 * 0.5 * 0.3 * std::cos(fold)); };
  EXPECT_NEAR(folded.reach, stretched(0.5), 1e-4);
  std::string stiff_urdf = folded_urdf;
  const std::string elbow_limits = R"(<axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
  <link name="l3"/>)";
  stiff_urdf.replace(stiff_urdf.find(elbow_limits), elbow_limits.size(),
                     R"(<axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <link name="l3"/>)");
  const ArmReach stiff = armReach(robot::RobotModel::fromUrdfString(stiff_urdf, "."));
  EXPECT_NEAR(stiff.reach, stretched(1.5), 1e-4);

  // The lying arm with its shoulder 0.2 m off the first joint's axis: turning that joint moves
  // the shoulder with the arm, so the reach stays the 0.8 m of the links beyond it (measured
  // from the shoulder kept in place, the tip would seem up to 0.4 m farther).
  std::string offset_urdf = urdf;
  const std::string shoulder_origin = R"(<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>)";
  offset_urdf.replace(offset_urdf.find(shoulder_origin), shoulder_origin.size(), R"(<origin xyz="0.2 0 0.1"/><axis xyz="0 1 0"/>)");
  const ArmReach offset = armReach(robot::RobotModel::fromUrdfString(offset_urdf, "."));
  EXPECT_NEAR(offset.reach, 0.8, 1e-9);
}

// Three links of `length` [m] on joints about y (the first about z), each a point mass `mass`
// [kg] at its end (a small sphere of inertia), standing upright at zero.
std::string pointMassArm(double length, double mass) {
  std::ostringstream urdf;
  urdf << "<robot name=\"points\"><link name=\"base\"/>";
  const char* axes[] = {"0 0 1", "0 1 0", "0 1 0", "0 1 0"};
  std::string parent = "base";
  for (int j = 0; j < 4; ++j) {
    const std::string child = "l" + std::to_string(j + 1);
    urdf << "<joint name=\"j" << j + 1 << "\" type=\"revolute\"><parent link=\"" << parent << "\"/><child link=\"" << child
         << "\"/><origin xyz=\"0 0 " << (j <= 1 ? 0.0 : length) << "\"/><axis xyz=\"" << axes[j] << "\"/>"
         << "<limit lower=\"-2\" upper=\"2\" velocity=\"1\" effort=\"100\"/></joint>"
         << "<link name=\"" << child << "\"><inertial><origin xyz=\"0 0 " << (j == 0 ? 0.0 : length) << "\"/><mass value=\"" << mass
         << "\"/><inertia ixx=\"1e-9\" ixy=\"0\" ixz=\"0\" iyy=\"1e-9\" iyz=\"0\" izz=\"1e-9\"/></inertial></link>";
    parent = child;
  }
  urdf << "</robot>";
  return urdf.str();
}

// M_jj of an upright chain of point masses: about the shoulder (j2), m (l² + (2l)² + (3l)²).
TEST(Evaluation, TheJointInertiaOfAnUprightChainOfPointMassesIsTheirMomentAboutEachAxis) {
  const double l = 0.3, m = 2.0;
  const auto model = robot::RobotModel::fromUrdfString(pointMassArm(l, m), ".");
  ASSERT_EQ(model.dof(), 4);
  const Eigen::VectorXd M = robot::jointInertiaDiagonal(model, Eigen::VectorXd::Zero(4));
  EXPECT_NEAR(M[0], 0.0, 1e-6);  // every mass on the first axis
  EXPECT_NEAR(M[1], m * (l * l + 4 * l * l + 9 * l * l), 1e-6);
  EXPECT_NEAR(M[2], m * (l * l + 4 * l * l), 1e-6);
  EXPECT_NEAR(M[3], m * (l * l), 1e-6);
  // Bent at the shoulder by 90°: the first axis now sees the masses 1, 2, 3 l out.
  Eigen::VectorXd bent = Eigen::VectorXd::Zero(4);
  bent[1] = std::numbers::pi / 2;
  EXPECT_NEAR(robot::jointInertiaDiagonal(model, bent)[0], m * 14 * l * l, 1e-6);
}

// The LWR IV and arm9 scale nothing; an arm half as long and a tenth as heavy as some arm the
// size of the LWR IV is half as long, a fortieth of its inertia, a tenth of its mass.
TEST(Evaluation, AnArmIsScaledAgainstTheLwrIvBySizeAndWeight) {
  for (const char* name : {"lwr4", "arm9"}) {
    const ArmScale scale = armScale(robot::RobotModel::fromUrdfFile(resolveRobotPath(name)));
    EXPECT_EQ(scale.length, 1.0) << name;
    EXPECT_EQ(scale.inertia, 1.0) << name;
    EXPECT_EQ(scale.mass(), 1.0) << name;
  }
  // The tip (the last link's origin) 0.4 m from the shoulder; 0.28 kg m² about it.
  const auto full = robot::RobotModel::fromUrdfString(pointMassArm(0.2, 0.5), ".");
  const auto small = robot::RobotModel::fromUrdfString(pointMassArm(0.1, 0.05), ".");
  const ArmScale a = armScale(full), b = armScale(small);
  EXPECT_NEAR(a.length, 0.4 / kLwrShoulderReach, 1e-6);
  EXPECT_NEAR(a.inertia, 0.28 / robot::kLwrLargestJointInertia, 1e-6);
  EXPECT_LT(a.mass(), 1.0);
  EXPECT_NEAR(b.length / a.length, 0.5, 1e-6);
  EXPECT_NEAR(b.inertia / a.inertia, 0.1 * 0.25, 1e-6);
  EXPECT_NEAR(b.mass() / a.mass(), 0.1, 1e-6);
  EXPECT_NEAR(b.force(), b.mass() * b.length, 1e-12);
  // As heavy as the LWR IV but half as long: its joints' torques are the LWR IV's, so a push
  // at its shorter levers is harder (force × length ∝ inertia).
  const ArmScale heavy = armScale(robot::RobotModel::fromUrdfString(pointMassArm(0.2, 20.0), "."));
  EXPECT_EQ(heavy.inertia, 1.0);
  EXPECT_LT(heavy.length, 0.5);
  EXPECT_NEAR(heavy.force() * heavy.length, heavy.inertia, 1e-12);
  EXPECT_GT(heavy.mass(), 1.0);
  // Up to four times the LWR IV's joint inertia (arm9: 3.1) the LWR IV's gains serve; beyond, they
  // grow with the arm, from 1 at four times. The shoulder's M_jj is m (l² + (2l)² + (3l)²).
  const double per_kg = 14.0 * 0.2 * 0.2;
  const auto withRatio = [per_kg](double ratio) {
    return armScale(robot::RobotModel::fromUrdfString(pointMassArm(0.2, ratio * robot::kLwrLargestJointInertia / per_kg), "."));
  };
  EXPECT_NEAR(withRatio(3.9).inertia, 1.0, 1e-12);
  EXPECT_NEAR(withRatio(4.0).inertia, 1.0, 1e-5);
  EXPECT_NEAR(withRatio(10.0).inertia, 2.5, 1e-5);
  EXPECT_NEAR(withRatio(86.0).inertia, 21.5, 1e-4);
}

// A SCARA: a lifting column, three joints about z, a wrist tilting about y at the tip. The first
// joint not about z is the tilt, at the tip itself: a sphere about it would hold nothing. The
// reach is then taken from the first joint with every joint free, and holds every tip position.
TEST(Evaluation, TheReachOfAScaraHoldsEveryTipPositionWithinItsLimits) {
  const std::string urdf = R"(<robot name="scara"><link name="base"/>
  <joint name="lift" type="prismatic"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.06"/><axis xyz="0 0 1"/>
    <limit lower="0.05" upper="0.5" velocity="1" effort="100"/></joint>
  <link name="l1"/>
  <joint name="shoulder" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-2.6" upper="2.6" velocity="1" effort="100"/></joint>
  <link name="l2"/>
  <joint name="elbow" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.35 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.6" upper="2.6" velocity="1" effort="100"/></joint>
  <link name="l3"/>
  <joint name="wrist" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.9" upper="2.9" velocity="1" effort="100"/></joint>
  <link name="l4"/>
  <joint name="tilt" type="revolute"><parent link="l4"/><child link="l5"/><origin xyz="0.1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" velocity="1" effort="100"/></joint>
  <link name="l5"/>
  <joint name="tool" type="fixed"><parent link="l5"/><child link="tip"/><origin xyz="0 0 -0.1"/></joint>
  <link name="tip"/></robot>)";
  // The same arm on a fixed column (no lift): the tilt is still the first joint not about z,
  // and it lies 0.75 m off the first axis.
  std::string fixed_column = urdf;
  const std::string lift = R"(<joint name="lift" type="prismatic">)";
  fixed_column.replace(fixed_column.find(lift), lift.size(), R"(<joint name="lift" type="fixed">)");
  for (const std::string& text : {urdf, fixed_column}) {
    const auto model = robot::RobotModel::fromUrdfString(text, ".");
    const ArmReach scara = armReach(model);
    EXPECT_DOUBLE_EQ(scara.base_radius, 0.0) << model.dof() << " joints";
    robot::Kinematics kinematics(model);
    learning::UniformRandom random(4);
    double farthest = 0.0;
    for (int sample = 0; sample < 3000; ++sample) {
      kinematics.update(random.uniform(model.lowerLimits(), model.upperLimits()));
      farthest = std::max(farthest, scara.fromShoulder(kinematics.p_WT()));
    }
    EXPECT_LE(farthest, scara.reach + 1e-9) << model.dof() << " joints";
    EXPECT_GT(farthest, 0.9 * scara.reach) << model.dof() << " joints: not far beyond what the arm reaches";
    // A place 0.5 m out at the height of the arm is within reach, and not in a base column.
    EXPECT_TRUE(scara.roomFor(Eigen::Vector3d(0.4, 0.3, 0.36 + (model.dof() == 5 ? 0.2 : 0.0)), 0.05)) << model.dof() << " joints";
  }
}

TEST(Evaluation, MotionReachesAFreeTargetWithoutCollision) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  robot::CollisionWorld world(lwr4(), empty);
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = start + Eigen::Vector3d(0.0, 0.15, 0.05);
  const MotionOutcome outcome = executeMotion(lwr4(), s.parameters, *map, ready(), [&](double) { return target; }, 0.0, 3.0, &world);
  EXPECT_FALSE(outcome.collided);
  EXPECT_LT(outcome.final_error_m, 1e-3);
  EXPECT_LT((robot::tipPose(lwr4(), outcome.q).translation() - target).norm(), 1e-3);
}

TEST(Evaluation, MotionThroughAnObstacleCountsAsCollision) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene scene;
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = start + Eigen::Vector3d(0.0, 0.3, 0.0);
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.6, 0.04, 0.6);
  wall.X_WO.translation() = start + Eigen::Vector3d(0.0, 0.15, 0.0);
  scene.obstacles.push_back(wall);
  robot::CollisionWorld world(lwr4(), scene);
  const MotionOutcome outcome = executeMotion(lwr4(), s.parameters, *map, ready(), [&](double) { return target; }, 0.0, 3.0, &world);
  EXPECT_TRUE(outcome.collided);
}

// Sect. 8.3 in a corridor of ITM nodes that a thin wall crosses: a motion through the wall is
// counted as collided and goes on to its goal (the collision world only counts contacts), and
// the next motion starts there. Only the motions that cross the wall collide, whatever came
// before them; stopping at the first contact would leave the arm on the near side and count
// every later goal beyond the wall as well.
TEST(Evaluation, PlanningGoalsAreNodesTheGraphConnectsToTheStart) {
  Parameters s;
  const auto map = constantMap();
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  // Three nodes in a row from the start, and two joined to each other 0.3 m above them but to
  // none of the three: a path to those cannot exist.
  planning::Itm graph(planning::ItmParameters{}, 7);
  const int a = graph.addNode(start, ready());
  const int b = graph.addNode(start + Eigen::Vector3d(0.0, 0.1, 0.0), ready());
  const int c = graph.addNode(start + Eigen::Vector3d(0.0, 0.2, 0.0), ready());
  graph.addEdge(a, b);
  graph.addEdge(b, c);
  const int d = graph.addNode(start + Eigen::Vector3d(0.0, 0.0, 0.3), ready());
  const int e = graph.addNode(start + Eigen::Vector3d(0.0, 0.1, 0.3), ready());
  graph.addEdge(d, e);
  robot::Scene empty;
  const PlanningResult result = evaluatePlanning(lwr4(), empty, s.parameters, *map, graph, ready(), 20, 5);
  EXPECT_EQ(result.disconnected_nodes, 2);
  EXPECT_EQ(result.found, 20);
  for (const PlannedMotion& motion : result.motions) {
    EXPECT_LT(motion.goal_W.z(), start.z() + 0.01);
    // Never the node the arm stands at: every goal is a move of at least one node (0.1 m).
    EXPECT_GT((motion.goal_W - motion.start_W).norm(), 0.05);
  }

  // Nothing joined to the start: refused with a reason, not 20 unfound paths.
  planning::Itm scattered(planning::ItmParameters{}, 7);
  scattered.addNode(start, ready());
  scattered.addNode(start + Eigen::Vector3d(0.0, 0.1, 0.0), ready());
  EXPECT_THROW(evaluatePlanning(lwr4(), empty, s.parameters, *map, scattered, ready(), 20, 5), InputError);
}

TEST(Evaluation, PlannedMotionsThroughAContactGoOnToTheirGoalAndTheNextStartsThere) {
  Parameters s;
  const auto map = constantMap();
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d step(0.0, 0.3, 0.0);
  robot::Scene scene;
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.3, 0.02, 0.2);  // low: only the hand passes it, never the elbow
  wall.X_WO.translation() = start + 0.5 * step;  // midway between the first two nodes
  scene.obstacles.push_back(wall);
  // Three nodes 0.3 m apart in a row, joined by edges: visited 0, 1, 2, 1, 0.
  planning::Itm graph(planning::ItmParameters{}, 7);
  for (const int k : {0, 1, 2, 1, 0}) graph.insert(start + k * step, ready());
  ASSERT_EQ(graph.nodeCount(), 3);
  ASSERT_GE(graph.edgeCount(), 2);
  const PlanningResult result = evaluatePlanning(lwr4(), scene, s.parameters, *map, graph, ready(), 12, 3);
  ASSERT_EQ(result.motions.size(), 12U);
  const double wall_y = wall.X_WO.translation().y();
  int crossings = 0, collided = 0;
  for (std::size_t i = 0; i < result.motions.size(); ++i) {
    const PlannedMotion& motion = result.motions[i];
    ASSERT_TRUE(motion.found) << "goal " << i;
    EXPECT_LT((motion.final_W - motion.goal_W).norm(), 0.01) << "goal " << i << " ended short of its goal";
    if (i > 0) {
      EXPECT_LT((motion.start_W - result.motions[i - 1].final_W).norm(), 1e-6) << "goal " << i;
    }
    const bool crosses = (motion.start_W.y() - wall_y) * (motion.goal_W.y() - wall_y) < 0.0;
    crossings += crosses ? 1 : 0;
    collided += motion.collided ? 1 : 0;
    EXPECT_EQ(motion.collided, crosses) << "goal " << i;
    EXPECT_FALSE(motion.ended_in_contact) << "goal " << i << ": the wall is passed, not stood in";
  }
  EXPECT_GE(crossings, 2) << "the seed should cross the wall more than once";
  EXPECT_EQ(result.collision_free, 12 - collided);
  // Within 1 cm is judged apart from the contacts (Sect. 8.3 counts them apart): a motion through
  // the wall still ends at its goal. It had counted only the collision-free ones.
  EXPECT_EQ(result.reached_1cm, 12);
  double largest_final_error = 0.0;
  for (const PlannedMotion& motion : result.motions) {
    EXPECT_NEAR(motion.final_error_m, (motion.final_W - motion.goal_W).norm(), 1e-12);
    EXPECT_TRUE(motion.reached_1cm);
    largest_final_error = std::max(largest_final_error, motion.final_error_m);
  }
  EXPECT_EQ(result.final_error_max_m, largest_final_error);
  EXPECT_GT(result.tracking_error_max_m, 0.0);
  int counted = 0;
  for (const auto& [contact, motions] : result.contacts) {
    EXPECT_NE(contact.find("/wall"), std::string::npos) << contact;
    counted += motions;
  }
  EXPECT_EQ(counted, collided);
}

// A goal inside a block: the motion ends with the hand in it, says so, and the next motion
// starts where the last one ended free (the JSON had shown a start that matched no end).
TEST(Evaluation, APlannedMotionThatEndsInContactSaysSoAndTheNextStartsWhereTheArmWasFree) {
  Parameters s;
  const auto map = constantMap();
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d goal = start + Eigen::Vector3d(0.0, 0.3, 0.0);
  robot::Scene scene;
  scene.obstacles.push_back(testing::boxObstacle("block", Eigen::Vector3d(0.1, 0.1, 0.1), goal));
  planning::Itm graph(planning::ItmParameters{}, 7);
  for (const int k : {0, 1, 0}) graph.insert(start + k * (goal - start), ready());
  ASSERT_EQ(graph.nodeCount(), 2);
  const PlanningResult result = evaluatePlanning(lwr4(), scene, s.parameters, *map, graph, ready(), 4, 3);
  ASSERT_EQ(result.motions.size(), 4U);
  int ended_in_contact = 0;
  for (std::size_t i = 0; i < result.motions.size(); ++i) {
    const PlannedMotion& motion = result.motions[i];
    const bool at_block = (motion.goal_W - goal).norm() < 1e-9;
    EXPECT_EQ(motion.ended_in_contact, at_block) << "goal " << i;
    ended_in_contact += motion.ended_in_contact ? 1 : 0;
    if (i == 0) continue;
    const PlannedMotion& before = result.motions[i - 1];
    const Eigen::Vector3d expected_start = before.ended_in_contact ? before.start_W : before.final_W;
    EXPECT_LT((motion.start_W - expected_start).norm(), 1e-6) << "goal " << i;
  }
  EXPECT_GE(ended_in_contact, 1);
}

// Grid points in front of the robot at z = 0.3 m, 0.4 m wide and 0.2 m deep.
robot::EvaluationGrid gridInFront(double spacing) {
  robot::EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.6, -0.2, 0.3);
  grid.upper = Eigen::Vector3d(-0.4, 0.2, 0.3);
  grid.spacing = spacing;
  return grid;
}

TEST(Evaluation, ExploredFractionCountsCellsHoldingSamples) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  const robot::EvaluationGrid grid = gridInFront(0.2);
  const std::vector<Eigen::Vector3d> points = grid.points();
  ASSERT_EQ(points.size(), 6U);
  // Samples near (within a third of a cell of) the first three points.
  Eigen::MatrixXd X(3, 3);
  for (int i = 0; i < 3; ++i) X.col(i) = points[static_cast<std::size_t>(i)] + Eigen::Vector3d::Constant(0.03);
  learning::TrainingSet samples;
  samples.X = X;
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, samples);
  EXPECT_EQ(result.grid_points, 6);
  EXPECT_EQ(result.targets, 6);  // all within reach, no obstacles
  EXPECT_DOUBLE_EQ(result.explored_fraction, 0.5);
  EXPECT_EQ(result.collided, 0);
  EXPECT_EQ(result.reached, 6);  // free space in front of the robot
}

// A looser "reached" had also shrunk T: the edge of the reach was drawn at reach − tolerance,
// and a 5 cm tolerance dropped points between 1 and 5 cm inside the edge from the targets.
TEST(Evaluation, TheGridsToleranceDoesNotChangeWhichPointsAreWithinReach) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  const ArmReach reach = armReach(lwr4());
  // A row of points straight out from the shoulder, 0.5 to 4.5 cm inside the edge of the reach.
  robot::EvaluationGrid grid;
  const Eigen::Vector3d out(-1.0, 0.0, 0.0);
  grid.lower = reach.shoulder + (reach.reach - 0.045) * out;
  grid.upper = reach.shoulder + (reach.reach - 0.005) * out;
  std::swap(grid.lower.x(), grid.upper.x());
  grid.spacing = 0.01;
  ASSERT_EQ(grid.points().size(), 5U);
  grid.tolerance = 0.01;
  const ReachableResult tight = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, {});
  grid.tolerance = 0.05;
  const ReachableResult loose = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, {});
  EXPECT_EQ(tight.out_of_reach, 1);  // only the point 0.5 cm from the edge
  EXPECT_EQ(loose.out_of_reach, tight.out_of_reach);
  EXPECT_EQ(loose.targets, tight.targets);
  EXPECT_GE(loose.reached, tight.reached);
}

TEST(Evaluation, ExcludedBoxesOfTheGridHoldNoTargets) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  robot::EvaluationGrid grid = gridInFront(0.2);
  // Holds the two points with y = 0.2 (on its boundary) and none other.
  grid.excluded.emplace_back(Eigen::Vector3d(-0.7, 0.2, 0.2), Eigen::Vector3d(-0.3, 0.5, 0.4));
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, learning::TrainingSet{});
  EXPECT_EQ(result.grid_points, 6);
  EXPECT_EQ(result.excluded, 2);
  EXPECT_EQ(result.targets, 4);
  ASSERT_EQ(result.target_points.size(), 4U);
  for (const Eigen::Vector3d& p : result.target_points) EXPECT_LT(p.y(), 0.1) << p.transpose();
  EXPECT_EQ(result.reached, 4);
}

// A mesh block and the box of its size hold the same grid points: neither is a target.
TEST(Evaluation, GridPointsInsideAMeshObstacleAreNoTargetsAsInItsBoxTwin) {
  Parameters s;
  const auto map = constantMap();
  const robot::EvaluationGrid grid = gridInFront(0.2);
  const std::filesystem::path cube_file =
      std::filesystem::temp_directory_path() / ("flexirob_evaluation_cube_" + std::to_string(::getpid()) + ".obj");
  std::ofstream(cube_file) << "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
                              "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
                              "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                              "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  // Holds the grid points (-0.6, 0, 0.3) and (-0.6, 0.2, 0.3).
  robot::Obstacle box;
  box.name = "block";
  box.size = Eigen::Vector3d(0.1, 0.3, 0.1);
  box.X_WO.translation() = Eigen::Vector3d(-0.6, 0.1, 0.3);
  robot::Obstacle mesh = box;
  mesh.shape = robot::Obstacle::Shape::kMesh;
  mesh.mesh_file = cube_file;
  mesh.mesh_scale = box.size;
  robot::Scene box_scene, mesh_scene;
  box_scene.obstacles = {box};
  mesh_scene.obstacles = {mesh};
  const ReachableResult with_box = evaluateReachable(lwr4(), box_scene, s.parameters, *map, ready(), grid, learning::TrainingSet{});
  const ReachableResult with_mesh = evaluateReachable(lwr4(), mesh_scene, s.parameters, *map, ready(), grid, learning::TrainingSet{});
  std::filesystem::remove(cube_file);
  EXPECT_EQ(with_box.in_obstacles, 2);
  EXPECT_EQ(with_mesh.in_obstacles, 2);
  EXPECT_EQ(with_mesh.target_points, with_box.target_points);
  for (const Eigen::Vector3d& p : with_mesh.target_points) EXPECT_GT((p - box.X_WO.translation()).norm(), 0.15) << p.transpose();
}

// Joint limits and the arm's own links bound the workspace without any obstacle: a point beside
// the base within the reach sphere is no target in the empty scene either.
TEST(Evaluation, PointsNoPostureReachesAreNoTargetsInAnEmptySceneEither) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  robot::EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.5, 0.0, 0.1);
  grid.upper = Eigen::Vector3d(-0.1, 0.0, 0.1);
  grid.spacing = 0.4;
  ASSERT_EQ(grid.points().size(), 2U);
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, learning::TrainingSet{});
  EXPECT_EQ(result.inaccessible, 1);  // (-0.1, 0, 0.1): the base's own housing
  ASSERT_EQ(result.target_points.size(), 1U);
  EXPECT_TRUE(result.target_points[0].isApprox(Eigen::Vector3d(-0.5, 0.0, 0.1)));
}

// -0.9 + 6 * 0.1 = -0.29999999999999993: a grid point a rounding error outside a face at
// x = -0.3 m lies on the face, and the tip cannot stand there without touching it.
TEST(Evaluation, AGridPointOnAnObstaclesFaceIsNoTarget) {
  Parameters s;
  const auto map = constantMap();
  robot::EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.9, -0.1, 0.3);
  grid.upper = Eigen::Vector3d(-0.1, -0.1, 0.3);
  grid.spacing = 0.1;
  const std::vector<Eigen::Vector3d> points = grid.points();
  ASSERT_EQ(points.size(), 9U);
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.2, 0.4, 0.4);
  wall.X_WO.translation() = Eigen::Vector3d(-0.4, -0.1, 0.3);  // x in [-0.5, -0.3]
  robot::Scene scene;
  scene.obstacles = {wall};
  ASSERT_EQ(robot::obstacleAt(scene, points[6]), nullptr) << "the rounding case this is about";
  ASSERT_LT(std::abs(points[6].x() + 0.3), 1e-12);
  const ReachableResult result = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, {});
  for (const Eigen::Vector3d& p : result.target_points) {
    const Eigen::Vector3d outside = ((p - wall.X_WO.translation()).cwiseAbs() - wall.size / 2).cwiseMax(0.0);
    EXPECT_GT(outside.norm(), 1e-6) << p.transpose();
  }
  EXPECT_EQ(result.in_obstacles, 3);  // x = -0.5 and -0.3 on the faces, -0.4 inside
  // The implicit scene model (Eq. 4.1) counts the obstacle's points as T does.
  EXPECT_EQ(evaluateSceneModel(lwr4(), scene, grid, {}).obstacle_points, 3);
}

// IK with the hierarchical controller (Eq. 2.11) from q0 with q0 as null-space target: an
// independent posture for a tip position, not the map's.
Eigen::VectorXd solveIk(const Eigen::VectorXd& q0, const Eigen::Vector3d& p_W) {
  Parameters s;
  robot::HierarchicalController controller(lwr4(), s.parameters);
  Eigen::VectorXd q = q0, q_next(q0.size());
  for (int it = 0; it < 2000; ++it) {
    controller.target(q, p_W, q0, 0.01, q_next);
    q = q_next;
  }
  return q;
}

// A map that gives the posture q everywhere near the evaluation points.
std::unique_ptr<learning::Learner> mapOf(const Eigen::VectorXd& q, const Eigen::Vector3d& around) {
  learning::TrainingSet data;
  data.X.resize(3, 8);
  data.Y.resize(7, 8);
  for (int l = 0; l < 8; ++l) {
    data.X.col(l) = around + Eigen::Vector3d(0.1 * (l % 2) - 0.05, 0.1 * ((l / 2) % 2) - 0.05, 0.1 * (l / 4) - 0.05);
    data.Y.col(l) = q;
  }
  auto elm = std::make_unique<learning::Elm>(3, 7);
  elm->fit(data);
  return elm;
}

// T is the scene's and the grid's (Sect. 3.3.2: T_I, T_II): two maps that resolve the arm in
// different postures, driven from different start postures, are judged on the same targets.
TEST(Evaluation, TheTargetsDoNotDependOnTheLearnedMapOrTheStartPosture) {
  Parameters s;
  robot::EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.7, -0.3, 0.1);
  grid.upper = Eigen::Vector3d(-0.3, 0.3, 0.5);
  grid.spacing = 0.1;
  robot::Obstacle pillar;
  pillar.name = "pillar";
  pillar.size = Eigen::Vector3d(0.1, 0.1, 0.6);
  pillar.X_WO.translation() = Eigen::Vector3d(-0.45, 0.05, 0.3);
  robot::Scene scene;
  scene.obstacles = {pillar};
  Eigen::VectorXd leaning_back = ready();
  leaning_back[1] = -0.6;
  leaning_back[3] = 1.6;
  leaning_back[5] = -0.9;
  const auto ready_map = constantMap();
  const auto elbow_up_map = mapOf(solveIk(leaning_back, Eigen::Vector3d(-0.5, 0.0, 0.3)), Eigen::Vector3d(-0.5, 0.0, 0.3));
  const ReachableResult a = evaluateReachable(lwr4(), scene, s.parameters, *ready_map, ready(), grid, {});
  const ReachableResult b = evaluateReachable(lwr4(), scene, s.parameters, *elbow_up_map, leaning_back, grid, {});
  ASSERT_GT(a.targets, 0);
  EXPECT_NE(a.reached, b.reached) << "maps this different should not reach the same targets";
  EXPECT_EQ(a.targets, b.targets);
  EXPECT_EQ(a.inaccessible, b.inaccessible);
  std::vector<Eigen::Vector3d> targets_a = a.target_points, targets_b = b.target_points;
  const auto byPosition = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    return std::lexicographical_compare(u.data(), u.data() + 3, v.data(), v.data() + 3);
  };
  std::sort(targets_a.begin(), targets_a.end(), byPosition);
  std::sort(targets_b.begin(), targets_b.end(), byPosition);
  EXPECT_EQ(targets_a, targets_b);
}

TEST(Evaluation, ReachabilityStartsEachTargetInTheLearnedPostureUnlessAskedForTheStartPosture) {
  Parameters s;
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = start + Eigen::Vector3d(0.0, 0.3, 0.0);
  const Eigen::VectorXd q_target = solveIk(ready(), target);
  ASSERT_LT((robot::tipPose(lwr4(), q_target).translation() - target).norm(), 1e-4);
  // A small box halfway along the tip's straight way from the start posture to the target.
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "box";
  box.size = Eigen::Vector3d(0.08, 0.04, 0.08);
  box.X_WO.translation() = 0.5 * (start + target);
  scene.obstacles.push_back(box);
  robot::CollisionWorld world(lwr4(), scene);
  world.update(q_target);
  ASSERT_TRUE(world.contacts().empty()) << "the posture at the target must be free for this test";
  world.update(ready());
  ASSERT_TRUE(world.contacts().empty());
  const auto map = mapOf(q_target, target);
  robot::EvaluationGrid grid;
  grid.lower = grid.upper = target;
  grid.spacing = 0.1;
  // From the learned posture q_c(target) the arm is already there: reached, no contact.
  const ReachableResult learned = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, learning::TrainingSet{}, {},
                                                    ApproachFrom::kLearnedPosture);
  ASSERT_EQ(learned.targets, 1);
  EXPECT_EQ(learned.reached, 1);
  EXPECT_EQ(learned.collided, 0);
  ASSERT_EQ(learned.final_postures.size(), 1U);
  EXPECT_LT((learned.final_postures[0] - q_target).norm(), 0.05);
  // From the start posture the tip runs into the box on its way: a collision on the way counts.
  const ReachableResult from_start = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, learning::TrainingSet{},
                                                       {}, ApproachFrom::kStartPosture);
  ASSERT_EQ(from_start.targets, 1);
  EXPECT_EQ(from_start.collided, 1);
  EXPECT_EQ(from_start.reached, 0);
  ASSERT_EQ(from_start.contacts.size(), 1U);
  EXPECT_NE(from_start.contacts.begin()->first.find("/box"), std::string::npos) << from_start.contacts.begin()->first;
  // The posture the learned map resolves at the target is q_target, free, whichever way the arm
  // was approached.
  EXPECT_EQ(learned.resolved_free, 1);
  EXPECT_EQ(from_start.resolved_free, 1);
  EXPECT_DOUBLE_EQ(from_start.resolved_fraction, 1.0);
}

// The learned posture at the target may put the arm into an obstacle although the posture the
// controller resolves from it, with the tip on the target, is free: the arm never stands in
// q_c(x) with its tip at x. The reachable count judges the way from q_c(x) (a contact at once
// here), the resolved count only where the arm ends.
TEST(Evaluation, ResolvedPostureIsJudgedWhereTheArmEndsNotOnTheWayThere) {
  Parameters s;
  const Eigen::Vector3d tip_of_ready = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = tip_of_ready + Eigen::Vector3d(0.0, 0.3, 0.0);
  robot::Scene scene;
  scene.obstacles.push_back(testing::boxObstacle("box", Eigen::Vector3d(0.05, 0.05, 0.05), tip_of_ready));
  robot::CollisionWorld world(lwr4(), scene);
  world.update(ready());
  ASSERT_FALSE(world.contacts().empty()) << "the learned posture must touch the box for this test";
  const auto map = mapOf(ready(), target);  // q_c(target) = the ready posture, its tip 0.3 m away
  robot::EvaluationGrid grid;
  grid.lower = grid.upper = target;
  grid.spacing = 0.1;
  const ReachableResult result = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, learning::TrainingSet{}, {},
                                                   ApproachFrom::kLearnedPosture);
  ASSERT_EQ(result.targets, 1);
  EXPECT_EQ(result.collided, 1);
  EXPECT_EQ(result.reached, 0);
  EXPECT_EQ(result.resolved_free, 1);
  EXPECT_EQ(result.target_resolved_free, std::vector<bool>{true});
  EXPECT_EQ(result.target_reached, std::vector<bool>{false});
  // The target's own first contact, as the count by pair has it.
  ASSERT_EQ(result.target_contact.size(), 1U);
  EXPECT_NE(result.target_contact[0].find("/box"), std::string::npos) << result.target_contact[0];
  EXPECT_EQ(result.contacts.count(result.target_contact[0]), 1U);
  // Where the arm ends: tip on the target, no contact.
  const MotionOutcome resolved = approachTarget(lwr4(), s.parameters, *map, ready(), target, nullptr);
  EXPECT_LT(resolved.final_error_m, 0.01);
  world.update(resolved.q);
  EXPECT_TRUE(world.contacts().empty());
}

TEST(Evaluation, ReachabilityFromThePreviousTargetVisitsNeighboursInTurn) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  const robot::EvaluationGrid grid = gridInFront(0.1);
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, learning::TrainingSet{}, {},
                                                   ApproachFrom::kPreviousTarget);
  ASSERT_EQ(result.targets, 15);
  EXPECT_EQ(result.reached, 15);
  // Nearest-neighbour order: each target visited once, nearly always one grid step after the
  // one before (a greedy tour on a 3 x 5 grid needs at most a couple of longer jumps).
  int single_steps = 0;
  for (std::size_t i = 1; i < result.target_points.size(); ++i) {
    const double step = (result.target_points[i] - result.target_points[i - 1]).norm();
    EXPECT_GT(step, 0.05) << "target " << i << " visited twice";
    single_steps += std::abs(step - 0.1) < 1e-6 ? 1 : 0;
  }
  EXPECT_GE(single_steps, 12);
}

TEST(Evaluation, ReachabilityFromTheNearestReachedTargetStartsWhereTheArmStoodNextToIt) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  const robot::EvaluationGrid grid = gridInFront(0.1);
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, learning::TrainingSet{},
                                                   {}, ApproachFrom::kNearestReached);
  ASSERT_EQ(result.targets, 15);
  ASSERT_EQ(result.reached, 15);
  // The first target from the start posture, every later one from the
  // final posture at the nearest target reached before it; at the tour's jumps that is not the
  // target visited last.
  const auto& points = result.target_points;
  EXPECT_EQ(result.final_postures[0], approachTarget(lwr4(), s.parameters, *map, ready(), points[0], nullptr).q);
  int jumps = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    std::size_t nearest = 0;
    for (std::size_t j = 1; j < i; ++j) {
      if ((points[j] - points[i]).squaredNorm() < (points[nearest] - points[i]).squaredNorm()) nearest = j;
    }
    jumps += nearest != i - 1 ? 1 : 0;
    const MotionOutcome expected = approachTarget(lwr4(), s.parameters, *map, result.final_postures[nearest], points[i], nullptr);
    EXPECT_EQ(result.final_postures[i], expected.q) << "target " << i;
  }
  EXPECT_GE(jumps, 1);
}

// The default protocol also starts from the demonstration: the posture of the sample whose tip
// lies nearest the target. Here the start posture touches a box, so a target approached from it
// fails at the first check, and one approached from the posture the tutor showed next to it
// does not.
TEST(Evaluation, ReachabilityStartsFromTheNearestPostureOfTheDemonstration) {
  Parameters s;
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "box";
  box.size = Eigen::Vector3d(0.05, 0.05, 0.05);
  box.X_WO.translation() = robot::tipPose(lwr4(), ready()).translation();
  scene.obstacles.push_back(box);
  Eigen::VectorXd shown = ready();
  shown[0] += 0.6;
  // The shown posture between two farther ones, so that neither the first nor the last sample
  // is the nearest.
  Eigen::VectorXd elsewhere = ready();
  elsewhere[0] -= 0.6;
  const Eigen::VectorXd farther = shown + 0.5 * Eigen::VectorXd::Unit(shown.size(), 0);
  learning::TrainingSet demonstration;
  demonstration.X.resize(3, 3);
  demonstration.Y.resize(7, 3);
  const std::vector<Eigen::VectorXd> postures{elsewhere, shown, farther};
  for (Eigen::Index l = 0; l < 3; ++l) {
    demonstration.X.col(l) = robot::tipPose(lwr4(), postures[static_cast<std::size_t>(l)]).translation();
    demonstration.Y.col(l) = postures[static_cast<std::size_t>(l)];
  }
  robot::EvaluationGrid grid;
  grid.lower = grid.upper = demonstration.X.col(1) + Eigen::Vector3d(0.0, 0.0, 0.03);
  grid.spacing = 0.1;
  const auto map = mapOf(shown, grid.lower);
  robot::CollisionWorld world(lwr4(), scene);
  world.update(shown);
  ASSERT_TRUE(world.contacts().empty()) << "the shown posture must be free for this test";

  const ReachableResult visited = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, demonstration);
  ASSERT_EQ(visited.targets, 1);
  EXPECT_EQ(visited.reached, 1);
  EXPECT_EQ(visited.final_postures[0], approachTarget(lwr4(), s.parameters, *map, shown, grid.lower, nullptr).q);
  // Without the demonstration's postures, or with `nearest`, the target starts at the start
  // posture, in the box.
  learning::TrainingSet positions_only;
  positions_only.X = demonstration.X;
  const ReachableResult without_postures = evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, positions_only);
  EXPECT_EQ(without_postures.reached, 0);
  EXPECT_EQ(without_postures.collided, 1);
  const ReachableResult nearest =
      evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, demonstration, {}, ApproachFrom::kNearestReached);
  EXPECT_EQ(nearest.reached, 0);
  EXPECT_EQ(nearest.collided, 1);
  // Postures that do not fit the positions or the robot are refused, not silently ignored.
  learning::TrainingSet mismatched = demonstration;
  mismatched.Y.conservativeResize(6, Eigen::NoChange);
  EXPECT_THROW(evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, mismatched), InputError);
  mismatched = demonstration;
  mismatched.Y.conservativeResize(Eigen::NoChange, 2);
  EXPECT_THROW(evaluateReachable(lwr4(), scene, s.parameters, *map, ready(), grid, mismatched), InputError);
}

TEST(Evaluation, ASingleTargetStartsFromTheDemonstratedPostureNearestItClampedToTheSoftLimits) {
  Eigen::VectorXd beyond = ready();
  beyond[1] = lwr4().softUpperLimits()[1] + 0.01;  // recorded a hair beyond the soft limit
  Eigen::VectorXd shown = ready();
  shown[0] += 0.6;
  Eigen::VectorXd broken = ready();
  broken[0] += 0.3;
  broken[2] = std::nan("");
  learning::TrainingSet demonstration;
  demonstration.X.resize(3, 4);
  demonstration.Y.resize(7, 4);
  const std::vector<Eigen::VectorXd> postures{shown, beyond, ready(), broken};
  for (Eigen::Index l = 0; l < 4; ++l) {
    const Eigen::VectorXd q = postures[static_cast<std::size_t>(l)].cwiseMin(lwr4().upperLimits());
    demonstration.X.col(l) = robot::tipPose(lwr4(), q.allFinite() ? q : ready()).translation();
    demonstration.Y.col(l) = postures[static_cast<std::size_t>(l)];
  }
  demonstration.X.col(3) += Eigen::Vector3d(0.0, 0.0, 0.05);  // the broken sample 5 cm above ready()'s tip
  const Eigen::VectorXd fallback = lwr4().midPosture();
  const Eigen::Vector3d near_shown = demonstration.X.col(0) + Eigen::Vector3d(0.01, 0.0, 0.0);
  const auto standing = demonstratedStandingPostures(lwr4(), demonstration);
  EXPECT_EQ(standing.size(), 3U);  // the broken sample is left out
  EXPECT_EQ(nearestStandingPosture(standing, near_shown, fallback), shown);
  const Eigen::VectorXd clamped = nearestStandingPosture(standing, demonstration.X.col(1), fallback);
  EXPECT_DOUBLE_EQ(clamped[1], lwr4().softUpperLimits()[1]);
  // The sample without a finite posture is passed over for the next nearest.
  EXPECT_EQ(nearestStandingPosture(standing, demonstration.X.col(3), fallback), ready());
  // Nothing that fits the robot: the fallback.
  learning::TrainingSet positions_only;
  positions_only.X = demonstration.X;
  EXPECT_TRUE(demonstratedStandingPostures(lwr4(), positions_only).empty());
  EXPECT_EQ(nearestStandingPosture({}, near_shown, fallback), fallback);
  learning::TrainingSet other_robot = demonstration;
  other_robot.Y.conservativeResize(6, Eigen::NoChange);
  EXPECT_TRUE(demonstratedStandingPostures(lwr4(), other_robot).empty());
}

TEST(Evaluation, ApproachNamesParseAndUnknownOnesAreRefused) {
  EXPECT_EQ(parseApproach("visited"), ApproachFrom::kNearestVisited);
  EXPECT_EQ(approachName(ApproachFrom::kNearestVisited), "visited");
  EXPECT_EQ(parseApproach("nearest"), ApproachFrom::kNearestReached);
  EXPECT_EQ(approachName(ApproachFrom::kNearestReached), "nearest");
  EXPECT_EQ(parseApproach("learned"), ApproachFrom::kLearnedPosture);
  EXPECT_EQ(parseApproach("start"), ApproachFrom::kStartPosture);
  EXPECT_EQ(parseApproach("previous"), ApproachFrom::kPreviousTarget);
  EXPECT_EQ(approachName(ApproachFrom::kPreviousTarget), "previous");
  EXPECT_THROW(parseApproach("home"), InputError);
}

}  // namespace
}  // namespace flexirob::app
