// A recorded session as the offline tools' files (app/session_export.hpp): the positions the
// configuration stage fed the ITM, replayed from the states with the workflow's sampling rule,
// and the training samples as the CSV learn fit reads.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "app/session_export.hpp"
#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_teaching.hpp"
#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

class SessionExport : public ::testing::Test {
 protected:
  void SetUp() override {
    file_ = fs::temp_directory_path() / ("flexirob-export-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".flexirob");
    fs::remove(file_);
    SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.scene_name = "empty";
    recorder_ = std::make_unique<SessionRecorder>(file_, metadata);
  }
  void TearDown() override {
    recorder_.reset();
    fs::remove(file_);
  }
  // States every millisecond from 1 ms to `end`; the tip's x is the state's time, so that a
  // position names the state it came from.
  void statesUntil(double end, int dof, const std::function<Eigen::VectorXd(double)>& posture) {
    for (int k = 1; k * 1e-3 <= end + 1e-12; ++k) {
      StateRecord state;
      state.time = k * 1e-3;
      state.dof = dof;
      const Eigen::VectorXd q = posture(state.time);
      for (int j = 0; j < dof; ++j) state.q[static_cast<std::size_t>(j)] = q[j];
      state.p_WT = {state.time, 0.0, 0.5};
      ASSERT_TRUE(recorder_->recordState(state));
    }
  }
  SessionReader read() {
    recorder_->flush();
    return SessionReader(file_);
  }
  fs::path file_;
  std::unique_ptr<SessionRecorder> recorder_;
};

std::vector<double> expectedTimes(std::initializer_list<std::pair<double, int>> runs) {
  std::vector<double> times;
  for (const auto& [first, count] : runs) {
    for (int k = 0; k < count; ++k) times.push_back(first + 0.02 * k);
  }
  return times;
}

TEST_F(SessionExport, TheStreamTakesAPositionEverySamplePeriodOfTheConfigurationStageAsTheWorkflowDoes) {
  statesUntil(1.0, 3, [](double) { return Eigen::VectorXd::Constant(3, 0.2); });
  // The workflow stamps its records with the time of a state: the same doubles.
  const auto at = [](int millisecond) { return millisecond * 1e-3; };
  // A button acts between cycles: CONFIGURATION holds from the state after 0.1 s. A trigger fires
  // at its state: the RECORDING begins with the state at 0.3 s and restarts the period there.
  ASSERT_TRUE(recorder_->recordButton(at(100), "start_configuration"));
  ASSERT_TRUE(recorder_->recordStage({at(100), "CONFIGURATION", "APPROACHING"}));
  ASSERT_TRUE(recorder_->recordTrigger(at(300), "on_affected"));
  ASSERT_TRUE(recorder_->recordStage({at(300), "CONFIGURATION", "RECORDING"}));
  ASSERT_TRUE(recorder_->recordTrigger(at(500), "on_converged"));
  ASSERT_TRUE(recorder_->recordStage({at(500), "CONFIGURATION", "APPROACHING"}));
  ASSERT_TRUE(recorder_->recordButton(at(700), "finished_configuration"));
  ASSERT_TRUE(recorder_->recordStage({at(700), "IDLE", ""}));
  // PROGRAMMING takes positions for its own recordings, never for the ITM.
  ASSERT_TRUE(recorder_->recordStage({at(800), "PROGRAMMING", "APPROACHING"}));
  const SessionReader reader = read();

  const ConfigurationStream stream = configurationStream(reader, 0.02, nullptr);
  // 0.101 … 0.281 s before the RECORDING, 0.300 … 0.700 s from its start on (the state at 0.7 s
  // was taken before the button ended the stage).
  const std::vector<double> expected = expectedTimes({{0.101, 10}, {0.300, 21}});
  ASSERT_EQ(stream.times.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_NEAR(stream.times[k], expected[k], 1e-9) << k;
    EXPECT_NEAR(stream.X(0, static_cast<Eigen::Index>(k)), expected[k], 1e-9) << k;
  }
  EXPECT_EQ(stream.Q.rows(), 3);
  EXPECT_EQ(stream.states_read, 1000);
  EXPECT_EQ(stream.left_out_in_contact, 0);

  // The CSV: a header itm build reads, one row per position, read back to the last digit.
  const std::string csv = configurationStreamCsv(stream);
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "x,y,z,q1,q2,q3");
  int rows = 0;
  while (std::getline(lines, line)) {
    EXPECT_EQ(std::stod(line.substr(0, line.find(','))), stream.X(0, rows)) << line;
    ++rows;
  }
  EXPECT_EQ(rows, static_cast<int>(expected.size()));
}

TEST_F(SessionExport, PositionsWhereTheArmTouchesAnObstacleAreLeftOutOfTheStream) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"), "");
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "box";
  box.shape = robot::Obstacle::Shape::kBox;
  box.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  box.X_WO.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);  // the stretched arm reaches 1.18 m up
  scene.obstacles.push_back(box);
  robot::CollisionWorld world(model, scene);
  const Eigen::VectorXd stretched = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd bent = Eigen::VectorXd::Zero(7);
  bent[1] = 1.0;  // leaning 57 degrees: the tip 0.8 m up, 0.7 m out
  world.update(stretched);
  ASSERT_FALSE(world.contacts().empty());
  world.update(bent);
  ASSERT_TRUE(world.contacts().empty()) << world.bodyName(world.contacts().front().body) << " touches "
                                        << world.otherName(world.contacts().front());

  // Stretched into the box during the second half of the stage.
  statesUntil(0.4, 7, [&](double t) { return t > 0.2 ? stretched : bent; });
  ASSERT_TRUE(recorder_->recordButton(0.0, "start_configuration"));
  ASSERT_TRUE(recorder_->recordStage({0.0, "CONFIGURATION", "APPROACHING"}));
  const SessionReader reader = read();

  const ConfigurationStream stream = configurationStream(reader, 0.02, &world);
  // Taken at 0.001, 0.021, … 0.381 s: 10 before 0.2 s are free, 10 after it in the box.
  EXPECT_EQ(stream.times.size(), 10u);
  EXPECT_EQ(stream.left_out_in_contact, 10);
  for (const double t : stream.times) EXPECT_LT(t, 0.2);
  const ConfigurationStream unchecked = configurationStream(reader, 0.02, nullptr);
  EXPECT_EQ(unchecked.times.size(), 20u);
}

TEST_F(SessionExport, TheSamplesCsvHoldsTheCompleteAreasLatestTakesWithTheirSessionIndices) {
  const auto sample = [&](double t, int area, double value) {
    ASSERT_TRUE(recorder_->recordSample({t, area, Eigen::Vector3d(value, 0.25, 0.5), Eigen::VectorXd::Constant(2, value / 3.0)}));
  };
  sample(1.0, 0, 0.1);
  sample(1.1, 0, 0.2);
  ASSERT_TRUE(recorder_->recordArea({0, 1.2, Eigen::Vector3d(0.1, 0.25, 0.5), Eigen::VectorXd::Constant(2, 0.0), "front"}));
  sample(2.0, 1, 0.7);
  ASSERT_TRUE(recorder_->recordArea({1, 2.1, Eigen::Vector3d(0.7, 0.25, 0.5), Eigen::VectorXd::Constant(2, 0.0), ""}));
  sample(3.0, 2, 0.9);  // a RECORDING the session ended in: not learned from, not exported
  const SessionReader reader = read();
  const std::string csv = trainingSamplesCsv(readRecordedTeaching(reader, false));
  EXPECT_EQ(csv,
            "area,x,y,z,q1,q2\n"
            "0,0.10000000000000001,0.25,0.5,0.033333333333333333,0.033333333333333333\n"
            "0,0.20000000000000001,0.25,0.5,0.066666666666666666,0.066666666666666666\n"
            "1,0.69999999999999996,0.25,0.5,0.23333333333333331,0.23333333333333331\n");
}

// A damaged file's times: the replay goes through the states in the order they were recorded
// and ends, however far apart or out of order their times are (it had stepped through time in
// 10 s windows: 1e300 never ended, -1e9 took 1e8 queries).
TEST_F(SessionExport, AbsurdStateTimesDoNotStopTheReplayFromEnding) {
  for (const double t : {0.0, 1e300, -1e9, 0.02, 0.04}) {
    StateRecord state;
    state.time = t;
    state.dof = 2;
    state.p_WT = {0.1, 0.2, 0.3};
    ASSERT_TRUE(recorder_->recordState(state));
  }
  ASSERT_TRUE(recorder_->recordStage({0.0, "CONFIGURATION", "WAITING"}));
  const SessionReader reader = read();
  const ConfigurationStream stream = configurationStream(reader, 0.02, nullptr);
  EXPECT_EQ(stream.states_read, 5);
  // 0 (the first state, after the start button), 1e300; then nothing until 1e300 + 0.02.
  ASSERT_EQ(stream.times.size(), 2u);
  EXPECT_EQ(stream.times[0], 0.0);
  EXPECT_EQ(stream.times[1], 1e300);
}

TEST_F(SessionExport, ASessionWithoutACompleteAreaHasNoSamplesToExport) {
  ASSERT_TRUE(recorder_->recordSample({1.0, 0, Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::VectorXd::Constant(2, 0.1)}));
  const SessionReader reader = read();
  EXPECT_THROW(trainingSamplesCsv(readRecordedTeaching(reader, false)), InputError);
  EXPECT_THROW(configurationStream(reader, 0.0, nullptr), InputError);
}

}  // namespace
}  // namespace flexirob::app
