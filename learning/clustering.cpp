#include "learning/clustering.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace flexirob::learning {

KMeansResult kMeans(const Eigen::MatrixXd& points, const Eigen::MatrixXd& initial_centres, int max_iterations) {
  if (points.cols() == 0) throw std::invalid_argument("k-means: no points");
  if (initial_centres.cols() == 0) throw std::invalid_argument("k-means: no initial centres");
  if (initial_centres.rows() != points.rows()) {
    throw std::invalid_argument("k-means: centres of dimension " + std::to_string(initial_centres.rows()) + ", points of " +
                                std::to_string(points.rows()));
  }
  if (max_iterations < 1) throw std::invalid_argument("k-means: max_iterations must be >= 1");
  if (!points.allFinite() || !initial_centres.allFinite()) throw std::invalid_argument("k-means: non-finite input");
  const Eigen::Index L = points.cols();
  const Eigen::Index K = initial_centres.cols();
  KMeansResult result;
  result.centres = initial_centres;
  result.assignment.assign(static_cast<std::size_t>(L), -1);
  for (result.iterations = 0; result.iterations < max_iterations;) {
    // Assignment step: nearest centre.
    bool changed = false;
    result.inertia = 0.0;
    for (Eigen::Index l = 0; l < L; ++l) {
      Eigen::Index best = 0;
      const double distance = (result.centres.colwise() - points.col(l)).colwise().squaredNorm().minCoeff(&best);
      result.inertia += distance;
      int& assigned = result.assignment[static_cast<std::size_t>(l)];
      if (assigned != static_cast<int>(best)) {
        assigned = static_cast<int>(best);
        changed = true;
      }
    }
    ++result.iterations;
    if (!changed) {
      result.converged = true;
      break;
    }
    // Update step: centre = mean of its points.
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(points.rows(), K);
    Eigen::VectorXd counts = Eigen::VectorXd::Zero(K);
    for (Eigen::Index l = 0; l < L; ++l) {
      const int k = result.assignment[static_cast<std::size_t>(l)];
      sums.col(k) += points.col(l);
      counts[k] += 1.0;
    }
    for (Eigen::Index k = 0; k < K; ++k) {
      if (counts[k] > 0.0) result.centres.col(k) = sums.col(k) / counts[k];
    }
  }
  return result;
}

std::vector<int> inferAreas(const Eigen::MatrixXd& X, double radius) {
  if (!(radius > 0.0) || !std::isfinite(radius)) throw std::invalid_argument("inferAreas: radius must be > 0");
  const Eigen::Index rows = std::min<Eigen::Index>(3, X.rows());
  std::vector<Eigen::Index> leaders;  // first sample of each area
  std::vector<int> labels(static_cast<std::size_t>(X.cols()));
  for (Eigen::Index l = 0; l < X.cols(); ++l) {
    int label = -1;
    for (std::size_t k = 0; k < leaders.size() && label < 0; ++k) {
      if ((X.col(l).head(rows) - X.col(leaders[k]).head(rows)).norm() <= radius) label = static_cast<int>(k);
    }
    if (label < 0) {
      label = static_cast<int>(leaders.size());
      leaders.push_back(l);
    }
    labels[static_cast<std::size_t>(l)] = label;
  }
  return labels;
}

Eigen::MatrixXd pairwiseDistances(const Eigen::MatrixXd& points) {
  const Eigen::Index L = points.cols();
  Eigen::MatrixXd distances(L, L);
  for (Eigen::Index i = 0; i < L; ++i) {
    distances(i, i) = 0.0;
    for (Eigen::Index j = i + 1; j < L; ++j) distances(i, j) = distances(j, i) = (points.col(i) - points.col(j)).norm();
  }
  return distances;
}

Eigen::MatrixXd classicalMds(const Eigen::MatrixXd& distances, int dims) {
  const Eigen::Index L = distances.rows();
  if (distances.cols() != L || L == 0) throw std::invalid_argument("MDS: expected a non-empty square distance matrix");
  if (dims < 1 || dims > L) throw std::invalid_argument("MDS: dims must be in 1..." + std::to_string(L));
  if (!distances.allFinite() || distances.minCoeff() < 0.0) throw std::invalid_argument("MDS: distances must be finite and >= 0");
  if ((distances - distances.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(1.0, distances.maxCoeff())) {
    throw std::invalid_argument("MDS: the distance matrix is not symmetric");
  }
  // B = −½ J D⁽²⁾ J with the centring matrix J = I − 11ᵀ/L.
  const Eigen::MatrixXd squared = distances.array().square().matrix();
  const Eigen::VectorXd row_means = squared.rowwise().mean();
  const double grand_mean = row_means.mean();
  Eigen::MatrixXd B = -0.5 * ((squared.colwise() - row_means).rowwise() - row_means.transpose());
  B.array() -= 0.5 * grand_mean;
  // Coordinates from the largest eigenpairs: X = Λ^½ Vᵀ (negative eigenvalues -> 0).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(B);
  if (eigen.info() != Eigen::Success) throw std::runtime_error("MDS: eigen decomposition failed");
  Eigen::MatrixXd coordinates(dims, L);
  for (int d = 0; d < dims; ++d) {
    const Eigen::Index index = L - 1 - d;  // eigenvalues ascend
    const double lambda = std::max(eigen.eigenvalues()[index], 0.0);
    coordinates.row(d) = std::sqrt(lambda) * eigen.eigenvectors().col(index).transpose();
  }
  return coordinates;
}

}  // namespace flexirob::learning
