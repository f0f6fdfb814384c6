// EXECUTION (replay a teach-in, plan through the ITM and execute), assistance blending with the
// online OS-ELM, and random request sequences that must never corrupt the workflow's state.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "app/workflow.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/reach.hpp"
#include "tests/app/workflow_rigs.hpp"

namespace flexirob::app {
namespace {

using workflow_rigs::lwr4;
using workflow_rigs::run;

// A kinematic arm: while `following`, the measured posture is the last command (an ideal
// position-controlled robot); otherwise the test places it (the tutor's hand) and sets τ_ext.
class KinematicBackend final : public robot::RobotBackend {
 public:
  bool touching = false;  ///< every link overlaps something (a simulated arm in the table)
  explicit KinematicBackend(const robot::RobotModel& model) : model_(&model), kinematics_(model) {
    state_.resize(model.dof());
    place(posture(0.0), 0.0);
  }
  static Eigen::VectorXd posture(double a1) {
    Eigen::VectorXd q = lwr4().midPosture();
    q[0] = a1;
    q[1] = 0.7;
    q[3] = -1.3;
    q[5] = 0.8;
    return q;
  }
  const robot::RobotModel& model() const override { return *model_; }
  double cycleTime() const override { return 1e-3; }
  void readState(robot::RobotState& state) const override {
    state = state_;
    state.in_contact = touching;
  }
  robot::CommandStatus writeCommand(const robot::JointImpedanceCommand& command) override {
    last_ = command;
    return robot::CommandStatus::kAccepted;
  }
  void step() override {
    state_.time += cycleTime();
    if (following && last_.q_cmd.size() == state_.q.size()) {
      state_.qd = (last_.q_cmd - state_.q) / cycleTime();
      setPosture(last_.q_cmd);
    }
  }
  void place(const Eigen::VectorXd& q, double speed) {
    state_.qd.setConstant(speed);
    setPosture(q);
  }
  void touch(double torque) {
    state_.tau_ext.setZero();
    state_.tau_ext[1] = torque;
  }
  void letGo() {
    state_.tau_ext.setZero();
    state_.qd.setZero();
  }
  const robot::JointImpedanceCommand& last() const { return last_; }
  Eigen::Vector3d tip() const { return state_.p_WT(); }
  bool following = false;

 private:
  void setPosture(const Eigen::VectorXd& q) {
    state_.q = q;
    state_.q_cmd = q;
    kinematics_.update(q);
    state_.X_WT = kinematics_.X_WT();
  }
  const robot::RobotModel* model_;
  robot::Kinematics kinematics_;
  robot::RobotState state_;
  robot::JointImpedanceCommand last_;
};

struct Rig {
  Rig() : backend(lwr4()), declarations(robot::reachParameters()), parameters(declarations) {}
  KinematicBackend backend;
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
};

WorkflowOptions syncOptions() { return workflow_rigs::syncOptions(40); }

// Moves the placed arm from its posture to q in `seconds`, as a hand would (samples every cycle).
void guide(Workflow& workflow, KinematicBackend& backend, const Eigen::VectorXd& from, const Eigen::VectorXd& to,
           double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / 1e-3));
  for (int i = 1; i <= steps; ++i) {
    const double s = static_cast<double>(i) / steps;
    backend.place(from + s * (to - from), (to - from).cwiseAbs().maxCoeff() / seconds);
    workflow.step();
  }
}

// One area: touch, guide from `from` to q_fixed, rest, touch, small circles, rest.
void teachArea(Workflow& workflow, KinematicBackend& backend, const Eigen::VectorXd& from, const Eigen::VectorXd& q_fixed) {
  backend.touch(3.0);
  run(workflow, 0.01);
  ASSERT_EQ(workflow.subStage(), SubStage::kApproaching);
  guide(workflow, backend, from, q_fixed, 1.0);
  backend.letGo();
  run(workflow, 2.1);
  ASSERT_EQ(workflow.subStage(), SubStage::kPosed);
  backend.touch(3.0);
  run(workflow, 0.01);
  ASSERT_EQ(workflow.subStage(), SubStage::kRecording);
  const Eigen::Index n = q_fixed.size();
  for (int i = 0; i < 60; ++i) {
    const Eigen::VectorXd q = q_fixed + 0.05 * std::sin(0.3 * i) * Eigen::VectorXd::Unit(n, 0) +
                              0.05 * std::cos(0.3 * i) * Eigen::VectorXd::Unit(n, 3);
    backend.place(q, 0.3);
    run(workflow, 0.02);
  }
  backend.place(q_fixed, 0.0);
  backend.letGo();
  run(workflow, 2.1);
  ASSERT_EQ(workflow.subStage(), SubStage::kWaiting);
}

// Two areas, learned, then a teach-in from the first area's posture towards the second.
void configureAndProgram(Workflow& workflow, KinematicBackend& backend) {
  const Eigen::VectorXd a = KinematicBackend::posture(-0.4), b = KinematicBackend::posture(0.4);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, backend, KinematicBackend::posture(0.0), a);
  teachArea(workflow, backend, a, b);
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  ASSERT_NE(workflow.model(), nullptr);
  ASSERT_TRUE(workflow.press(Button::kStartProgramming));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_EQ(workflow.subStage(), SubStage::kTeachIn);
  guide(workflow, backend, b, a, 1.5);
  backend.letGo();
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_EQ(workflow.teachIns().size(), 1U);
  ASSERT_TRUE(workflow.press(Button::kFinishedProgramming));
  ASSERT_EQ(workflow.stage(), Stage::kExecution);
}

// Runs EXECUTION (the arm following its commands) until the motion is done and settled;
// returns the largest distance of the tip from the moving target after the first 0.3 s.
double execute(Workflow& workflow, KinematicBackend& backend, double max_seconds) {
  backend.following = true;
  double max_lag = 0.0;
  for (int i = 0; i < static_cast<int>(max_seconds / 1e-3) && !workflow.executionDone(); ++i) {
    workflow.step();
    if (i >= 300) max_lag = std::max(max_lag, (backend.tip() - workflow.taskTarget()).norm());
  }
  run(workflow, 0.5);
  return max_lag;
}

TEST(WorkflowExecution, ReplaysATeachInToItsEnd) {
  Rig rig;
  Workflow workflow(rig.backend, rig.parameters, syncOptions());
  configureAndProgram(workflow, rig.backend);
  const Eigen::MatrixXd trajectory = workflow.teachIns()[0];
  EXPECT_FALSE(workflow.replayTeachIn(1));  // only one teach-in
  ASSERT_TRUE(workflow.replayTeachIn(0));
  EXPECT_FALSE(workflow.executionDone());
  // The target moves at 0.1 m/s; its velocity is fed forward, so the tip stays well inside
  // the lag v/κ_x = 10 mm that Eq. 2.11's feedback alone leaves (measured: 9.9 mm without).
  const double max_lag = execute(workflow, rig.backend, 20.0);
  EXPECT_LT(max_lag, 0.005);
  EXPECT_TRUE(workflow.executionDone());
  const Eigen::Vector3d end = trajectory.col(trajectory.cols() - 1);
  EXPECT_LT((rig.backend.tip() - end).norm(), 0.005) << "tip " << rig.backend.tip().transpose();
}

// Runs EXECUTION as execute() does, calling `check` after every cycle of the motion.
template <typename Check>
void backendFollowsEveryCycle(Workflow& workflow, KinematicBackend& backend, Check check) {
  backend.following = true;
  for (int i = 0; i < 30000 && !workflow.executionDone(); ++i) {
    workflow.step();
    check();
  }
  run(workflow, 0.5);
}

TEST(WorkflowExecution, PlansThroughTheItmAndExecutesThePath) {
  Rig rig;
  Workflow workflow(rig.backend, rig.parameters, syncOptions());
  configureAndProgram(workflow, rig.backend);
  // The arm is at the first area (end of the teach-in); plan to the second area's centre.
  const Eigen::Vector3d goal = workflow.areas()[1].centre;
  ASSERT_GT(workflow.itm().nodeCount(), 1);
  const auto result = workflow.planTo(goal);
  ASSERT_TRUE(result) << result.reason;
  ASSERT_NE(workflow.plannedPath(), nullptr);
  EXPECT_TRUE(workflow.plannedPath()->found);
  EXPECT_EQ(workflow.pathVersion(), 1U);
  execute(workflow, rig.backend, 30.0);
  EXPECT_LT((rig.backend.tip() - goal).norm(), 0.005) << "tip " << rig.backend.tip().transpose();
}

TEST(WorkflowExecution, APlannedMotionFollowsThePosturesShownAlongItsPathUnlessToldToFollowTheMap) {
  for (const planning::PlanPostures postures : {planning::PlanPostures::kDemonstrated, planning::PlanPostures::kLearned}) {
    SCOPED_TRACE(planning::toString(postures));
    Rig rig;
    WorkflowOptions options = syncOptions();
    options.plan_postures = postures;
    Workflow workflow(rig.backend, rig.parameters, options);
    configureAndProgram(workflow, rig.backend);
    const Eigen::Vector3d goal = workflow.areas()[1].centre;
    ASSERT_TRUE(workflow.planTo(goal));
    const planning::PlannedPath& path = *workflow.plannedPath();
    // What the arm showed along the path: the start posture and the nodes' q_i.
    robot::RobotState state;
    rig.backend.readState(state);
    Eigen::VectorXd lowest = state.q.cwiseMin(path.node_joints.rowwise().minCoeff());
    Eigen::VectorXd highest = state.q.cwiseMax(path.node_joints.rowwise().maxCoeff());
    double largest_departure = 0.0;  // of the null-space posture from the map's [rad]
    int cycle = 0;
    backendFollowsEveryCycle(workflow, rig.backend, [&] {
      const Eigen::VectorXd learned = workflow.model()->predict(workflow.taskTarget());
      const Eigen::VectorXd& target = workflow.mapPosture();
      if (++cycle > 2) largest_departure = std::max(largest_departure, (target - learned).norm());
      if (postures == planning::PlanPostures::kDemonstrated) {
        EXPECT_TRUE((target.array() >= lowest.array() - 1e-9).all() && (target.array() <= highest.array() + 1e-9).all())
            << target.transpose();
      }
    });
    EXPECT_LT((rig.backend.tip() - goal).norm(), 0.005);
    // The shown postures differ from the map's by up to 0.08 rad in A1 here (the ELM averages
    // the two areas' postures).
    if (postures == planning::PlanPostures::kLearned) {
      EXPECT_LT(largest_departure, 1e-9);
    } else {
      EXPECT_GT(largest_departure, 0.03);
    }
    // A keyboard nudge leaves the path: q_c again.
    ASSERT_TRUE(workflow.nudgeTask(Eigen::Vector3d(0.0, 0.0, 0.01)));
    run(workflow, 0.01);
    EXPECT_LT((workflow.mapPosture() - workflow.model()->predict(workflow.taskTarget())).norm(), 1e-9);
  }
}

TEST(WorkflowExecution, RefusesAGoalOutsideTheExploredSpaceWithoutMoving) {
  Rig rig;
  Workflow workflow(rig.backend, rig.parameters, syncOptions());
  configureAndProgram(workflow, rig.backend);
  const auto result = workflow.planTo(Eigen::Vector3d(0.0, -0.7, 0.2));
  EXPECT_FALSE(result);
  EXPECT_NE(result.reason.find("explored"), std::string::npos) << result.reason;
  EXPECT_TRUE(workflow.executionDone());
  EXPECT_EQ(workflow.plannedPath(), nullptr);
  EXPECT_EQ(workflow.stage(), Stage::kExecution);
  EXPECT_FALSE(workflow.planTo(Eigen::Vector3d(NAN, 0.0, 0.0)));
}

// Taught with the arm in the table, the map of free space keeps nothing: the refusal says why,
// instead of only blaming the goal.
TEST(WorkflowExecution, APlanRefusedForAMapTaughtInContactSaysThePositionsWereLeftOut) {
  Rig rig;
  rig.backend.touching = true;
  Workflow workflow(rig.backend, rig.parameters, syncOptions());
  configureAndProgram(workflow, rig.backend);
  const auto result = workflow.planTo(Eigen::Vector3d(0.0, -0.7, 0.2));
  EXPECT_FALSE(result);
  EXPECT_NE(result.reason.find("the ITM graph is empty"), std::string::npos) << result.reason;
  EXPECT_NE(result.reason.find(" positions of CONFIGURATION were left out of it because the arm touched something"), std::string::npos)
      << result.reason;

  Rig clear;
  Workflow cleanly_taught(clear.backend, clear.parameters, syncOptions());
  configureAndProgram(cleanly_taught, clear.backend);
  const auto refused = cleanly_taught.planTo(Eigen::Vector3d(0.0, -0.7, 0.2));
  EXPECT_EQ(refused.reason.find("left out"), std::string::npos) << refused.reason;
}

TEST(WorkflowExecution, OnlineOsElmBlendsAssistanceByConfidence) {
  Rig rig;
  WorkflowOptions options = syncOptions();
  options.learner = LearnerKind::kOsElm;
  Workflow workflow(rig.backend, rig.parameters, options);
  const Eigen::VectorXd a = KinematicBackend::posture(-0.4);
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  teachArea(workflow, rig.backend, KinematicBackend::posture(0.0), a);
  // Touching the arm inside the first area: assistance blending with α = C(x) high (Eq. 6.2).
  rig.backend.touch(3.0);
  run(workflow, 0.05);
  ASSERT_EQ(workflow.controller(), InteractionController::kAssistanceBlending);
  EXPECT_GT(workflow.alpha(), 0.5);
  // Far from every area the robot has no confidence: α ≈ 0, the tutor's posture rules.
  rig.backend.letGo();
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));  // POSED
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));   // RECORDING...
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));  // ...without a sample: no area
  ASSERT_EQ(workflow.areas().size(), 1U);
  rig.backend.place(KinematicBackend::posture(1.6), 0.0);
  rig.backend.touch(3.0);
  run(workflow, 0.05);
  ASSERT_EQ(workflow.controller(), InteractionController::kAssistanceBlending);
  EXPECT_LT(workflow.alpha(), 0.05);
}

// Random sequences of requests and hand actions: a refused request changes nothing, and the
// state always satisfies the invariants of Fig. 2.5 / 2.8.
TEST(WorkflowExecution, RandomRequestSequencesNeverCorruptTheState) {
  Rig rig;
  Workflow workflow(rig.backend, rig.parameters, syncOptions());
  std::mt19937_64 random(7);
  std::uniform_int_distribution<int> pick(0, 13);
  std::uniform_int_distribution<int> index(-1, 3);
  const Eigen::VectorXd postures[] = {KinematicBackend::posture(-0.4), KinematicBackend::posture(0.4),
                                      KinematicBackend::posture(0.0)};
  int accepted = 0, refused = 0;
  for (int action = 0; action < 600; ++action) {
    const Stage stage = workflow.stage();
    const SubStage sub_stage = workflow.subStage();
    const std::size_t areas = workflow.areas().size(), teach_ins = workflow.teachIns().size();
    const std::uint64_t areas_version = workflow.areasVersion(), path_version = workflow.pathVersion();
    std::optional<RequestResult> result;
    switch (pick(random)) {
      case 0: result = workflow.press(Button::kStartConfiguration); break;
      case 1: result = workflow.press(Button::kFinishedConfiguration); break;
      case 2: result = workflow.press(Button::kStartProgramming); break;
      case 3: result = workflow.press(Button::kFinishedProgramming); break;
      case 4: result = workflow.fire(Trigger::kOnAffected); break;
      case 5: result = workflow.fire(Trigger::kOnConverged); break;
      case 6: result = workflow.removeArea(index(random)); break;
      case 7: result = workflow.reteachArea(index(random)); break;
      case 8: result = workflow.replayTeachIn(index(random)); break;
      case 9: result = workflow.planTo(Eigen::Vector3d(0.3 * index(random), 0.2, 0.5)); break;
      case 10: result = workflow.nudgeJoint(index(random) * 3, 0.01); break;
      case 11: rig.backend.touch(3.0); break;
      case 12: rig.backend.letGo(); break;
      case 13: rig.backend.place(postures[std::abs(index(random)) % 3], 0.0); break;
    }
    if (result && !result->accepted) {
      ++refused;
      EXPECT_FALSE(result->reason.empty());
      EXPECT_EQ(workflow.stage(), stage);
      EXPECT_EQ(workflow.subStage(), sub_stage);
      EXPECT_EQ(workflow.areas().size(), areas);
      EXPECT_EQ(workflow.teachIns().size(), teach_ins);
      EXPECT_EQ(workflow.areasVersion(), areas_version);
      EXPECT_EQ(workflow.pathVersion(), path_version);
    } else if (result) {
      ++accepted;
    }
    run(workflow, 0.03);
    // Invariants.
    const bool interactive = workflow.stage() == Stage::kConfiguration || workflow.stage() == Stage::kProgramming;
    ASSERT_EQ(workflow.subStage() != SubStage::kNone, interactive) << workflow.stateName();
    if (workflow.subStage() == SubStage::kRecording) {
      ASSERT_EQ(workflow.stage(), Stage::kConfiguration);
    }
    if (workflow.subStage() == SubStage::kTeachIn) {
      ASSERT_EQ(workflow.stage(), Stage::kProgramming);
    }
    if (workflow.stage() == Stage::kProgramming || workflow.stage() == Stage::kExecution) {
      ASSERT_FALSE(workflow.areas().empty());
    }
    for (const auto& area : workflow.areas()) {
      ASSERT_GT(area.X.cols(), 0);
      ASSERT_EQ(area.X.cols(), area.Q.cols());
      ASSERT_TRUE(area.q_fixed.allFinite());
    }
    ASSERT_TRUE(rig.backend.last().q_cmd.allFinite());
  }
  EXPECT_GT(accepted, 30);
  EXPECT_GT(refused, 30);
}

}  // namespace
}  // namespace flexirob::app
