// Collision world: contacts with the right link and obstacle, self-collision, distances.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/controllers.hpp"
#include "robot/mesh_solid.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"
#include "robot/sim/simulation.hpp"
#include "test_urdf.hpp"

namespace flexirob::robot {
namespace {

// Three links of 0.4, 0.4 and 0.45 m with cylinder collision geometry (radius 0.05 m): j1 turns
// about z, j2 and j3 about y, so at j2 = 90° the second link points along +x at z = 0.4 m.
constexpr const char* kPlanarArm = R"(<?xml version="1.0"?>
<robot name="three_link">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="2" effort="200"/></joint>
  <link name="link1">
    <inertial><origin xyz="0 0 0.2"/><mass value="2"/><inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.0025"/></inertial>
    <collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
  </link>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/><limit lower="-2.8" upper="2.8" velocity="2" effort="200"/></joint>
  <link name="link2">
    <inertial><origin xyz="0 0 0.2"/><mass value="2"/><inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.0025"/></inertial>
    <collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
  </link>
  <joint name="j3" type="revolute"><parent link="link2"/><child link="link3"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/><limit lower="-2.8" upper="2.8" velocity="2" effort="200"/></joint>
  <link name="link3">
    <inertial><origin xyz="0 0 0.225"/><mass value="1"/><inertia ixx="0.017" ixy="0" ixz="0" iyy="0.017" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 0.225"/><geometry><cylinder radius="0.05" length="0.45"/></geometry></collision>
  </link>
  <joint name="tip_joint" type="fixed"><parent link="link3"/><child link="tip"/><origin xyz="0 0 0.45"/></joint>
  <link name="tip"/>
</robot>)";

const RobotModel& threeLinkArm() {
  static const RobotModel model = RobotModel::fromUrdfString(kPlanarArm, ".");
  return model;
}

// The three-link arm with link1's cylinder centred `centre_z` up and `length` long (0.2 and 0.4
// m: standing on the table).
RobotModel withLink1Cylinder(double centre_z, double length) {
  std::string urdf = kPlanarArm;
  const std::string link1_cylinder = R"(<collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.05" length="0.4"/>)";
  const std::size_t at = urdf.find(link1_cylinder);
  if (at == std::string::npos || at != urdf.find("<collision>")) throw std::logic_error("link1's cylinder not found");
  std::ostringstream replacement;
  replacement << R"(<collision><origin xyz="0 0 )" << centre_z << R"("/><geometry><cylinder radius="0.05" length=")" << length << R"("/>)";
  urdf.replace(at, link1_cylinder.size(), replacement.str());
  return RobotModel::fromUrdfString(urdf, ".");
}

Obstacle box(const std::string& name, const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  Obstacle obstacle;
  obstacle.name = name;
  obstacle.shape = Obstacle::Shape::kBox;
  obstacle.X_WO.translation() = centre;
  obstacle.size = size;
  return obstacle;
}

Obstacle sphere(const std::string& name, const Eigen::Vector3d& centre, double radius) {
  Obstacle obstacle;
  obstacle.name = name;
  obstacle.shape = Obstacle::Shape::kSphere;
  obstacle.X_WO.translation() = centre;
  obstacle.size = Eigen::Vector3d(radius, 0, 0);
  return obstacle;
}

TEST(CollisionWorld, ReportsABoxAcrossTheArmsPathWithTheLinkThatHitsIt) {
  Scene scene;
  // A bar across the path of link2 when j2 swings it down towards +x.
  scene.obstacles.push_back(box("crossbar", Eigen::Vector3d(0.25, 0.0, 0.4), Eigen::Vector3d(0.06, 0.5, 0.06)));
  ParameterSet parameters(simulationParameters());
  Simulation sim(threeLinkArm(), &scene, parameters);
  sim.reset(Eigen::Vector3d(0.0, 0.0, 0.0));
  EXPECT_TRUE(sim.contacts().empty());
  RobotState free_state;
  sim.readState(free_state);
  EXPECT_FALSE(free_state.in_contact);
  ParameterSet limits(limiterParameters());
  CommandLimiter limiter(threeLinkArm(), limits, sim.cycleTime());
  limiter.reset(Eigen::Vector3d::Zero());
  JointImpedanceCommand command;
  command.resize(3);
  command.stiffness.setConstant(300.0);
  command.damping.setConstant(0.95);
  const Eigen::Vector3d goal(0.0, std::numbers::pi / 2, 0.0);
  double first_contact_angle = -1.0;
  for (int k = 0; k < 3000; ++k) {
    command.q_cmd = limiter.update(goal);
    sim.writeCommand(command);
    sim.step();
    if (first_contact_angle < 0 && !sim.contacts().empty()) {
      RobotState state;
      sim.readState(state);
      EXPECT_TRUE(state.in_contact) << "the measured state says the arm overlaps an obstacle";
      first_contact_angle = state.q[1];
    }
  }
  ASSERT_GE(sim.collisions().events(), 1U);
  const auto& event = sim.collisions().eventLog().front();
  EXPECT_EQ(sim.collisionWorld()->bodyName(event.contact.body), "link2");
  EXPECT_EQ(sim.collisionWorld()->otherName(event.contact), "crossbar");
  EXPECT_FALSE(event.contact.isSelfCollision());
  // First touch when the bar's upper near edge (x = 0.22, z = 0.43, i.e. (0.22, 0.03) from
  // the pivot) comes within the cylinder's radius of link2's axis (sin θ, cos θ):
  // 0.22·cos θ − 0.03·sin θ = 0.05, solved by bisection.
  double low = 0.5, high = std::numbers::pi / 2;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (low + high);
    (0.22 * std::cos(mid) - 0.03 * std::sin(mid) > 0.05 ? low : high) = mid;
  }
  EXPECT_GT(first_contact_angle, low - 2e-3);
  EXPECT_LT(first_contact_angle, low + 1e-2);  // detected within a few cycles of the touch
  EXPECT_GT(sim.collisions().collidingSteps(), 100U);
}

TEST(CollisionWorld, DistanceToASphereMatchesTheGeometry) {
  Scene scene;
  scene.obstacles.push_back(sphere("ball", Eigen::Vector3d(0.4, 0.0, 0.2), 0.1));
  CollisionWorld world(threeLinkArm(), scene);
  world.update(Eigen::Vector3d::Zero());
  // link1's axis is the z axis: distance = 0.4 − 0.1 (ball) − 0.05 (cylinder).
  EXPECT_NEAR(world.distance(1, 0), 0.25, 1e-3);
  const Clearance clearance = world.clearance();
  EXPECT_EQ(clearance.body, 1);
  EXPECT_NEAR(clearance.distance, 0.25, 1e-3);
  EXPECT_TRUE(world.contacts().empty());
}

TEST(CollisionWorld, AFineMeshObstacleCollidesAsTheSimplifiedSolidTheInsideTestsUse) {
  // A ball of 0.1 m as 80 000 triangles: simplified, and the collision model takes those.
  TriangleMesh fine;
  constexpr std::uint32_t kRings = 200, kSegments = 200;
  for (std::uint32_t i = 0; i <= kRings; ++i) {
    for (std::uint32_t j = 0; j < kSegments; ++j) {
      const double polar = std::numbers::pi * i / kRings, azimuth = 2.0 * std::numbers::pi * j / kSegments;
      fine.vertices.emplace_back(Eigen::Vector3d(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                                                 std::cos(polar)).cast<float>() * 0.1F);
    }
  }
  fine.normals = fine.vertices;
  const auto at = [](std::uint32_t i, std::uint32_t j) { return i * kSegments + j % kSegments; };
  for (std::uint32_t i = 0; i < kRings; ++i) {
    for (std::uint32_t j = 0; j < kSegments; ++j) {
      if (i > 0) fine.indices.insert(fine.indices.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
      if (i + 1 < kRings) fine.indices.insert(fine.indices.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  Obstacle ball;
  ball.name = "scanned ball";
  ball.shape = Obstacle::Shape::kMesh;
  ball.X_WO.translation() = Eigen::Vector3d(0.4, 0.0, 0.2);
  ball.mesh_solid = std::make_shared<const MeshSolid>(fine);  // no file: the model must take the solid's triangles
  const double deviation = ball.mesh_solid->deviation();
  ASSERT_GT(deviation, 0.0);
  Scene scene;
  scene.obstacles.push_back(ball);
  CollisionWorld world(threeLinkArm(), scene);
  world.update(Eigen::Vector3d::Zero());
  // As the primitive ball above: 0.4 − 0.1 − 0.05, up to what the simplification moved.
  EXPECT_NEAR(world.clearance().distance, 0.25, deviation + 1e-3);
  ASSERT_EQ(sceneNotes(scene).size(), 1U);
  EXPECT_NE(sceneNotes(scene)[0].find("'scanned ball': its 79600 triangles are simplified to"), std::string::npos)
      << sceneNotes(scene)[0];
}

// The plane the robot stands on (Sect. 4.2.1: q2 ≫ π/2 "would result in collisions with the
// table surface").
TEST(CollisionWorld, TheTableTopStopsEveryLinkButThoseStandingOnIt) {
  CollisionWorld world(threeLinkArm(), Scene{});
  ASSERT_EQ(world.obstacleCount(), 1);
  const int table = 0;
  EXPECT_EQ(world.obstacleName(table), "table");
  // Upright, link2's cylinder starts 0.4 m above the table; link1 stands on it and is not
  // checked against it.
  world.update(Eigen::Vector3d::Zero());
  EXPECT_TRUE(world.contacts().empty());
  EXPECT_EQ(world.distance(1, table), std::numeric_limits<double>::infinity());
  const Clearance clearance = world.clearance();
  EXPECT_EQ(clearance.body, 2);
  EXPECT_NEAR(clearance.distance, 0.4, 1e-3);
  // The same with link1's cylinder reaching 1 cm into the table: standing on it, not a contact.
  const RobotModel sunk = withLink1Cylinder(0.195, 0.41);
  CollisionWorld sunk_world(sunk, Scene{});
  for (const double j2 : {0.0, 1.0, 2.0}) {
    sunk_world.update(Eigen::Vector3d(0.5, j2, 0.0));
    EXPECT_TRUE(sunk_world.contacts().empty()) << "j2 = " << j2;
  }
  EXPECT_EQ(sunk_world.distance(1, table), std::numeric_limits<double>::infinity());
  // link2 along +x at z = 0.4 m and link3 hanging from its end: its 0.45 m reach 5 cm into the table.
  world.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, std::numbers::pi / 2));
  const auto& contacts = world.contacts();
  ASSERT_EQ(contacts.size(), 1U);
  EXPECT_EQ(world.bodyName(contacts[0].body), "link3");
  EXPECT_EQ(world.otherName(contacts[0]), "table");
  EXPECT_NEAR(contacts[0].depth, 0.05, 1e-3);
  EXPECT_NEAR(world.distance(3, table), -0.05, 1e-3);
  // Swung down to its limit, link3 ends 0.4176 m below the table top (its axis 2.8 rad from the
  // vertical, the cap's rim 0.05 sin 2.8 below its centre): the depth is still taken from the top.
  world.update(Eigen::Vector3d(0.0, 2.8, 0.0));
  const double tip_z = 0.4 + (0.4 + 0.45) * std::cos(2.8) - 0.05 * std::sin(2.8);
  double link3_depth = 0.0;
  for (const auto& contact : world.contacts()) {
    if (world.bodyName(contact.body) == "link3" && world.otherName(contact) == "table") link3_depth = contact.depth;
  }
  EXPECT_NEAR(link3_depth, -tip_z, 2e-3);
  EXPECT_NEAR(world.distance(3, table), tip_z, 2e-3);

  // A scene can say the robot stands on no table; one naming an obstacle "table" keeps it.
  Scene no_table;
  no_table.table = false;
  CollisionWorld without(threeLinkArm(), no_table);
  EXPECT_EQ(without.obstacleCount(), 0);
  without.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, std::numbers::pi / 2));
  EXPECT_TRUE(without.contacts().empty());
  Scene named;
  named.obstacles.push_back(box("table", Eigen::Vector3d(2.0, 0.0, 0.5), Eigen::Vector3d(0.1, 0.1, 0.1)));
  CollisionWorld both(threeLinkArm(), named);
  ASSERT_EQ(both.obstacleCount(), 2);
  EXPECT_EQ(both.obstacleName(0), "table");
  EXPECT_EQ(both.obstacleName(1), "table (z = 0)");
}

TEST(CollisionWorld, ALinkNoJointCanLowerIsNoClearanceProblemButOneTheReferencePutsInTheTableIs) {
  // link1 raised 1.4 cm above the table: j1 only turns it about the vertical, so the gap can
  // never close or widen and the clearance is that of link2 and link3, 0.4 m upright.
  const RobotModel raised = withLink1Cylinder(0.207, 0.386);
  CollisionWorld raised_world(raised, Scene{});
  raised_world.update(Eigen::Vector3d::Zero());
  EXPECT_EQ(raised_world.distance(1, 0), std::numeric_limits<double>::infinity());
  const Clearance clearance = raised_world.clearance();
  EXPECT_NE(clearance.body, 1);
  EXPECT_NEAR(clearance.distance, 0.4, 1e-3);

  // j2's range [1.6, 2.8] puts the reference (mid-range) posture's link3 into the table: that
  // is a posture to avoid, not a link standing on the table.
  std::string bent_urdf = kPlanarArm;
  const std::string j2_limits = R"(<limit lower="-2.8" upper="2.8" velocity="2" effort="200"/></joint>
  <link name="link2">)";
  ASSERT_NE(bent_urdf.find(j2_limits), std::string::npos);
  bent_urdf.replace(bent_urdf.find(j2_limits), j2_limits.size(), R"(<limit lower="1.6" upper="2.8" velocity="2" effort="200"/></joint>
  <link name="link2">)");
  const RobotModel bent = RobotModel::fromUrdfString(bent_urdf, ".");
  ASSERT_NEAR(bent.midPosture()[1], 2.2, 1e-12);
  CollisionWorld bent_world(bent, Scene{});
  bent_world.update(bent.midPosture());
  bool link3_on_table = false;
  for (const auto& contact : bent_world.contacts()) link3_on_table |= bent_world.bodyName(contact.body) == "link3";
  EXPECT_TRUE(link3_on_table);
  EXPECT_LT(bent_world.distance(3, 0), 0.0);
}

// The three-link arm on a carriage 2 cm above the table, the carriage on a rail: a horizontal
// rail keeps its height as a vertical axis does, so the carriage's gap to the table is no
// clearance (every posture of the arm kept only 2 cm); a vertical lift can lower it.
RobotModel armOnCarriage(const std::string& rail_axis) {
  std::string urdf = kPlanarArm;
  const std::string base = R"(<link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>)";
  EXPECT_NE(urdf.find(base), std::string::npos);
  urdf.replace(urdf.find(base), base.size(), R"(<link name="base"/>
  <joint name="rail" type="prismatic"><parent link="base"/><child link="carriage"/>
    <origin xyz="0 0 0.02"/><axis xyz=")" + rail_axis + R"("/><limit lower="0" upper="0.5" velocity="0.5" effort="200"/></joint>
  <link name="carriage">
    <inertial><origin xyz="0 0 0.02"/><mass value="3"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.02"/><geometry><box size="0.2 0.2 0.04"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="carriage"/><child link="link1"/><origin xyz="0 0 0.04"/>)");
  return RobotModel::fromUrdfString(urdf, ".");
}

TEST(CollisionWorld, ACarriageOnAHorizontalRailIsNoClearanceProblemOneOnALiftIs) {
  const RobotModel rail = armOnCarriage("0 1 0");
  ASSERT_EQ(rail.dof(), 4);
  CollisionWorld rail_world(rail, Scene{});
  ASSERT_EQ(rail_world.bodyName(1), "carriage");
  rail_world.update(Eigen::Vector4d(0.25, 0.0, 0.0, 0.0));
  EXPECT_EQ(rail_world.distance(1, 0), std::numeric_limits<double>::infinity());
  EXPECT_NE(rail_world.clearance(0.5).body, 1);

  const RobotModel lift = armOnCarriage("0 0 1");
  CollisionWorld lift_world(lift, Scene{});
  lift_world.update(Eigen::Vector4d(0.25, 0.0, 0.0, 0.0));
  EXPECT_NEAR(lift_world.distance(1, 0), 0.27, 1e-3);
  lift_world.update(Eigen::Vector4d::Zero());
  EXPECT_NEAR(lift_world.distance(1, 0), 0.02, 1e-3);
}

TEST(CollisionWorld, AGapToTheFirstLinkItsJointCannotChangeIsNoClearanceProblemButStillMeasured) {
  // A fixture flush against the LWR IV's base, as high as the base: link1 turns about its own
  // axis beside it, 1.7-1.8 cm away whatever A1 does. The clearance a posture keeps is the
  // rest of the arm's; the gap itself is still measured (and a contact would still count).
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  Scene scene;
  Obstacle fixture;
  fixture.name = "fixture";
  fixture.shape = Obstacle::Shape::kBox;
  fixture.size = Eigen::Vector3d(0.2, 0.3, 0.11);
  fixture.X_WO.translation() = Eigen::Vector3d(-0.186, 0.0, 0.055);
  scene.obstacles.push_back(fixture);
  CollisionWorld world(model, scene);
  for (const double a1 : {-2.0, 0.0, 1.0}) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
    q[0] = a1;
    world.update(q);
    EXPECT_NEAR(world.distance(1, 0), 0.0175, 0.002) << "A1 = " << a1;
    const Clearance clearance = world.clearance(0.05);
    EXPECT_FALSE(clearance.body == 1 && clearance.obstacle == 0) << "A1 = " << a1 << ": " << clearance.distance;
  }
  // Without the table, the nearest the upright arm comes to the fixture is link1 no longer.
  scene.table = false;
  CollisionWorld without_table(model, scene);
  without_table.update(Eigen::VectorXd::Zero(7));
  const Clearance upright = without_table.clearance(0.5);
  EXPECT_GT(upright.body, 1);
  EXPECT_EQ(upright.obstacle, 0);
}

TEST(CollisionWorld, TheLwr4LowersItsFlangeIntoTheTableAndNotBefore) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  CollisionWorld world(model, Scene{});
  const int table = world.obstacleCount() - 1;
  ASSERT_EQ(world.obstacleName(table), "table");
  // Upright, link1's mesh starts 11 cm above the table, and A1 only turns it about the
  // vertical: it never reaches the table and is not checked against it. link2 is, 0.24 m above
  // (A2 0.3105 m up, its mesh reaching 7 cm below the axis).
  world.update(Eigen::VectorXd::Zero(7));
  EXPECT_EQ(world.distance(1, table), std::numeric_limits<double>::infinity());
  EXPECT_NEAR(world.distance(2, table), 0.24, 0.01);
  // The stretched arm tilted forward at A2: the flange crosses z = 0 near A2 = 2 rad
  // (shoulder 0.3105 m up, 0.868 m from shoulder to flange).
  Kinematics kinematics(model);
  for (const double a2 : {1.0, 1.5, 2.0}) {
    SCOPED_TRACE(a2);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
    q[1] = a2;
    kinematics.update(q);
    world.update(q);
    const bool flange_below = kinematics.p_WT().z() < 0.0;
    EXPECT_EQ(flange_below, a2 == 2.0) << kinematics.p_WT().transpose();
    bool flange_on_table = false;
    for (const auto& contact : world.contacts()) {
      EXPECT_EQ(world.otherName(contact), "table");
      flange_on_table |= world.bodyName(contact.body) == "link7";
    }
    EXPECT_EQ(flange_on_table, flange_below);
  }
}

// A query answers for the posture given, whatever the world was asked before: postures near
// setup II's boxes, queried one after another, get the contacts a fresh world finds for each.
TEST(CollisionWorld, ContactsDependOnThePostureAloneNotOnThePosturesQueriedBefore) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const Scene scene = loadScene("setup_II");
  CollisionWorld queried_in_turn(model, scene);
  Eigen::VectorXd between_the_boxes(7);
  between_the_boxes << 0.0, 0.6, 0.0, -1.6, 0.0, 0.9, 0.0;
  std::mt19937_64 bits(3);
  std::normal_distribution<double> step(0.0, 0.25);
  const auto expectSameContacts = [&](const Eigen::VectorXd& q) {
    queried_in_turn.update(q);
    const std::vector<Contact> in_turn = queried_in_turn.contacts();
    CollisionWorld fresh(model, scene);
    fresh.update(q);
    const std::vector<Contact>& alone = fresh.contacts();
    ASSERT_EQ(in_turn.size(), alone.size());
    for (std::size_t c = 0; c < alone.size(); ++c) {
      EXPECT_EQ(in_turn[c].body, alone[c].body);
      EXPECT_EQ(in_turn[c].obstacle, alone[c].obstacle);
      EXPECT_NEAR(in_turn[c].depth, alone[c].depth, 1e-9);
      if (c > 0) {
        EXPECT_GE(alone[c - 1].depth, alone[c].depth) << "the deepest contact first";
      }
    }
  };
  int in_contact = 0;
  for (int k = 0; k < 60; ++k) {
    SCOPED_TRACE(k);
    Eigen::VectorXd q = between_the_boxes;
    for (int j = 0; j < 7; ++j) q[j] += step(bits);
    q = q.cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
    expectSameContacts(q);
    // Again after a move of a few millimetres, where contact points of the posture before
    // would still lie within Bullet's breaking distance.
    expectSameContacts(q + Eigen::VectorXd::Constant(7, 0.01));
    CollisionWorld fresh(model, scene);
    fresh.update(q);
    in_contact += fresh.contacts().empty() ? 0 : 1;
  }
  // Both kinds of posture were asked.
  EXPECT_GT(in_contact, 5);
  EXPECT_LT(in_contact, 55);
}

TEST(CollisionWorld, ReportsSelfCollisionButNeverAdjacentLinks) {
  CollisionWorld world(threeLinkArm(), Scene{});
  EXPECT_FALSE(world.selfPairChecked(1, 2));
  EXPECT_FALSE(world.selfPairChecked(2, 3));
  EXPECT_TRUE(world.selfPairChecked(1, 3));
  // Fold link3 back onto link1: at j2 = 90°, j3 = 2.7 rad link3 points down and back across the z axis.
  world.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, 2.7));
  const auto& contacts = world.contacts();
  ASSERT_EQ(contacts.size(), 1U);
  EXPECT_TRUE(contacts[0].isSelfCollision());
  EXPECT_EQ(world.bodyName(contacts[0].body), "link1");
  EXPECT_EQ(world.otherName(contacts[0]), "link3");
}

TEST(CollisionWorld, SelfClearanceIsTheGapBetweenLinksApartAlongTheChain) {
  CollisionWorld world(threeLinkArm(), Scene{});
  // link2 along +x at z = 0.4 m, link3 straight down from its end: link1 (the z axis) and link3
  // are parallel cylinders 0.4 m apart, radius 0.05 m each.
  world.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, std::numbers::pi / 2));
  EXPECT_NEAR(world.selfClearance(2), 0.3, 1e-3);
  // Beyond the search distance there is nothing to report.
  EXPECT_TRUE(std::isinf(world.selfClearance(2, 0.2)));
  // No two of the four bodies (base and three links) are four apart along the chain.
  EXPECT_TRUE(std::isinf(world.selfClearance(4)));
  // Folded onto link1, the pair penetrates (as contacts() reports); three apart, only the base
  // (a small sphere at the origin) and link3 count, and they stay clear.
  world.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, 2.7));
  EXPECT_LT(world.selfClearance(2), 0.0);
  EXPECT_GT(world.selfClearance(3), 0.0);
  // At 90° + 30°, link3 leans back towards link1: its lower end (0.4 − 0.45 sin 30°) m
  // from the z axis, 0.4 − 0.45 cos 30° m high, is the closest point, minus both radii.
  world.update(Eigen::Vector3d(0.0, std::numbers::pi / 2, std::numbers::pi / 2 + std::numbers::pi / 6));
  EXPECT_NEAR(world.selfClearance(2), 0.4 - 0.45 * 0.5 - 0.05 - 0.05 * std::cos(std::numbers::pi / 6), 3e-3);
}

TEST(CollisionWorld, LinksWithoutCollisionGeometryGetCapsules) {
  std::string bare = kPlanarArm;
  for (std::size_t start; (start = bare.find("<collision>")) != std::string::npos;) {
    bare.erase(start, bare.find("</collision>", start) + std::string("</collision>").size() - start);
  }
  const RobotModel model = RobotModel::fromUrdfString(bare, ".");
  Scene scene;
  // 1 cm beside link2's capsule surface when the arm is straight up: the capsule radius comes
  // from the link's inertia, r = sqrt(2·0.0025/2) = 0.05 m.
  scene.obstacles.push_back(sphere("ball", Eigen::Vector3d(0.11, 0.0, 0.6), 0.05));
  CollisionWorld world(model, scene);
  EXPECT_EQ(world.bodyShapeSource(2), "capsule");
  world.update(Eigen::Vector3d::Zero());
  EXPECT_NEAR(world.distance(2, 0), 0.01, 1e-3);
  EXPECT_TRUE(world.contacts().empty());
  world.update(Eigen::Vector3d(0.0, 0.05, 0.0));  // lean link2 towards the ball
  ASSERT_FALSE(world.contacts().empty());
  EXPECT_EQ(world.bodyName(world.contacts()[0].body), "link2");
}

TEST(CollisionWorld, ALinkWhoseMassWasAssumedGetsTheDefaultCapsule) {
  // The 1 kg the model assumes for a link without <inertial> says nothing of its girth: l1
  // (0.4 m along z from 0.1 m) keeps the 5 cm default radius, not the 0.18 m the assumed
  // sphere inertia would give.
  const RobotModel model = RobotModel::fromUrdfString(flexirob::testing::masslessArm(), ".");
  ASSERT_TRUE(model.bodies()[1].inertia_assumed);
  Scene scene;
  scene.obstacles.push_back(sphere("ball", Eigen::Vector3d(0.1, 0.0, 0.3), 0.02));
  CollisionWorld world(model, scene);
  EXPECT_EQ(world.bodyShapeSource(1), "capsule");
  world.update(Eigen::Vector3d::Zero());
  EXPECT_NEAR(world.distance(1, 0), 0.1 - 0.02 - 0.05, 1e-3);
  EXPECT_TRUE(world.contacts().empty());
}

TEST(CollisionWorld, UsesTheLwr4CollisionMeshes) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  CollisionWorld world(model, Scene{});
  for (int b = 1; b <= model.dof(); ++b) EXPECT_EQ(world.bodyShapeSource(b), "urdf") << b;
  // The arm at its reference posture does not collide with itself.
  world.update(model.midPosture());
  EXPECT_TRUE(world.contacts().empty());
  // A small block in the middle of the forearm at a bent posture touches the forearm link.
  Eigen::VectorXd q(7);
  q << 0.0, 0.8, 0.0, -1.2, 0.0, 0.5, 0.0;
  Kinematics kinematics(model);
  kinematics.update(q);
  Scene scene;
  const Eigen::Vector3d wrist = kinematics.X_WB(6).translation();
  const Eigen::Vector3d elbow = kinematics.X_WB(4).translation();
  scene.obstacles.push_back(box("block", elbow + 0.6 * (wrist - elbow), Eigen::Vector3d(0.02, 0.02, 0.02)));
  CollisionWorld with_box(model, scene);
  with_box.update(q);
  const auto& contacts = with_box.contacts();
  ASSERT_FALSE(contacts.empty());
  EXPECT_EQ(with_box.bodyName(contacts[0].body), "link5");
  EXPECT_EQ(with_box.otherName(contacts[0]), "block");
}

TEST(CollisionWorld, LeavesPairsAroundShoulderElbowAndWristToTheJointLimits) {
  // The LWR IV's A1/A2, A3/A4, A5/A6 and A6/A7 axes cross in one point: the bodies on either
  // side only turn about it, and the joint limits keep them apart on the real arm.
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  CollisionWorld world(model, Scene{});
  EXPECT_FALSE(world.selfPairChecked(5, 7)) << "forearm and flange, around the wrist";
  EXPECT_FALSE(world.selfPairChecked(3, 5)) << "upper arm and forearm, around the elbow";
  EXPECT_TRUE(world.selfPairChecked(1, 4));
  EXPECT_TRUE(world.selfPairChecked(2, 7));
  // The wrist bent to its software limit is not a collision.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  q << 0.0, 0.5, 0.0, -1.2, 0.0, model.joints()[5].limits.soft_upper, 0.0;
  world.update(q);
  for (const auto& contact : world.contacts()) {
    EXPECT_FALSE(contact.isSelfCollision()) << world.bodyName(contact.body) << " / " << world.otherName(contact);
  }
}

// A mesh the importer cannot read is found when the collision model is built: the importer's
// words name a file, the message also the link and the robot it belongs to.
TEST(CollisionWorld, AnUnreadableLinkMeshIsNamedWithItsLinkAndRobot) {
  flexirob::testing::TempDir dir;
  dir.write("meshes/hand.dae", "<COLLADA><this is not");
  const auto urdf = dir.write("arm.urdf", R"(<robot name="meshy"><link name="base"/>
    <joint name="j" type="revolute"><parent link="base"/><child link="hand"/><origin xyz="0 0 0.3"/>
      <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="10"/></joint>
    <link name="hand"><collision><geometry><mesh filename="meshes/hand.dae"/></geometry></collision></link></robot>)");
  const RobotModel model = RobotModel::fromUrdfFile(urdf);
  try {
    CollisionWorld world(model, Scene{});
    FAIL() << "an unreadable mesh was accepted";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("link 'hand' of robot 'meshy': cannot load mesh '", 0), 0U) << message;
    EXPECT_NE(message.find("hand.dae"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace flexirob::robot
