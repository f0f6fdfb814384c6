#include "planning/spline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flexirob::planning {

void TrajectoryLimits::validate() const {
  if (!(max_speed > 0.0 && std::isfinite(max_speed))) {
    throw std::invalid_argument("trajectory: expected a positive finite speed limit, got " + std::to_string(max_speed));
  }
  if (!(max_acceleration > 0.0 && std::isfinite(max_acceleration))) {
    throw std::invalid_argument("trajectory: expected a positive finite acceleration limit, got " +
                                std::to_string(max_acceleration));
  }
}

CubicSplineTrajectory::CubicSplineTrajectory(const Eigen::MatrixXd& waypoints, const TrajectoryLimits& limits) {
  limits.validate();
  if (waypoints.rows() < 1 || waypoints.cols() < 1) throw std::invalid_argument("trajectory: expected at least one waypoint");
  if (!waypoints.allFinite()) throw std::invalid_argument("trajectory: waypoints must be finite");
  // Merge repeated waypoints: a zero-length segment has no direction to pass through.
  std::vector<Eigen::Index> kept{0};
  for (Eigen::Index k = 1; k < waypoints.cols(); ++k) {
    if ((waypoints.col(k) - waypoints.col(kept.back())).norm() > 1e-9) kept.push_back(k);
  }
  waypoints_.resize(waypoints.rows(), static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) waypoints_.col(static_cast<Eigen::Index>(i)) = waypoints.col(kept[i]);

  const int segments = static_cast<int>(kept.size()) - 1;
  durations_.resize(static_cast<std::size_t>(segments));
  // A rest-to-rest cubic over length L peaks at speed 1.5 L / T and acceleration 6 L / T^2:
  // a safe first guess that the iterations below shorten or stretch per segment.
  for (int i = 0; i < segments; ++i) {
    const double length = (waypoints_.col(i + 1) - waypoints_.col(i)).norm();
    durations_[static_cast<std::size_t>(i)] =
        std::max(1.5 * length / limits.max_speed, std::sqrt(6.0 * length / limits.max_acceleration));
  }
  solve();
  if (segments == 0) return;

  const auto ratio = [&](int i) {
    return std::max(segmentMaxSpeed(i) / limits.max_speed, std::sqrt(segmentMaxAcceleration(i) / limits.max_acceleration));
  };
  // Per-segment retiming towards a ratio just below one; neighbours interact through the C2
  // conditions, hence a few rounds.
  for (int round = 0; round < 30; ++round) {
    bool changed = false;
    for (int i = 0; i < segments; ++i) {
      const double r = ratio(i);
      if (r > 1.0 || r < 0.95) {
        durations_[static_cast<std::size_t>(i)] *= std::clamp(r / 0.98, 0.8, 1.5);
        changed = true;
      }
    }
    if (!changed) break;
    solve();
  }
  // Guarantee: stretching all durations by k scales speeds by 1/k and accelerations by 1/k^2
  // (the clamped spline is invariant under uniform time scaling).
  double worst = 0.0;
  for (int i = 0; i < segments; ++i) worst = std::max(worst, ratio(i));
  if (worst > 1.0) {
    for (double& duration : durations_) duration *= worst * (1.0 + 1e-9);
    solve();
  }
}

void CubicSplineTrajectory::solve() {
  const int knots = static_cast<int>(waypoints_.cols());
  const int segments = knots - 1;
  const Eigen::Index dims = waypoints_.rows();
  knot_times_.assign(static_cast<std::size_t>(knots), 0.0);
  for (int i = 0; i < segments; ++i) {
    knot_times_[static_cast<std::size_t>(i + 1)] = knot_times_[static_cast<std::size_t>(i)] + durations_[static_cast<std::size_t>(i)];
  }
  // Knot velocities: zero at both ends; continuity of acceleration at interior knot i gives
  //   v_{i-1}/h0 + 2 v_i (1/h0 + 1/h1) + v_{i+1}/h1 = 3 (dp0/h0^2 + dp1/h1^2),
  // a strictly diagonally dominant tridiagonal system (Thomas algorithm).
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(dims, knots);
  const int unknowns = knots - 2;
  if (unknowns > 0) {
    std::vector<double> lower(static_cast<std::size_t>(unknowns)), diag(static_cast<std::size_t>(unknowns)),
        upper(static_cast<std::size_t>(unknowns));
    Eigen::MatrixXd rhs(dims, unknowns);
    for (int k = 0; k < unknowns; ++k) {
      const int i = k + 1;
      const double h0 = durations_[static_cast<std::size_t>(i - 1)];
      const double h1 = durations_[static_cast<std::size_t>(i)];
      lower[static_cast<std::size_t>(k)] = 1.0 / h0;
      diag[static_cast<std::size_t>(k)] = 2.0 * (1.0 / h0 + 1.0 / h1);
      upper[static_cast<std::size_t>(k)] = 1.0 / h1;
      rhs.col(k) = 3.0 * ((waypoints_.col(i) - waypoints_.col(i - 1)) / (h0 * h0) +
                          (waypoints_.col(i + 1) - waypoints_.col(i)) / (h1 * h1));
    }
    for (int k = 1; k < unknowns; ++k) {
      const double m = lower[static_cast<std::size_t>(k)] / diag[static_cast<std::size_t>(k - 1)];
      diag[static_cast<std::size_t>(k)] -= m * upper[static_cast<std::size_t>(k - 1)];
      rhs.col(k) -= m * rhs.col(k - 1);
    }
    v.col(unknowns) = rhs.col(unknowns - 1) / diag[static_cast<std::size_t>(unknowns - 1)];
    for (int k = unknowns - 2; k >= 0; --k) {
      v.col(k + 1) = (rhs.col(k) - upper[static_cast<std::size_t>(k)] * v.col(k + 2)) / diag[static_cast<std::size_t>(k)];
    }
  }
  // Cubic Hermite coefficients per segment.
  coefficients_.assign(static_cast<std::size_t>(segments), Eigen::MatrixXd(dims, 4));
  for (int i = 0; i < segments; ++i) {
    const double h = durations_[static_cast<std::size_t>(i)];
    const Eigen::VectorXd p0 = waypoints_.col(i), p1 = waypoints_.col(i + 1), v0 = v.col(i), v1 = v.col(i + 1);
    auto& c = coefficients_[static_cast<std::size_t>(i)];
    c.col(0) = p0;
    c.col(1) = v0;
    c.col(2) = (3.0 * (p1 - p0) / h - 2.0 * v0 - v1) / h;
    c.col(3) = (2.0 * (p0 - p1) / h + v0 + v1) / (h * h);
  }
}

int CubicSplineTrajectory::segmentAt(double t, double& tau) const {
  const int segments = static_cast<int>(coefficients_.size());
  if (segments == 0) {
    tau = 0.0;
    return -1;
  }
  t = std::clamp(t, 0.0, duration());
  const auto it = std::upper_bound(knot_times_.begin(), knot_times_.end(), t);
  int segment = static_cast<int>(it - knot_times_.begin()) - 1;
  segment = std::clamp(segment, 0, segments - 1);
  tau = t - knot_times_[static_cast<std::size_t>(segment)];
  return segment;
}

Eigen::VectorXd CubicSplineTrajectory::position(double t) const {
  double tau;
  const int s = segmentAt(t, tau);
  if (s < 0) return waypoints_.col(0);
  const auto& c = coefficients_[static_cast<std::size_t>(s)];
  return c.col(0) + tau * (c.col(1) + tau * (c.col(2) + tau * c.col(3)));
}

Eigen::VectorXd CubicSplineTrajectory::velocity(double t) const {
  double tau;
  const int s = segmentAt(t, tau);
  if (s < 0) return Eigen::VectorXd::Zero(waypoints_.rows());
  const auto& c = coefficients_[static_cast<std::size_t>(s)];
  return c.col(1) + tau * (2.0 * c.col(2) + 3.0 * tau * c.col(3));
}

Eigen::VectorXd CubicSplineTrajectory::acceleration(double t) const {
  double tau;
  const int s = segmentAt(t, tau);
  if (s < 0) return Eigen::VectorXd::Zero(waypoints_.rows());
  const auto& c = coefficients_[static_cast<std::size_t>(s)];
  return 2.0 * c.col(2) + 6.0 * tau * c.col(3);
}

double CubicSplineTrajectory::segmentMaxAcceleration(int segment) const {
  const auto& c = coefficients_[static_cast<std::size_t>(segment)];
  const double h = durations_[static_cast<std::size_t>(segment)];
  return std::max((2.0 * c.col(2)).norm(), (2.0 * c.col(2) + 6.0 * h * c.col(3)).norm());
}

double CubicSplineTrajectory::segmentMaxSpeed(int segment) const {
  const auto& c = coefficients_[static_cast<std::size_t>(segment)];
  const double h = durations_[static_cast<std::size_t>(segment)];
  // v(tau) = A + B tau + C tau^2 with A = c1, B = 2 c2, C = 3 c3, so |v|^2 is the quartic
  // AA + 2AB tau + (BB + 2AC) tau^2 + 2BC tau^3 + CC tau^4, evaluated from five dot products.
  const Eigen::VectorXd A = c.col(1), B = 2.0 * c.col(2), C = 3.0 * c.col(3);
  const double k0 = A.dot(A), k1 = 2.0 * A.dot(B), k2 = B.dot(B) + 2.0 * A.dot(C), k3 = 2.0 * B.dot(C), k4 = C.dot(C);
  const auto speedSquared = [&](double t) { return k0 + t * (k1 + t * (k2 + t * (k3 + t * k4))); };
  // d|v|^2/dt: the speed peaks where it falls through zero (or at an end).
  const auto slope = [&](double t) { return k1 + t * (2.0 * k2 + t * (3.0 * k3 + t * 4.0 * k4)); };
  double best = std::max(speedSquared(0.0), speedSquared(h));
  constexpr int kBrackets = 64;
  double t0 = 0.0, f0 = slope(0.0);
  for (int k = 1; k <= kBrackets; ++k) {
    const double t1 = h * k / kBrackets;
    const double f1 = slope(t1);
    if (f0 > 0.0 && f1 <= 0.0) {
      double lo = t0, hi = t1;
      for (int iteration = 0; iteration < 60; ++iteration) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0.0 ? lo : hi) = mid;
      }
      best = std::max(best, speedSquared(0.5 * (lo + hi)));
    }
    best = std::max(best, speedSquared(t1));
    t0 = t1;
    f0 = f1;
  }
  return std::sqrt(std::max(best, 0.0));
}

double CubicSplineTrajectory::maxSpeed() const {
  double best = 0.0;
  for (int i = 0; i < static_cast<int>(coefficients_.size()); ++i) best = std::max(best, segmentMaxSpeed(i));
  return best;
}

double CubicSplineTrajectory::maxAcceleration() const {
  double best = 0.0;
  for (int i = 0; i < static_cast<int>(coefficients_.size()); ++i) best = std::max(best, segmentMaxAcceleration(i));
  return best;
}

CubicSplineTrajectory::Samples CubicSplineTrajectory::sample(double period) const {
  if (!(period > 0.0) || !std::isfinite(period)) throw std::invalid_argument("trajectory: expected a positive sample period");
  const double steps = std::floor(duration() / period);
  if (steps > 1e7) throw std::invalid_argument("trajectory: more than 10^7 samples at this period");
  auto count = static_cast<Eigen::Index>(steps) + 1;
  const bool add_end = duration() - static_cast<double>(count - 1) * period > 1e-12;
  if (add_end) ++count;
  Samples samples;
  samples.times.resize(static_cast<std::size_t>(count));
  samples.positions.resize(waypoints_.rows(), count);
  samples.velocities.resize(waypoints_.rows(), count);
  for (Eigen::Index k = 0; k < count; ++k) {
    const double t = (add_end && k == count - 1) ? duration() : static_cast<double>(k) * period;
    samples.times[static_cast<std::size_t>(k)] = t;
    samples.positions.col(k) = position(t);
    samples.velocities.col(k) = velocity(t);
  }
  return samples;
}

}  // namespace flexirob::planning
