// LLM (Eq. 3.14–3.19) and the Thales-circle width rule (Eq. 3.18, Fig. 3.5), and BPDC.
#include <gtest/gtest.h>

#include <cmath>

#include "learning/bpdc.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

using testing::helixAreas;
using testing::sixAreaCentres;
using testing::smoothMap;

constexpr double kDegree = M_PI / 180.0;

// Five centres on an arc of radius 2 spanning 150° (less than a half circle), as in Fig. 3.5:
// for any two non-neighbours, a centre between them on the arc sees their chord under more
// than 90°, so it lies inside their Thales circle; only neighbours qualify. Chords of
// neighbours: 2·2·sin(Δ/2) for Δ = 30°, 40°, 30°, 50°; the largest is 4 sin 25°.
Eigen::MatrixXd arcLayout() {
  const double angles[] = {0.0, 30.0, 70.0, 100.0, 150.0};
  Eigen::MatrixXd centres(2, 5);
  for (int k = 0; k < 5; ++k) centres.col(k) << 2.0 * std::cos(angles[k] * kDegree), 2.0 * std::sin(angles[k] * kDegree);
  return centres;
}

TEST(ThalesWidth, IsTheLargestEmptyThalesCircleOfAHandMadeLayout) {
  EXPECT_NEAR(thalesWidth(arcLayout()), 4.0 * std::sin(25.0 * kDegree), 1e-12);
}

TEST(ThalesWidth, ExcludesPairsWithAnotherCentreInsideTheirCircle) {
  // Collinear centres at 0, 1, 3: the pair (0, 3) holds centre 1 inside its circle.
  Eigen::MatrixXd line(2, 3);
  line << 0.0, 1.0, 3.0, 0.0, 0.0, 0.0;
  EXPECT_NEAR(thalesWidth(line), 2.0, 1e-12);
  // A centre exactly on the circle does not exclude the pair ((c_i − c_k)ᵀ(c_j − c_k) = 0).
  Eigen::MatrixXd right_angle(2, 3);
  right_angle << 0.0, 2.0, 1.0, 0.0, 0.0, 1.0;
  EXPECT_NEAR(thalesWidth(right_angle), 2.0, 1e-12);
  // Adding a centre inside the largest circle of the arc layout shrinks d.
  Eigen::MatrixXd arc = arcLayout();
  Eigen::MatrixXd more(2, 6);
  more << arc, 0.5 * (arc.col(3) + arc.col(4));
  EXPECT_LT(thalesWidth(more), thalesWidth(arc) - 0.1);
  EXPECT_THROW(thalesWidth(Eigen::MatrixXd::Zero(2, 1)), std::invalid_argument);
}

TEST(Llm, UsesTheThalesWidthOfTheAreasFirstSamples) {
  // The arc layout in metres, at z = 0.4, as the first samples of five areas.
  const Eigen::MatrixXd arc = arcLayout() * 0.2;
  std::vector<Eigen::Vector3d> centres;
  for (int k = 0; k < 5; ++k) centres.emplace_back(arc(0, k) - 0.5, arc(1, k) - 0.2, 0.4);
  const TrainingSet data = helixAreas(centres, 5, 7, 0.01);
  LlmParams params;
  params.max_epochs = 5;
  Llm llm(3, 7, params);
  llm.fit(data);
  ASSERT_EQ(llm.models(), 5);
  // d is kept in normalized units; positions share one scale.
  EXPECT_NEAR(llm.width() * llm.normalization().scale[0], 0.2 * 4.0 * std::sin(25.0 * kDegree), 1e-12);
}

TEST(Llm, StartsEachModelAtTheAreasFirstSample) {
  // c_k = x_init, b_k = y_init, W_k = 0: with a vanishing learning rate one epoch leaves the
  // initial models in place, and the areas' first samples are not their first rows in the data.
  TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  std::swap(data.area[0], data.area[4]);  // the first sample now belongs to area 1
  LlmParams params;
  params.eta = 1e-300;
  params.max_epochs = 1;
  Llm llm(3, 7, params);
  llm.fit(data);
  ASSERT_EQ(llm.models(), 6);
  const std::vector<Eigen::Index> first_samples = {0, 1, 8, 12, 16, 20};  // areas 1, 0, 2, 3, 4, 5
  for (int k = 0; k < 6; ++k) {
    const Eigen::Index l = first_samples[static_cast<std::size_t>(k)];
    EXPECT_TRUE(llm.centres().col(k).isApprox(llm.normalization().apply(data.X.col(l)), 1e-12)) << k;
    EXPECT_TRUE(llm.biases().col(k).isApprox(data.Y.col(l), 1e-12)) << k;
  }
}

TEST(Llm, ReproducesSmoothMapFromFewerThanFiveSamplesPerArea) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  Llm llm(3, 7);
  llm.fit(data);
  EXPECT_LT(testing::rmsJointError(llm, data.X, 7), 0.03);
  const auto c = sixAreaCentres();
  Eigen::MatrixXd between(3, 4);
  between << 0.5 * (c[0] + c[1]), 0.5 * (c[2] + c[3]), 0.5 * (c[0] + c[2]), 0.5 * (c[4] + c[5]);
  EXPECT_LT(testing::rmsJointError(llm, between, 7), 0.05);
}

TEST(Llm, StopsByItsRuleBeforeTheEpochLimitAndLowersTheError) {
  const TrainingSet data = helixAreas({{-0.75, -0.35, 0.35}, {-0.25, 0.35, 0.55}}, 60, 7);
  LlmParams params;
  params.max_epochs = 1;
  Llm one_epoch(3, 7, params);
  one_epoch.fit(data);
  params.max_epochs = 100000;
  Llm converged(3, 7, params);
  converged.fit(data);
  EXPECT_LT(converged.epochs(), params.max_epochs);
  EXPECT_LT(converged.meanSquaredError(data), 0.5 * one_epoch.meanSquaredError(data));
}

// Six areas on a line, 0.2 m apart, so d is the spacing whichever end area is removed.
std::vector<Eigen::Vector3d> lineCentres(int first, int last) {
  std::vector<Eigen::Vector3d> centres;
  for (int k = first; k <= last; ++k) centres.emplace_back(-0.5, -0.5 + 0.2 * k, 0.4);
  return centres;
}

double changeAt(const Learner& a, const Learner& b, const Eigen::Vector3d& x) { return (a.predict(x) - b.predict(x)).norm(); }

TEST(Llm, ReplacingOneAreaChangesTheMapOnlyLocally) {
  const TrainingSet original = helixAreas(lineCentres(0, 5), 20, 7, 0.03);
  TrainingSet replaced = original;
  // Area 0 re-taught with another posture (all joints +0.8 rad).
  for (Eigen::Index l = 0; l < replaced.size(); ++l) {
    if (replaced.area[static_cast<std::size_t>(l)] == 0) replaced.Y.col(l).array() += 0.8;
  }
  // The same number of epochs in the same sample order for both, so that any difference
  // comes from the replaced area and not from where the stopping rule happened to stop.
  LlmParams params;
  params.max_epochs = 300;
  params.tolerance = 0.0;
  params.patience = 1000;
  Llm before(3, 7, params), after(3, 7, params);
  before.fit(original);
  after.fit(replaced);
  const auto c = lineCentres(0, 5);
  const double near = changeAt(before, after, c[0]);
  EXPECT_GT(near, 0.5 * 0.8 * std::sqrt(7.0));
  // Three and more areas away the map moves by less than 1 % of the change at the area
  // (what remains travels along the chain of neighbouring models that compensate each other).
  for (int k = 3; k <= 5; ++k) EXPECT_LT(changeAt(before, after, c[static_cast<std::size_t>(k)]), 0.01 * near) << k;
  // A global learner on the same data moves everywhere: the contrast that makes this local.
  Elm global_before(3, 7), global_after(3, 7);
  global_before.fit(original);
  global_after.fit(replaced);
  EXPECT_GT(changeAt(global_before, global_after, c[3]), 0.02 * changeAt(global_before, global_after, c[0]));
}

TEST(Llm, RemovingOneAreaChangesTheMapOnlyLocally) {
  const TrainingSet all = helixAreas(lineCentres(0, 5), 20, 7, 0.03);
  const TrainingSet without_first = helixAreas(lineCentres(1, 5), 20, 7, 0.03);
  LlmParams params;
  params.max_epochs = 300;
  params.tolerance = 0.0;
  params.patience = 1000;
  Llm before(3, 7, params), after(3, 7, params);
  before.fit(all);
  after.fit(without_first);
  // Same width in metres (the normalization differs because the data's box changed).
  EXPECT_NEAR(before.width() * before.normalization().scale[0], after.width() * after.normalization().scale[0], 1e-9);
  const auto c = lineCentres(0, 5);
  const Eigen::Vector3d beyond_removed = c[0] + Eigen::Vector3d(0.0, -0.2, 0.0);
  const double near = changeAt(before, after, beyond_removed);
  EXPECT_GT(near, 1e-2);
  EXPECT_LT(changeAt(before, after, c[4]), 0.01 * near);
  EXPECT_LT(changeAt(before, after, c[5]), 0.01 * near);
}

TEST(Llm, PredictionsStayFiniteFarFromEveryCentre) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  Llm llm(3, 7);
  llm.fit(data);
  for (const double value : {10.0, -1e6, 1e300, -1.7e308}) {
    EXPECT_TRUE(llm.predict(Eigen::Vector3d(value, 0.3, -value)).allFinite()) << value;
  }
  EXPECT_THROW(llm.predict(Eigen::Vector3d(INFINITY, 0, 0)), std::invalid_argument);
}

TEST(Llm, FitHonoursCancellation) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  CancellationToken token;
  token.cancel();
  Llm llm(3, 7);
  EXPECT_THROW(llm.fit(data, token), TrainingCancelled);
}

// What a progress line shows: every epoch in order, with the training MSE of the weights it
// left (the last one is the fitted map's own error, computed here by prediction).
TEST(Llm, TellsItsObserverEachEpochAndTheTrainingErrorAfterIt) {
  const TrainingSet data = helixAreas({{-0.75, -0.35, 0.35}, {-0.25, 0.35, 0.55}}, 30, 7);
  std::vector<std::pair<int, double>> told;
  LlmParams params;
  params.max_epochs = 40;
  params.on_epoch = [&told](int epochs, double mse) { told.emplace_back(epochs, mse); };
  Llm llm(3, 7, params);
  llm.fit(data);
  ASSERT_EQ(static_cast<int>(told.size()), llm.epochs());
  ASSERT_GT(llm.epochs(), 1);
  for (std::size_t i = 0; i < told.size(); ++i) EXPECT_EQ(told[i].first, static_cast<int>(i) + 1);
  EXPECT_NEAR(told.back().second, llm.meanSquaredError(data), 1e-12 * (1.0 + told.back().second));
}

TEST(Bpdc, LearnsASmoothMapAsProofOfConcept) {
  const TrainingSet data = helixAreas({{-0.75, -0.35, 0.35}, {-0.25, 0.35, 0.55}}, 30, 7);
  BpdcParams params;
  params.max_epochs = 150;
  Bpdc net(3, 7, params);
  net.fit(data);
  ASSERT_FALSE(net.history().empty());
  // Error of the best constant predictor (the mean posture).
  const Eigen::VectorXd mean = data.Y.rowwise().mean();
  const double variance = (data.Y.colwise() - mean).colwise().squaredNorm().mean();
  const double final_mse = net.meanSquaredError(data);
  EXPECT_LT(final_mse, 0.05 * variance);
  EXPECT_LT(final_mse, 0.2 * net.history().front());
  EXPECT_TRUE(net.predict(Eigen::Vector3d(1e9, -1e9, 0.0)).allFinite());
}

TEST(Bpdc, TellsItsObserverEachEpochWithTheErrorItRecords) {
  const TrainingSet data = helixAreas({{-0.75, -0.35, 0.35}, {-0.25, 0.35, 0.55}}, 10, 7);
  std::vector<double> told;
  BpdcParams params;
  params.max_epochs = 5;
  params.on_epoch = [&told](int epochs, double mse) {
    EXPECT_EQ(epochs, static_cast<int>(told.size()) + 1);
    told.push_back(mse);
  };
  Bpdc net(3, 7, params);
  net.fit(data);
  EXPECT_EQ(told, net.history());
}

}  // namespace
}  // namespace flexirob::learning
