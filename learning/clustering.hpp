#pragma once
// Study analysis helpers (App. B.4): k-means from given initial centres (Tab. B.1) and a
// classical multi-dimensional scaling to 2-D for plots.
#include <Eigen/Core>
#include <vector>

namespace flexirob::learning {

struct KMeansResult {
  Eigen::MatrixXd centres;      ///< D x K final centres
  std::vector<int> assignment;  ///< cluster of each point, 0...K−1
  int iterations = 0;
  bool converged = false;       ///< assignments stopped changing before max_iterations
  double inertia = 0.0;         ///< Σ squared distances of the points to their centres
};

/// Lloyd's k-means on the columns of `points` (D x L) starting from `initial_centres` (D x K),
/// deterministic (ties go to the lower cluster index). A cluster that loses all its points
/// keeps its previous centre.
KMeansResult kMeans(const Eigen::MatrixXd& points, const Eigen::MatrixXd& initial_centres, int max_iterations = 100);

/// Groups samples into training areas when the data carries no area labels ("leader"
/// clustering in sample order): a sample joins the first area whose first sample lies within
/// `radius` (Euclidean, over the first min(3, D) rows: positions [m]), else it starts a new
/// area. Returns one label per column of X (D x L), 0, 1, ... in order of first appearance.
std::vector<int> inferAreas(const Eigen::MatrixXd& X, double radius);

/// Euclidean distances between the columns of `points` (D x L), L x L.
Eigen::MatrixXd pairwiseDistances(const Eigen::MatrixXd& points);

/// Classical (Torgerson) MDS: coordinates (dims x L) whose pairwise distances best match the
/// symmetric distance matrix `distances` (L x L), from the top eigenpairs of the double-
/// centred squared distances. Exact when the points live in a `dims`-dimensional subspace.
Eigen::MatrixXd classicalMds(const Eigen::MatrixXd& distances, int dims = 2);

}  // namespace flexirob::learning
