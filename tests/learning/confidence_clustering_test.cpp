// Confidence model (Eq. 6.6–6.9), k-means with given centres and classical MDS (App. B.4).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "learning/clustering.hpp"
#include "learning/confidence.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

// Six samples at μ ± a along each axis: the sample covariance (Eq. 6.8 with L − 1 = 5) is
// 2a²/5 on the diagonal, so Σ = d (2a²/5 + min_std²) I.
Eigen::MatrixXd axisStar(const Eigen::Vector3d& mu, double a) {
  Eigen::MatrixXd samples(3, 6);
  for (int i = 0; i < 3; ++i) {
    samples.col(2 * i) = mu + a * Eigen::Vector3d::Unit(i);
    samples.col(2 * i + 1) = mu - a * Eigen::Vector3d::Unit(i);
  }
  return samples;
}

TEST(Confidence, MatchesTheClosedFormGaussianOfOneArea) {
  const double d = 15.0, min_std = 0.005, a = 0.04;
  const Eigen::Vector3d mu(-0.5, 0.1, 0.4);
  ConfidenceModel model(d, min_std);
  model.addArea(axisStar(mu, a));
  const double variance = d * (2.0 * a * a / 5.0 + min_std * min_std);
  EXPECT_NEAR(model.evaluate(mu), 1.0, 1e-15);
  for (const double t : {0.01, 0.1, 0.3}) {
    const Eigen::Vector3d x = mu + Eigen::Vector3d(t, -t, 0.5 * t);
    EXPECT_NEAR(model.evaluate(x), std::exp(-0.5 * 2.25 * t * t / variance), 1e-12) << t;
  }
}

TEST(Confidence, IsZeroWithoutAreasAndTheMaximumOverAreasOtherwise) {
  ConfidenceModel model;
  EXPECT_EQ(model.evaluate(Eigen::Vector3d(0.1, 0.2, 0.3)), 0.0);
  const Eigen::Vector3d left(-0.6, -0.4, 0.3), right(-0.6, 0.4, 0.3);
  ConfidenceModel only_left, only_right;
  model.addArea(axisStar(left, 0.05));
  model.addArea(axisStar(right, 0.03));
  only_left.addArea(axisStar(left, 0.05));
  only_right.addArea(axisStar(right, 0.03));
  for (double y = -1.0; y <= 1.0; y += 0.05) {
    const Eigen::Vector3d x(-0.6, y, 0.35);
    const double c = model.evaluate(x);
    EXPECT_GE(c, 0.0);
    EXPECT_LE(c, 1.0);
    EXPECT_DOUBLE_EQ(c, std::max(only_left.evaluate(x), only_right.evaluate(x)));
  }
  // Far away the confidence vanishes; a larger d widens the Gaussians.
  EXPECT_LT(model.evaluate(Eigen::Vector3d(0.5, 0.0, 1.5)), 1e-6);
  ConfidenceModel wide(25.0);
  wide.addArea(axisStar(left, 0.05));
  const Eigen::Vector3d off = left + Eigen::Vector3d(0.2, 0.0, 0.0);
  EXPECT_GT(wide.evaluate(off), only_left.evaluate(off));
}

TEST(Confidence, GridEvaluationEqualsPointwiseEvaluation) {
  const TrainingSet data = testing::helixAreas(testing::sixAreaCentres(), 12, 7);
  const ConfidenceModel model = ConfidenceModel::fromTrainingSet(data);
  ASSERT_EQ(model.areas(), 6);
  const Eigen::Vector3d lower(-0.9, -0.55, 0.05), upper(0.0, 0.55, 0.8);  // grid G, Sect. 3.3.2
  const std::vector<int> counts = {7, 5, 4};
  const Eigen::VectorXd grid = model.evaluateGrid(lower, upper, counts);
  ASSERT_EQ(grid.size(), 7 * 5 * 4);
  int index = 0;
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < 5; ++j) {
      for (int i = 0; i < 7; ++i, ++index) {
        const Eigen::Vector3d x(lower[0] + 0.9 * i / 6.0, lower[1] + 1.1 * j / 4.0, lower[2] + 0.75 * k / 3.0);
        EXPECT_NEAR(grid[index], model.evaluate(x), 1e-12);
      }
    }
  }
}

TEST(Confidence, HandlesAreasWithOneOrCollinearSamples) {
  ConfidenceModel model;
  model.addArea(Eigen::Vector3d(0.1, 0.2, 0.3));  // one sample: only the floor
  Eigen::MatrixXd line(3, 4);
  line << 0, 0.1, 0.2, 0.3, 0, 0, 0, 0, 0.5, 0.5, 0.5, 0.5;
  model.addArea(line);
  EXPECT_NEAR(model.evaluate(Eigen::Vector3d(0.1, 0.2, 0.3)), 1.0, 1e-12);
  EXPECT_TRUE(std::isfinite(model.evaluate(Eigen::Vector3d(0.15, 0.0, 0.5))));
  EXPECT_THROW(model.addArea(Eigen::Vector2d(0, 0)), std::invalid_argument);
  EXPECT_THROW(ConfidenceModel(0.0), std::invalid_argument);
}

// Tab. B.1 (left area): three prototypical postures q1..q6 [rad].
Eigen::MatrixXd tableB1LeftCentres() {
  const double h = M_PI / 2;
  Eigen::MatrixXd centres(6, 3);
  centres.col(0) << 0, h, -h, -h, h, h;
  centres.col(1) << 0, h, -h, -h, -h, -h;
  centres.col(2) << 0, h, h, h, -h, h;
  return centres;
}

TEST(KMeans, FindsClustersAroundTheGivenInitialCentres) {
  // 30 postures scattered (±0.3 rad) around each of the three prototypes, listed mixed.
  const Eigen::MatrixXd prototypes = tableB1LeftCentres();
  UniformRandom random(7);
  Eigen::MatrixXd points(6, 90);
  std::vector<int> truth;
  for (int l = 0; l < 90; ++l) {
    const int cluster = (l * 7) % 3;
    truth.push_back(cluster);
    for (int i = 0; i < 6; ++i) points(i, l) = prototypes(i, cluster) + random.uniform(-0.3, 0.3);
  }
  // Start from perturbed prototypes, as in App. B.4.
  const KMeansResult result = kMeans(points, prototypes.array() + 0.2);
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.assignment, truth);
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(6);
    int count = 0;
    for (int l = 0; l < 90; ++l) {
      if (truth[static_cast<std::size_t>(l)] == k) {
        mean += points.col(l);
        ++count;
      }
    }
    EXPECT_TRUE(result.centres.col(k).isApprox(mean / count, 1e-12)) << k;
  }
}

TEST(KMeans, KeepsTheCentreOfAClusterThatGetsNoPoints) {
  Eigen::MatrixXd points(1, 4);
  points << 0.0, 0.1, 1.0, 1.1;
  Eigen::MatrixXd centres(1, 3);
  centres << 0.0, 1.0, 50.0;
  const KMeansResult result = kMeans(points, centres);
  EXPECT_NEAR(result.centres(0, 0), 0.05, 1e-15);
  EXPECT_NEAR(result.centres(0, 1), 1.05, 1e-15);
  EXPECT_EQ(result.centres(0, 2), 50.0);
  EXPECT_NEAR(result.inertia, 4 * 0.05 * 0.05, 1e-15);
  EXPECT_THROW(kMeans(points, Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
}

TEST(InferAreas, GroupsSamplesAroundTheFirstSampleOfEachArea) {
  // Two areas visited alternately; a third far away; a sample just outside the radius of the
  // first area's leader starts its own area.
  Eigen::MatrixXd X(3, 6);
  X << 0.0, 1.0, 0.05, 1.04, 5.0, 0.16,  //
      0.0, 0.0, 0.0, 0.0, 0.0, 0.0,      //
      0.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  EXPECT_EQ(inferAreas(X, 0.15), (std::vector<int>{0, 1, 0, 1, 2, 3}));
  EXPECT_THROW(inferAreas(X, 0.0), std::invalid_argument);
}

TEST(Mds, RecoversPairwiseDistancesOfPlanarPointsEmbeddedInSixDimensions) {
  UniformRandom random(3);
  Eigen::MatrixXd planar(2, 25);
  for (Eigen::Index l = 0; l < 25; ++l) planar.col(l) << random.uniform(-1, 1), random.uniform(-2, 2);
  // Embed in R^6 with an orthonormal basis and an offset.
  Eigen::MatrixXd basis = Eigen::MatrixXd::Zero(6, 2);
  basis.col(0) << 1, 2, 0, -1, 0.5, 0;
  basis.col(1) << 0, 1, 1, 1, -2, 0.3;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(6, 2);
  const Eigen::MatrixXd embedded = (Q * planar).colwise() + (Eigen::VectorXd(6) << 1, 2, 3, 4, 5, 6).finished();
  const Eigen::MatrixXd projected = classicalMds(pairwiseDistances(embedded), 2);
  ASSERT_EQ(projected.rows(), 2);
  EXPECT_LT((pairwiseDistances(projected) - pairwiseDistances(planar)).cwiseAbs().maxCoeff(), 1e-9);
  // Centred at the origin.
  EXPECT_LT(projected.rowwise().mean().norm(), 1e-12);
  EXPECT_THROW(classicalMds(Eigen::MatrixXd::Ones(2, 3)), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::learning
