#include "learning/confidence.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace flexirob::learning {

ConfidenceModel::ConfidenceModel(double d, double min_std) : d_(d), min_std_(min_std) {
  if (!(d > 0.0) || !std::isfinite(d)) throw std::invalid_argument("confidence model: d must be > 0, got " + std::to_string(d));
  if (!(min_std > 0.0) || !std::isfinite(min_std)) {
    throw std::invalid_argument("confidence model: min_std must be > 0, got " + std::to_string(min_std));
  }
}

void ConfidenceModel::addArea(const Eigen::MatrixXd& samples) {
  const Eigen::Index M = samples.rows();
  const Eigen::Index L = samples.cols();
  if (L < 1 || M < 1 || M > kMaxInputDim) throw std::invalid_argument("confidence model: an area needs at least one sample");
  if (!samples.allFinite()) throw std::invalid_argument("confidence model: non-finite sample");
  if (dim_ != 0 && M != dim_) {
    throw std::invalid_argument("confidence model: area of dimension " + std::to_string(M) + ", expected " + std::to_string(dim_));
  }
  // Eq. 6.7: μ_k; Eq. 6.8: Σ_k = d / (L − 1) Σ (x − μ)(x − μ)ᵀ, plus the floor d · min_std² I.
  const Eigen::VectorXd mu = samples.rowwise().mean();
  const Eigen::MatrixXd centred = samples.colwise() - mu;
  Eigen::MatrixXd sigma = Eigen::MatrixXd::Identity(M, M) * (d_ * min_std_ * min_std_);
  if (L > 1) sigma += (d_ / static_cast<double>(L - 1)) * centred * centred.transpose();
  const Eigen::LLT<Eigen::MatrixXd> cholesky(sigma);
  if (cholesky.info() != Eigen::Success) throw std::invalid_argument("confidence model: covariance is not positive definite");
  dim_ = static_cast<int>(M);
  means_.push_back(mu);
  covariances_.push_back(sigma);
  factors_.emplace_back(cholesky.matrixL());
}

ConfidenceModel ConfidenceModel::fromTrainingSet(const TrainingSet& data, double d, double min_std) {
  data.validate();
  ConfidenceModel model(d, min_std);
  for (const auto& samples : data.samplesByArea()) {
    Eigen::MatrixXd area(data.X.rows(), static_cast<Eigen::Index>(samples.size()));
    for (std::size_t i = 0; i < samples.size(); ++i) area.col(static_cast<Eigen::Index>(i)) = data.X.col(samples[i]);
    model.addArea(area);
  }
  return model;
}

double ConfidenceModel::evaluate(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  return evaluateColumns(x)[0];
}

Eigen::VectorXd ConfidenceModel::evaluateColumns(const Eigen::MatrixXd& X) const {
  if (means_.empty()) return Eigen::VectorXd::Zero(X.cols());  // no area taught yet: C ≡ 0
  if (X.rows() != dim_) {
    throw std::invalid_argument("confidence model: points of dimension " + std::to_string(X.rows()) + ", expected " +
                                std::to_string(dim_));
  }
  // Smallest Mahalanobis distance over areas, then one exp: max_k exp(−½ m_k) = exp(−½ min_k m_k).
  Eigen::VectorXd smallest = Eigen::VectorXd::Constant(X.cols(), std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k < means_.size(); ++k) {
    // Eq. 6.6: (x − μ)ᵀ Σ⁻¹ (x − μ) = ‖L⁻¹ (x − μ)‖², by a triangular solve on all points.
    const Eigen::MatrixXd z = factors_[k].triangularView<Eigen::Lower>().solve(X.colwise() - means_[k]);
    smallest = smallest.cwiseMin(z.colwise().squaredNorm().transpose());
  }
  // NaN inputs propagate as NaN distances; report them as "no confidence" rather than NaN.
  return smallest.unaryExpr([](double m) { return std::isnan(m) ? 0.0 : std::exp(-0.5 * m); });
}

Eigen::VectorXd ConfidenceModel::evaluateGrid(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                              const std::vector<int>& counts) const {
  const auto M = static_cast<std::size_t>(lower.size());
  if (upper.size() != lower.size() || counts.size() != M || M == 0) {
    throw std::invalid_argument("confidence grid: lower, upper and counts must have the same dimension");
  }
  if (dim_ != 0 && static_cast<int>(M) != dim_) throw std::invalid_argument("confidence grid: wrong dimension");
  Eigen::Index total = 1;
  for (int c : counts) {
    if (c < 1 || c > 100000) throw std::invalid_argument("confidence grid: counts must be in 1...100000");
    total *= c;
    if (total > 100'000'000) throw std::invalid_argument("confidence grid: more than 1e8 points");
  }
  Eigen::MatrixXd points(static_cast<Eigen::Index>(M), total);
  for (Eigen::Index p = 0; p < total; ++p) {
    Eigen::Index rest = p;
    for (std::size_t i = 0; i < M; ++i) {
      const int n = counts[i];
      const Eigen::Index index = rest % n;
      rest /= n;
      const auto e = static_cast<Eigen::Index>(i);
      points(e, p) = n == 1 ? 0.5 * (lower[e] + upper[e])
                            : lower[e] + (upper[e] - lower[e]) * static_cast<double>(index) / static_cast<double>(n - 1);
    }
  }
  return evaluateColumns(points);
}

}  // namespace flexirob::learning
