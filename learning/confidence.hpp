#pragma once
// Confidence model of Sect. 6.3 (Eq. 6.6–6.9): one Gaussian responsibility per training area,
// C(x) = max_k g_k(x) ∈ [0, 1]; with no area yet C ≡ 0.
#include <Eigen/Core>
#include <vector>

#include "learning/learner.hpp"

namespace flexirob::learning {

class ConfidenceModel {
 public:
  /// d scales the covariance (Eq. 6.8; 10 <= d <= 25 works, default 15). min_std [input
  /// units, m] is added as min_std² · d to every variance so that an area with one sample or
  /// with samples on a line or plane still has a proper (invertible) Gaussian.
  explicit ConfidenceModel(double d = 15.0, double min_std = 0.005);

  /// Adds area k from its samples (M x L_k): μ_k (Eq. 6.7), Σ_k (Eq. 6.8).
  void addArea(const Eigen::MatrixXd& samples);
  /// One area per area label of `data`.
  static ConfidenceModel fromTrainingSet(const TrainingSet& data, double d = 15.0, double min_std = 0.005);

  int areas() const { return static_cast<int>(means_.size()); }
  int inputDim() const { return dim_; }
  double d() const { return d_; }
  const Eigen::VectorXd& mean(int k) const { return means_.at(static_cast<std::size_t>(k)); }
  const Eigen::MatrixXd& covariance(int k) const { return covariances_.at(static_cast<std::size_t>(k)); }

  /// C(x) (Eq. 6.9).
  double evaluate(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// C at every column of X (M x P), vectorized per area.
  Eigen::VectorXd evaluateColumns(const Eigen::MatrixXd& X) const;
  /// C on a regular grid over the box [lower, upper] with counts[i] >= 1 points along axis i
  /// (a single point sits at the box centre). Returns the values with axis 0 varying fastest.
  Eigen::VectorXd evaluateGrid(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                               const std::vector<int>& counts) const;

 private:
  double d_;
  double min_std_;
  int dim_ = 0;
  std::vector<Eigen::VectorXd> means_;
  std::vector<Eigen::MatrixXd> covariances_;
  std::vector<Eigen::MatrixXd> factors_;  // L_k with Σ_k = L_k L_kᵀ (Cholesky)
};

}  // namespace flexirob::learning
