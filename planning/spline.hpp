#pragma once
// A smooth, rest-to-rest trajectory through waypoints: a C2 cubic spline in time with zero
// velocity at both ends, whose segment durations are chosen so that the speed and the
// acceleration (Euclidean norms over all coordinates) stay within given limits. It is what the
// hierarchical controller tracks after A* has chosen the waypoints (Sect. 7.4).
#include <Eigen/Core>
#include <vector>

namespace flexirob::planning {

struct TrajectoryLimits {
  double max_speed = 0.25;         ///< [m/s] bound on |dx/dt|
  double max_acceleration = 1.0;   ///< [m/s^2] bound on |d2x/dt2|
  void validate() const;           ///< both positive and finite, else std::invalid_argument
};

class CubicSplineTrajectory {
 public:
  /// waypoints: D x K (D >= 1, K >= 1), finite. Consecutive waypoints closer than 1e-9 are merged.
  CubicSplineTrajectory(const Eigen::MatrixXd& waypoints, const TrajectoryLimits& limits);

  int dimension() const { return static_cast<int>(waypoints_.rows()); }
  /// The (merged) waypoints the trajectory passes through, at knotTimes().
  const Eigen::MatrixXd& waypoints() const { return waypoints_; }
  const std::vector<double>& knotTimes() const { return knot_times_; }
  double duration() const { return knot_times_.back(); }

  /// Position, velocity and acceleration at time t [s], clamped to [0, duration()].
  Eigen::VectorXd position(double t) const;
  Eigen::VectorXd velocity(double t) const;
  Eigen::VectorXd acceleration(double t) const;

  /// Largest speed and acceleration over the whole trajectory (per segment: acceleration is
  /// linear in time, so its norm peaks at a segment end; the speed's peaks are found at the
  /// roots of v . a).
  double maxSpeed() const;
  double maxAcceleration() const;

  struct Samples {
    std::vector<double> times;   ///< 0, dt, 2 dt, ..., duration() (the last one exactly)
    Eigen::MatrixXd positions;   ///< D x S
    Eigen::MatrixXd velocities;  ///< D x S
  };
  /// Samples the trajectory every period seconds (period > 0; at most 10^7 samples).
  Samples sample(double period) const;

 private:
  void solve();  // knot velocities and coefficients for the current durations
  int segmentAt(double t, double& tau) const;
  double segmentMaxSpeed(int segment) const;
  double segmentMaxAcceleration(int segment) const;

  Eigen::MatrixXd waypoints_;
  std::vector<double> durations_;
  std::vector<double> knot_times_;
  // Per segment: p(tau) = c0 + c1 tau + c2 tau^2 + c3 tau^3, tau in [0, duration]; D x 4 each.
  std::vector<Eigen::MatrixXd> coefficients_;
};

}  // namespace flexirob::planning
