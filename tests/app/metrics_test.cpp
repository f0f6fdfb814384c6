// Study metrics against closed-form cases.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "app/study_metrics.hpp"

namespace flexirob::app {
namespace {

// A planar-ish 3-D curve with curvature in every direction (a helix with a drift).
Eigen::MatrixXd helix(int count) {
  Eigen::MatrixXd points(3, count);
  for (int i = 0; i < count; ++i) {
    const double s = 4.0 * static_cast<double>(i) / (count - 1);
    points.col(i) << 0.3 * std::cos(s), 0.2 * std::sin(s), 0.1 * s + 0.05 * s * s;
  }
  return points;
}

TEST(StudyMetrics, TaskErrorOfAConstantOffsetIsTheOffsetLength) {
  const Eigen::MatrixXd targets = helix(50);
  const Eigen::Vector3d offset(0.003, -0.004, 0.0);  // 5 mm
  const Eigen::MatrixXd reached = targets.colwise() + offset;
  EXPECT_NEAR(taskSpaceError(targets, reached), 0.005, 1e-15);
}

TEST(StudyMetrics, TaskErrorIsTheMeanOfPointDistances) {
  Eigen::MatrixXd targets = Eigen::MatrixXd::Zero(3, 2);
  Eigen::MatrixXd reached = Eigen::MatrixXd::Zero(3, 2);
  reached(0, 0) = 0.01;
  reached(2, 1) = -0.03;
  EXPECT_NEAR(taskSpaceError(targets, reached), 0.02, 1e-15);
  EXPECT_THROW(taskSpaceError(targets, Eigen::MatrixXd::Zero(3, 3)), std::invalid_argument);
}

TEST(StudyMetrics, MaxDeviationIsThePerpendicularDistanceToTheTargetPolyline) {
  Eigen::MatrixXd target(3, 3);
  target << 0.0, 1.0, 1.0,  //
      0.0, 0.0, 1.0,        //
      0.0, 0.0, 0.0;
  Eigen::MatrixXd user(3, 3);
  user << 0.5, 1.2, 0.9,  // 0.1 above the first segment; 0.2 beside the second; 0.1 beside it
      0.1, 0.5, 0.8,      //
      0.0, 0.0, 0.0;
  EXPECT_NEAR(maxDeviation(user, target), 0.2, 1e-15);
  // A point beyond the polyline's end measures to the end point.
  Eigen::MatrixXd beyond(3, 1);
  beyond << 1.0, 1.3, 0.4;
  EXPECT_NEAR(maxDeviation(beyond, target), 0.5, 1e-15);
}

TEST(StudyMetrics, ResamplingSpacesPointsEquallyInArcLength) {
  Eigen::MatrixXd points(3, 3);
  points << 0.0, 0.1, 1.0,  // unevenly spaced points along a straight line of length 1
      0.0, 0.0, 0.0,        //
      0.0, 0.0, 0.0;
  const Eigen::MatrixXd resampled = resampleByArcLength(points, 5);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(resampled(0, i), 0.25 * i, 1e-15);
}

TEST(StudyMetrics, RotatedAndShiftedCopyHasProcrustesDistanceZero) {
  const Eigen::MatrixXd target = helix(120);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d shift(0.4, -1.2, 0.7);
  // The copy is also sampled with another velocity profile (the time normalization removes it).
  Eigen::MatrixXd user(3, 300);
  for (int i = 0; i < 300; ++i) {
    const double u = static_cast<double>(i) / 299.0;
    const double s = 4.0 * u * u;  // slow start, fast end
    user.col(i) = R * Eigen::Vector3d(0.3 * std::cos(s), 0.2 * std::sin(s), 0.1 * s + 0.05 * s * s) + shift;
  }
  const ProcrustesResult result = procrustesDistance(user, target, 200);
  EXPECT_LT(result.distance, 2e-4);  // only the polyline discretization remains
  EXPECT_NEAR((result.R_TU - R.transpose()).norm(), 0.0, 1e-3);
  // Unlike a rotation, a mirror image is not superimposed: no reflections.
  Eigen::MatrixXd mirrored = target;
  mirrored.row(2) *= -1.0;
  EXPECT_GT(procrustesDistance(mirrored, target).distance, 0.01);
}

TEST(StudyMetrics, ProcrustesDoesNotScale) {
  // A straight segment and the same segment twice as long, both centred at the origin: without
  // scaling the resampled points differ by |s|·L/2 for s in [-1, 1], a mean of L/4.
  Eigen::MatrixXd a(3, 2);
  a << -0.5, 0.5, 0, 0, 0, 0;
  Eigen::MatrixXd b = 2.0 * a;
  const double mean = procrustesDistance(a, b, 1001).distance;
  EXPECT_NEAR(mean, 0.25, 1e-3);
}

TEST(StudyMetrics, JerkOfACubicIsSixTimesItsLeadingCoefficient) {
  // p(t) = (a t³ + t, b t², c t³): jerk (6a, 0, 6c) everywhere, on an uneven time grid.
  const double a = 0.7, b = -2.0, c = 0.2;
  const int k = 40;
  Eigen::VectorXd times(k);
  Eigen::MatrixXd positions(3, k);
  for (int i = 0; i < k; ++i) {
    times(i) = 0.05 * i + 0.01 * std::sin(3.0 * i);
    const double t = times(i);
    positions.col(i) << a * t * t * t + t, b * t * t, c * t * t * t;
  }
  const JerkStatistics stats = jerk(times, positions);
  const double expected = 6.0 * std::hypot(a, c);
  EXPECT_EQ(stats.samples, k - 3);
  EXPECT_NEAR(stats.mean, expected, 1e-8);
  EXPECT_NEAR(stats.rms, expected, 1e-8);
  EXPECT_NEAR(stats.max, expected, 1e-8);
}

TEST(StudyMetrics, JerkOfUniformMotionIsZeroAndOfASineIsItsThirdDerivative) {
  const int k = 2001;
  const double dt = 0.001;
  Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(k, 0.0, dt * (k - 1));
  Eigen::MatrixXd line(3, k);
  Eigen::MatrixXd sine(3, k);
  for (int i = 0; i < k; ++i) {
    line.col(i) << 0.1 * times(i), -0.2 * times(i), 0.3;
    sine.col(i) << 0.05 * std::sin(2.0 * times(i)), 0.0, 0.0;  // jerk −0.4 cos(2t)
  }
  EXPECT_NEAR(jerk(times, line).max, 0.0, 1e-5);  // rounding amplified by 1/dt³
  // max |−0.4 cos 2t| on [0, 2] is 0.4 (at t = 0); rms over the interval from the integral.
  const JerkStatistics stats = jerk(times, sine);
  EXPECT_NEAR(stats.max, 0.4, 1e-3);
  const double rms = std::sqrt(0.16 * (0.5 + std::sin(8.0) / 16.0));
  EXPECT_NEAR(stats.rms, rms, 2e-3);
  EXPECT_THROW(jerk(times.head(3), line.leftCols(3)), std::invalid_argument);
}

TEST(StudyMetrics, TimePerPhaseSumsStagesUntilTheNextChange) {
  const std::vector<StageRecord> stages{{1.0, "CONFIGURATION", "APPROACHING"},
                                        {4.0, "CONFIGURATION", "RECORDING"},
                                        {10.0, "CONFIGURATION", "APPROACHING"},
                                        {12.0, "PROGRAMMING", "TEACH-IN"}};
  const auto seconds = timePerPhase(stages, 20.0);
  EXPECT_DOUBLE_EQ(seconds.at("CONFIGURATION"), 11.0);
  EXPECT_DOUBLE_EQ(seconds.at("CONFIGURATION/APPROACHING"), 5.0);
  EXPECT_DOUBLE_EQ(seconds.at("CONFIGURATION/RECORDING"), 6.0);
  EXPECT_DOUBLE_EQ(seconds.at("PROGRAMMING"), 8.0);
}

TEST(StudyMetrics, ExecutionTargetsFollowTheReferenceInNormalizedTime) {
  TrajectoryRecord reference;
  reference.times = Eigen::Vector2d(0.0, 1.0);
  reference.positions.resize(3, 2);
  reference.positions << 0.0, 1.0, 0.0, 0.0, 0.0, 0.0;
  TrajectoryRecord executed;
  executed.times = Eigen::Vector3d(5.0, 5.5, 7.0);  // a quarter of the way at 5.5 s
  executed.positions = Eigen::MatrixXd::Zero(3, 3);
  const Eigen::MatrixXd targets = targetsForExecution(executed, reference);
  EXPECT_NEAR(targets(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(targets(0, 1), 0.25, 1e-15);
  EXPECT_NEAR(targets(0, 2), 1.0, 1e-15);
}

TEST(StudyMetrics, TeachInsAreJudgedAgainstTheTargetTheyNameOrElseTheFirstTarget) {
  const auto straight = [](std::int64_t id, TrajectoryKind kind, std::int64_t reference_id, double y) {
    TrajectoryRecord record;
    record.id = id;
    record.kind = kind;
    record.reference_id = reference_id;
    record.times = Eigen::Vector2d(0.0, 1.0);
    record.positions = Eigen::MatrixXd::Zero(3, 2);
    record.positions.row(0) << 0.0, 1.0;
    record.positions.row(1).setConstant(y);
    return record;
  };
  const std::vector<TrajectoryRecord> trajectories = {
      straight(1, TrajectoryKind::TeachIn, -1, 0.5),    // before any target, names none
      straight(2, TrajectoryKind::Target, -1, 0.0),
      straight(3, TrajectoryKind::Target, -1, 0.2),
      straight(4, TrajectoryKind::TeachIn, 3, 0.3),     // names the second target
      straight(5, TrajectoryKind::Executed, 3, 0.25),   // 5 cm off its reference all along
      straight(6, TrajectoryKind::Executed, 99, 0.0),   // names a trajectory the session lacks
      straight(7, TrajectoryKind::Executed, -1, 0.0)};  // names none
  const TrajectoryReferences references(trajectories);
  EXPECT_EQ(references.targetOf(trajectories[0]), &trajectories[1]);
  EXPECT_EQ(references.targetOf(trajectories[3]), &trajectories[2]);
  EXPECT_EQ(references.referenceOf(trajectories[0]), nullptr);
  const auto error = references.executionError(trajectories[4]);
  ASSERT_TRUE(error.has_value());
  EXPECT_NEAR(error->first, 0.05, 1e-12);
  EXPECT_EQ(error->second, 2);
  EXPECT_FALSE(references.executionError(trajectories[5]).has_value());
  EXPECT_FALSE(references.executionError(trajectories[6]).has_value());
}

}  // namespace
}  // namespace flexirob::app
