// Hierarchical controller (Eq. 2.11) and command limiter: convergence, null-space motion that
// leaves the tip in place, limits under hostile inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"

namespace flexirob::robot {
namespace {

constexpr double kDt = 1e-3;

const RobotModel& lwr4() {
  static const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

const RobotModel& arm9() {
  static const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  return model;
}

ParameterSet controlParameters() {
  std::vector<ParameterDeclaration> all(hierarchicalParameters().begin(), hierarchicalParameters().end());
  all.insert(all.end(), limiterParameters().begin(), limiterParameters().end());
  return ParameterSet(all);
}

Eigen::VectorXd randomPosture(const RobotModel& model, std::mt19937& rng, double margin) {
  const Eigen::VectorXd lower = model.softLowerLimits();
  const Eigen::VectorXd upper = model.softUpperLimits();
  Eigen::VectorXd q(model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    std::uniform_real_distribution<double> uniform(lower[i] + margin, upper[i] - margin);
    q[i] = uniform(rng);
  }
  return q;
}

// Runs controller + limiter kinematically (perfect tracking) and returns the final posture.
Eigen::VectorXd runPipeline(const RobotModel& model, const ParameterSet& parameters, const Eigen::VectorXd& q0,
                            const Eigen::Vector3d& p_des, const Eigen::VectorXd& q_c, int steps,
                            double* max_tip_deviation = nullptr) {
  HierarchicalController controller(model, parameters);
  CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(q0);
  Kinematics kinematics(model);
  Eigen::VectorXd qd(model.dof());
  for (int k = 0; k < steps; ++k) {
    controller.velocity(limiter.command(), p_des, q_c, qd, &limiter);
    limiter.updateVelocity(qd);
    if (max_tip_deviation != nullptr) {
      kinematics.update(limiter.command());
      *max_tip_deviation = std::max(*max_tip_deviation, (kinematics.p_WT() - p_des).norm());
    }
  }
  return limiter.command();
}

TEST(HierarchicalController, TaskErrorConvergesWhateverTheNullSpaceTarget) {
  for (const RobotModel* model : {&lwr4(), &arm9()}) {
    const ParameterSet parameters = controlParameters();
    std::mt19937 rng(7);
    for (int trial = 0; trial < 6; ++trial) {
      // Reachable by construction: the tip position of a random posture.
      const Eigen::VectorXd q_goal = randomPosture(*model, rng, 0.3);
      const Eigen::Vector3d p_des = tipPose(*model, q_goal).translation();
      const Eigen::VectorXd q_start = randomPosture(*model, rng, 0.3);
      const Eigen::VectorXd q_c = randomPosture(*model, rng, 0.0);
      const Eigen::VectorXd q_final = runPipeline(*model, parameters, q_start, p_des, q_c, 8000);
      const double error = (tipPose(*model, q_final).translation() - p_des).norm();
      EXPECT_LE(error, 1e-4) << model->name() << " trial " << trial;
    }
  }
}

// An arm whose joints the URDF lets move 0.02 rad/s: an IK search of 400 steps of 0.02 s would
// move each joint 0.16 rad at most, and a target 1 rad of the shoulder away would read as
// unreachable. As a kinematic search its joints step at 1.5 rad/s at least.
TEST(HierarchicalController, AKinematicSearchCoversASlowArmsJointRange) {
  std::string urdf = "<robot name=\"slow\"><link name=\"base\"/>";
  std::string parent = "base";
  for (int i = 1; i <= 4; ++i) {
    const std::string link = "l" + std::to_string(i);
    urdf += "<joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + link +
            "\"/><origin xyz=\"0 0 " + (i == 1 ? "0.1" : "0.25") + "\"/><axis xyz=\"" + (i == 1 ? "0 0 1" : "0 1 0") +
            "\"/><limit lower=\"-2.5\" upper=\"2.5\" velocity=\"0.02\" effort=\"100\"/></joint><link name=\"" + link + "\"/>";
    parent = link;
  }
  urdf += R"(<joint name="tip_joint" type="fixed"><parent link="l4"/><child link="tip"/><origin xyz="0 0 0.25"/></joint><link name="tip"/></robot>)";
  const RobotModel slow = RobotModel::fromUrdfString(urdf, ".");
  const ParameterSet parameters = controlParameters();
  Eigen::VectorXd q_goal(4);
  q_goal << 1.0, 0.6, 0.5, 0.4;
  const Eigen::Vector3d p_des = tipPose(slow, q_goal).translation();
  const auto search = [&](bool as_kinematic_search) {
    HierarchicalController controller(slow, parameters);
    if (as_kinematic_search) controller.useForKinematicSearch();
    Eigen::VectorXd q = Eigen::VectorXd::Zero(4), q_target(4);
    q[1] = 0.1;  // off the straight-up singularity
    for (int it = 0; it < 400; ++it) {
      controller.target(q, p_des, q_goal, 0.02, q_target);
      q = q_target;
    }
    return (tipPose(slow, q).translation() - p_des).norm();
  };
  EXPECT_GT(search(false), 0.1) << "a motion keeps to the URDF's 0.02 rad/s";
  EXPECT_LT(search(true), 1e-4);
}

// Four links turning about parallel axes (y): the tip moves in the x-z plane only, so J has a
// zero singular value in every posture. Targets in that plane are reached as precisely as by the
// LWR IV, not held short by damping meant for singularities.
const RobotModel& planarArm() {
  static const RobotModel model = [] {
    std::string urdf = R"(<robot name="planar4"><link name="base"/>)";
    std::string parent = "base";
    for (int i = 1; i <= 4; ++i) {
      const std::string link = "l" + std::to_string(i);
      urdf += "<joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + link +
              "\"/><origin xyz=\"0 0 " + (i == 1 ? "0.1" : "0.25") + "\"/><axis xyz=\"0 1 0\"/>"
              "<limit lower=\"-2.5\" upper=\"2.5\" velocity=\"2\" effort=\"100\"/></joint><link name=\"" + link + "\"/>";
      parent = link;
    }
    urdf += R"(<joint name="tip_joint" type="fixed"><parent link="l4"/><child link="tip"/><origin xyz="0 0 0.25"/></joint><link name="tip"/></robot>)";
    return RobotModel::fromUrdfString(urdf, ".");
  }();
  return model;
}

TEST(HierarchicalController, APlanarArmReachesTargetsInItsPlaneWithoutDampingThem) {
  const RobotModel& model = planarArm();
  const ParameterSet parameters = controlParameters();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    // Postures of one elbow family (within ±1.2 rad), so that no joint limit stands between
    // start and goal on the straight way of the tip.
    const Eigen::VectorXd q_goal = randomPosture(model, rng, 1.3);
    const Eigen::Vector3d p_des = tipPose(model, q_goal).translation();
    ASSERT_NEAR(p_des.y(), 0.0, 1e-12);
    const Eigen::VectorXd q_start = randomPosture(model, rng, 1.3);
    const Eigen::VectorXd q_c = randomPosture(model, rng, 1.3);
    const Eigen::VectorXd q_final = runPipeline(model, parameters, q_start, p_des, q_c, 8000);
    EXPECT_LE((tipPose(model, q_final).translation() - p_des).norm(), 1e-4) << "trial " << trial;
  }
  // Its damping is that of its own directions: none far from a singularity.
  HierarchicalController controller(model, parameters);
  Eigen::VectorXd q = Eigen::VectorXd::Constant(4, 0.4), qd(4);
  controller.velocity(q, tipPose(model, q).translation() + Eigen::Vector3d(0.01, 0.0, 0.0), q, qd);
  EXPECT_EQ(controller.damping(), 0.0);
  EXPECT_GT(controller.smallestSingularValue(), 0.05);
}

TEST(HierarchicalController, NullSpaceTermMovesJointsButNotTheTip) {
  const RobotModel& model = lwr4();
  const ParameterSet parameters = controlParameters();
  Eigen::VectorXd q0(7);
  q0 << 0.3, 0.6, -0.2, -1.2, 0.4, 0.8, 0.1;
  const Eigen::Vector3d p_des = tipPose(model, q0).translation();
  Eigen::VectorXd q_c = q0;
  q_c[0] += 0.8;  // ask for another elbow position
  q_c[2] -= 1.0;
  double max_deviation = 0.0;
  const Eigen::VectorXd q_final = runPipeline(model, parameters, q0, p_des, q_c, 4000, &max_deviation);
  EXPECT_LE(max_deviation, 1e-4);
  EXPECT_GT((q_final - q0).norm(), 0.3);
  // The elbow (origin of body 4) moved: a real self-motion, not a standstill.
  Kinematics before(model), after(model);
  before.update(q0);
  after.update(q_final);
  EXPECT_GT((after.X_WB(4).translation() - before.X_WB(4).translation()).norm(), 0.05);
}

TEST(HierarchicalController, TaskVelocityMatchesFiniteDifferencesOfTheForwardKinematics) {
  const RobotModel& model = lwr4();
  const ParameterSet parameters = controlParameters();
  HierarchicalController controller(model, parameters);
  Eigen::VectorXd q(7);
  q << -0.4, 0.7, 0.3, -1.0, -0.2, 0.9, 0.5;
  const Eigen::Vector3d p = tipPose(model, q).translation();
  const Eigen::Vector3d p_des = p + Eigen::Vector3d(0.01, -0.02, 0.015);
  const Eigen::VectorXd q_c = q + 0.5 * Eigen::VectorXd::Unit(7, 2);
  Eigen::VectorXd qd(7);
  ASSERT_EQ(controller.velocity(q, p_des, q_c, qd), HierarchicalController::Status::kOk);
  // ẋ = J q̇ = κ_x (x_des − x): the null-space part contributes nothing (exact J⁺ away from
  // singularities). Checked on the forward kinematics, not on the Jacobian.
  const double h = 1e-7;
  const Eigen::Vector3d xdot = (tipPose(model, q + h * qd).translation() - tipPose(model, q - h * qd).translation()) / (2 * h);
  EXPECT_LT((xdot - controller.kappaX() * (p_des - p)).norm(), 1e-6);
  EXPECT_EQ(controller.damping(), 0.0);
}

// A target moving at constant velocity v: Eq. 2.11's feedback alone settles at the lag
// e = v/κ_x (the fixed point of e ← e + v·Δt − κ_x·Δt·e); with v fed forward the lag vanishes.
// Returns the mean tip lag over the last half of a 1 s line, run through the limiter.
double steadyLag(bool feed_forward) {
  const RobotModel& model = lwr4();
  const ParameterSet parameters = controlParameters();
  HierarchicalController controller(model, parameters);
  CommandLimiter limiter(model, parameters, kDt);
  Eigen::VectorXd q0(7);
  q0 << -0.4, 0.7, 0.3, -1.0, -0.2, 0.9, 0.5;
  limiter.reset(q0);
  Kinematics kinematics(model);
  const Eigen::Vector3d start = tipPose(model, q0).translation();
  const Eigen::Vector3d velocity(0.06, -0.05, 0.055);  // |v| ≈ 0.095 m/s
  Eigen::VectorXd qd(7);
  double lag_sum = 0.0;
  int samples = 0;
  for (int k = 1; k <= 1000; ++k) {
    const Eigen::Vector3d p_des = start + velocity * (k * kDt);
    const Eigen::Vector3d pd_des = feed_forward ? velocity : Eigen::Vector3d::Zero();
    controller.velocity(limiter.command(), p_des, pd_des, q0, qd, &limiter);
    limiter.updateVelocity(qd);
    if (k > 500) {
      kinematics.update(limiter.command());
      lag_sum += (kinematics.p_WT() - p_des).norm();
      ++samples;
    }
  }
  return lag_sum / samples;
}

TEST(HierarchicalController, TrailsAMovingTargetByVOverKappaWithoutFeedForward) {
  const double expected = Eigen::Vector3d(0.06, -0.05, 0.055).norm() / 10.0;  // κ_x = 10 /s
  ASSERT_EQ(HierarchicalController(lwr4(), controlParameters()).kappaX(), 10.0);
  EXPECT_NEAR(steadyLag(false), expected, 0.05 * expected);
}

TEST(HierarchicalController, FollowsAMovingTargetWithoutLagWhenItsVelocityIsFedForward) {
  const double without = Eigen::Vector3d(0.06, -0.05, 0.055).norm() / 10.0;
  EXPECT_LT(steadyLag(true), 0.02 * without);
}

TEST(HierarchicalController, StaysBoundedAtTheStretchedSingularity) {
  const RobotModel& model = lwr4();
  const ParameterSet parameters = controlParameters();
  HierarchicalController controller(model, parameters);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(7);  // arm straight up: J has rank 2
  Eigen::VectorXd qd(7);
  ASSERT_EQ(controller.velocity(q, Eigen::Vector3d(0.3, 0.0, 1.5), q, qd), HierarchicalController::Status::kOk);
  EXPECT_TRUE(qd.allFinite());
  EXPECT_LT(controller.smallestSingularValue(), 1e-6);
  EXPECT_GT(controller.damping(), 0.0);
  EXPECT_TRUE((qd.array().abs() <= model.velocityLimits().array() * (1 + 1e-12)).all());
}

TEST(HierarchicalController, RejectsNonFiniteTargetsWithZeroVelocity) {
  const RobotModel& model = lwr4();
  HierarchicalController controller(model, controlParameters());
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3);
  Eigen::VectorXd qd = Eigen::VectorXd::Ones(7);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(controller.velocity(q, Eigen::Vector3d(nan, 0, 0.5), q, qd), HierarchicalController::Status::kRejectedTarget);
  EXPECT_TRUE(qd.isZero());
  Eigen::VectorXd q_c = q;
  q_c[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(controller.velocity(q, Eigen::Vector3d(0.3, 0, 0.5), q_c, qd), HierarchicalController::Status::kRejectedTarget);
  EXPECT_EQ(controller.counters().rejected, 2U);
}

TEST(CommandLimiter, NoCommandLeavesTheLimitsForTenThousandHostileInputs) {
  const RobotModel& model = lwr4();
  const ParameterSet parameters = controlParameters();
  HierarchicalController controller(model, parameters);
  CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(model.midPosture());
  const Eigen::VectorXd lower = model.softLowerLimits();
  const Eigen::VectorXd upper = model.softUpperLimits();
  const Eigen::VectorXd v_max = limiter.velocityLimit();
  const double a_max = limiter.accelerationLimit();
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> kind(0, 9);
  std::uniform_real_distribution<double> wide(-10.0, 10.0);
  std::uniform_real_distribution<double> huge(-1e300, 1e300);
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity()};
  std::uint64_t non_finite_inputs = 0;
  Eigen::VectorXd q_target(7), previous = limiter.command(), previous_velocity = Eigen::VectorXd::Zero(7);
  for (int k = 0; k < 10000; ++k) {
    const int input = kind(rng);
    Eigen::Vector3d p_des(wide(rng) * 0.2, wide(rng) * 0.2, wide(rng) * 0.2);
    Eigen::VectorXd q_c = randomPosture(model, rng, -1.0);  // partly outside the limits
    bool finite = true;
    if (input == 0) {
      p_des[k % 3] = specials[k % 3];
      finite = false;
    } else if (input == 1) {
      q_c[k % 7] = specials[(k / 3) % 3];
      finite = false;
    } else if (input == 2) {
      p_des = Eigen::Vector3d(huge(rng), huge(rng), huge(rng));
    }
    const Eigen::VectorXd* result = nullptr;
    if (input <= 2 || input >= 6) {
      Eigen::VectorXd qd(7);
      controller.velocity(limiter.command(), p_des, q_c, qd, input == 6 ? nullptr : &limiter);
      if (input == 7) qd *= 1e6;  // absurd velocity requests
      result = &limiter.updateVelocity(qd);
    } else if (input == 3) {
      for (int i = 0; i < 7; ++i) q_target[i] = huge(rng);  // raw targets straight to the limiter
    } else {
      q_target = q_c;
      if (input == 5) {
        q_target[k % 7] = specials[k % 3];
        finite = false;
      }
    }
    if (!finite) ++non_finite_inputs;
    if (result == nullptr) result = &limiter.update(q_target);
    const Eigen::VectorXd& q_cmd = *result;
    ASSERT_TRUE(q_cmd.allFinite()) << "step " << k;
    ASSERT_TRUE((q_cmd.array() >= lower.array()).all() && (q_cmd.array() <= upper.array()).all()) << "step " << k;
    const Eigen::VectorXd velocity = (q_cmd - previous) / kDt;
    ASSERT_TRUE((velocity.array().abs() <= v_max.array() * (1 + 1e-9)).all()) << "step " << k;
    ASSERT_TRUE(((velocity - previous_velocity).array().abs() <= a_max * kDt * (1 + 1e-6) + 1e-9).all())
        << "step " << k << " acceleration " << ((velocity - previous_velocity) / kDt).transpose();
    previous = q_cmd;
    previous_velocity = velocity;
  }
  // Every non-finite input was refused by the controller or by the limiter, and counted.
  EXPECT_EQ(controller.counters().rejected + limiter.counters().rejected, non_finite_inputs);
  EXPECT_GT(limiter.counters().position, 0U);
  EXPECT_GT(limiter.counters().velocity + limiter.counters().acceleration, 0U);
}

TEST(CommandLimiter, ReachesAStepTargetWithoutOvershoot) {
  const RobotModel& model = lwr4();
  CommandLimiter limiter(model, controlParameters(), kDt);
  limiter.reset(Eigen::VectorXd::Zero(7));
  Eigen::VectorXd target = Eigen::VectorXd::Constant(7, 0.5);
  for (int k = 0; k < 3000; ++k) {
    limiter.update(target);
    ASSERT_TRUE((limiter.command().array() <= 0.5 + 1e-9).all()) << k << ": " << limiter.command().transpose() - target.transpose();
  }
  EXPECT_LT((limiter.command() - target).norm(), 1e-9);
  EXPECT_TRUE(limiter.velocity().isZero(1e-9));
}

TEST(Parameters, RefusesValuesOutsideTheDeclaredRange) {
  ParameterSet parameters = controlParameters();
  EXPECT_THROW(parameters.set("hierarchical.kappa_x", -1.0), InputError);
  EXPECT_THROW(parameters.set("hierarchical.kappa_x", std::numeric_limits<double>::quiet_NaN()), InputError);
  EXPECT_THROW(parameters.set("no.such.parameter", 1.0), InputError);
  parameters.set("hierarchical.kappa_x", 30.0);
  EXPECT_EQ(parameters.get("hierarchical.kappa_x"), 30.0);
  EXPECT_EQ(parameters.applyOverrides({{"hierarchical.kappa_q", 4.0}, {"other.component", 1.0}}), 1);
  EXPECT_EQ(parameters.get("hierarchical.kappa_q"), 4.0);
  // A scene's value out of range names the scene file, the parameter, the range and its unit.
  try {
    parameters.applyOverrides({{"hierarchical.kappa_q", -5.0}}, "cell.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "cell.yaml: parameter 'hierarchical.kappa_q': expected a value in [0, 100] 1/s, got -5");
  }
}

}  // namespace
}  // namespace flexirob::robot

// Interaction controllers (Sect. 4.1, 5.1, 6.1, 8.1) on the simulated arm.
#include "robot/interaction.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::robot {
namespace {

struct InteractionRig {
  const RobotModel& model = lwr4();
  Simulation sim{model, nullptr, ParameterSet(simulationParameters())};
  std::vector<ParameterDeclaration> declarations = interactionControllerParameters();
  InteractionController controller{model, ParameterSet(declarations), 1e-3};
  RobotState state;
  JointImpedanceCommand command;

  explicit InteractionRig(const Eigen::VectorXd& q0, InteractionMode mode) {
    sim.reset(q0);
    sim.readState(state);
    controller.start(mode, state);
  }
  void run(int steps) {
    for (int k = 0; k < steps; ++k) {
      controller.update(state, command);
      ASSERT_EQ(sim.writeCommand(command), CommandStatus::kAccepted);
      sim.step();
      sim.readState(state);
    }
  }
};

Eigen::VectorXd restPosture() {
  Eigen::VectorXd q(7);
  q << 0.2, 0.7, -0.3, -1.1, 0.4, 0.6, -0.2;
  return q;
}

// Tab. A.1's stiffness is the LWR IV's; a lighter arm gets it times its inertia ratio, and so
// does a much heavier one (a factor above 1 had been ignored: a 260 kg arm kept 300 Nm/rad in
// HIERARCHICAL CONTROL and crept). Values that are no scale leave it as it was.
TEST(InteractionControllers, TheJointStiffnessScalesWithTheArmBothWays) {
  InteractionRig rig(restPosture(), InteractionMode::kHierarchicalControl);
  rig.run(1);
  const double lwr = rig.command.stiffness[0];
  ASSERT_GT(lwr, 0.0);
  for (const double inertia : {0.01, 21.5}) {
    rig.controller.setArmScale(inertia, 1.0);
    rig.run(1);
    EXPECT_NEAR(rig.command.stiffness[0], lwr * inertia, 1e-9 * lwr * inertia) << inertia;
  }
  for (const double no_scale : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    rig.controller.setArmScale(no_scale, 1.0);
    rig.run(1);
    EXPECT_NEAR(rig.command.stiffness[0], lwr * 21.5, 1e-9 * lwr * 21.5) << no_scale;
  }
}

TEST(InteractionControllers, GravityCompensationFollowsTheHandAndStopsWhenReleased) {
  InteractionRig rig(restPosture(), InteractionMode::kGravityCompensation);
  EXPECT_EQ(rig.command.stiffness.size(), 0);
  rig.sim.setHandForce(7, rig.state.p_WT(), Eigen::Vector3d(0.0, 10.0, 0.0));
  rig.run(1000);
  EXPECT_DOUBLE_EQ(rig.command.stiffness[0], 20.0);  // Tab. A.1
  EXPECT_DOUBLE_EQ(rig.command.damping[0], 0.7);
  const Eigen::Vector3d pushed_to = rig.state.p_WT();
  EXPECT_GT(pushed_to.y() - tipPose(rig.model, restPosture()).translation().y(), 0.05);
  rig.sim.clearHandForce();
  rig.run(3000);
  // At rest where it was left, not sprung back, and the command sits on the arm.
  EXPECT_LT(rig.state.qd.norm(), 1e-3);
  EXPECT_LT((rig.state.q - rig.state.q_cmd).norm(), 1e-3);
  EXPECT_GT((rig.state.q - restPosture()).norm(), 0.05);
}

// A plot of |x_des − x| must not read the hand's pull away from where π_q began as a task
// error: under the hand π_q and π_rec hold a posture and have no task target.
TEST(InteractionControllers, OnlyTheModesThatSteerTheTipHaveATaskTarget) {
  InteractionRig rig(restPosture(), InteractionMode::kGravityCompensation);
  const Eigen::Vector3d started_at = rig.controller.taskTarget();
  rig.sim.setHandForce(7, rig.state.p_WT(), Eigen::Vector3d(0.0, 10.0, 0.0));
  rig.run(1000);
  EXPECT_GT((rig.state.p_WT() - started_at).norm(), 0.05);
  EXPECT_TRUE(rig.controller.taskTarget().isApprox(started_at));
  EXPECT_FALSE(rig.controller.tracksTaskTarget());
  rig.controller.setKeyboardMode(true);  // the keys move x_des (Fig. 8.1(a))
  EXPECT_TRUE(rig.controller.tracksTaskTarget());
  rig.controller.setKeyboardMode(false);
  rig.controller.start(InteractionMode::kCompliantRecording, rig.state);
  EXPECT_FALSE(rig.controller.tracksTaskTarget());
  for (const InteractionMode mode : {InteractionMode::kHierarchicalControl, InteractionMode::kAssistedGravityCompensation,
                                     InteractionMode::kAssistanceBlending}) {
    rig.controller.start(mode, rig.state);
    EXPECT_TRUE(rig.controller.tracksTaskTarget());
  }
}

TEST(InteractionControllers, CompliantRecordingSpringsBackToTheFixedPosture) {
  InteractionRig rig(restPosture(), InteractionMode::kCompliantRecording);
  rig.controller.setFixedPosture(restPosture());
  rig.sim.setHandForce(7, rig.state.p_WT(), Eigen::Vector3d(8.0, 0.0, 0.0));
  rig.run(1000);
  EXPECT_GT((rig.state.q - restPosture()).norm(), 0.02);  // deflected locally
  EXPECT_LT((rig.state.q - restPosture()).norm(), 0.5);
  rig.sim.clearHandForce();
  rig.run(3000);
  EXPECT_LT((rig.state.q - restPosture()).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(InteractionControllers, AssistedGravityCompensationMovesTheTipAndResolvesTheNullSpace) {
  InteractionRig rig(restPosture(), InteractionMode::kAssistedGravityCompensation);
  Eigen::VectorXd q_c = restPosture();
  q_c[0] += 0.5;  // the taught elbow lies elsewhere
  q_c[2] -= 0.6;
  FixedPosture map(q_c);
  rig.controller.setRedundancyMap(&map);
  const Eigen::Vector3d start = rig.state.p_WT();
  rig.sim.setHandForce(7, start, Eigen::Vector3d(0.0, 0.0, -10.0));
  rig.run(1500);
  rig.sim.clearHandForce();
  rig.run(4000);
  // The tutor moved the tip down; released, it stays there.
  EXPECT_LT(rig.state.p_WT().z(), start.z() - 0.03);
  EXPECT_LT(rig.state.qd.norm(), 2e-3);
  // The posture satisfies q_c as far as the null space allows: the null-space part of
  // (q_c − q) is gone, checked with an SVD-based projector independent of the controller.
  Kinematics kinematics(rig.model);
  kinematics.update(rig.state.q);
  Matrix3Xd J;
  kinematics.tipPositionJacobian(J);
  const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(7, 7) - J.completeOrthogonalDecomposition().pseudoInverse() * J;
  EXPECT_LT((P * (q_c - rig.state.q)).norm(), 0.05);
  EXPECT_GT((P * (q_c - restPosture())).norm(), 0.3);
}

TEST(InteractionControllers, AssistanceBlendingFollowsEquationSixTwo) {
  Eigen::VectorXd q_c = restPosture();
  q_c[2] += 0.8;
  FixedPosture map(q_c);
  for (double c : {0.0, 1.0}) {
    InteractionRig rig(restPosture(), InteractionMode::kAssistanceBlending);
    ConstantConfidence confidence(c);
    rig.controller.setRedundancyMap(&map);
    rig.controller.setConfidence(&confidence);
    rig.run(3000);
    EXPECT_DOUBLE_EQ(rig.controller.alpha(), c);
    if (c == 0.0) {
      // α = 0: pure gravity compensation, the untouched arm stays where it is; pushed, it follows.
      EXPECT_LT((rig.state.q - restPosture()).norm(), 1e-3);
      rig.sim.setHandForce(7, rig.state.p_WT(), Eigen::Vector3d(0.0, 10.0, 0.0));
      rig.run(1000);
      rig.sim.clearHandForce();
      rig.run(2000);
      EXPECT_GT(rig.state.p_WT().y() - tipPose(rig.model, restPosture()).translation().y(), 0.03);
      EXPECT_LT(rig.state.qd.norm(), 2e-3);
    } else {
      // α = 1: the null space is pulled to q_c, the tip stays.
      EXPECT_GT((rig.state.q - restPosture()).norm(), 0.2);
      EXPECT_LT((rig.state.p_WT() - tipPose(rig.model, restPosture()).translation()).norm(), 2e-3);
    }
  }
}

// Where the robot is confident (α = 1) it holds its null space against the hand, so a hand can
// push on without the arm following. What the hand asks for must stay a deflection of the arm
// (Sect. 6.1: q_des "relates to the damped current position"), not pile up: once released and
// out of the confident region (α = 0, gravity compensation) the arm stays where it is instead of
// swinging by itself to a posture the hand had pushed for far beyond it.
// The largest joint motion of the arm after the push and release below, α falling to 0.
double moveAfterAHeldBackPush(double anchor_rate) {
  FixedPosture map(restPosture());
  InteractionRig rig(restPosture(), InteractionMode::kAssistanceBlending);
  ParameterSet parameters(rig.declarations);
  parameters.set("interaction.blending_anchor_rate", anchor_rate);
  rig.controller = InteractionController(rig.model, parameters, 1e-3);
  rig.controller.start(InteractionMode::kAssistanceBlending, rig.state);
  ConstantConfidence confident(1.0);
  rig.controller.setRedundancyMap(&map);
  rig.controller.setConfidence(&confident);
  rig.run(500);
  // The hand pushes the elbow sideways for 3 s: a null-space motion the assistance resists.
  Kinematics kinematics(rig.model);
  kinematics.update(rig.state.q);
  const Eigen::Vector3d sideways = Eigen::Vector3d::UnitZ().cross(kinematics.X_WB(4).translation()).normalized();
  for (int k = 0; k < 3000; ++k) {
    kinematics.update(rig.state.q);
    rig.sim.setHandForce(4, kinematics.X_WB(4).translation(), 20.0 * sideways);
    rig.run(1);
  }
  const double held_back = (rig.state.q - restPosture()).norm();
  rig.sim.clearHandForce();
  rig.run(1000);  // the hand is off; the arm comes to rest
  ConstantConfidence unsure(0.0);
  rig.controller.setConfidence(&unsure);
  const Eigen::VectorXd at_rest = rig.state.q;
  double largest_move = 0.0;
  for (int k = 0; k < 4000; ++k) {
    rig.run(1);
    largest_move = std::max(largest_move, (rig.state.q - at_rest).cwiseAbs().maxCoeff());
  }
  if (anchor_rate > 0.0) {
    EXPECT_LT(rig.state.qd.norm(), 2e-3) << "held " << held_back << " rad from the assisted posture";
  }
  return largest_move;
}

TEST(InteractionControllers, AssistanceBlendingDoesNotStoreUpAPushTheAssistanceHeldBack) {
  EXPECT_LT(moveAfterAHeldBackPush(5.0), 0.05) << "the arm moved by itself after the hand had let go";
  // Without the anchor the same push is stored up and released as a swing.
  EXPECT_GT(moveAfterAHeldBackPush(0.0), 0.3);
}

TEST(InteractionControllers, HierarchicalControlFollowsAMovingTargetAndHoldsWhereItStops) {
  InteractionRig rig(restPosture(), InteractionMode::kHierarchicalControl);
  rig.controller.setFixedPosture(restPosture());
  Kinematics kinematics(rig.model);
  const Eigen::Vector3d start = rig.state.p_WT();
  const Eigen::Vector3d velocity(0.0, 0.1, -0.02);
  double max_lag = 0.0;
  for (int k = 1; k <= 1000; ++k) {
    rig.controller.setTaskTarget(start + velocity * (k * 1e-3), velocity);
    rig.run(1);
    kinematics.update(rig.command.q_cmd);
    if (k > 200) max_lag = std::max(max_lag, (kinematics.p_WT() - rig.controller.taskTarget()).norm());
  }
  EXPECT_LT(max_lag, 1e-3);  // Eq. 2.11's feedback alone: |v|/κ_x ≈ 10 mm
  // The target stops: the velocity it was given last holds for one cycle, not for ever.
  const Eigen::Vector3d end = rig.controller.taskTarget();
  rig.run(2000);
  kinematics.update(rig.command.q_cmd);
  EXPECT_LT((kinematics.p_WT() - end).norm(), 1e-4);
}

TEST(InteractionControllers, KeyboardStepsMoveTheTipAndTheNullSpaceSeparately) {
  InteractionRig rig(restPosture(), InteractionMode::kGravityCompensation);
  rig.controller.setKeyboardMode(true);
  const Eigen::Vector3d start = rig.state.p_WT();
  for (int press = 0; press < 10; ++press) rig.controller.nudgeTask(Eigen::Vector3d(0.005, 0.0, 0.0));
  rig.run(4000);
  EXPECT_LT((rig.state.p_WT() - (start + Eigen::Vector3d(0.05, 0, 0))).norm(), 1e-4);
  const Eigen::VectorXd before = rig.state.q;
  rig.controller.nudgeJoints(0.4 * Eigen::VectorXd::Unit(7, 0));
  rig.run(5000);
  EXPECT_GT((rig.state.q - before).norm(), 0.1);
  EXPECT_LT((rig.state.p_WT() - (start + Eigen::Vector3d(0.05, 0, 0))).norm(), 1e-4);
}

}  // namespace
}  // namespace flexirob::robot
