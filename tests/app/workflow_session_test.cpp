// The session is written while the workflow runs: an area, its samples, the learned model and
// the ITM are in the file as soon as they exist, before the session ends.
#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_teaching.hpp"
#include "app/workflow.hpp"
#include "app/workflow_session.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {
namespace {

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

std::filesystem::path sessionPath(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("flexirob-" + name + "-" + std::to_string(::getpid()) + ".flexirob");
}

// The simulated LWR IV at rest, its workflow, and a session recorded by the writer.
struct RecordedRig {
  explicit RecordedRig(const std::string& name)
      : declarations(robot::reachParameters()), parameters(declarations), sim(lwr4(), nullptr, parameters),
        workflow(rest(sim), parameters, options()), file(sessionPath(name)),
        recorder(file, metadata(), recorderOptions()), writer(recorder, workflow, &sim) {}
  ~RecordedRig() {
    writer.finish();
    recorder.close();
    std::filesystem::remove(file);
  }
  static robot::Simulation& rest(robot::Simulation& sim) {
    Eigen::VectorXd q = lwr4().midPosture();
    q[1] = 0.6;
    q[3] = -1.4;
    sim.reset(q);
    return sim;
  }
  static WorkflowOptions options() {
    WorkflowOptions options;
    options.background_learning = false;
    options.elm.hidden = 30;
    return options;
  }
  static SessionMetadata metadata() {
    SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    return metadata;
  }
  static RecorderOptions recorderOptions() {
    RecorderOptions options;
    options.overwrite = true;
    return options;
  }
  /// Control cycles for `seconds` of simulated time, the state and the writer after each.
  void run(double seconds) {
    for (int i = 0; i < static_cast<int>(seconds / 1e-3); ++i) {
      workflow.step();
      recorder.recordState(workflow.state());
      writer.poll();
    }
  }
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
  robot::Simulation sim;
  Workflow workflow;
  std::filesystem::path file;
  SessionRecorder recorder;
  WorkflowSessionWriter writer;
};

TEST(WorkflowSession, GraphSnapshotsTakeBoundedBytesPerSecondHoweverLargeTheGraphGrows) {
  EXPECT_DOUBLE_EQ(itmSnapshotPeriod(1.0, 2000), 1.0) << "a small graph: every second it changes";
  EXPECT_DOUBLE_EQ(itmSnapshotPeriod(1.0, 1000000), 100.0);
  // A graph growing by 300 bytes a second over an hour, snapshotted as the writer does: the
  // bytes stay within the budget instead of growing with the square of the time.
  double next = 0.0, bytes_total = 0.0;
  const double hour = 3600.0;
  for (double t = 0.0; t < hour; t += 0.5) {
    if (t + 1e-9 < next) continue;
    const auto size = static_cast<std::size_t>(300.0 * t);
    bytes_total += static_cast<double>(size);
    next = t + itmSnapshotPeriod(1.0, size);
  }
  EXPECT_LE(bytes_total, kItmSnapshotBytesPerSecond * hour * 1.05);
  EXPECT_GT(bytes_total, 0.5 * kItmSnapshotBytesPerSecond * hour) << "and still snapshots as often as that allows";
}

TEST(WorkflowSession, AreasSamplesModelAndGraphAreInTheFileBeforeTheSessionEnds) {
  RecordedRig rig("workflow-session");
  Workflow& workflow = rig.workflow;
  SessionRecorder& recorder = rig.recorder;
  const auto& file = rig.file;
  const auto run = [&rig](double seconds) { rig.run(seconds); };

  // One area through the keyboard triggers; the arm rests, so the samples repeat one posture.
  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  workflow.nameNextArea("shelf_top");
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  run(0.2);
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
  run(1.2);
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  run(0.01);
  ASSERT_EQ(workflow.areas().size(), 1U);
  recorder.flush();
  {
    const SessionReader reader(file);
    ASSERT_EQ(reader.areas().size(), 1U);
    EXPECT_TRUE(reader.areas()[0].q_fixed.isApprox(workflow.areas()[0].q_fixed));
    EXPECT_EQ(reader.areas()[0].name, "shelf_top");
    EXPECT_EQ(static_cast<Eigen::Index>(reader.samples(0).size()), workflow.areas()[0].X.cols());
    EXPECT_GE(reader.stages().size(), 4U);
    EXPECT_FALSE(reader.itmSnapshots().empty());  // the ITM after its first second
    EXPECT_TRUE(reader.models().empty());
  }

  ASSERT_TRUE(workflow.press(Button::kFinishedConfiguration));
  run(0.01);
  recorder.flush();
  {
    const SessionReader reader(file);
    ASSERT_EQ(reader.models().size(), 1U);
    EXPECT_EQ(reader.models()[0].learner_kind, "elm");
    EXPECT_FALSE(reader.models()[0].bytes.empty());
    EXPECT_GT(reader.stateCount(), 1000);
  }
  rig.writer.finish();
  recorder.close();
  EXPECT_TRUE(recorder.status().message.empty()) << recorder.status().message;
}

// kill -9 in the middle of a RECORDING: what the file holds then is what was flushed. The samples
// taken so far are there (an unfinished take); once the area ends they are its take; a re-taught
// area's later take replaces the first one.
TEST(WorkflowSession, StreamsTheSamplesOfARecordingAndKeepsTheLatestTakeOfAReTaughtArea) {
  RecordedRig rig("workflow-streaming");
  Workflow& workflow = rig.workflow;
  SessionRecorder& recorder = rig.recorder;
  const auto& file = rig.file;
  const auto run = [&rig](double seconds) { rig.run(seconds); };
  const auto teaching = [&]() {
    recorder.flush();
    return readRecordedTeaching(SessionReader(file));
  };
  const auto record = [&](double seconds, bool finish) {
    ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
    run(0.1);
    ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
    ASSERT_TRUE(workflow.fire(Trigger::kOnAffected));
    run(seconds);
    if (finish) {
      ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
      run(0.01);
    }
  };

  ASSERT_TRUE(workflow.press(Button::kStartConfiguration));
  record(0.5, false);
  ASSERT_EQ(workflow.subStage(), SubStage::kRecording);
  const Eigen::Index so_far = workflow.recordingSamples();
  ASSERT_GE(so_far, 20);
  {
    const RecordedTeaching mid = teaching();
    ASSERT_EQ(mid.areas.size(), 1U);
    EXPECT_FALSE(mid.areas[0].complete);
    EXPECT_EQ(mid.areas[0].X.cols(), 0);
    ASSERT_EQ(mid.areas[0].unfinished_X.cols(), so_far);
    EXPECT_TRUE(mid.areas[0].unfinished_X.isApprox(workflow.recordingX().leftCols(so_far)));
  }
  ASSERT_TRUE(workflow.fire(Trigger::kOnConverged));
  run(0.01);
  ASSERT_EQ(workflow.areas().size(), 1U);
  const Eigen::Index first_take = workflow.areas()[0].X.cols();
  {
    const RecordedTeaching done = teaching();
    ASSERT_EQ(done.areas.size(), 1U);
    EXPECT_TRUE(done.areas[0].complete);
    EXPECT_EQ(done.areas[0].unfinished_X.cols(), 0);
    ASSERT_EQ(done.areas[0].X.cols(), first_take);
    EXPECT_TRUE(done.areas[0].X.isApprox(workflow.areas()[0].X));
    EXPECT_TRUE(done.areas[0].Q.isApprox(workflow.areas()[0].Q));
    EXPECT_TRUE(done.areas[0].q_fixed.isApprox(workflow.areas()[0].q_fixed));
  }

  ASSERT_TRUE(workflow.reteachArea(0));
  record(0.3, true);
  ASSERT_EQ(workflow.areas().size(), 1U);
  const Eigen::Index second_take = workflow.areas()[0].X.cols();
  ASSERT_LT(second_take, first_take);
  {
    const RecordedTeaching retaught = teaching();
    ASSERT_EQ(retaught.areas.size(), 1U);
    EXPECT_TRUE(retaught.areas[0].complete);
    EXPECT_EQ(retaught.areas[0].X.cols(), second_take);
    EXPECT_EQ(retaught.areas[0].unfinished_X.cols(), 0);
    // Every sample is in the file once: both takes.
    EXPECT_EQ(static_cast<Eigen::Index>(SessionReader(file).samples(0).size()), first_take + second_take);
  }
}

}  // namespace
}  // namespace flexirob::app
