// The workflow on the simulated arm under a hand's force (Simulation::setHandForce): what a
// tutor's hand does to the sub-stages, with the interaction triggers reading the arm's own
// measurements (App. A.3).
#include <gtest/gtest.h>

#include "app/workflow.hpp"
#include "robot/sim/simulation.hpp"
#include "tests/app/workflow_rigs.hpp"

namespace flexirob::app {
namespace {

using workflow_rigs::lwr4;
using workflow_rigs::run;
using workflow_rigs::syncOptions;
using Rig = workflow_rigs::SimulatedLwr4;

// One area where the arm stands, taught with the keyboard's triggers, learned; then
// PROGRAMMING with the arm posed (APPROACHING, then POSED).
void poseInProgramming(Workflow& workflow) {
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  run(workflow, 0.3);
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_EQ(workflow.areas().size(), 1U);
  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  ASSERT_NE(workflow.model(), nullptr);
  ASSERT_TRUE(workflow.press(Button::kStartProgramming));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_EQ(workflow.subStage(), SubStage::kPosed);
  run(workflow, 0.5);  // the arm settles where it was posed
}

// A hand that takes the posed arm slowly, its pull growing by 2 N per second: the arm holds
// its start position against it, so the pull shows as external torque before the arm moves,
// and TEACH-IN starts. Before, the arm gave way to the pull at once (x_des followed the tip),
// moved off its start position and never started recording.
TEST(WorkflowUnderAHand, ASlowSteadyPullOnThePosedArmStartsTheTeachIn) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, syncOptions());
  poseInProgramming(workflow);
  if (HasFatalFailure()) return;
  const Eigen::Vector3d start = rig.state().p_WT();
  const int tip_body = lwr4().dof();
  const double rate = 2.0;  // [N/s]
  double pulled = 0.0;
  for (int k = 0; k < 5000 && workflow.subStage() == SubStage::kPosed; ++k) {
    pulled = rate * (k + 1) * 1e-3;
    rig.sim.setHandForce(tip_body, rig.state().p_WT(), Eigen::Vector3d(0.0, pulled, 0.0));
    workflow.step();
  }
  EXPECT_EQ(workflow.subStage(), SubStage::kTeachIn) << "after a pull of " << pulled << " N";
  // Until then the arm stayed at its start position (the recorded path begins there).
  EXPECT_LT((rig.state().p_WT() - start).norm(), 0.03);  // the hold gives about 1 cm per newton
  // Once recording, the arm follows the same hand.
  run(workflow, 1.0);
  EXPECT_GT((rig.state().p_WT() - start).norm(), 0.05);
  rig.sim.clearHandForce();
}

// The window's mouse hand: a spring of 250 N/m (ui/mouse_perturbation.hpp) from the tip to a
// cursor dragged away slowly, 3 cm/s. An arm that gave way would keep the spring short and its
// force below the threshold however far the cursor went; the posed arm holds, the spring
// stretches, and TEACH-IN starts within the first few centimetres.
TEST(WorkflowUnderAHand, ACursorDraggedSlowlyFromThePosedTipStartsTheTeachIn) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, syncOptions());
  poseInProgramming(workflow);
  if (HasFatalFailure()) return;
  const Eigen::Vector3d start = rig.state().p_WT();
  const int tip_body = lwr4().dof();
  const double stiffness = 250.0, speed = 0.03;
  Eigen::Vector3d cursor = start;
  for (int k = 0; k < 4000 && workflow.subStage() == SubStage::kPosed; ++k) {
    cursor = start + Eigen::Vector3d(0.0, speed * (k + 1) * 1e-3, 0.0);
    const Eigen::Vector3d tip = rig.state().p_WT();
    rig.sim.setHandForce(tip_body, tip, stiffness * (cursor - tip));
    workflow.step();
  }
  EXPECT_EQ(workflow.subStage(), SubStage::kTeachIn) << "with the cursor " << (cursor - start).norm() << " m away";
  EXPECT_LT((cursor - start).norm(), 0.06);
  rig.sim.clearHandForce();
}

}  // namespace
}  // namespace flexirob::app
