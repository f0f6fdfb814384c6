#include "learning/llm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace flexirob::learning {

double thalesWidth(const Eigen::MatrixXd& centres) {
  const Eigen::Index K = centres.cols();
  if (K < 2) throw std::invalid_argument("thalesWidth: expected at least 2 centres, got " + std::to_string(K));
  if (!centres.allFinite()) throw std::invalid_argument("thalesWidth: non-finite centre");
  double width = 0.0;
  for (Eigen::Index i = 0; i < K; ++i) {
    for (Eigen::Index j = i + 1; j < K; ++j) {
      const double distance = (centres.col(i) - centres.col(j)).norm();
      if (distance <= width) continue;  // cannot raise the maximum
      // Eq. 3.18: no other centre strictly inside the Thales sphere of (c_i, c_j).
      bool empty_sphere = true;
      for (Eigen::Index k = 0; k < K && empty_sphere; ++k) {
        if (k == i || k == j) continue;
        empty_sphere = (centres.col(i) - centres.col(k)).dot(centres.col(j) - centres.col(k)) >= 0.0;
      }
      if (empty_sphere) width = distance;
    }
  }
  return width;
}

void LlmParams::validate() const {
  if (!(eta > 0.0) || !std::isfinite(eta)) throw std::invalid_argument("LLM parameter eta: expected > 0, got " + std::to_string(eta));
  if (max_epochs < 1 || max_epochs > 1000000) {
    throw std::invalid_argument("LLM parameter max_epochs: expected 1...1000000, got " + std::to_string(max_epochs));
  }
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance)) throw std::invalid_argument("LLM parameter tolerance: expected >= 0");
  if (patience < 1) throw std::invalid_argument("LLM parameter patience: expected >= 1, got " + std::to_string(patience));
  if (!(target_mse >= 0.0) || !std::isfinite(target_mse)) throw std::invalid_argument("LLM parameter target_mse: expected >= 0");
}

Llm::Llm(int input_dim, int output_dim, LlmParams params)
    : input_dim_(input_dim), output_dim_(output_dim), params_(params) {
  if (input_dim < 1 || input_dim > kMaxInputDim || output_dim < 1 || output_dim > kMaxOutputDim) {
    throw std::invalid_argument("LLM dimensions: got " + std::to_string(input_dim) + " inputs and " +
                                std::to_string(output_dim) + " outputs");
  }
  params_.validate();
}

void Llm::responsibilities(const Eigen::VectorXd& x_normalized, Eigen::VectorXd& r, Eigen::MatrixXd& u) const {
  const Eigen::Index K = centres_.cols();
  u = (centres_.colwise() - x_normalized) * (-1.0 / width_);  // u_k = (x̃ − c_k) / d
  // g(u) = exp(−‖u‖²) (Eq. 3.16), normalized by n(x) (Eq. 3.15); shifting the exponents by
  // their maximum leaves r unchanged and keeps it finite anywhere in space.
  r = -u.colwise().squaredNorm().transpose();
  const double largest = r.maxCoeff();
  for (Eigen::Index k = 0; k < K; ++k) r[k] = std::exp(r[k] - largest);
  r /= r.sum();
}

void Llm::fit(const TrainingSet& data, const CancellationToken& cancel) {
  data.validate();
  if (data.inputDim() != input_dim_ || data.outputDim() != output_dim_) {
    throw std::invalid_argument("LLM fit: expected data with " + std::to_string(input_dim_) + " inputs and " +
                                std::to_string(output_dim_) + " outputs");
  }
  const int M = input_dim_;
  const int N = output_dim_;
  normalization_ = InputNormalization::fromData(data.X);
  const Eigen::MatrixXd X = normalization_.applyColumns(data.X);

  // One model per area: c_k = x_init, b_k = y_init, W_k = 0.
  const auto areas = data.samplesByArea();
  const auto K = static_cast<Eigen::Index>(areas.size());
  centres_.resize(M, K);
  b_.resize(N, K);
  W_ = Eigen::MatrixXd::Zero(N, K * M);
  for (Eigen::Index k = 0; k < K; ++k) {
    centres_.col(k) = X.col(areas[static_cast<std::size_t>(k)].front());
    b_.col(k) = data.Y.col(areas[static_cast<std::size_t>(k)].front());
  }
  // Width d (Eq. 3.18); with one area the rule has no pair, so the area's own extent is used
  // (any d gives the same map there; this one keeps ‖u‖ <= 1 for the step size).
  if (K >= 2) {
    width_ = thalesWidth(centres_);
  } else {
    width_ = (X.colwise() - centres_.col(0)).colwise().norm().maxCoeff();
  }
  width_ = std::max(width_, 1e-6);  // coincident centres

  // Gradient descent in epochs (Eq. 3.19) on ½‖ŷ − y‖² per sample, samples in random order.
  UniformRandom random(params_.seed);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(data.size()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  Eigen::VectorXd r(K), y_hat(N), error(N);
  Eigen::MatrixXd u(M, K);
  const auto trainingMse = [&] {
    double sum = 0.0;
    for (Eigen::Index l = 0; l < data.size(); ++l) {
      responsibilities(X.col(l), r, u);
      y_hat.setZero();
      for (Eigen::Index k = 0; k < K; ++k) y_hat += r[k] * (W_.middleCols(k * M, M) * u.col(k) + b_.col(k));
      sum += (y_hat - data.Y.col(l)).squaredNorm();
    }
    return sum / static_cast<double>(data.size());
  };
  double best = trainingMse();
  int stale_epochs = 0;
  epochs_ = 0;
  while (epochs_ < params_.max_epochs && best > params_.target_mse && stale_epochs < params_.patience) {
    cancel.throwIfCancelled();
    for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);
    for (const Eigen::Index l : order) {
      responsibilities(X.col(l), r, u);
      y_hat.setZero();
      double input_energy = 0.0;  // Σ_k r_k² (1 + ‖u_k‖²): squared norm of the sample's regressor
      for (Eigen::Index k = 0; k < K; ++k) {
        y_hat += r[k] * (W_.middleCols(k * M, M) * u.col(k) + b_.col(k));
        input_energy += r[k] * r[k] * (1.0 + u.col(k).squaredNorm());
      }
      error = data.Y.col(l) - y_hat;
      // Step η, capped at the normalized-LMS bound 1 / energy so that one sample can never
      // overshoot (it only binds for samples far outside their area, ‖u‖ >~ 3 at η = 0.1).
      const double step = std::min(params_.eta, 1.0 / input_energy);
      for (Eigen::Index k = 0; k < K; ++k) {
        if (r[k] < 1e-12) continue;  // no measurable gradient
        W_.middleCols(k * M, M).noalias() += (step * r[k]) * error * u.col(k).transpose();
        b_.col(k) += (step * r[k]) * error;
      }
    }
    ++epochs_;
    const double mse = trainingMse();
    if (!std::isfinite(mse)) throw std::runtime_error("LLM fit diverged; lower eta");
    if (params_.on_epoch) params_.on_epoch(epochs_, mse);
    if (mse < best * (1.0 - params_.tolerance)) {
      stale_epochs = 0;
    } else {
      ++stale_epochs;
    }
    best = std::min(best, mse);
  }
}

void Llm::predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
  checkPredictArguments(x, y.size());
  const int M = input_dim_;
  Eigen::VectorXd r;
  Eigen::MatrixXd u;
  responsibilities(normalization_.apply(x), r, u);
  // Eq. 3.14 with h_k(u) = W_k u + b_k (Eq. 3.17).
  y.setZero();
  for (Eigen::Index k = 0; k < centres_.cols(); ++k) {
    if (r[k] < 1e-300) continue;
    y.noalias() += r[k] * (W_.middleCols(k * M, M) * u.col(k) + b_.col(k));
  }
}

void Llm::write(ModelWriter& writer) const {
  if (!trained()) throw std::logic_error("LLM: cannot save an untrained model");
  writer.set("input_dim", input_dim_);
  writer.set("output_dim", output_dim_);
  writer.set("models", static_cast<int>(centres_.cols()));
  writer.set("eta", params_.eta);
  writer.set("max_epochs", params_.max_epochs);
  writer.set("tolerance", params_.tolerance);
  writer.set("patience", params_.patience);
  writer.set("target_mse", params_.target_mse);
  writer.set("seed", std::to_string(params_.seed));
  writer.set("width", width_);
  writer.set("epochs", epochs_);
  normalization_.write(writer);
  writer.setMatrix("centres", centres_);
  writer.setMatrix("W", W_);
  writer.setMatrix("b", b_);
}

Llm Llm::read(const ModelReader& reader) {
  reader.expectKind("llm");
  const int M = static_cast<int>(reader.integer("input_dim", 1, kMaxInputDim));
  const int N = static_cast<int>(reader.integer("output_dim", 1, kMaxOutputDim));
  const auto K = static_cast<Eigen::Index>(reader.integer("models", 1, 100000));
  LlmParams params;
  params.eta = reader.number("eta");
  params.max_epochs = static_cast<int>(reader.integer("max_epochs", 1, 1000000));
  params.tolerance = reader.number("tolerance");
  params.patience = static_cast<int>(reader.integer("patience", 1, 1000000));
  params.target_mse = reader.number("target_mse");
  params.seed = reader.unsignedInteger("seed");
  try {
    params.validate();
  } catch (const std::invalid_argument& e) {
    reader.fail(e.what());
  }
  Llm llm(M, N, params);
  llm.width_ = reader.number("width");
  if (!(llm.width_ > 0.0)) reader.fail("width must be > 0");
  llm.epochs_ = static_cast<int>(reader.integer("epochs", 0, 1000000));
  llm.normalization_ = InputNormalization::read(reader, M);
  llm.centres_ = reader.matrix("centres", M, K);
  llm.W_ = reader.matrix("W", N, K * M);
  llm.b_ = reader.matrix("b", N, K);
  return llm;
}

}  // namespace flexirob::learning
