// Interaction triggers (App. A.3): on_affected and on_converged at the right simulated times.
#include <gtest/gtest.h>

#include <vector>

#include "robot/interaction.hpp"
#include "robot/resources.hpp"
#include "robot/sim/simulation.hpp"
#include "robot/triggers.hpp"

namespace flexirob::robot {
namespace {

RobotState stateAt(double time, double speed, double torque) {
  RobotState state;
  state.resize(3);
  state.time = time;
  state.qd[1] = speed;
  state.tau_ext[2] = torque;
  return state;
}

TEST(InteractionTriggers, FireAtTheTimesOfTouchAndStillness) {
  InteractionTriggers triggers{ParameterSet(triggerParameters())};
  std::vector<TriggerEvent> events;
  // 1 kHz: untouched until 1.0 s; a touch of 2 Nm while still at 1.0 s; the arm moves from
  // 1.2 s to 1.8 s; the hand lets go at 1.8 s; still ever since.
  for (int k = 0; k <= 5000; ++k) {
    const double t = k * 1e-3;
    const double speed = (t >= 1.2 && t < 1.8) ? 0.3 : 0.0;
    const double torque = (t >= 1.0 && t < 1.8) ? -2.0 : 0.3;
    if (auto event = triggers.update(stateAt(t, speed, torque))) events.push_back(*event);
  }
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].kind, TriggerKind::kOnAffected);
  EXPECT_NEAR(events[0].time, 1.0, 1e-9);
  EXPECT_EQ(events[1].kind, TriggerKind::kOnConverged);
  // Last moving sample at 1.799 s, then 2 s without motion.
  EXPECT_NEAR(events[1].time, 1.799 + 2.0, 1e-9);
}

TEST(InteractionTriggers, NeitherFiresWhileMovingNorTwiceForOneTouch) {
  InteractionTriggers triggers{ParameterSet(triggerParameters())};
  int affected = 0;
  for (int k = 0; k < 3000; ++k) {
    const double t = k * 1e-3;
    // Pushed hard but moving: no on_affected until it stops at 1.5 s, then only once.
    const double speed = t < 1.5 ? 0.5 : 0.0;
    if (auto event = triggers.update(stateAt(t, speed, 5.0))) {
      if (event->kind == TriggerKind::kOnAffected) {
        ++affected;
        EXPECT_NEAR(event->time, 1.5, 1e-9);
      }
    }
  }
  EXPECT_EQ(affected, 1);
  // A torque at the threshold itself is no touch.
  InteractionTriggers fresh{ParameterSet(triggerParameters())};
  EXPECT_FALSE(fresh.update(stateAt(0.0, 0.0, 1.5)).has_value());
}

// A compliant arm yields to the hand at once, and a measured τ_ext shows the push one cycle (or
// more) after it acted: the touch counts when it began on a still robot (triggers.onset_window).
// A hand (or a held mouse pull) that keeps still for 2 s ends the phase; held on after that,
// it starts no new one: the touch must end first. Its grip loosened for a moment during the
// phase (a pull going round in circles passes near zero force) must not count as that end.
TEST(InteractionTriggers, AHandHeldOnThroughOnConvergedStartsNothingUntilItLetsGo) {
  InteractionTriggers triggers{ParameterSet(triggerParameters())};
  std::vector<TriggerEvent> events;
  for (int k = 0; k <= 7000; ++k) {
    const double t = k * 1e-3;
    const bool loosened = t >= 1.5 && t < 1.6;
    const bool let_go = t >= 5.0 && t < 5.5;
    const double torque = t < 1.0 ? 0.0 : (loosened || let_go ? 0.5 : 4.0);
    if (auto event = triggers.update(stateAt(t, 0.0, torque))) events.push_back(*event);
  }
  ASSERT_EQ(events.size(), 3U);
  EXPECT_EQ(events[0].kind, TriggerKind::kOnAffected);
  EXPECT_NEAR(events[0].time, 1.0, 1e-9);
  EXPECT_EQ(events[1].kind, TriggerKind::kOnConverged);
  EXPECT_NEAR(events[1].time, 3.0, 1e-9);
  EXPECT_EQ(events[2].kind, TriggerKind::kOnAffected);  // the next touch, after letting go
  EXPECT_NEAR(events[2].time, 5.5, 1e-9);
}

TEST(InteractionTriggers, ATouchThatBeganOnAStillRobotFiresEvenWhenTheArmYieldsFirst) {
  const ParameterSet parameters(triggerParameters());
  const double window = parameters.get("triggers.onset_window");
  ASSERT_GT(window, 0.002);
  InteractionTriggers triggers(parameters);
  std::vector<TriggerEvent> events;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * 1e-3;
    // Still until 1.000 s; from then on the arm moves under the hand; τ_ext shows it from 1.001 s.
    const double speed = t >= 1.0 - 1e-9 ? 0.5 : 0.0;
    const double torque = t >= 1.001 - 1e-9 ? 4.0 : 0.0;
    if (auto event = triggers.update(stateAt(t, speed, torque))) events.push_back(*event);
  }
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].kind, TriggerKind::kOnAffected);
  EXPECT_NEAR(events[0].time, 1.001, 1e-9);

  // The same push, but τ_ext rises only after the arm has moved for longer than the window: it
  // is not a touch of a still robot (e.g. the robot was already moving), so nothing fires.
  InteractionTriggers late(parameters);
  int fired = 0;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * 1e-3;
    const double speed = t >= 1.0 - 1e-9 ? 0.5 : 0.0;
    const double torque = t >= 1.0 + window + 0.01 ? 4.0 : 0.0;
    if (late.update(stateAt(t, speed, torque))) ++fired;
  }
  EXPECT_EQ(fired, 0);
}

// A hand taking a held arm slowly: τ_ext rises by 3 Nm/s from 1.0 s, and the arm gives way
// (faster than still) once it exceeds 0.6 Nm, long before the 1.5 Nm threshold. The touch
// began while the arm was still, so on_affected fires where the torque crosses the threshold.
TEST(InteractionTriggers, ASlowPullThatBeganOnAStillArmFiresWhereItsTorqueCrossesTheThreshold) {
  const ParameterSet parameters(triggerParameters());
  const double threshold = parameters.get("triggers.torque_threshold");
  const auto pull = [](double t) { return t >= 1.0 ? 3.0 * (t - 1.0) : 0.0; };
  InteractionTriggers triggers(parameters);
  std::vector<TriggerEvent> events;
  for (int k = 0; k < 2500; ++k) {
    const double t = k * 1e-3;
    const double torque = pull(t);
    if (auto event = triggers.update(stateAt(t, torque > 0.6 ? 0.2 : 0.0, torque))) events.push_back(*event);
  }
  ASSERT_EQ(events.size(), 1U);
  EXPECT_EQ(events[0].kind, TriggerKind::kOnAffected);
  EXPECT_NEAR(events[0].time, 1.0 + threshold / 3.0, 1.5e-3);

  // The same pull on an arm that was already moving when it began: nothing fires.
  InteractionTriggers moving(parameters);
  int fired = 0;
  for (int k = 0; k < 2500; ++k) {
    const double t = k * 1e-3;
    if (moving.update(stateAt(t, t >= 0.5 ? 0.2 : 0.0, pull(t)))) ++fired;
  }
  EXPECT_EQ(fired, 0);

  // A touch that ended (the torque gone below a third of the threshold) before the arm moved
  // does not count for a later pull that begins on the moving arm.
  InteractionTriggers ended(parameters);
  fired = 0;
  for (int k = 0; k < 3000; ++k) {
    const double t = k * 1e-3;
    const double torque = t >= 0.5 && t < 0.6 ? 1.0 : (t >= 1.5 ? 3.0 * (t - 1.5) : 0.0);
    if (ended.update(stateAt(t, t >= 0.7 ? 0.2 : 0.0, torque))) ++fired;
  }
  EXPECT_EQ(fired, 0);

  // A standing τ_ext of 0.7 Nm (a real arm's estimate may stand off zero) above a third of the
  // threshold since the start: a push seconds later on the moving arm is no touch of a still arm.
  InteractionTriggers offset(parameters);
  fired = 0;
  for (int k = 0; k < 5000; ++k) {
    const double t = k * 1e-3;
    if (offset.update(stateAt(t, t >= 1.0 ? 0.2 : 0.0, t >= 3.5 ? 4.0 : 0.7))) ++fired;
  }
  EXPECT_EQ(fired, 0);
}

TEST(InteractionTriggers, FireWhenATutorPushesAndReleasesTheSimulatedArm) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  Simulation sim(model, nullptr, ParameterSet(simulationParameters()));
  Eigen::VectorXd q0(7);
  q0 << 0.2, 0.7, -0.3, -1.1, 0.4, 0.6, -0.2;
  sim.reset(q0);
  const auto declarations = interactionControllerParameters();
  InteractionController controller(model, ParameterSet(declarations), sim.cycleTime());
  const ParameterSet trigger_parameters(triggerParameters());
  InteractionTriggers triggers(trigger_parameters);
  RobotState state;
  sim.readState(state);
  // The robot holds its posture stiffly (hierarchical control) until touched.
  controller.setFixedPosture(q0);
  controller.start(InteractionMode::kHierarchicalControl, state);
  JointImpedanceCommand command;
  // The hand presses on the flange from 0.5 s on, its force rising to 12 N within 1 s, and lets
  // go at 2.5 s. Once on_affected fires the arm switches to gravity compensation and moves.
  const Eigen::Vector3d full_force(0.0, 12.0, 0.0);
  const Eigen::Vector3d p_hand = state.p_WT();
  Kinematics kinematics(model);
  kinematics.update(q0);
  Matrix3Xd J;
  kinematics.pointJacobian(7, p_hand, J);
  // τ_ext grows linearly with the force: it crosses 1.5 Nm at this time (posture held).
  const double expected_touch = 0.5 + 1.5 / (J.transpose() * full_force).cwiseAbs().maxCoeff();
  std::vector<TriggerEvent> events;
  double last_moving = 0.0;
  for (int k = 0; k < 7000; ++k) {
    const double t = k * 1e-3;
    if (t >= 0.5 && t < 2.5) {
      sim.setHandForce(7, kinematics.X_WB(7) * (model.X_LastBodyTip().translation()), std::min(1.0, t - 0.5) * full_force);
    } else {
      sim.clearHandForce();
    }
    controller.update(state, command);
    sim.writeCommand(command);
    sim.step();
    sim.readState(state);
    kinematics.update(state.q);
    if (state.qd.cwiseAbs().maxCoeff() > trigger_parameters.get("triggers.still_velocity")) last_moving = state.time;
    if (auto event = triggers.update(state)) {
      events.push_back(*event);
      if (event->kind == TriggerKind::kOnAffected) controller.start(InteractionMode::kGravityCompensation, state);
    }
  }
  ASSERT_EQ(events.size(), 2U);
  EXPECT_EQ(events[0].kind, TriggerKind::kOnAffected);
  EXPECT_NEAR(events[0].time, expected_touch, 3e-3);
  EXPECT_EQ(events[1].kind, TriggerKind::kOnConverged);
  EXPECT_GT(last_moving, 2.5);  // moved while pushed, came to rest after the release
  EXPECT_NEAR(events[1].time, last_moving + 2.0, 1.5e-3);
}

}  // namespace
}  // namespace flexirob::robot
