// The teaching workflow running in the real-time control thread: requests through the queue,
// snapshots out of the triple buffer, the hand of the GUI pushing the simulated arm.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <unistd.h>

#include "app/realtime.hpp"
#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_teaching.hpp"
#include "app/workflow_thread.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"
#include "tests/app/workflow_rigs.hpp"

namespace flexirob::app {
namespace {

using workflow_rigs::lwr4;
using Rig = workflow_rigs::SimulatedLwr4;

WorkflowThread::Options fast() {
  WorkflowThread::Options options;
  options.paced = false;  // the simulation as fast as the machine allows
  return options;
}

/// Reads snapshots until `done` holds for one (or the wall-clock timeout passes); returns it.
WorkflowSnapshot waitFor(WorkflowThread& thread, const std::function<bool(const WorkflowSnapshot&)>& done,
                         double timeout_s = 60.0) {
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    const WorkflowSnapshot& snapshot = thread.snapshot();
    if (done(snapshot) || snapshot.failed) return snapshot;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > timeout_s) return snapshot;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

WorkflowSnapshot handled(WorkflowThread& thread, std::uint64_t id) {
  return waitFor(thread, [id](const WorkflowSnapshot& s) { return s.last_request_id >= id; });
}

bool hasEvent(const WorkflowSnapshot& snapshot, const std::string& name) {
  for (const auto& event : snapshot.events) {
    if (event.sequence > 0 && name == event.name.data()) return true;
  }
  return false;
}

// The simulation behind a robot controller's clock: step() first waits for the next
// "measurement", as the FRI backend does.
class WaitingBackend final : public robot::RobotBackend {
 public:
  WaitingBackend(robot::RobotBackend& arm, std::chrono::microseconds wait) : arm_(arm), wait_(wait) {}
  const robot::RobotModel& model() const override { return arm_.model(); }
  double cycleTime() const override { return arm_.cycleTime(); }
  void readState(robot::RobotState& state) const override { arm_.readState(state); }
  robot::CommandStatus writeCommand(const robot::JointImpedanceCommand& command) override { return arm_.writeCommand(command); }
  void step() override {
    std::this_thread::sleep_for(wait_);
    arm_.step();
  }

 private:
  robot::RobotBackend& arm_;
  std::chrono::microseconds wait_;
};

// The GUI reads warnings from the snapshot's fixed buffers: a warning cut there lost its
// advice mid-word ("re-teach the area with the arm cle").
TEST(WorkflowThread, TextTooLongForASnapshotBufferIsCutAfterAWholeWordWithAnEllipsis) {
  std::array<char, 24> buffer{};
  realtime::copyText(buffer, "short text");
  EXPECT_STREQ(buffer.data(), "short text");
  realtime::copyText(buffer, "re-teach the area with the arm clear of it");
  EXPECT_STREQ(buffer.data(), "re-teach the area\u2026");
  // One word longer than the buffer: cut, but never inside a UTF-8 character.
  realtime::copyText(buffer, "\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4");
  EXPECT_STREQ(buffer.data(), "\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u00e4\u2026");
  // Exactly as long as the buffer holds: whole.
  realtime::copyText(buffer, std::string(23, 'x'));
  EXPECT_EQ(std::string(buffer.data()), std::string(23, 'x'));
}

TEST(WorkflowThread, ARobotThatPacesTheLoopIsWaitedForWithoutCountingTheWaitAsComputing) {
  Rig rig;
  // The robot's measurements come every 3 ms: three times the loop's period.
  WaitingBackend robot(rig.sim, std::chrono::microseconds(3000));
  Workflow workflow(robot, rig.parameters, rig.options());
  WorkflowThread::Options options;
  options.backend_paces = true;
  WorkflowThread thread(workflow, nullptr, options);
  thread.start();
  const WorkflowSnapshot snapshot = waitFor(thread, [](const WorkflowSnapshot& s) { return s.cycle >= 40; });
  thread.stop();
  ASSERT_GE(snapshot.cycle, 40U);
  // Computing is what the loop does between measurements, not the 3 ms it waits for them;
  // counted with the wait, every cycle would take 3 ms and miss the 1 ms period. The mean,
  // not the maximum: one preempted cycle on a loaded machine may take longer than the wait.
  EXPECT_LT(snapshot.statistics.mean_compute_us, 1500.0);
  EXPECT_LT(snapshot.statistics.deadline_misses, snapshot.statistics.cycles / 4);
}

TEST(WorkflowThread, ButtonsThroughTheQueueDriveTheStages) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  thread.start();
  const std::uint64_t id = thread.post(WorkflowRequest::press(Button::kStartConfiguration));
  ASSERT_GT(id, 0U);
  WorkflowSnapshot s = handled(thread, id);
  EXPECT_TRUE(s.last_request_accepted);
  EXPECT_EQ(s.stage, Stage::kConfiguration);
  EXPECT_EQ(s.sub_stage, SubStage::kWaiting);
  EXPECT_TRUE(hasEvent(s, "start_configuration"));

  // Keyboard triggers: APPROACHING under π_q, then POSED under π_rec.
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  EXPECT_EQ(s.sub_stage, SubStage::kPosed);
  EXPECT_EQ(s.controller, InteractionController::kCompliantRecording);
  thread.stop();
  EXPECT_EQ(workflow.subStage(), SubStage::kPosed);
}

// The control thread records into an attached session: the state of every cycle, the samples of a
// RECORDING while it runs, the area when it ends; a recorder attached later gets the areas taught.
TEST(WorkflowThread, RecordsEveryCycleAndTheTrainingSamplesIntoAnAttachedSession) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  const auto file = std::filesystem::temp_directory_path() / ("flexirob-thread-" + std::to_string(::getpid()) + ".flexirob");
  const auto later_file = std::filesystem::temp_directory_path() / ("flexirob-thread-later-" + std::to_string(::getpid()) + ".flexirob");
  std::filesystem::remove(file);
  std::filesystem::remove(later_file);
  SessionMetadata metadata;
  metadata.robot_name = "lwr4";
  RecorderOptions recorder_options;
  recorder_options.state_capacity = 1 << 17;  // the unpaced loop runs far faster than 1 kHz
  auto recorder = std::make_unique<SessionRecorder>(file, metadata, recorder_options);
  thread.setRecorder(recorder.get());
  thread.start();
  handled(thread, thread.post(WorkflowRequest::press(Button::kStartConfiguration)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  WorkflowSnapshot s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  ASSERT_EQ(s.sub_stage, SubStage::kRecording);
  const double recording_start = s.time;
  s = waitFor(thread, [recording_start](const WorkflowSnapshot& x) { return x.time > recording_start + 0.5; });
  recorder->flush();
  {
    // Mid-RECORDING, as a kill -9 would leave the file: the samples taken so far are there.
    const RecordedTeaching mid = readRecordedTeaching(SessionReader(file));
    ASSERT_EQ(mid.areas.size(), 1U);
    EXPECT_FALSE(mid.areas[0].complete);
    EXPECT_GE(mid.areas[0].unfinished_X.cols(), 20);  // 0.5 s at one sample per 20 ms
  }
  s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  ASSERT_EQ(s.areas, 1);
  const std::uint64_t cycles_attached = thread.statistics().cycles;  // each of them recorded
  thread.setRecorder(nullptr);

  // A second file attached after the area was taught receives it whole.
  auto later = std::make_unique<SessionRecorder>(later_file, metadata, recorder_options);
  thread.setRecorder(later.get());
  const double attached = thread.snapshot().time;
  waitFor(thread, [attached](const WorkflowSnapshot& x) { return x.time > attached + 0.05; });
  thread.stop();
  thread.setRecorder(nullptr);
  const std::uint64_t cycles_run = thread.statistics().cycles;
  recorder->close();
  later->close();

  ASSERT_EQ(workflow.areas().size(), 1U);
  const TrainingArea& taught = workflow.areas()[0];
  for (const auto& path : {file, later_file}) {
    const SessionReader reader(path);
    const RecordedTeaching teaching = readRecordedTeaching(reader);
    ASSERT_EQ(teaching.areas.size(), 1U) << path;
    EXPECT_TRUE(teaching.areas[0].complete);
    ASSERT_EQ(teaching.areas[0].X.cols(), taught.X.cols()) << path;
    EXPECT_TRUE(teaching.areas[0].X.isApprox(taught.X));
    EXPECT_TRUE(teaching.areas[0].q_fixed.isApprox(taught.q_fixed));
    EXPECT_EQ(teaching.areas[0].unfinished_X.cols(), 0);
  }
  // One state per cycle while attached (none dropped with this ring), in time order.
  const SessionReader reader(file);
  EXPECT_EQ(reader.meta("states_dropped", "0"), "0");
  const auto states = reader.states(0.0, 1e9);
  ASSERT_GT(states.size(), 500U);
  EXPECT_LE(states.size(), cycles_run);
  EXPECT_GE(states.size() + thread.recorderSkips(), cycles_attached);  // attached before the first cycle
  for (std::size_t i = 1; i < states.size(); ++i) ASSERT_GT(states[i].time, states[i - 1].time);
  std::filesystem::remove(file);
  std::filesystem::remove(later_file);
}

// The GUI's sessions are recorded by the control thread: they hold what teach's do besides the
// states and samples (a refusal as a meta line, the teach-in, the replay that follows it, the
// simulated arm's collisions). They had held none of these.
TEST(WorkflowThread, RecordsRefusalsTeachInsReplaysAndCollisionsAsTeachDoes) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  const auto file = std::filesystem::temp_directory_path() / ("flexirob-thread-activity-" + std::to_string(::getpid()) + ".flexirob");
  std::filesystem::remove(file);
  SessionMetadata metadata;
  metadata.robot_name = "lwr4";
  RecorderOptions recorder_options;
  recorder_options.state_capacity = 1 << 17;
  auto recorder = std::make_unique<SessionRecorder>(file, metadata, recorder_options);
  thread.setRecorder(recorder.get());
  thread.start();
  EXPECT_FALSE(handled(thread, thread.post(WorkflowRequest::press(Button::kStartProgramming))).last_request_accepted);
  // One area, learned at finished_configuration.
  handled(thread, thread.post(WorkflowRequest::press(Button::kStartConfiguration)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  WorkflowSnapshot s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  s = waitFor(thread, [t = s.time](const WorkflowSnapshot& x) { return x.time > t + 0.3; });
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  s = handled(thread, thread.post(WorkflowRequest::press(Button::kFinishedConfiguration)));
  s = waitFor(thread, [](const WorkflowSnapshot& x) { return x.model_ready; });
  ASSERT_TRUE(s.model_ready);
  // One teach-in, replayed.
  handled(thread, thread.post(WorkflowRequest::press(Button::kStartProgramming)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnAffected)));
  s = waitFor(thread, [t = s.time](const WorkflowSnapshot& x) { return x.time > t + 0.3; });
  s = handled(thread, thread.post(WorkflowRequest::fire(Trigger::kOnConverged)));
  ASSERT_EQ(s.teach_ins, 1);
  handled(thread, thread.post(WorkflowRequest::press(Button::kFinishedProgramming)));
  s = handled(thread, thread.post(WorkflowRequest::replayTeachIn(0)));
  ASSERT_TRUE(s.last_request_accepted) << s.last_request_reason.data();
  s = waitFor(thread, [t = s.time](const WorkflowSnapshot& x) { return x.execution_done && x.time > t + 0.05; });
  ASSERT_TRUE(s.execution_done);
  // The arm pushed into the table top: a collision of the simulation.
  Eigen::VectorXd into_table = lwr4().midPosture();
  into_table[1] = 2.0;
  thread.stop();
  rig.sim.reset(into_table);
  thread.start();
  waitFor(thread, [](const WorkflowSnapshot& x) { return x.collision_events > 0; });
  const WorkflowSnapshot last = waitFor(thread, [t = thread.snapshot().time](const WorkflowSnapshot& x) { return x.time > t + 0.05; });
  thread.stop();
  thread.setRecorder(nullptr);
  recorder->close();
  ASSERT_GT(last.collision_events, 0U);

  const SessionReader reader(file);
  bool refusal = false;
  for (int i = 0; i < 8; ++i) {
    refusal = refusal || reader.meta("event." + std::to_string(i)).rfind("refused start_programming", 0) == 0;
  }
  EXPECT_TRUE(refusal) << reader.meta("event.0");
  const auto teach_ins = reader.trajectories(TrajectoryKind::TeachIn);
  ASSERT_EQ(teach_ins.size(), 1U);
  EXPECT_TRUE(teach_ins[0].positions.isApprox(workflow.teachIns()[0]));
  const auto executed = reader.trajectories(TrajectoryKind::Executed);
  ASSERT_EQ(executed.size(), 1U);
  EXPECT_EQ(executed[0].reference_id, teach_ins[0].id);
  EXPECT_EQ(executed[0].outcome, "reached");
  EXPECT_GE(executed[0].positions.cols(), 1);  // a teach-in where the arm stood still replays in a few cycles
  const auto collisions = reader.collisions();
  ASSERT_FALSE(collisions.empty());
  EXPECT_EQ(collisions.size(), rig.sim.collisions().eventLog().size());
  std::filesystem::remove(file);
}

TEST(WorkflowThread, RefusedRequestsCarryTheReasonAndChangeNothing) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  thread.start();
  const WorkflowSnapshot s = handled(thread, thread.post(WorkflowRequest::press(Button::kStartProgramming)));
  EXPECT_FALSE(s.last_request_accepted);
  EXPECT_NE(std::string(s.last_request_reason.data()).find("configure"), std::string::npos) << s.last_request_reason.data();
  EXPECT_EQ(s.stage, Stage::kIdle);
  const WorkflowSnapshot p = handled(thread, thread.post(WorkflowRequest::planTo(Eigen::Vector3d(0.4, 0.0, 0.5))));
  EXPECT_FALSE(p.last_request_accepted);
  EXPECT_EQ(p.last_request_kind, WorkflowRequest::Kind::kPlanTo);
  const WorkflowSnapshot h = handled(thread, thread.post(WorkflowRequest::handForce(0, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX())));
  EXPECT_FALSE(h.last_request_accepted);  // the base cannot be pushed
  EXPECT_FALSE(h.hand_active);
  EXPECT_EQ(h.stage, Stage::kIdle);
  EXPECT_EQ(h.areas, 0);
}

TEST(WorkflowThread, SnapshotsAreConsistentWhileTheLoopRuns) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  robot::Kinematics kinematics(lwr4());
  const double t0 = rig.sim.time();
  thread.start();
  // A hand pushes the arm so that q changes every cycle.
  thread.post(WorkflowRequest::press(Button::kStartConfiguration));
  thread.post(WorkflowRequest::fire(Trigger::kOnAffected));
  thread.post(WorkflowRequest::handForce(4, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 15.0, 0.0)));
  std::uint64_t last_cycle = 0;
  int checked = 0;
  Eigen::VectorXd q(lwr4().dof());
  // Until 200 distinct cycles were seen (a slow, sanitized or loaded machine publishes fewer per
  // wall-clock second; a hung loop ends at the bound on reads).
  for (int i = 0; checked <= 200 && i < 2'000'000; ++i) {
    const WorkflowSnapshot& s = thread.snapshot();
    ASSERT_FALSE(s.failed) << s.failure.data();
    ASSERT_GE(s.cycle, last_cycle);
    if (s.cycle > last_cycle && s.cycle > 0) {
      // One cycle's values together: the tip is the kinematics of the published posture and
      // the state of cycle c was measured after c - 1 periods.
      for (int j = 0; j < q.size(); ++j) q[j] = s.q[static_cast<std::size_t>(j)];
      kinematics.update(q);
      const Eigen::Vector3d p(s.p_WT[0], s.p_WT[1], s.p_WT[2]);
      ASSERT_LT((kinematics.p_WT() - p).norm(), 1e-9) << "cycle " << s.cycle;
      ASSERT_NEAR(s.time - t0, static_cast<double>(s.cycle - 1) * 1e-3, 1e-6);
      ++checked;
    }
    last_cycle = s.cycle;
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  thread.stop();
  EXPECT_GT(checked, 200);
}

TEST(WorkflowThread, AHandOnALinkTeachesAnAreaThroughTheTriggers) {
  Rig rig;
  Workflow workflow(rig.sim, rig.parameters, rig.options());
  WorkflowThread thread(workflow, &rig.sim, fast());
  thread.start();
  handled(thread, thread.post(WorkflowRequest::press(Button::kStartConfiguration)));
  // Push link 4 sideways: on_affected, APPROACHING under π_q, the arm moves.
  const Eigen::Vector3d push(0.0, 20.0, 0.0);
  thread.post(WorkflowRequest::handForce(4, Eigen::Vector3d(0.0, 0.0, 0.1), push));
  WorkflowSnapshot s = waitFor(thread, [](const WorkflowSnapshot& x) { return x.sub_stage == SubStage::kApproaching; });
  ASSERT_EQ(s.sub_stage, SubStage::kApproaching) << s.last_request_reason.data();
  EXPECT_EQ(s.controller, InteractionController::kGravityCompensation);
  EXPECT_TRUE(s.hand_active);
  const double touched = s.time;
  s = waitFor(thread, [touched](const WorkflowSnapshot& x) { return x.time > touched + 0.5; });
  // Let go: the arm comes to rest and after 2 s still on_converged poses it.
  thread.post(WorkflowRequest::releaseHand());
  s = waitFor(thread, [](const WorkflowSnapshot& x) { return x.sub_stage == SubStage::kPosed; });
  ASSERT_EQ(s.sub_stage, SubStage::kPosed) << "at t = " << s.time;
  EXPECT_EQ(s.on_affected, 1U);
  EXPECT_EQ(s.on_converged, 1U);
  EXPECT_TRUE(hasEvent(s, "on_converged"));
  EXPECT_GT(s.itm_nodes, 0);  // the approach fed the ITM
  thread.stop();
  EXPECT_EQ(workflow.subStage(), SubStage::kPosed);
}

}  // namespace
}  // namespace flexirob::app
