// The teaching workflow's state machine driven by buttons and triggers over a stand-in backend
// whose measured torques and motion the test sets directly.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "app/workflow.hpp"
#include "learning/learner.hpp"
#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/reach.hpp"
#include "tests/app/workflow_rigs.hpp"
#include "tests/common/cylinder_arms.hpp"

namespace flexirob::app {
namespace {

using workflow_rigs::lwr4;
using workflow_rigs::run;
using workflow_rigs::syncOptions;

// A backend the test moves by hand: q follows what the test sets, τ_ext and q̇ are given.
class ScriptedBackend final : public robot::RobotBackend {
 public:
  explicit ScriptedBackend(const robot::RobotModel& model) : model_(&model), kinematics_(model) {
    state_.resize(model.dof());
    state_.q = model.midPosture();
    state_.q[1] = 0.6;
    state_.q[3] = -1.4;
    kinematics_.update(state_.q);
    state_.X_WT = kinematics_.X_WT();
  }
  const robot::RobotModel& model() const override { return *model_; }
  double cycleTime() const override { return 1e-3; }
  void readState(robot::RobotState& state) const override { state = state_; }
  robot::CommandStatus writeCommand(const robot::JointImpedanceCommand& command) override {
    last_ = command;
    ++commands_;
    return robot::CommandStatus::kAccepted;
  }
  void step() override { state_.time += cycleTime(); }

  void push(double torque) { state_.tau_ext.setZero(); state_.tau_ext[1] = torque; }
  void move(const Eigen::VectorXd& q, double speed) {
    state_.q = q;
    state_.qd.setConstant(speed);
    kinematics_.update(q);
    state_.X_WT = kinematics_.X_WT();
  }
  void rest() { state_.qd.setZero(); state_.tau_ext.setZero(); }
  void overlapObstacle(bool in_contact) { state_.in_contact = in_contact; }
  const robot::JointImpedanceCommand& last() const { return last_; }
  const robot::RobotState& state() const { return state_; }

 private:
  const robot::RobotModel* model_;
  robot::Kinematics kinematics_;
  robot::RobotState state_;
  robot::JointImpedanceCommand last_;
  int commands_ = 0;
};

struct Fixture {
  Fixture() : backend(lwr4()), declarations(robot::reachParameters()), parameters(declarations) {}
  ScriptedBackend backend;
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
};

// One CONFIGURATION area through the real triggers: touch, move, rest, touch, circle (of
// `circle` rad in A1 and A4; none: the tutor let go at once), rest.
void teachArea(Workflow& workflow, ScriptedBackend& backend, const Eigen::VectorXd& q_fixed, double circle = 0.05) {
  backend.push(3.0);  // touched at rest: on_affected
  run(workflow, 0.01);
  EXPECT_EQ(workflow.subStage(), SubStage::kApproaching);
  backend.move(q_fixed, 0.0);
  backend.rest();
  run(workflow, 2.1);  // still for 2 s: on_converged
  EXPECT_EQ(workflow.subStage(), SubStage::kPosed);
  backend.push(3.0);
  run(workflow, 0.01);
  EXPECT_EQ(workflow.subStage(), SubStage::kRecording);
  for (int i = 0; i < 40; ++i) {
    const Eigen::Index n = q_fixed.size();
    const Eigen::VectorXd q = q_fixed + circle * std::sin(0.3 * i) * Eigen::VectorXd::Unit(n, 0) +
                              circle * std::cos(0.3 * i) * Eigen::VectorXd::Unit(n, 3);
    backend.move(q, circle > 0.0 ? 0.3 : 0.0);
    run(workflow, 0.02);
  }
  backend.move(q_fixed, 0.0);
  backend.rest();
  run(workflow, 2.1);
  EXPECT_EQ(workflow.subStage(), SubStage::kWaiting);
}

Eigen::VectorXd posture(double a1) {
  Eigen::VectorXd q = lwr4().midPosture();
  q[0] = a1;
  q[1] = 0.7;
  q[3] = -1.3;
  q[5] = 0.8;
  return q;
}


TEST(Workflow, HoldsWhereTheFirstMeasurementPutsTheRobotNotTheZerosBeforeIt) {
  Fixture f;
  // A real robot's backend before its controller's first measurement: time 0, every joint 0.
  f.backend.move(Eigen::VectorXd::Zero(7), 0.0);
  Workflow workflow(f.backend, f.parameters, syncOptions());
  Eigen::VectorXd measured(7);
  measured << 0.4, 0.5, -0.2, -1.3, 0.1, 0.9, 0.3;
  f.backend.move(measured, 0.0);
  f.backend.rest();
  run(workflow, 1.0);
  ASSERT_EQ(workflow.stage(), Stage::kIdle);
  // IDLE holds the measured posture; holding the zeros would drag the arm towards the stretched
  // posture, 0.5 rad/s within a second.
  EXPECT_LT((f.backend.last().q_cmd - measured).cwiseAbs().maxCoeff(), 1e-3) << f.backend.last().q_cmd.transpose();
  EXPECT_LT((workflow.taskTarget() - f.backend.state().p_WT()).norm(), 1e-6);
}

TEST(Workflow, RefusesProgrammingBeforeConfigurationWithoutChangingState) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  const auto result = workflow.press(Button::kStartProgramming);
  EXPECT_FALSE(result.accepted);
  EXPECT_NE(result.reason.find("configure"), std::string::npos) << result.reason;
  EXPECT_EQ(workflow.stage(), Stage::kIdle);
  EXPECT_FALSE(workflow.press(Button::kFinishedConfiguration));
  EXPECT_FALSE(workflow.press(Button::kFinishedProgramming));
  EXPECT_FALSE(workflow.fire(Trigger::kOnAffected));
  EXPECT_FALSE(workflow.removeArea(0));
  EXPECT_EQ(workflow.stage(), Stage::kIdle);
  EXPECT_EQ(workflow.subStage(), SubStage::kNone);
  EXPECT_TRUE(workflow.areas().empty());
  int refused = 0;
  for (const auto& event : workflow.events()) refused += event.kind == WorkflowEvent::Kind::kRefused ? 1 : 0;
  EXPECT_EQ(refused, 5);
}

TEST(Workflow, FinishingConfigurationNeedsAnAreaAndNoRunningRecording) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  EXPECT_FALSE(workflow.press(Button::kStartConfiguration));
  EXPECT_FALSE(workflow.press(Button::kFinishedConfiguration));  // no area yet
  EXPECT_EQ(workflow.stage(), Stage::kConfiguration);
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_EQ(workflow.subStage(), SubStage::kRecording);
  EXPECT_FALSE(workflow.press(Button::kFinishedConfiguration));
  EXPECT_EQ(workflow.subStage(), SubStage::kRecording);
}

TEST(Workflow, TriggersSelectTheInteractionControllerOfEachSubStage) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  EXPECT_EQ(workflow.controller(), InteractionController::kHierarchicalControl);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  EXPECT_EQ(workflow.controller(), InteractionController::kHierarchicalControl);
  f.backend.push(2.0);
  run(workflow, 0.005);
  EXPECT_EQ(workflow.controller(), InteractionController::kGravityCompensation);
  workflow.step();
  EXPECT_DOUBLE_EQ(f.backend.last().stiffness[0], 20.0);
  EXPECT_DOUBLE_EQ(f.backend.last().damping[0], 0.7);
  // A torque below 1.5 Nm is no touch; moving without converging keeps APPROACHING.
  f.backend.rest();
  f.backend.move(posture(0.3), 0.5);
  run(workflow, 3.0);
  EXPECT_EQ(workflow.subStage(), SubStage::kApproaching);
  f.backend.move(posture(0.3), 0.0);
  run(workflow, 1.9);
  EXPECT_EQ(workflow.subStage(), SubStage::kApproaching);
  run(workflow, 0.2);
  EXPECT_EQ(workflow.subStage(), SubStage::kPosed);
  EXPECT_EQ(workflow.controller(), InteractionController::kCompliantRecording);
  workflow.step();
  EXPECT_DOUBLE_EQ(f.backend.last().stiffness[0], 80.0);
  EXPECT_TRUE(f.backend.last().q_cmd.isApprox(posture(0.3), 1e-12));  // springs back to q_fixed
}

TEST(Workflow, TheItmLeavesOutWhereTheSimulatedArmOverlapsAnObstacle) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  const auto tipAt = [](const Eigen::VectorXd& q) {
    robot::Kinematics kinematics(lwr4());
    kinematics.update(q);
    return Eigen::Vector3d(kinematics.X_WT().translation());
  };
  const auto nearestNodeTo = [&](const Eigen::Vector3d& p) {
    double nearest = 1e9;
    for (int id : workflow.itm().nodeIds()) nearest = std::min(nearest, (workflow.itm().prototype(id).head<3>() - p).norm());
    return nearest;
  };
  // Free, then sunk into an obstacle on the other side, then free again.
  for (const auto& [a1, overlapping] : {std::pair{-1.2, false}, std::pair{1.2, true}, std::pair{0.0, false}}) {
    f.backend.overlapObstacle(overlapping);
    for (int i = 0; i <= 50; ++i) {
      f.backend.move(posture(a1 + 0.2 * i / 50.0), 0.3);
      run(workflow, 0.01);
    }
  }
  ASSERT_GE(workflow.itm().nodeCount(), 2);
  EXPECT_LT(nearestNodeTo(tipAt(posture(-1.1))), 0.05);
  EXPECT_LT(nearestNodeTo(tipAt(posture(0.1))), 0.05);
  EXPECT_GT(nearestNodeTo(tipAt(posture(1.3))), 0.3) << "no node where the arm overlapped the obstacle";
}

// The ITM's e_max (0.1 m, Sect. 7.4) and the goal gap are a person's distances with the LWR IV.
// A 17 cm arm's configuration stage had left an ITM of 3 nodes, and plans ran between them; its
// distances are scaled with the arm's reach, so the same motion of either arm (here a 25 cm one)
// leaves about as many nodes. The LWR IV keeps the thesis' values.
TEST(Workflow, TheItmResolvesASmallArmsMotionAsFinelyAsTheLwrIvs) {
  const robot::RobotModel small = robot::RobotModel::fromUrdfString(testing::smallLightArmUrdf(), ".");
  struct Swing {
    int nodes = 0;
    double e_max = 0.0, goal_gap = 0.0, d_c_max = 0.0;
  };
  const auto swing = [](const robot::RobotModel& model) {
    Swing result;
    ScriptedBackend backend(model);
    const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
    const robot::ParameterSet parameters(declarations);
    Workflow workflow(backend, parameters, syncOptions());
    result.e_max = workflow.options().itm.e_max;
    result.goal_gap = workflow.options().max_goal_gap;
    result.d_c_max = workflow.options().itm.d_c_max;
    EXPECT_TRUE(workflow.press(Button::kStartConfiguration));
    // The arm leant out and swung about its vertical axis, 3 rad.
    Eigen::VectorXd q(7);
    q << 0.0, 1.0, 0.0, -0.8, 0.0, 0.0, 0.0;
    for (int i = 0; i <= 300; ++i) {
      q[0] = -1.5 + 3.0 * i / 300.0;
      backend.move(q, 0.3);
      run(workflow, 0.01);
    }
    result.nodes = workflow.itm().nodeCount();
    return result;
  };
  const Swing lwr = swing(lwr4());
  const Swing light = swing(small);
  EXPECT_EQ(lwr.e_max, WorkflowOptions{}.itm.e_max);
  EXPECT_EQ(lwr.goal_gap, WorkflowOptions{}.max_goal_gap);
  EXPECT_NEAR(light.e_max, WorkflowOptions{}.itm.e_max * armScale(small).length, 1e-12);
  EXPECT_NEAR(light.goal_gap, WorkflowOptions{}.max_goal_gap * armScale(small).length, 1e-12);
  EXPECT_NEAR(light.d_c_max, WorkflowOptions{}.itm.d_c_max * armScale(small).length, 1e-12);
  ASSERT_GE(lwr.nodes, 8);
  EXPECT_GE(light.nodes, lwr.nodes / 2) << "the LWR IV's swing left " << lwr.nodes << " nodes";
}

// The OS-ELM normalizes its input over a fixed box, the LWR IV's workspace; a shorter arm's is
// the box about its shoulder as far as it reaches, so that it holds every tip position (the LWR
// IV's box shrunk about the world's origin had ended under a pedestal arm's shoulder).
TEST(Workflow, TheOnlineLearnersBoxHoldsWhereASmallArmOnAPedestalReaches) {
  const robot::RobotModel tall = robot::RobotModel::fromUrdfString(
      testing::cylinderArmUrdf("tall", {0.06, 0.06, 0.05, 0.05, 0.04, 0.04, 0.03}, {0.3, 0.25, 0.2, 0.15, 0.1, 0.07, 0.05}, 0.018,
                               0.001, 0.025, 1.0, 20.0),
      ".");
  ASSERT_LT(armScale(tall).length, 0.5);
  ScriptedBackend backend(tall);
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  const robot::ParameterSet parameters(declarations);
  Workflow workflow(backend, parameters, syncOptions());
  const Eigen::Vector3d lower = workflow.options().workspace_lower, upper = workflow.options().workspace_upper;
  learning::UniformRandom random(3);
  robot::Kinematics kinematics(tall);
  for (int i = 0; i < 200; ++i) {
    kinematics.update(random.uniform(tall.softLowerLimits(), tall.softUpperLimits()));
    const Eigen::Vector3d tip = kinematics.p_WT();
    EXPECT_TRUE((tip.array() >= lower.array()).all() && (tip.array() <= upper.array()).all())
        << tip.transpose() << " outside [" << lower.transpose() << "] [" << upper.transpose() << "]";
  }
  // No larger than the arm needs: its reach about the shoulder.
  EXPECT_LT((upper - lower).maxCoeff(), 2.5 * 0.3);
}

// Every refit checks the transitions again: an OS-ELM session's `teach` had listed one pair
// once per refit (137 and 138 colliding samples) and counted 7 warnings beside 2 lines. The last
// map's transition warnings stand; a joint-limit warning stands whatever was learned after it.
// An event as the workflow emits it, for standingWarnings().
WorkflowEvent event(WorkflowEvent::Kind kind, const std::string& name, const std::string& detail, int area = -1) {
  WorkflowEvent e;
  e.kind = kind;
  e.name = name;
  e.detail = detail;
  e.area = area;
  return e;
}

// `--learner ELM`, as the thesis writes it, had been refused.
TEST(Workflow, NamesALearnerInAnyCaseWithOrWithoutAHyphen) {
  EXPECT_EQ(learnerKindFromString("elm"), LearnerKind::kElm);
  EXPECT_EQ(learnerKindFromString("ELM"), LearnerKind::kElm);
  EXPECT_EQ(learnerKindFromString("OS-ELM"), LearnerKind::kOsElm);
  EXPECT_EQ(learnerKindFromString("oselm"), LearnerKind::kOsElm);
  EXPECT_EQ(learnerKindFromString("Llm"), LearnerKind::kLlm);
  EXPECT_THROW(learnerKindFromString("bpdc"), InputError);
  EXPECT_THROW(learnerKindFromString(""), InputError);
}

TEST(Workflow, OnlyTheLastMapsTransitionWarningsStand) {
  using Kind = WorkflowEvent::Kind;
  const std::vector<WorkflowEvent> events = {
      event(Kind::kWarning, "joint_limit", "posture near the joint limit at area 'a'", 0),
      event(Kind::kAreaCreated, "a", "a", 0),
      event(Kind::kModelLearned, "oselm", "from 2 areas"),
      event(Kind::kWarning, "transition_inconsistent", "a -> b: colliding samples 137"),
      event(Kind::kWarning, "joint_limit", "posture near the joint limit at area 'c'", 2),
      event(Kind::kAreaCreated, "c", "c", 2),
      event(Kind::kModelLearned, "oselm", "from 3 areas"),
      event(Kind::kWarning, "transition_inconsistent", "a -> b: colliding samples 138"),
      event(Kind::kCheck, "transition_ok", "b -> c: fine"),
  };
  EXPECT_EQ(standingWarnings(events),
            (std::vector<std::string>{"posture near the joint limit at area 'a'", "posture near the joint limit at area 'c'",
                                      "a -> b: colliding samples 138"}));
  // A joint-limit warning of the pose being recorded stands for the window meanwhile, not for
  // a finished run's list (its area is not made).
  std::vector<WorkflowEvent> posing = events;
  posing.push_back(event(Kind::kStage, "CONFIGURATION/POSED", "controller joint impedance"));
  posing.push_back(event(Kind::kWarning, "joint_limit", "posture near the joint limit at area 'd'", 3));
  posing.push_back(event(Kind::kStage, "CONFIGURATION/RECORDING", "controller reconfiguration"));
  EXPECT_EQ(standingWarnings(posing), standingWarnings(events));
  EXPECT_EQ(standingWarnings(posing, true).back(), "posture near the joint limit at area 'd'");
  // Without a refit after them, transition warnings stand.
  const std::vector<WorkflowEvent> once(events.begin(), events.begin() + 4);
  EXPECT_EQ(standingWarnings(once),
            (std::vector<std::string>{"posture near the joint limit at area 'a'", "a -> b: colliding samples 137"}));
}

// The tutor takes back an area that made the map worse; `teach` had still warned of its posture
// near a joint limit. A removal takes the removed area's warning with it, and the later areas'
// indices move down as the workflow's do.
TEST(Workflow, AnAreaRemovedTakesItsJointLimitWarningWithIt) {
  using Kind = WorkflowEvent::Kind;
  std::vector<WorkflowEvent> events = {
      event(Kind::kWarning, "joint_limit", "near the limit at area 'a'", 0),
      event(Kind::kAreaCreated, "area_created", "a", 0),
      event(Kind::kWarning, "joint_limit", "near the limit at area 'b'", 1),
      event(Kind::kAreaCreated, "area_created", "b", 1),
      event(Kind::kWarning, "joint_limit", "near the limit at area 'c'", 2),
      event(Kind::kAreaCreated, "area_created", "c", 2),
      event(Kind::kAreaRemoved, "area_removed", "b", 1),
  };
  EXPECT_EQ(standingWarnings(events), (std::vector<std::string>{"near the limit at area 'a'", "near the limit at area 'c'"}));
  events.push_back(event(Kind::kAreaRemoved, "area_removed", "c", 1));  // 'c' is area 1 now
  EXPECT_EQ(standingWarnings(events), (std::vector<std::string>{"near the limit at area 'a'"}));
}

// A joint-limit warning is said as the recording starts, before the recording has made an area.
// `teach` had kept the warning of a recording that made none, and of an area's posture that a
// re-teaching had replaced.
TEST(Workflow, AJointLimitWarningStandsOnlyForThePostureAnAreaHoldsNow) {
  using Kind = WorkflowEvent::Kind;
  std::vector<WorkflowEvent> events = {
      event(Kind::kWarning, "joint_limit", "a: joint 2 at 3 deg", 0),
      event(Kind::kAreaCreated, "a", "a", 0),
      event(Kind::kWarning, "joint_limit", "b: joint 4 at 1 deg", 1),
      event(Kind::kWarning, "empty_recording", "the recording held no sample; no area created"),
  };
  EXPECT_EQ(standingWarnings(events),
            (std::vector<std::string>{"a: joint 2 at 3 deg", "the recording held no sample; no area created"}));
  // Area a re-taught in another posture near a limit: only the new posture's warning stands.
  events.push_back(event(Kind::kButton, "reteach_area", "a", 0));
  events.push_back(event(Kind::kWarning, "joint_limit", "a: joint 6 at 2 deg", 0));
  events.push_back(event(Kind::kAreaCreated, "a", "a", 0));
  EXPECT_EQ(standingWarnings(events),
            (std::vector<std::string>{"the recording held no sample; no area created", "a: joint 6 at 2 deg"}));
  // Re-taught once more, away from every limit: no joint-limit warning stands for it.
  events.push_back(event(Kind::kAreaCreated, "a", "a", 0));
  EXPECT_EQ(standingWarnings(events), (std::vector<std::string>{"the recording held no sample; no area created"}));
  // A recording still running has made no area yet.
  events.push_back(event(Kind::kWarning, "joint_limit", "b: joint 1 at 0.5 deg", 1));
  EXPECT_EQ(standingWarnings(events), (std::vector<std::string>{"the recording held no sample; no area created"}));
  // That pose given up (configuration finished in POSED), the next area, posed away from every
  // limit, carries no warning of it.
  events.push_back(event(Kind::kButton, "finished_configuration", ""));
  events.push_back(event(Kind::kButton, "start_configuration", ""));
  events.push_back(event(Kind::kTrigger, "on_converged", "CONFIGURATION/APPROACHING"));
  events.push_back(event(Kind::kAreaCreated, "b", "b", 1));
  EXPECT_EQ(standingWarnings(events), (std::vector<std::string>{"the recording held no sample; no area created"}));
  // The events of a whole recording, as the workflow emits them: the pose's warning stands.
  events.push_back(event(Kind::kTrigger, "on_converged", "CONFIGURATION/APPROACHING"));
  events.push_back(event(Kind::kStage, "CONFIGURATION/POSED", "controller joint impedance"));
  events.push_back(event(Kind::kWarning, "joint_limit", "c: joint 5 at 2 deg", 2));
  events.push_back(event(Kind::kTrigger, "on_affected", "CONFIGURATION/POSED"));
  events.push_back(event(Kind::kStage, "CONFIGURATION/RECORDING", "controller recording"));
  events.push_back(event(Kind::kTrigger, "on_converged", "CONFIGURATION/RECORDING"));
  events.push_back(event(Kind::kAreaCreated, "c", "c", 2));
  EXPECT_EQ(standingWarnings(events),
            (std::vector<std::string>{"the recording held no sample; no area created", "c: joint 5 at 2 deg"}));
  // A pose near a limit, then POSED entered anew before any area was made (its own check found
  // nothing): the area then made holds the new pose, and the old pose's warning does not stand.
  events.push_back(event(Kind::kStage, "CONFIGURATION/POSED", "controller joint impedance"));
  events.push_back(event(Kind::kWarning, "joint_limit", "d: joint 3 at 1 deg", 3));
  events.push_back(event(Kind::kStage, "CONFIGURATION/APPROACHING", "controller gravity compensation"));
  events.push_back(event(Kind::kStage, "CONFIGURATION/POSED", "controller joint impedance"));
  events.push_back(event(Kind::kAreaCreated, "d", "d", 3));
  EXPECT_EQ(standingWarnings(events),
            (std::vector<std::string>{"the recording held no sample; no area created", "c: joint 5 at 2 deg"}));
}

// A teach-in whose tip stood still replays as standing still: kept, and said; one that moved
// the tip says nothing.
TEST(Workflow, ATeachInThatDidNotMoveTheTipIsKeptWithAWarning) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  ASSERT_TRUE(workflow.press(Button::kStartProgramming));
  const auto teachIn = [&](double swing) {
    ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
    ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
    ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
    ASSERT_EQ(workflow.subStage(), SubStage::kTeachIn);
    for (int i = 0; i <= 20; ++i) {
      f.backend.move(posture(-0.5 + swing * i / 20.0), swing > 0.0 ? 0.3 : 0.0);
      run(workflow, 0.02);
    }
    ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  };
  const auto smallTeachInWarnings = [&] {
    std::vector<std::string> details;
    for (const auto& event : workflow.events()) {
      if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "small_teach_in") details.push_back(event.detail);
    }
    return details;
  };
  teachIn(0.0);
  ASSERT_EQ(workflow.teachIns().size(), 1U);
  ASSERT_EQ(smallTeachInWarnings().size(), 1U);
  EXPECT_NE(smallTeachInWarnings()[0].find("teach-in 1: the tip moved at most 0.0 mm"), std::string::npos) << smallTeachInWarnings()[0];
  teachIn(0.3);  // joint 1 turned by 0.3 rad: the tip sweeps centimetres
  ASSERT_EQ(workflow.teachIns().size(), 2U);
  EXPECT_EQ(smallTeachInWarnings().size(), 1U);
}

TEST(Workflow, FullSessionCreatesAreasLearnsAndReachesExecution) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_EQ(workflow.areas().size(), 2U);
  EXPECT_TRUE(workflow.areas()[0].q_fixed.isApprox(posture(-0.5)));
  EXPECT_GE(workflow.areas()[0].X.cols(), 30);
  EXPECT_GT(workflow.itm().nodeCount(), 0);
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  EXPECT_EQ(workflow.stage(), Stage::kIdle);
  ASSERT_NE(workflow.model(), nullptr);
  // Two areas: the transition between them is checked and reported.
  ASSERT_EQ(workflow.transitionChecks().size(), 1U);
  // The learned map reproduces each area's posture at its centre.
  for (const auto& area : workflow.areas()) {
    EXPECT_LT((workflow.model()->predict(area.centre) - area.q_fixed).norm(), 0.1);
  }
  ASSERT_TRUE(workflow.press(Button::kStartProgramming));
  EXPECT_EQ(workflow.subStage(), SubStage::kWaiting);
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  EXPECT_EQ(workflow.controller(), InteractionController::kAssistedGravityCompensation);
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  EXPECT_EQ(workflow.subStage(), SubStage::kTeachIn);
  EXPECT_FALSE(workflow.press(Button::kFinishedProgramming));
  run(workflow, 0.2);
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_EQ(workflow.teachIns().size(), 1U);
  EXPECT_GE(workflow.teachIns()[0].cols(), 5);
  ASSERT_TRUE(workflow.press(Button::kFinishedProgramming));
  EXPECT_EQ(workflow.stage(), Stage::kExecution);
  EXPECT_TRUE(workflow.execute({workflow.areas()[1].centre}));
  EXPECT_TRUE(workflow.press(Button::kStartConfiguration));  // back to configuring
  bool learned = false, created = false;
  for (const auto& event : workflow.events()) {
    learned = learned || event.kind == WorkflowEvent::Kind::kModelLearned;
    created = created || event.kind == WorkflowEvent::Kind::kAreaCreated;
  }
  EXPECT_TRUE(learned);
  EXPECT_TRUE(created);
}

TEST(Workflow, RemovingAnAreaRelearnsFromTheRest) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  ASSERT_TRUE(workflow.removeArea(0));
  ASSERT_EQ(workflow.areas().size(), 1U);
  ASSERT_NE(workflow.model(), nullptr);
  EXPECT_TRUE(workflow.areas()[0].q_fixed.isApprox(posture(0.5)));
  EXPECT_LT((workflow.model()->predict(workflow.areas()[0].centre) - posture(0.5)).norm(), 0.1);
  EXPECT_TRUE(workflow.transitionChecks().empty());  // one area: nothing to check
}

// area_1 removed and area_2 kept: the next area counted as the second would be a second
// area_2, which the area list, Remove and Re-teach could not tell apart.
TEST(Workflow, AnAreaTaughtAfterARemovalTakesANameNoAreaBears) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_TRUE(workflow.removeArea(0));
  ASSERT_EQ(workflow.areas().size(), 1U);
  ASSERT_EQ(workflow.areas()[0].name, "area_2");
  teachArea(workflow, f.backend, posture(-0.8));
  ASSERT_EQ(workflow.areas().size(), 2U);
  EXPECT_EQ(workflow.areas()[1].name, "area_3");
  teachArea(workflow, f.backend, posture(0.8));
  EXPECT_EQ(workflow.areas()[2].name, "area_4");
}

TEST(Workflow, AnAreaTakesTheNameGivenBeforeItsRecordingAndKeepsItWhenRetaught) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  workflow.nameNextArea("under_the_board");
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_EQ(workflow.areas().size(), 2U);
  EXPECT_EQ(workflow.areas()[0].name, "under_the_board");
  EXPECT_EQ(workflow.areas()[1].name, "area_2") << "a name is for one area only";
  ASSERT_TRUE(workflow.reteachArea(0));
  workflow.nameNextArea("ignored");
  teachArea(workflow, f.backend, posture(-0.8));
  EXPECT_EQ(workflow.areas()[0].name, "under_the_board");
  // The transition checks after learning speak of the areas by name.
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  int checks = 0;
  for (const auto& event : workflow.events()) {
    if (event.name.rfind("transition", 0) == 0) {
      ++checks;
      EXPECT_NE(event.detail.find("under_the_board -> area_2"), std::string::npos) << event.detail;
    }
  }
  EXPECT_EQ(checks, 1);
}

TEST(Workflow, ReteachingReplacesTheArea) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  EXPECT_FALSE(workflow.reteachArea(2));
  ASSERT_TRUE(workflow.reteachArea(0));
  teachArea(workflow, f.backend, posture(-0.8));
  ASSERT_EQ(workflow.areas().size(), 2U);
  EXPECT_TRUE(workflow.areas()[0].q_fixed.isApprox(posture(-0.8)));
}

TEST(Workflow, WarnsWhenThePostureIsNearAJointLimit) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  Eigen::VectorXd q = posture(0.0);
  q[0] = lwr4().softUpperLimits()[0] - 0.05;
  teachArea(workflow, f.backend, q);
  workflow.nameNextArea("shelf");
  teachArea(workflow, f.backend, q);
  ASSERT_TRUE(workflow.reteachArea(1));  // the shelf again: the warning names it, not a third area
  teachArea(workflow, f.backend, q);
  std::vector<std::string> details;
  for (const auto& event : workflow.events()) {
    if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "joint_limit") details.push_back(event.detail);
  }
  ASSERT_EQ(details.size(), 3U);
  EXPECT_NE(details[2].find("at area 'shelf'"), std::string::npos) << details[2];
  for (const auto& detail : details) EXPECT_NE(detail.find("joint 1 (A1)"), std::string::npos) << detail;
  EXPECT_NE(details[0].find("at area 'area_1'"), std::string::npos) << details[0];
  EXPECT_NE(details[1].find("at area 'shelf'"), std::string::npos) << details[1];
  ASSERT_EQ(workflow.areas().size(), 2U);
  EXPECT_EQ(workflow.areas()[1].name, "shelf") << "the name the warning gave it";
}

// A recording in which the tip never moved makes an area of one point; the operator is told
// after the stage's event (a window clears its warnings at a new stage), and the warning goes
// when the area is taught again with motion.
TEST(Workflow, WarnsOfAnAreaRecordedWithoutMovingUntilItIsRetaught) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(0.0), 0.0);
  teachArea(workflow, f.backend, posture(0.6));
  const auto smallAreaWarnings = [&workflow] {
    std::vector<std::string> details;
    for (const auto& event : workflow.events()) {
      if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "small_area") details.push_back(event.detail);
    }
    return details;
  };
  ASSERT_EQ(smallAreaWarnings().size(), 1U) << "the second area was circled";
  EXPECT_EQ(smallAreaWarnings()[0].rfind("area_1: the tip moved at most 0.0 mm", 0), 0U) << smallAreaWarnings()[0];
  const auto& events = workflow.events();
  const auto warning = std::find_if(events.begin(), events.end(), [](const auto& e) { return e.name == "small_area"; });
  const auto created = std::find_if(events.begin(), events.end(), [](const auto& e) { return e.kind == WorkflowEvent::Kind::kAreaCreated; });
  const auto waiting = std::find_if(created, events.end(), [](const auto& e) { return e.kind == WorkflowEvent::Kind::kStage; });
  ASSERT_NE(waiting, events.end());
  EXPECT_EQ(waiting->name, "CONFIGURATION/WAITING");
  EXPECT_GT(warning - events.begin(), waiting - events.begin()) << "said before the stage's event, which clears it";
  EXPECT_EQ(standingWarnings(events), std::vector<std::string>{smallAreaWarnings()[0]});

  ASSERT_TRUE(workflow.reteachArea(0));
  teachArea(workflow, f.backend, posture(0.0));
  EXPECT_EQ(smallAreaWarnings().size(), 1U);
  EXPECT_TRUE(standingWarnings(workflow.events()).empty());
}

// A simulated link passes through the table; an area recorded that way leaves the map of free
// space empty, which the tutor hears when the area is made, not at the first refused plan.
TEST(Workflow, WarnsOfAnAreaRecordedInContactUntilItIsRetaughtClear) {
  Fixture f;
  Workflow workflow(f.backend, f.parameters, syncOptions());
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  const auto contactWarnings = [&workflow] {
    std::vector<std::string> details;
    for (const auto& event : workflow.events()) {
      if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "area_in_contact") details.push_back(event.detail);
    }
    return details;
  };
  f.backend.overlapObstacle(true);
  teachArea(workflow, f.backend, posture(0.0));
  f.backend.overlapObstacle(false);
  teachArea(workflow, f.backend, posture(0.6));
  ASSERT_EQ(contactWarnings().size(), 1U) << "the second area was recorded clear";
  EXPECT_EQ(contactWarnings()[0].rfind("area_1: ", 0), 0U) << contactWarnings()[0];
  const std::size_t samples = workflow.areas()[0].X.cols();
  EXPECT_NE(contactWarnings()[0].find(std::to_string(samples) + " of " + std::to_string(samples) + " samples"), std::string::npos)
      << contactWarnings()[0];
  EXPECT_EQ(standingWarnings(workflow.events()), std::vector<std::string>{contactWarnings()[0]});

  ASSERT_TRUE(workflow.reteachArea(0));
  teachArea(workflow, f.backend, posture(0.0));
  EXPECT_EQ(contactWarnings().size(), 1U);
  EXPECT_TRUE(standingWarnings(workflow.events()).empty());
}

// The joint-limit warnings of an area taught in posture q.
std::vector<std::string> jointLimitWarnings(const robot::RobotModel& model, const Eigen::VectorXd& q) {
  ScriptedBackend backend(model);
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  Workflow workflow(backend, parameters, syncOptions());
  EXPECT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, backend, q);
  std::vector<std::string> details;
  for (const auto& event : workflow.events()) {
    if (event.kind == WorkflowEvent::Kind::kWarning && event.name == "joint_limit") details.push_back(event.detail);
  }
  return details;
}

// A 4-joint arm whose third joint is `third` (a joint element's type, axis and limit).
robot::RobotModel armWithThirdJoint(const std::string& third) {
  return robot::RobotModel::fromUrdfString(R"(<robot name="arm">
    <link name="base"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
      <axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
    <link name="l1"/>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.1"/>
      <axis xyz="0 1 0"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
    <link name="l2"/>
    )" + third + R"(
    <link name="l3"/>
    <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0 0 0.1"/>
      <axis xyz="0 1 0"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
    <link name="l4"/>
    <joint name="tool" type="fixed"><parent link="l4"/><child link="tip"/><origin xyz="0 0 0.2"/></joint>
    <link name="tip"/>
  </robot>)",
                                           std::filesystem::temp_directory_path());
}

TEST(Workflow, APrismaticJointIsNearItsLimitInMillimetresOfItsOwnTravel) {
  // Joint 3 slides 0.2 m: the radian margin of the rotary joints would call every position of
  // it near a limit, and in degrees.
  const robot::RobotModel slider = armWithThirdJoint(R"(<joint name="slide" type="prismatic"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.3"/>
      <axis xyz="0 0 1"/><limit lower="0" upper="0.2" velocity="0.5" effort="100"/></joint>)");
  const auto warningsFor = [&](double slide) { return jointLimitWarnings(slider, Eigen::Vector4d(0.3, 0.5, slide, -1.0)); };
  EXPECT_TRUE(warningsFor(0.1).empty()) << "mid-travel, 0.1 m from either end";
  const std::vector<std::string> near_end = warningsFor(0.19);
  ASSERT_EQ(near_end.size(), 1U);
  EXPECT_NE(near_end[0].find("joint 3 (slide)"), std::string::npos) << near_end[0];
  EXPECT_NE(near_end[0].find(" mm from its software limit (200.0 mm)"), std::string::npos) << near_end[0];
}

TEST(Workflow, ANarrowRotaryJointIsNearItsLimitWithinATenthOfItsRangeAndSaysWhereItIs) {
  // Joint 3 turns ±0.1 rad: every position of it is within the 0.17 rad of the wide joints.
  const robot::RobotModel narrow = armWithThirdJoint(R"(<joint name="wrist" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.3"/>
      <axis xyz="0 1 0"/><limit lower="-0.1" upper="0.1" velocity="1" effort="100"/></joint>)");
  const auto warningsFor = [&](double wrist) { return jointLimitWarnings(narrow, Eigen::Vector4d(0.3, 0.5, wrist, -1.0)); };
  EXPECT_TRUE(warningsFor(0.0).empty()) << "in the middle, 0.1 rad from either end";
  const std::vector<std::string> near_end = warningsFor(0.095);
  ASSERT_EQ(near_end.size(), 1U);
  EXPECT_NE(near_end[0].find("joint 3 (wrist) is 0.3 deg from its software limit (5.7 deg)"), std::string::npos) << near_end[0];
  // Near it, some room is left; at it, none.
  EXPECT_NE(near_end[0].find("has little room left"), std::string::npos) << near_end[0];
  const std::vector<std::string> at_end = warningsFor(0.1);
  ASSERT_EQ(at_end.size(), 1U);
  EXPECT_NE(at_end[0].find("joint 3 (wrist) is at its limit (5.7 deg)"), std::string::npos) << at_end[0];
  EXPECT_NE(at_end[0].find("has no room left"), std::string::npos) << at_end[0];
}

// The tutor's feedback on a transition names what the arm hit and where along the line: a box
// on the line between two areas, the map giving each area's posture.
TEST(Workflow, ATransitionCheckNamesItsFirstContactAndWhereAlongTheLine) {
  Fixture f;
  TrainingArea from, to;
  from.name = "A";
  from.q_fixed = posture(-0.5);
  to.name = "B";
  to.q_fixed = posture(0.5);
  const Eigen::Vector3d start = robot::tipPose(lwr4(), from.q_fixed).translation();
  to.centre = robot::tipPose(lwr4(), to.q_fixed).translation();
  learning::TrainingSet data;
  data.X.resize(3, 2);
  data.Y.resize(7, 2);
  data.X << start, to.centre;
  data.Y << from.q_fixed, to.q_fixed;
  WorkflowOptions options;
  const auto map = makeLearner(options, 7);
  map->fit(data);
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "box";
  box.size = Eigen::Vector3d::Constant(0.1);
  box.X_WO.translation() = 0.5 * (start + to.centre);
  scene.obstacles.push_back(box);
  robot::CollisionWorld world(lwr4(), scene);
  const double speed = 0.1;
  const TransitionCheck blocked = checkTransition(lwr4(), f.parameters, *map, from, to, 0, 1, &world, speed, 0.01);
  EXPECT_FALSE(blocked.ok);
  EXPECT_GT(blocked.colliding_samples, 0);
  ASSERT_FALSE(blocked.first_contact.empty());
  EXPECT_EQ(blocked.first_contact.substr(blocked.first_contact.find('/')), "/box") << blocked.first_contact;
  // At the latest where the tip enters the box (0.05 m before its centre), 10 ms of motion late;
  // not before the hand (within 0.15 m of the tip, the wrist's links) can reach the box.
  const double tip_enters = 0.5 * (to.centre - start).norm() - 0.05;
  EXPECT_GE(blocked.first_contact_along_m, tip_enters - 0.15);
  EXPECT_LE(blocked.first_contact_along_m, tip_enters + 0.01 * speed + 1e-9);

  robot::CollisionWorld empty(lwr4(), robot::Scene{});
  const TransitionCheck free = checkTransition(lwr4(), f.parameters, *map, from, to, 0, 1, &empty, speed, 0.01);
  EXPECT_EQ(free.colliding_samples, 0);
  EXPECT_TRUE(free.first_contact.empty());
  EXPECT_EQ(free.first_contact_along_m, 0.0);
}

TEST(Workflow, OnlineOsElmLearnsDuringRecording) {
  Fixture f;
  WorkflowOptions options = syncOptions();
  options.learner = LearnerKind::kOsElm;
  Workflow workflow(f.backend, f.parameters, options);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  // Second approach: assistance blending, since an online map exists already.
  f.backend.push(3.0);
  run(workflow, 0.01);
  EXPECT_EQ(workflow.controller(), InteractionController::kAssistanceBlending);
}

TEST(Workflow, OsElmRefitAfterConfigurationMatchesTheAreas) {
  Fixture f;
  WorkflowOptions options = syncOptions();
  options.learner = LearnerKind::kOsElm;
  Workflow workflow(f.backend, f.parameters, options);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  ASSERT_NE(workflow.model(), nullptr);
  EXPECT_EQ(workflow.model()->kind(), "oselm");
  for (const auto& area : workflow.areas()) {
    EXPECT_LT((workflow.model()->predict(area.centre) - area.q_fixed).norm(), 0.1);
  }
  ASSERT_TRUE(workflow.removeArea(1));
  ASSERT_NE(workflow.model(), nullptr);
  EXPECT_LT((workflow.model()->predict(workflow.areas()[0].centre) - posture(-0.5)).norm(), 0.1);
}

TEST(Workflow, BackgroundLearningDoesNotBlockTheControlCycle) {
  Fixture f;
  WorkflowOptions options = syncOptions();
  options.background_learning = true;
  Workflow workflow(f.backend, f.parameters, options);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, f.backend, posture(-0.5));
  teachArea(workflow, f.backend, posture(0.5));
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  run(workflow, 0.01);  // control continues while learning runs
  workflow.waitForLearning();
  EXPECT_NE(workflow.model(), nullptr);
  EXPECT_TRUE(workflow.press(Button::kStartProgramming));
}

}  // namespace
}  // namespace flexirob::app
