#pragma once
// Synthetic tutor streams for the ITM tests: correlated samples in time order, as a person
// moving the arm produces them.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "planning/itm.hpp"

namespace flexirob::planning::testing {

struct Sample {
  Eigen::VectorXd x;
  Eigen::VectorXd q;
};

/// Circle of the given radius in the z = height plane, `laps` times, a sample every `step` m.
inline std::vector<Sample> ringStream(double radius, double step, int laps, const Eigen::VectorXd& q, double height = 0.5) {
  std::vector<Sample> stream;
  const int per_lap = static_cast<int>(std::ceil(2.0 * std::numbers::pi * radius / step));
  for (int k = 0; k <= laps * per_lap; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / per_lap;
    stream.push_back({Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), height), q});
  }
  return stream;
}

/// Straight motion from a to b with joints interpolated from qa to qb, a sample every `step` m.
inline void appendLine(std::vector<Sample>& stream, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                       const Eigen::VectorXd& qa, const Eigen::VectorXd& qb, double step) {
  const int count = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  for (int k = 0; k <= count; ++k) {
    const double s = static_cast<double>(k) / count;
    stream.push_back({a + s * (b - a), qa + s * (qb - qa)});
  }
}

/// A compliant-recording-like session: in each area the tutor deflects the end-effector in
/// noisy circles of growing radius around the centre (Sect. 2.3.1), and moves between areas.
inline std::vector<Sample> recordingSession(const std::vector<Eigen::Vector3d>& centres, const Eigen::VectorXd& q,
                                            std::uint32_t seed, double max_radius = 0.3) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Sample> stream;
  Eigen::Vector3d last = centres.front();
  for (const auto& centre : centres) {
    appendLine(stream, last, centre, q, q, 0.005);
    for (int lap = 0; lap < 8; ++lap) {
      const double radius = max_radius * (lap + 1) / 8.0;
      const Eigen::Vector3d normal = Eigen::Vector3d(noise(rng), noise(rng), 1.0).normalized();
      const Eigen::Vector3d u = normal.unitOrthogonal();
      const Eigen::Vector3d v = normal.cross(u);
      const int steps = static_cast<int>(2.0 * std::numbers::pi * radius / 0.005) + 1;
      for (int k = 0; k < steps; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / steps;
        const Eigen::Vector3d p = centre + radius * (std::cos(angle) * u + std::sin(angle) * v) +
                                  Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) * 0.3;
        stream.push_back({p, q});
      }
      last = stream.back().x;
    }
  }
  return stream;
}

/// A bounded random walk (smooth heading changes) inside the box [lo, hi], joints following a
/// smooth function of the position.
inline std::vector<Sample> randomWalk(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int count, double step,
                                      int joints, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> turn(0.0, 0.3);
  std::vector<Sample> stream;
  Eigen::Vector3d p = 0.5 * (lo + hi);
  Eigen::Vector3d heading(1.0, 0.3, 0.1);
  heading.normalize();
  for (int k = 0; k < count; ++k) {
    heading += Eigen::Vector3d(turn(rng), turn(rng), turn(rng)) * 0.3;
    heading.normalize();
    Eigen::Vector3d next = p + step * heading;
    for (int i = 0; i < 3; ++i) {
      if (next[i] < lo[i] || next[i] > hi[i]) {
        heading[i] = -heading[i];
        next[i] = std::clamp(next[i], lo[i], hi[i]);
      }
    }
    p = next;
    Eigen::VectorXd q(joints);
    for (int j = 0; j < joints; ++j) q[j] = std::sin(1.3 * p[j % 3] + 0.7 * j) + 0.5 * p[(j + 1) % 3];
    stream.push_back({p, q});
  }
  return stream;
}

inline void feed(Itm& itm, const std::vector<Sample>& stream) {
  for (const auto& sample : stream) itm.insert(sample.x, sample.q);
}

}  // namespace flexirob::planning::testing
