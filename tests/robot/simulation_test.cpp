// Bullet simulation backend: gravity-compensated joint impedance, the hand and τ_ext,
// deterministic stepping.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <numbers>
#include <regex>
#include <utility>

#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/sim/simulation.hpp"
#include "test_urdf.hpp"

namespace flexirob::robot {
namespace {

const RobotModel& lwr4() {
  static const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

ParameterSet simParameters() { return ParameterSet(simulationParameters()); }

Eigen::VectorXd bentPosture() {
  Eigen::VectorXd q(7);
  q << 0.2, 0.7, -0.3, -1.1, 0.4, 0.6, -0.2;
  return q;
}

JointImpedanceCommand holdCommand(const Eigen::VectorXd& q, double stiffness, double damping) {
  JointImpedanceCommand command;
  command.resize(static_cast<int>(q.size()));
  command.q_cmd = q;
  command.stiffness.setConstant(stiffness);
  command.damping.setConstant(damping);
  return command;
}

TEST(Simulation, HoldsABentPostureAgainstGravity) {
  // Gravity compensation and Bullet's multibody must agree on every mass and frame, or the arm sags.
  Simulation sim(lwr4(), nullptr, simParameters());
  sim.reset(bentPosture());
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 300.0, 0.95)), CommandStatus::kAccepted);
  for (int k = 0; k < 1000; ++k) sim.step();
  RobotState state;
  sim.readState(state);
  EXPECT_NEAR(state.time, 1.0, 1e-9);
  EXPECT_LT((state.q - bentPosture()).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT(state.qd.cwiseAbs().maxCoeff(), 1e-3);
}

TEST(Simulation, WithoutGravityCompensationTheArmFalls) {
  // The counter-check of the test above: the same arm with no stiffness sags under gravity,
  // as predicted by the sign of g(q) (a joint whose gravity torque is positive moves negative).
  ParameterSet parameters = simParameters();
  parameters.set("sim.drift_damping", 0.0);
  Simulation sim(lwr4(), nullptr, parameters);
  sim.reset(bentPosture());
  const Eigen::VectorXd g = sim.gravityTorque();
  JointImpedanceCommand command = holdCommand(bentPosture(), 300.0, 0.95);
  command.stiffness.setZero();
  command.damping.setZero();
  sim.writeCommand(command);
  // Turn gravity compensation off by commanding stiffness against it is not possible, so the
  // check is made through a heavier gravity in a second simulation.
  ParameterSet heavy = parameters;
  heavy.set("sim.gravity", 19.62);
  Simulation heavier(lwr4(), nullptr, heavy);
  heavier.reset(bentPosture());
  heavier.writeCommand(command);
  for (int k = 0; k < 20; ++k) {
    sim.step();
    heavier.step();
  }
  RobotState light_state, heavy_state;
  sim.readState(light_state);
  heavier.readState(heavy_state);
  EXPECT_LT((light_state.q - bentPosture()).norm(), 1e-6);  // compensated exactly
  // With twice the gravity but compensation for it, the arm still holds: compensation follows sim.gravity.
  EXPECT_LT((heavy_state.q - bentPosture()).norm(), 1e-6);
  EXPECT_GT(std::abs(g[1]), 1.0);  // the shoulder carries the arm
}

TEST(Simulation, TracksACommandedPostureAndMatchesTheKinematics) {
  Simulation sim(lwr4(), nullptr, simParameters());
  sim.reset(lwr4().midPosture());
  Eigen::VectorXd target = bentPosture();
  ASSERT_EQ(sim.writeCommand(holdCommand(target, 300.0, 0.95)), CommandStatus::kAccepted);
  for (int k = 0; k < 3000; ++k) sim.step();
  RobotState state;
  sim.readState(state);
  EXPECT_LT((state.q - target).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT((state.p_WT() - tipPose(lwr4(), state.q).translation()).norm(), 1e-12);
}

TEST(Simulation, AKinematicsOnlyArmHoldsItsPostureWithinItsLimits) {
  // No link of this arm has <inertial>: with a token gram per link the joint impedance made the
  // integration blow up and a joint ran to hundreds of radians.
  const RobotModel bare = RobotModel::fromUrdfString(flexirob::testing::masslessArm(), std::filesystem::temp_directory_path());
  Simulation sim(bare, nullptr, simParameters());
  Eigen::VectorXd start(3);
  start << 0.0, 0.3, 0.5;
  Eigen::VectorXd target(3);
  target << 0.5, 0.8, -0.4;
  sim.reset(start);
  ASSERT_EQ(sim.writeCommand(holdCommand(target, 300.0, 0.95)), CommandStatus::kAccepted);
  RobotState state;
  for (int k = 0; k < 3000; ++k) {
    sim.step();
    sim.readState(state);
    ASSERT_TRUE(state.q.allFinite()) << k;
    ASSERT_LT(state.q.cwiseAbs().maxCoeff(), 2.0 + 1e-2) << "step " << k;
  }
  EXPECT_LT((state.q - target).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(Simulation, RejectsCommandsItCannotExecute) {
  Simulation sim(lwr4(), nullptr, simParameters());
  JointImpedanceCommand command = holdCommand(bentPosture(), 300.0, 0.7);
  command.q_cmd[3] = std::nan("");
  EXPECT_EQ(sim.writeCommand(command), CommandStatus::kRejected);
  command = holdCommand(bentPosture(), 300.0, 0.7);
  command.q_cmd[1] = 3.0;  // beyond A2's hardware limit
  EXPECT_EQ(sim.writeCommand(command), CommandStatus::kRejected);
  command = holdCommand(bentPosture(), -1.0, 0.7);
  EXPECT_EQ(sim.writeCommand(command), CommandStatus::kRejected);
  EXPECT_THROW(sim.reset(Eigen::VectorXd::Constant(7, 3.5)), InputError);
  EXPECT_THROW(sim.setHandForce(0, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()), InputError);
}

TEST(Simulation, HandForceGivesTheExternalTorqueThatJacobianTransposePredicts) {
  Simulation sim(lwr4(), nullptr, simParameters());
  const Eigen::VectorXd q0 = bentPosture();
  sim.reset(q0);
  sim.writeCommand(holdCommand(q0, 300.0, 0.95));
  // Push the forearm (body 5) 5 cm beyond the elbow, sideways and down.
  Kinematics kinematics(lwr4());
  kinematics.update(q0);
  const Eigen::Vector3d p_B(0.0, 0.0, 0.05);
  const Eigen::Vector3d p_W = kinematics.X_WB(5) * p_B;
  const Eigen::Vector3d F_W(5.0, -8.0, -4.0);
  sim.setHandForce(5, p_W, F_W);
  for (int k = 0; k < 3000; ++k) sim.step();
  RobotState state;
  sim.readState(state);
  // τ_j = F · ∂p/∂q_j by central differences of the forward kinematics at the current posture.
  Eigen::VectorXd expected(7);
  const double h = 1e-6;
  for (int j = 0; j < 7; ++j) {
    Eigen::VectorXd plus = state.q, minus = state.q;
    plus[j] += h;
    minus[j] -= h;
    kinematics.update(plus);
    const Eigen::Vector3d p_plus = kinematics.X_WB(5) * p_B;
    kinematics.update(minus);
    const Eigen::Vector3d p_minus = kinematics.X_WB(5) * p_B;
    expected[j] = F_W.dot((p_plus - p_minus) / (2 * h));
  }
  EXPECT_LT((state.tau_ext - expected).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(state.tau_ext.tail(2).norm(), 0.0);  // joints after the forearm feel nothing
  // The force really acts in the physics: at rest, the springs balance it, K (q_cmd − q) = −τ_ext.
  EXPECT_LT(state.qd.cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_LT((300.0 * (state.q_cmd - state.q) + state.tau_ext).cwiseAbs().maxCoeff(), 2e-2);
  EXPECT_GT(state.tau_ext.cwiseAbs().maxCoeff(), 1.5);
}

// The hardware limits are stops: a hand pushing a joint beyond one holds it there. Before the
// links had colliders, Bullet never solved their limit constraints (a multibody constraint is
// solved only within its links' simulation island): 20 N at the LWR IV's tip took A2 0.15 rad
// through its stop and 150 N 0.8 rad, and a prismatic slide sank 9 cm below its lower limit.
TEST(Simulation, JointLimitStopsHoldAgainstAHandPushingBeyondThem) {
  const std::string slide_arm = R"(<robot name="slide">
  <link name="base"/>
  <joint name="lift" type="prismatic"><parent link="base"/><child link="carriage"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="0" upper="0.5" velocity="1" effort="200"/></joint>
  <link name="carriage"><inertial><origin xyz="0 0 0.1"/><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="carriage"/><child link="arm"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="2" effort="100"/></joint>
  <link name="arm"><inertial><origin xyz="0 0 0.2"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
</robot>)";
  testing::TempDir dir;
  const RobotModel slide = RobotModel::fromUrdfFile(dir.write("slide.urdf", slide_arm));
  struct Case {
    const RobotModel* model;
    Eigen::VectorXd q0;
    int joint;        // pushed towards its limit
    bool upper;       // which one
    int body;         // where the hand pushes
    Eigen::Vector3d direction;
  };
  Eigen::VectorXd lwr_q = bentPosture();
  lwr_q[1] = lwr4().joints()[1].limits.upper - 0.02;
  Kinematics lwr_kinematics(lwr4());
  lwr_kinematics.update(lwr_q);
  Matrix6Xd J;
  lwr_kinematics.tipJacobian(J);
  const std::vector<Case> cases = {
      // The tip pushed along A2's own tip velocity: A2 turns on towards its upper limit.
      {&lwr4(), lwr_q, 1, true, 7, J.block<3, 1>(0, 1).normalized()},
      // The slide's carriage pushed down onto its lower limit, 1 cm above it.
      {&slide, Eigen::Vector2d(0.01, 0.3), 0, false, 1, -Eigen::Vector3d::UnitZ()},
  };
  for (const Case& c : cases) {
    Simulation sim(*c.model, nullptr, simParameters());
    sim.reset(c.q0);
    sim.writeCommand(holdCommand(c.q0, 80.0, 0.7));
    Kinematics kinematics(*c.model);
    const JointLimits& limits = c.model->joints()[static_cast<std::size_t>(c.joint)].limits;
    for (const double force : {20.0, 150.0}) {
      RobotState state;
      for (int k = 0; k < 2000; ++k) {
        sim.readState(state);
        kinematics.update(state.q);
        sim.setHandForce(c.body, kinematics.X_WB(c.body).translation(), force * c.direction);
        sim.step();
      }
      sim.readState(state);
      const double beyond = c.upper ? state.q[c.joint] - limits.upper : limits.lower - state.q[c.joint];
      EXPECT_LT(beyond, 1e-3) << c.model->name() << " joint " << c.joint + 1 << " under " << force << " N";
      // It does reach the stop (the push is strong enough to get there at all).
      EXPECT_GT(beyond, -1e-3) << c.model->name() << " joint " << c.joint + 1 << " under " << force << " N";
    }
  }
}

TEST(Simulation, SteppingIsDeterministic) {
  auto run = [] {
    Simulation sim(lwr4(), nullptr, simParameters());
    sim.reset(bentPosture());
    sim.writeCommand(holdCommand(lwr4().midPosture(), 50.0, 0.7));
    sim.setHandForce(7, tipPose(lwr4(), bentPosture()).translation(), Eigen::Vector3d(3, 2, 1));
    for (int k = 0; k < 500; ++k) sim.step();
    RobotState state;
    sim.readState(state);
    return state.q;
  };
  const Eigen::VectorXd first = run();
  const Eigen::VectorXd second = run();
  EXPECT_EQ(first, second);
}

TEST(Simulation, ReleasedArmComesToRestUnderLowStiffness) {
  // Gravity-compensation stiffness (Tab. A.1: 20 Nm/rad, 0.7) plus the drift damping.
  Simulation sim(lwr4(), nullptr, simParameters());
  sim.reset(bentPosture());
  sim.writeCommand(holdCommand(bentPosture(), 20.0, 0.7));
  sim.setHandForce(7, tipPose(lwr4(), bentPosture()).translation(), Eigen::Vector3d(0, 20, 0));
  for (int k = 0; k < 300; ++k) sim.step();
  sim.clearHandForce();
  RobotState state;
  sim.readState(state);
  EXPECT_GT(state.qd.norm(), 0.05);
  for (int k = 0; k < 4000; ++k) sim.step();
  sim.readState(state);
  EXPECT_LT(state.qd.norm(), 1e-3);
  EXPECT_LT((state.q - bentPosture()).norm(), 1e-3);
}

// The LWR IV with every mass and inertia scaled: the same kinematics, a lighter arm.
RobotModel scaledLwr4(double factor) {
  const std::filesystem::path file = resolveRobotPath("lwr4");
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::regex number(R"re(((?:mass value|ixx|iyy|izz|ixy|ixz|iyz)=")([-0-9.eE+]+)")re");
  std::string scaled;
  auto begin = std::sregex_iterator(text.begin(), text.end(), number);
  std::size_t last = 0;
  for (auto match = begin; match != std::sregex_iterator(); ++match) {
    scaled += text.substr(last, static_cast<std::size_t>(match->position()) - last);
    scaled += (*match)[1].str() + std::to_string(std::stod((*match)[2].str()) * factor) + "\"";
    last = static_cast<std::size_t>(match->position() + match->length());
  }
  scaled += text.substr(last);
  return RobotModel::fromUrdfString(scaled, file.parent_path());
}

TEST(Simulation, AnArmOfAHundredthOfTheLwrsMassesSettlesOnItsCommandInsteadOfShaking) {
  // 0.16 kg in all. The impedance law is applied explicitly: at 4 physics steps per cycle its
  // damping on links this light overshot each step, the torques saturated and the arm shook
  // far from its command. The step count now follows what the arm and the gains need.
  const RobotModel light = scaledLwr4(0.01);
  Simulation sim(light, nullptr, simParameters());
  sim.reset(bentPosture() + Eigen::VectorXd::Constant(7, 0.05));  // within every effort limit
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 300.0, 0.95)), CommandStatus::kAccepted);
  for (int k = 0; k < 2000; ++k) sim.step();
  RobotState state;
  sim.readState(state);
  EXPECT_LT((state.q - bentPosture()).cwiseAbs().maxCoeff(), 1e-4);
  // Bullet steps in single precision: at 20-odd steps per cycle a joint moving at 1e-3 rad/s
  // no longer changes its angle, and a velocity of that size stays with the arm at rest.
  EXPECT_LT(state.qd.cwiseAbs().maxCoeff(), 5e-3);
  EXPECT_EQ(sim.torqueSaturations(), 0U);
  EXPECT_GT(sim.maxSubsteps(), static_cast<int>(simParameters().get("sim.substeps")));
  EXPECT_LE(sim.maxSubsteps(), Simulation::kSubstepCap);
}

TEST(Simulation, TheLwrKeepsTheConfiguredPhysicsStepsWhereverItStands) {
  // Its joints are heavy enough for sim.substeps under every gain of Tab. A.1, so what it does
  // does not depend on the step-count rule. The rule is not idle: allowed a single step, the
  // stiffest gains need more (its flange: 2hc + h²ω² = 2.6 at 4 steps, 11.6 at 1).
  ParameterSet one_step = simParameters();
  one_step.set("sim.substeps", 1.0);
  Simulation single(lwr4(), nullptr, one_step);
  single.reset(bentPosture());
  ASSERT_EQ(single.writeCommand(holdCommand(bentPosture(), 300.0, 0.95)), CommandStatus::kAccepted);
  EXPECT_GE(single.stableSubsteps(), 3);
  EXPECT_LE(single.stableSubsteps(), 4);
  std::mt19937 engine(7);
  const Eigen::VectorXd lower = lwr4().lowerLimits(), upper = lwr4().upperLimits();
  Simulation sim(lwr4(), nullptr, simParameters());
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd q(7);
    for (int j = 0; j < 7; ++j) q[j] = std::uniform_real_distribution<double>(lower[j], upper[j])(engine);
    sim.reset(q);
    for (const auto& [stiffness, damping] : {std::pair{300.0, 0.95}, std::pair{80.0, 0.7}, std::pair{20.0, 0.7}}) {
      ASSERT_EQ(sim.writeCommand(holdCommand(q, stiffness, damping)), CommandStatus::kAccepted);
      EXPECT_EQ(sim.stableSubsteps(), 4) << "posture " << q.transpose() << ", stiffness " << stiffness;
    }
  }
}

TEST(Simulation, TheJointSpaceInertiaIsTheSumOverTheBodiesOfTheirJacobiansWeighted) {
  // M = Σ_b m_b J_v,bᵀ J_v,b + J_ω,bᵀ I_b,W J_ω,b, with J_v,b the Jacobian of body b's centre of
  // mass from Kinematics::pointJacobian and J_ω,b the axes of the joints before it.
  const RobotModel arm9 = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  Simulation sim(arm9, nullptr, simParameters());
  std::mt19937 engine(3);
  const int n = arm9.dof();
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) {
      q[j] = std::uniform_real_distribution<double>(arm9.softLowerLimits()[j], arm9.softUpperLimits()[j])(engine);
    }
    sim.reset(q);
    sim.stableSubsteps();
    Kinematics kinematics(arm9);
    kinematics.update(q);
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(n, n);
    Matrix3Xd J_v(3, n);
    for (int b = 1; b <= n; ++b) {
      const Body& body = arm9.bodies()[static_cast<std::size_t>(b)];
      const Eigen::Isometry3d& X_WB = kinematics.X_WB(b);
      kinematics.pointJacobian(b, X_WB * body.p_BCom, J_v);
      Matrix3Xd J_w = Matrix3Xd::Zero(3, n);
      for (int j = 0; j < b; ++j) J_w.col(j) = kinematics.axis_W(j);
      const Eigen::Matrix3d I_W = X_WB.linear() * body.I_BCom * X_WB.linear().transpose();
      expected += body.mass * J_v.transpose() * J_v + J_w.transpose() * I_W * J_w;
    }
    const Eigen::MatrixXd& M = sim.jointSpaceInertia();
    // The simulation raises every principal moment to at least 1e-6 kg m² (Bullet needs them
    // positive); the rotational terms are 1e-3 kg m² and more.
    EXPECT_LT((M - expected).cwiseAbs().maxCoeff(), 2e-6) << "posture " << q.transpose();
    // The diagonal alone, as the gains are scaled by it (robot/kinematics.hpp), is Bullet's too.
    EXPECT_LT((jointInertiaDiagonal(arm9, q) - M.diagonal()).cwiseAbs().maxCoeff(), 2e-6);
    EXPECT_GT((expected - Eigen::MatrixXd(expected.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 0.1);  // coupled
  }
}

TEST(Simulation, GravityLoadIsTheSlopeOfThePotentialEnergyAgainstTheEffortLimits) {
  // g_j = ∂V/∂q_j with V = Σ_b m_b g z_b (the bodies' centres of mass), by central differences;
  // the load names the joint with the largest |g_j| / effort_j.
  const RobotModel arm9 = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  const ParameterSet parameters = simParameters();
  Simulation sim(arm9, nullptr, parameters);
  const double g = parameters.get("sim.gravity");
  const int n = arm9.dof();
  const auto potential = [&](const Eigen::VectorXd& q) {
    Kinematics kinematics(arm9);
    kinematics.update(q);
    double V = 0.0;
    for (int b = 1; b <= n; ++b) {
      const Body& body = arm9.bodies()[static_cast<std::size_t>(b)];
      V += body.mass * g * (kinematics.X_WB(b) * body.p_BCom).z();
    }
    return V;
  };
  std::mt19937 engine(5);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) {
      q[j] = std::uniform_real_distribution<double>(arm9.softLowerLimits()[j], arm9.softUpperLimits()[j])(engine);
    }
    int worst = -1;
    double worst_ratio = 0.0, worst_torque = 0.0;
    for (int j = 0; j < n; ++j) {
      constexpr double kStep = 1e-6;
      const Eigen::VectorXd dq = kStep * Eigen::VectorXd::Unit(n, j);
      const double torque = std::abs(potential(q + dq) - potential(q - dq)) / (2.0 * kStep);
      const double ratio = torque / arm9.joints()[static_cast<std::size_t>(j)].limits.effort;
      if (ratio > worst_ratio) worst = j, worst_ratio = ratio, worst_torque = torque;
    }
    const Simulation::GravityLoad load = sim.gravityLoad(q);
    ASSERT_EQ(load.joint, worst) << "posture " << q.transpose();
    EXPECT_NEAR(load.torque, worst_torque, 1e-5 * std::max(1.0, worst_torque));
    EXPECT_NEAR(load.ratio, worst_ratio, 1e-6);
    EXPECT_GT(load.torque, 1.0) << "a posture that loads some joint";
  }
  EXPECT_THROW(sim.gravityLoad(Eigen::VectorXd::Zero(3)), InputError);
}

TEST(Simulation, TheBuiltInArmsHoldThemselvesUpWhereverTheirLimitsLetThemStand) {
  // The simulated tutor chooses no posture whose gravity load exceeds 0.9 of an effort limit;
  // for the arms of the thesis' experiments that must leave every posture open.
  for (const char* robot : {"lwr4", "arm9"}) {
    const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath(robot));
    Simulation sim(model, nullptr, simParameters());
    std::mt19937 engine(11);
    double heaviest = 0.0;
    for (int trial = 0; trial < 2000; ++trial) {
      Eigen::VectorXd q(model.dof());
      for (int j = 0; j < model.dof(); ++j) {
        q[j] = std::uniform_real_distribution<double>(model.lowerLimits()[j], model.upperLimits()[j])(engine);
      }
      heaviest = std::max(heaviest, sim.gravityLoad(q).ratio);
    }
    EXPECT_LT(heaviest, 0.9) << robot;
    EXPECT_GT(heaviest, 0.05) << robot << ": some posture loads a joint";
  }
}

TEST(Simulation, SaysWhenEvenTheMostPhysicsStepsAreNotEnough) {
  const RobotModel feather = scaledLwr4(1e-4);
  Simulation sim(feather, nullptr, simParameters());
  sim.reset(bentPosture());
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 300.0, 0.95)), CommandStatus::kAccepted);
  sim.step();
  EXPECT_FALSE(sim.substepCapReached());
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 1e6, 0.95)), CommandStatus::kAccepted);
  sim.step();
  EXPECT_TRUE(sim.substepCapReached());
  EXPECT_EQ(sim.lastSubsteps(), Simulation::kSubstepCap);
  sim.reset(bentPosture());
  EXPECT_FALSE(sim.substepCapReached());
}

TEST(Simulation, AStifferCommandTakesMorePhysicsStepsAtOnce) {
  const RobotModel light = scaledLwr4(0.01);
  Simulation sim(light, nullptr, simParameters());
  sim.reset(bentPosture());
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 20.0, 0.7)), CommandStatus::kAccepted);
  sim.step();
  const int soft = sim.lastSubsteps();
  ASSERT_EQ(sim.writeCommand(holdCommand(bentPosture(), 300.0, 0.95)), CommandStatus::kAccepted);
  sim.step();  // not a multiple of the 10-cycle check: the new gains alone must trigger it
  EXPECT_GT(sim.lastSubsteps(), soft);
}

}  // namespace
}  // namespace flexirob::robot

// Reaching in simulation (the `reach` command's engine).
#include "robot/sim/reach.hpp"

namespace flexirob::robot {
namespace {

TEST(Reach, ConvergesToReachableTargetsWhateverThePosture) {
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  Eigen::VectorXd start(7), elbow_up(7), elbow_turned(7);
  start << 0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0;
  elbow_up << 0.5, 0.6, -1.0, -1.4, 0.3, 0.4, 0.0;
  elbow_turned << -0.6, 0.4, 1.2, -1.0, -0.5, 0.8, 0.3;
  for (const Eigen::VectorXd& posture : {start, elbow_up, elbow_turned}) {
    ReachRequest request;
    request.start = start;
    request.posture = posture;
    request.target = Eigen::Vector3d(-0.45, 0.25, 0.45);
    const ReachResult result = reach(lwr4(), nullptr, parameters, request);
    EXPECT_EQ(result.status, "reached");
    EXPECT_LE(result.error_m, 1e-4);
    EXPECT_LE((tipPose(lwr4(), result.q).translation() - request.target).norm(), 1e-4);
    EXPECT_EQ(result.rejected_commands, 0U);
    EXPECT_EQ(result.collisions, 0U);
  }
}

// The LWR IV with every joint allowed 0.05 rad/s: its tip closes in on the target by well under
// 1 % per the LWR IV's 2 s, yet it gets there. Progress is judged on its own time scale, not
// called out of reach after 3 s.
TEST(Reach, ASlowArmIsGivenTheTimeItNeedsInsteadOfCalledOutOfReach) {
  const std::filesystem::path file = resolveRobotPath("lwr4");
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const RobotModel slow =
      RobotModel::fromUrdfString(std::regex_replace(text, std::regex(R"re(velocity="[0-9.]+")re"), R"(velocity="0.05")"), file.parent_path());
  ASSERT_DOUBLE_EQ(slow.velocityLimits().maxCoeff(), 0.05);
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;
  request.start = slow.midPosture();
  request.target = Eigen::Vector3d(-0.4, 0.2, 0.4);
  request.max_time = 90.0;
  const ReachResult result = reach(slow, nullptr, parameters, request);
  EXPECT_EQ(result.status, "reached") << "after " << result.time_s << " s, " << result.error_m << " m short";
  EXPECT_GT(result.time_s, 10.0) << "slowly";
}

// A continuous joint ten turns round is the same posture; the single-precision simulation had
// lost the resolution to reach from there (a timeout 0.45 mm short).
TEST(Reach, AContinuousJointManyTurnsRoundReachesAsFromWithinOneTurn) {
  const std::filesystem::path file = resolveRobotPath("lwr4");
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string a1 = R"(<joint name="A1" type="revolute">)";
  ASSERT_NE(text.find(a1), std::string::npos);
  text.replace(text.find(a1), a1.size(), R"(<joint name="A1" type="continuous">)");
  const RobotModel turning = RobotModel::fromUrdfString(text, file.parent_path());
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;
  request.start = Eigen::VectorXd(7);
  request.start << 0.2, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0;
  request.target = Eigen::Vector3d(-0.45, 0.25, 0.45);
  const ReachResult within = reach(turning, nullptr, parameters, request);
  ASSERT_EQ(within.status, "reached");
  request.start[0] += 20.0 * std::numbers::pi;
  request.posture = request.start;
  const ReachResult round = reach(turning, nullptr, parameters, request);
  EXPECT_EQ(round.status, "reached");
  EXPECT_EQ(round.steps, within.steps);
  EXPECT_NEAR(round.error_m, within.error_m, 1e-9);
  EXPECT_LE(std::abs(round.q[0]), std::numbers::pi);
  EXPECT_NEAR(turning.withinOneTurn(Eigen::VectorXd::Constant(7, 3.0 * std::numbers::pi + 0.1))[0], -std::numbers::pi + 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(turning.withinOneTurn(Eigen::VectorXd::Constant(7, 2.5))[1], 2.5) << "a revolute joint stays";
}

TEST(Reach, StartsFromMidRangeWhenNoStartIsGiven) {
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;  // no start, no posture: both mid-range
  request.target = Eigen::Vector3d(-0.45, 0.25, 0.45);
  const ReachResult result = reach(lwr4(), nullptr, parameters, request);
  EXPECT_EQ(result.status, "reached");
  EXPECT_EQ(result.gravity_overload, "");
}

// Three joints, the second held to ±0.3 rad: a target low beside the arm needs it tilted 1.2 rad.
// The controller pushes it onto its limit, and the elbow onto its own as far as it folds out,
// and stalls there; the result names both.
TEST(Reach, NamesTheJointsItStalledOnAtTheirLimits) {
  const RobotModel arm = RobotModel::fromUrdfString(R"(<robot name="held"><link name="base"/>
    <joint name="turn" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
      <limit lower="-2" upper="2" velocity="2" effort="100"/></joint><link name="l1"/>
    <joint name="tilt" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
      <limit lower="-0.3" upper="0.3" velocity="2" effort="100"/></joint><link name="l2"/>
    <joint name="bend" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
      <limit lower="-2" upper="2" velocity="2" effort="100"/></joint><link name="l3"/>
    <joint name="tool" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0 0 0.4"/></joint><link name="tip"/></robot>)",
                                                    ".");
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;
  request.start = Eigen::Vector3d(0.0, 0.0, 0.3);
  request.target = Eigen::Vector3d(0.75, 0.0, 0.05);
  request.max_time = 20.0;
  const ReachResult result = reach(arm, nullptr, parameters, request);
  EXPECT_EQ(result.status, "unreachable");
  EXPECT_EQ(result.joints_at_limits, (std::vector<std::string>{"tilt", "bend"}));
  EXPECT_NEAR(result.q[1], arm.softUpperLimits()[1], 1e-3);
}

TEST(Reach, TheNineJointArmReachesFromMidRangeWithoutItsWristShaking) {
  // Where two of arm9's wrist axes come close to parallel, a mode of little inertia and the sum
  // of both joints' damping made 4 physics steps per cycle unstable: the torques saturated for
  // 30 s and the tip stayed 14 cm short.
  const RobotModel arm9 = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;
  request.start = arm9.midPosture();
  request.target = Eigen::Vector3d(-0.6, 0.3, 0.5);
  const ReachResult result = reach(arm9, nullptr, parameters, request);
  EXPECT_EQ(result.status, "reached");
  EXPECT_LE((tipPose(arm9, result.q).translation() - request.target).norm(), 1e-4);
  EXPECT_EQ(result.torque_saturations, 0U);
  EXPECT_GT(result.max_substeps, 4);
}

TEST(Reach, ReportsATargetOutOfTheWorkspaceWithTheBestError) {
  const std::vector<ParameterDeclaration> declarations = reachParameters();
  const ParameterSet parameters(declarations);
  ReachRequest request;
  request.start = bentPosture();
  request.target = Eigen::Vector3d(1.5, 0.0, 0.4);  // the arm is 1.18 m long
  const ReachResult result = reach(lwr4(), nullptr, parameters, request);
  EXPECT_EQ(result.status, "unreachable");
  // The closest the arm gets: stretched towards the target from the shoulder at z = 0.3105.
  const double shoulder_to_target = (request.target - Eigen::Vector3d(0, 0, 0.3105)).norm();
  EXPECT_NEAR(result.best_error_m, shoulder_to_target - (0.4 + 0.39 + 0.078), 0.02);
  EXPECT_LT(result.time_s, request.max_time);
  EXPECT_NEAR(result.error_m, result.best_error_m, 1e-3);
}

}  // namespace
}  // namespace flexirob::robot

