// The smooth trajectory through the path's waypoints.
#include <gtest/gtest.h>

#include <random>

#include "planning/spline.hpp"

namespace flexirob::planning {
namespace {

Eigen::MatrixXd randomWaypoints(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> step(-0.15, 0.15);
  Eigen::MatrixXd waypoints(3, count);
  waypoints.col(0) = Eigen::Vector3d(-0.5, 0.0, 0.4);
  for (int k = 1; k < count; ++k) waypoints.col(k) = waypoints.col(k - 1) + Eigen::Vector3d(step(rng), step(rng), step(rng));
  return waypoints;
}

TEST(Spline, PassesThroughItsWaypointsAtRest) {
  std::mt19937 rng(5);
  const Eigen::MatrixXd waypoints = randomWaypoints(rng, 12);
  const CubicSplineTrajectory trajectory(waypoints, {0.3, 1.0});
  ASSERT_EQ(trajectory.knotTimes().size(), 12U);
  for (int k = 0; k < 12; ++k) {
    EXPECT_LT((trajectory.position(trajectory.knotTimes()[static_cast<std::size_t>(k)]) - waypoints.col(k)).norm(), 1e-12);
  }
  EXPECT_LT(trajectory.velocity(0.0).norm(), 1e-12);
  EXPECT_LT(trajectory.velocity(trajectory.duration()).norm(), 1e-12);
  EXPECT_LT((trajectory.position(trajectory.duration() + 5.0) - waypoints.col(11)).norm(), 1e-12);
}

TEST(Spline, IsTwiceContinuouslyDifferentiable) {
  std::mt19937 rng(6);
  const CubicSplineTrajectory trajectory(randomWaypoints(rng, 8), {0.3, 1.0});
  for (std::size_t k = 1; k + 1 < trajectory.knotTimes().size(); ++k) {
    const double t = trajectory.knotTimes()[k];
    const double h = 1e-7;
    EXPECT_LT((trajectory.velocity(t - h) - trajectory.velocity(t + h)).norm(), 1e-5);
    EXPECT_LT((trajectory.acceleration(t - h) - trajectory.acceleration(t + h)).norm(), 1e-5);
  }
}

TEST(Spline, RespectsSpeedAndAccelerationLimits) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const TrajectoryLimits limits{0.05 + 0.05 * trial, 0.2 + 0.3 * (trial % 5)};
    const CubicSplineTrajectory trajectory(randomWaypoints(rng, 3 + trial), limits);
    // Independent check: finite differences of the positions, densely sampled.
    const double dt = 1e-3;
    double max_speed = 0.0, max_acceleration = 0.0;
    for (double t = dt; t + dt <= trajectory.duration(); t += dt) {
      const Eigen::VectorXd p0 = trajectory.position(t - dt), p1 = trajectory.position(t), p2 = trajectory.position(t + dt);
      max_speed = std::max(max_speed, (p2 - p0).norm() / (2 * dt));
      max_acceleration = std::max(max_acceleration, (p2 - 2 * p1 + p0).norm() / (dt * dt));
      // The analytic derivatives agree with the differences.
      EXPECT_NEAR(trajectory.velocity(t).norm(), (p2 - p0).norm() / (2 * dt), 1e-3 * limits.max_acceleration + 1e-6);
    }
    EXPECT_LE(max_speed, limits.max_speed * (1 + 1e-4));
    EXPECT_LE(max_acceleration, limits.max_acceleration * (1 + 1e-2));
    EXPECT_LE(trajectory.maxSpeed(), limits.max_speed * (1 + 1e-9));
    EXPECT_LE(trajectory.maxAcceleration(), limits.max_acceleration * (1 + 1e-9));
    EXPECT_GE(trajectory.maxSpeed(), max_speed * (1 - 1e-6));
    // Not needlessly slow: one of the limits is nearly reached.
    EXPECT_GT(std::max(trajectory.maxSpeed() / limits.max_speed, trajectory.maxAcceleration() / limits.max_acceleration), 0.8);
  }
}

TEST(Spline, SamplesEveryPeriodAndEndsAtTheGoal) {
  Eigen::MatrixXd waypoints(3, 3);
  waypoints << 0, 0.2, 0.2, 0, 0, 0.3, 0.5, 0.5, 0.5;
  const CubicSplineTrajectory trajectory(waypoints, {0.25, 1.0});
  const auto samples = trajectory.sample(0.01);
  ASSERT_GE(samples.times.size(), 3U);
  EXPECT_EQ(samples.times.front(), 0.0);
  EXPECT_DOUBLE_EQ(samples.times.back(), trajectory.duration());
  for (std::size_t k = 1; k + 1 < samples.times.size(); ++k) EXPECT_NEAR(samples.times[k] - samples.times[k - 1], 0.01, 1e-12);
  EXPECT_LT((samples.positions.rightCols(1) - waypoints.col(2)).norm(), 1e-12);
  EXPECT_THROW(trajectory.sample(0.0), std::invalid_argument);
}

TEST(Spline, MergesRepeatedWaypointsAndHandlesASinglePoint) {
  Eigen::MatrixXd waypoints(3, 4);
  waypoints << 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0;
  const CubicSplineTrajectory trajectory(waypoints, {0.5, 1.0});
  EXPECT_EQ(trajectory.waypoints().cols(), 2);
  const CubicSplineTrajectory still(Eigen::MatrixXd::Ones(3, 1), {0.5, 1.0});
  EXPECT_EQ(still.duration(), 0.0);
  EXPECT_TRUE(still.position(1.0).isApprox(Eigen::Vector3d::Ones()));
  EXPECT_THROW(CubicSplineTrajectory(waypoints, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(CubicSplineTrajectory(Eigen::MatrixXd(3, 0), {0.5, 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace flexirob::planning
