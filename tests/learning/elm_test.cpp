// ELM (Eq. 3.9–3.13) and OS-ELM (Eq. 6.3–6.5).
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>

#include "learning/elm.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

using testing::helixAreas;
using testing::sixAreaCentres;
using testing::smoothMap;

// Independent ridge solution: min ‖Hᵀ Wᵀ − Yᵀ‖² + ε‖W‖² is the ordinary least-squares problem
// of the stacked system [Hᵀ; √ε I] Wᵀ = [Yᵀ; 0], solved by a column-pivoting QR.
Eigen::MatrixXd ridgeByQr(const Eigen::MatrixXd& H, const Eigen::MatrixXd& Y, double epsilon) {
  const Eigen::Index R = H.rows(), L = H.cols();
  Eigen::MatrixXd A(L + R, R);
  A << H.transpose(), std::sqrt(epsilon) * Eigen::MatrixXd::Identity(R, R);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(L + R, Y.rows());
  B.topRows(L) = Y.transpose();
  return A.colPivHouseholderQr().solve(B).transpose();
}

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

TEST(Elm, ReadoutEqualsIndependentLeastSquaresWithMoreSamplesThanNeurons) {
  ElmParams params;
  params.hidden = 40;
  const TrainingSet data = helixAreas(sixAreaCentres(), 20, 7);  // 120 samples > 40 neurons
  Elm elm(3, 7, params);
  elm.fit(data);
  const Eigen::MatrixXd H = elm.features().computeColumns(data.X);
  EXPECT_LT(relativeDifference(elm.outputWeights(), ridgeByQr(H, data.Y, params.epsilon)), 1e-9);
}

TEST(Elm, ReadoutEqualsIndependentLeastSquaresWithFewerSamplesThanNeurons) {
  ElmParams params;
  params.hidden = 150;
  params.epsilon = 1e-3;
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 9);  // 24 samples < 150 neurons
  Elm elm(3, 9, params);
  elm.fit(data);
  const Eigen::MatrixXd H = elm.features().computeColumns(data.X);
  EXPECT_LT(relativeDifference(elm.outputWeights(), ridgeByQr(H, data.Y, params.epsilon)), 1e-8);
}

TEST(Elm, HiddenLayerIsTheDocumentedLogisticOfRandomProjection) {
  ElmParams params;
  params.hidden = 5;
  const InputNormalization normalization = InputNormalization::identity(3);
  const RandomFeatures features(3, params, normalization);
  // Re-draw the documented sequence: W_in row by row, then all gains, then all biases.
  UniformRandom random(params.seed);
  Eigen::MatrixXd W_in(5, 3);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 3; ++j) W_in(i, j) = random.uniform(-params.input_weight_range, params.input_weight_range);
  Eigen::VectorXd a(5), b(5);
  for (int i = 0; i < 5; ++i) a[i] = random.uniform(params.gain_min, params.gain_max);
  for (int i = 0; i < 5; ++i) b[i] = random.uniform(-params.bias_range, params.bias_range);
  const Eigen::Vector3d x(0.3, -0.2, 0.7);
  Eigen::VectorXd h(5);
  features.compute(x, h);
  for (int i = 0; i < 5; ++i) {
    const double s = W_in.row(i).dot(x);
    EXPECT_NEAR(h[i], 1.0 / (1.0 + std::exp(-a[i] * s - b[i])), 1e-15);
  }
}

TEST(Elm, SameSeedGivesSameModelAndOtherSeedDiffers) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 10, 7);
  ElmParams params;
  Elm first(3, 7, params), second(3, 7, params);
  first.fit(data);
  second.fit(data);
  EXPECT_EQ(first.outputWeights(), second.outputWeights());
  params.seed = 2;
  Elm other(3, 7, params);
  other.fit(data);
  EXPECT_GT((other.outputWeights() - first.outputWeights()).norm(), 1e-3);
}

TEST(Elm, ModelWithTheLargestSeedRoundTrips) {
  ElmParams params;
  params.seed = std::numeric_limits<std::uint64_t>::max();
  Elm elm(3, 7, params);
  elm.fit(helixAreas(sixAreaCentres(), 4, 7));
  ModelWriter writer("elm");
  elm.write(writer);
  const Elm loaded = Elm::read(ModelReader(writer.text(), "seed"));
  EXPECT_EQ(loaded.params().seed, params.seed);
  EXPECT_EQ(loaded.outputWeights(), elm.outputWeights());
}

TEST(OsElm, EqualsBatchRidgeElmWithSameFeaturesAfterSameSamples) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 50, 7);  // 300 samples
  const InputNormalization normalization = InputNormalization::fromData(data.X);
  ElmParams params;
  OsElm online(3, 7, normalization, params);
  // Learns from the very first sample: W_0 = 0, P_0 = (εI)⁻¹.
  EXPECT_FALSE(online.trained());
  for (Eigen::Index l = 0; l < data.size(); ++l) {
    online.update(data.X.col(l), data.Y.col(l));
    if (l == 0) {
      // After one sample, W_1 = y hᵀ / (ε + hᵀh) in closed form.
      Eigen::VectorXd h(params.hidden);
      online.features().compute(data.X.col(0), h);
      const Eigen::MatrixXd expected = data.Y.col(0) * h.transpose() / (params.epsilon + h.squaredNorm());
      EXPECT_LT(relativeDifference(online.outputWeights(), expected), 1e-12);
    }
  }
  Elm batch(3, 7, params);
  batch.fit(data, normalization);
  EXPECT_LT(relativeDifference(online.outputWeights(), batch.outputWeights()), 1e-6);
  const Eigen::Vector3d between(-0.5, 0.0, 0.45);
  EXPECT_LT((online.predict(between) - batch.predict(between)).norm() / batch.predict(between).norm(), 1e-6);
}

TEST(OsElm, BatchFitEqualsElmFitOnTheSameData) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 30, 9);
  ElmParams params;
  OsElm online(3, 9, InputNormalization::identity(3), params);
  online.fit(data);
  Elm batch(3, 9, params);
  batch.fit(data);
  EXPECT_EQ(online.samples(), data.size());
  EXPECT_LT(relativeDifference(online.outputWeights(), batch.outputWeights()), 1e-6);
}

TEST(Elm, ReproducesSmoothMapAtAndBetweenSixAreas) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 40, 7);
  Elm elm(3, 7);
  elm.fit(data);
  // At the areas: the training inputs themselves.
  EXPECT_LT(testing::rmsJointError(elm, data.X, 7), 0.01);
  // Between the areas: midpoints of neighbouring centres and the centre of the layout.
  const auto c = sixAreaCentres();
  Eigen::MatrixXd between(3, 5);
  between << 0.5 * (c[0] + c[1]), 0.5 * (c[2] + c[3]), 0.5 * (c[0] + c[2]), 0.5 * (c[1] + c[3]), 0.5 * (c[4] + c[5]);
  EXPECT_LT(testing::rmsJointError(elm, between, 7), 0.03);
}

TEST(Elm, GeneralizesFromFewerThanFiveSamplesPerArea) {
  // Tab. 3.4: sub-sampling leaves at most 4 samples per area.
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  Elm elm(3, 7);
  elm.fit(data);
  EXPECT_LT(testing::rmsJointError(elm, data.X, 7), 0.03);
  const auto c = sixAreaCentres();
  Eigen::MatrixXd between(3, 4);
  between << 0.5 * (c[0] + c[1]), 0.5 * (c[2] + c[3]), 0.5 * (c[0] + c[2]), 0.5 * (c[4] + c[5]);
  EXPECT_LT(testing::rmsJointError(elm, between, 7), 0.05);
}

TEST(Elm, PredictionsStayFiniteForExtremeFiniteInputs) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  Elm elm(3, 7);
  elm.fit(data);
  OsElm online(3, 7, InputNormalization::identity(3));
  online.fit(data);
  for (const double value : {0.0, 1e3, -1e6, 1e300, -1.7e308, 4.9e-324}) {
    const Eigen::Vector3d x(value, -value, 0.5 * value);
    EXPECT_TRUE(elm.predict(x).allFinite()) << value;
    EXPECT_TRUE(online.predict(x).allFinite()) << value;
  }
}

TEST(Elm, RefusesNonFiniteInputAndWrongSizes) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  Elm elm(3, 7);
  EXPECT_THROW(elm.predict(Eigen::Vector3d(0, 0, 0)), std::logic_error);  // untrained
  elm.fit(data);
  EXPECT_THROW(elm.predict(Eigen::Vector3d(NAN, 0, 0)), std::invalid_argument);
  EXPECT_THROW(elm.predict(Eigen::Vector2d(0, 0)), std::invalid_argument);
  TrainingSet wrong = data;
  wrong.Y.conservativeResize(6, Eigen::NoChange);
  EXPECT_THROW(elm.fit(wrong), std::invalid_argument);
  ElmParams bad;
  bad.epsilon = 0.0;
  EXPECT_THROW(Elm(3, 7, bad), std::invalid_argument);
}

TEST(Elm, LearnsSixDimensionalInputsAndNineJoints) {
  TrainingSet data = helixAreas(sixAreaCentres(), 20, 9);
  // Orientation inputs (rotation vector, rad) that the target does not depend on.
  data.X.conservativeResize(6, Eigen::NoChange);
  for (Eigen::Index l = 0; l < data.size(); ++l) data.X.col(l).tail(3) = Eigen::Vector3d(0.1 * std::sin(l), 0.2, -0.1);
  Elm elm(6, 9);
  elm.fit(data);
  EXPECT_LT(std::sqrt(elm.meanSquaredError(data) / 9.0), 0.03);
}

TEST(Elm, FitHonoursCancellation) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 10, 7);
  CancellationToken token;
  token.cancel();
  Elm elm(3, 7);
  EXPECT_THROW(elm.fit(data, token), TrainingCancelled);
  EXPECT_FALSE(elm.trained());
  OsElm online(3, 7, InputNormalization::identity(3));
  EXPECT_THROW(online.fit(data, token), TrainingCancelled);
}

}  // namespace
}  // namespace flexirob::learning
