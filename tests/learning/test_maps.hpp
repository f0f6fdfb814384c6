#pragma once
// Known smooth maps and synthetic training areas for the learning tests.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "learning/learner.hpp"

namespace flexirob::learning::testing {

/// A smooth posture map R^3 -> R^N [rad] over the thesis' evaluation grid
/// G = [−0.9, 0] x [−0.55, 0.55] x [0.05, 0.8] m: low-frequency trigonometric terms plus a slope.
inline Eigen::VectorXd smoothMap(const Eigen::Vector3d& x, int N) {
  Eigen::VectorXd q(N);
  for (int j = 0; j < N; ++j) {
    q[j] = 0.1 * j - 0.3 + 0.5 * std::sin(1.5 * x[0] + 0.7 * j) + 0.4 * std::cos(2.0 * x[1] - 0.4 * j) +
           0.6 * x[2] * (j % 2 == 0 ? 1.0 : -1.0);
  }
  return q;
}

/// `per_area` samples on a small helix (radius `radius` m, height 2 radius) around each centre,
/// like the tutor's circles in RECORDING; the first sample of each area is its centre.
inline TrainingSet helixAreas(const std::vector<Eigen::Vector3d>& centres, int per_area, int N, double radius = 0.05) {
  TrainingSet data;
  const auto K = static_cast<Eigen::Index>(centres.size());
  data.X.resize(3, K * per_area);
  data.Y.resize(N, K * per_area);
  for (Eigen::Index k = 0; k < K; ++k) {
    for (int l = 0; l < per_area; ++l) {
      const double t = per_area > 1 ? static_cast<double>(l) / (per_area - 1) : 0.0;
      const double angle = 6.0 * M_PI * t;
      Eigen::Vector3d x = centres[static_cast<std::size_t>(k)];
      if (l > 0) x += Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), radius * (2.0 * t - 1.0));
      const Eigen::Index column = k * per_area + l;
      data.X.col(column) = x;
      data.Y.col(column) = smoothMap(x, N);
      data.area.push_back(static_cast<int>(k));
    }
  }
  return data;
}

/// Six training areas spread over G.
inline std::vector<Eigen::Vector3d> sixAreaCentres() {
  return {{-0.7, -0.4, 0.3}, {-0.7, 0.4, 0.3}, {-0.3, -0.4, 0.6}, {-0.3, 0.4, 0.6}, {-0.5, 0.0, 0.15}, {-0.5, 0.0, 0.7}};
}

/// Largest Euclidean error of `learner` against smoothMap at the columns of X.
inline double maxError(const Learner& learner, const Eigen::MatrixXd& X, int N) {
  double worst = 0.0;
  for (Eigen::Index l = 0; l < X.cols(); ++l) {
    const Eigen::Vector3d x = X.col(l);
    worst = std::max(worst, (learner.predict(x) - smoothMap(x, N)).norm());
  }
  return worst;
}

/// Root mean squared joint error [rad] against smoothMap at the columns of X.
inline double rmsJointError(const Learner& learner, const Eigen::MatrixXd& X, int N) {
  double sum = 0.0;
  for (Eigen::Index l = 0; l < X.cols(); ++l) {
    const Eigen::Vector3d x = X.col(l);
    sum += (learner.predict(x) - smoothMap(x, N)).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(X.cols() * N));
}

}  // namespace flexirob::learning::testing
