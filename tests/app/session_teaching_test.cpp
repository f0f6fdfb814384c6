// Which samples belong to which area when a recording is read back (app/session_teaching.hpp):
// takes bounded by the area records, an unfinished RECORDING kept apart, damaged input refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_teaching.hpp"
#include "planning/itm.hpp"
#include "planning/itm_file.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

class SessionTeaching : public ::testing::Test {
 protected:
  void SetUp() override {
    file_ = fs::temp_directory_path() / ("flexirob-teaching-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".flexirob");
    fs::remove(file_);
    SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.tip_link = "lwr_link_7";
    metadata.scene_name = "setup_I";
    recorder_ = std::make_unique<SessionRecorder>(file_, metadata);
  }
  void TearDown() override {
    recorder_.reset();
    fs::remove(file_);
  }
  // A sample whose position encodes its area and its number, so that the test can tell them apart.
  void sample(double t, int area, int number, int dof = 3) {
    ASSERT_TRUE(recorder_->recordSample({t, area, Eigen::Vector3d(area, number, t), Eigen::VectorXd::Constant(dof, 0.1 * number)}));
  }
  void area(double t, int index, double posture) {
    ASSERT_TRUE(recorder_->recordArea({index, t, Eigen::Vector3d(index, 0, 0), Eigen::VectorXd::Constant(3, posture), ""}));
  }
  RecordedTeaching read() {
    recorder_->flush();
    return readRecordedTeaching(SessionReader(file_));
  }
  fs::path file_;
  std::unique_ptr<SessionRecorder> recorder_;
};

TEST_F(SessionTeaching, EachAreaKeepsItsLatestTakeAndAnUnfinishedRecordingStaysApart) {
  for (int l = 0; l < 5; ++l) sample(1.0 + 0.1 * l, 0, l);       // area 0, first take
  area(1.5, 0, 0.3);
  for (int l = 0; l < 4; ++l) sample(2.0 + 0.1 * l, 1, l);       // area 1
  area(2.4, 1, 0.4);
  for (int l = 0; l < 3; ++l) sample(3.0 + 0.1 * l, 0, 10 + l);  // area 0 re-taught
  area(3.3, 0, 0.5);
  for (int l = 0; l < 2; ++l) sample(4.0 + 0.1 * l, 2, l);       // area 2: the session ends here
  const RecordedTeaching teaching = read();
  EXPECT_EQ(teaching.robot, "lwr4");
  EXPECT_EQ(teaching.tip, "lwr_link_7");
  EXPECT_EQ(teaching.scene, "setup_I");
  ASSERT_EQ(teaching.areas.size(), 3U);

  const RecordedArea& retaught = teaching.areas[0];
  EXPECT_EQ(retaught.index, 0);
  EXPECT_TRUE(retaught.complete);
  EXPECT_DOUBLE_EQ(retaught.time, 3.3);
  EXPECT_DOUBLE_EQ(retaught.q_fixed[0], 0.5);
  ASSERT_EQ(retaught.X.cols(), 3);
  for (Eigen::Index l = 0; l < 3; ++l) EXPECT_DOUBLE_EQ(retaught.X(1, l), 10.0 + static_cast<double>(l));
  EXPECT_EQ(retaught.Q.rows(), 3);
  EXPECT_EQ(retaught.unfinished_X.cols(), 0);

  EXPECT_TRUE(teaching.areas[1].complete);
  EXPECT_EQ(teaching.areas[1].X.cols(), 4);
  EXPECT_DOUBLE_EQ(teaching.areas[1].q_fixed[0], 0.4);

  const RecordedArea& unfinished = teaching.areas[2];
  EXPECT_EQ(unfinished.index, 2);
  EXPECT_FALSE(unfinished.complete);
  EXPECT_EQ(unfinished.X.cols(), 0);
  EXPECT_EQ(unfinished.q_fixed.size(), 0);
  EXPECT_EQ(unfinished.unfinished_X.cols(), 2);
  EXPECT_FALSE(teaching.itm.has_value());
}

// Recordings written before samples were streamed stamp every sample with its area's time.
TEST_F(SessionTeaching, SamplesStampedWithTheirAreasTimeBelongToThatTake) {
  for (int l = 0; l < 4; ++l) sample(2.0, 0, l);
  area(2.0, 0, 0.2);
  for (int l = 0; l < 6; ++l) sample(5.0, 0, 20 + l);
  area(5.0, 0, 0.6);
  const RecordedTeaching teaching = read();
  ASSERT_EQ(teaching.areas.size(), 1U);
  ASSERT_EQ(teaching.areas[0].X.cols(), 6);
  EXPECT_DOUBLE_EQ(teaching.areas[0].X(1, 0), 20.0);
}

// The workflow renumbers the areas above a removed one; the replay does the same, so a later
// area that takes a freed index is not mistaken for a re-take of another.
TEST_F(SessionTeaching, ARemovedAreaShiftsTheLaterIndicesDownAsTheWorkflowDoes) {
  for (int l = 0; l < 2; ++l) sample(1.0 + 0.01 * l, 0, l);
  area(1.1, 0, 0.1);
  for (int l = 0; l < 3; ++l) sample(2.0 + 0.01 * l, 1, l);
  area(2.1, 1, 0.2);
  for (int l = 0; l < 4; ++l) sample(3.0 + 0.01 * l, 2, l);
  area(3.1, 2, 0.3);
  ASSERT_TRUE(recorder_->recordButton(4.0, "remove_area 1"));  // old area 2 is area 1 from now on
  for (int l = 0; l < 5; ++l) sample(5.0 + 0.01 * l, 2, l);     // the next area: index 2 again
  area(5.1, 2, 0.4);
  const RecordedTeaching teaching = read();
  ASSERT_EQ(teaching.areas.size(), 3U);
  EXPECT_EQ(teaching.areas[0].X.cols(), 2);
  EXPECT_DOUBLE_EQ(teaching.areas[0].q_fixed[0], 0.1);
  EXPECT_EQ(teaching.areas[1].X.cols(), 4);
  EXPECT_DOUBLE_EQ(teaching.areas[1].q_fixed[0], 0.3);
  EXPECT_EQ(teaching.areas[2].X.cols(), 5);
  EXPECT_DOUBLE_EQ(teaching.areas[2].q_fixed[0], 0.4);
  for (const RecordedArea& area : teaching.areas) EXPECT_TRUE(area.complete);
  // The same records seen at 3.5 s: three areas, none removed yet.
  SessionReader reader(file_);
  const auto earlier = replayTeaching(reader.areas(), reader.samples(), reader.signals(), 3.5);
  ASSERT_EQ(earlier.size(), 3U);
  EXPECT_EQ(earlier[1].X.cols(), 3);
}

TEST_F(SessionTeaching, ReadsTheLastItmSnapshot) {
  planning::Itm graph(planning::ItmParameters{}, 3);
  graph.insert(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::VectorXd::Zero(3));
  graph.insert(Eigen::Vector3d(0.3, 0.0, 0.5), Eigen::VectorXd::Constant(3, 0.1));
  ItmRecord record;
  record.time = 1.0;
  record.nodes = graph.nodeCount();
  record.edges = graph.edgeCount();
  record.bytes = planning::itmToBytes(graph);
  ASSERT_TRUE(recorder_->recordItm(record));
  const RecordedTeaching teaching = read();
  ASSERT_TRUE(teaching.itm.has_value());
  EXPECT_EQ(teaching.itm->nodeCount(), graph.nodeCount());
  EXPECT_EQ(teaching.itm->edgeCount(), graph.edgeCount());
}

TEST_F(SessionTeaching, RefusesSamplesWithPosturesOfDifferentSizes) {
  sample(1.0, 0, 0, 3);
  sample(1.1, 0, 1, 4);
  EXPECT_THROW(read(), InputError);
}

TEST_F(SessionTeaching, RefusesANonFiniteSample) {
  ASSERT_TRUE(recorder_->recordSample({1.0, 0, Eigen::Vector3d(0.0, std::nan(""), 0.0), Eigen::VectorXd::Zero(3)}));
  EXPECT_THROW(read(), InputError);
}

TEST_F(SessionTeaching, RefusesADamagedGraphSnapshot) {
  planning::Itm graph(planning::ItmParameters{}, 3);
  graph.insert(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::VectorXd::Zero(3));
  ItmRecord record;
  record.time = 1.0;
  record.bytes = planning::itmToBytes(graph);
  record.bytes[record.bytes.size() / 2] ^= 0x5a;  // the checksum no longer matches
  ASSERT_TRUE(recorder_->recordItm(record));
  try {
    (void)read();
    FAIL() << "a damaged graph was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ITM"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flexirob::app
