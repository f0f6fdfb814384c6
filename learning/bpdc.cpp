#include "learning/bpdc.hpp"

#include <cmath>
#include <limits>
#include <numeric>

namespace flexirob::learning {
namespace {

inline double logistic(double s) {
  if (s >= 0.0) return 1.0 / (1.0 + std::exp(-s));
  const double e = std::exp(s);
  return e / (1.0 + e);
}

// Sparse random matrix: each entry non-zero with probability `density`, then U(−range, range).
Eigen::SparseMatrix<double> sparseRandom(Eigen::Index rows, Eigen::Index cols, double density, double range,
                                         UniformRandom& random) {
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) {
      if (random.unit() < density) entries.emplace_back(r, c, random.uniform(-range, range));
    }
  }
  Eigen::SparseMatrix<double> m(rows, cols);
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

void requireRange(double value, double low, double high, const char* name) {
  if (!(value >= low && value <= high)) {
    throw std::invalid_argument(std::string("BPDC parameter ") + name + ": expected " + std::to_string(low) + "..." +
                                std::to_string(high) + ", got " + std::to_string(value));
  }
}

}  // namespace

void BpdcParams::validate() const {
  if (reservoir < 1 || reservoir > 5000) throw std::invalid_argument("BPDC parameter reservoir: expected 1...5000");
  requireRange(input_density, 0.0, 1.0, "input_density");
  requireRange(recurrent_density, 0.0, 1.0, "recurrent_density");
  requireRange(output_density, 0.0, 1.0, "output_density");
  requireRange(input_range, 0.0, 1e3, "input_range");
  requireRange(recurrent_range, 0.0, 1e3, "recurrent_range");
  requireRange(output_range, 0.0, 1e3, "output_range");
  requireRange(eta, 1e-12, 2.0, "eta");
  requireRange(eta_ip, 0.0, 1.0, "eta_ip");
  requireRange(mu_ip, 1e-3, 0.999, "mu_ip");
  requireRange(input_scale, 1e-6, 1e6, "input_scale");
  if (settle_steps < 1 || settle_steps > 1000) throw std::invalid_argument("BPDC parameter settle_steps: expected 1...1000");
  if (max_epochs < 1 || max_epochs > 1000000) throw std::invalid_argument("BPDC parameter max_epochs: expected 1...1000000");
  if (patience < 1) throw std::invalid_argument("BPDC parameter patience: expected >= 1");
  requireRange(target_mse, 0.0, 1e12, "target_mse");
  requireRange(tolerance, 0.0, 1.0, "tolerance");
}

Bpdc::Bpdc(int input_dim, int output_dim, BpdcParams params)
    : input_dim_(input_dim), output_dim_(output_dim), params_(params) {
  if (input_dim < 1 || input_dim > kMaxInputDim || output_dim < 1 || output_dim > kMaxOutputDim) {
    throw std::invalid_argument("BPDC dimensions: got " + std::to_string(input_dim) + " inputs and " +
                                std::to_string(output_dim) + " outputs");
  }
  params_.validate();
  normalization_ = InputNormalization::identity(input_dim);
  initialize();
}

void Bpdc::initialize() {
  // Fixed random weights of Tab. 3.1, drawn in this order: W_in, W_rec, initial W_out.
  UniformRandom random(params_.seed);
  const int R = params_.reservoir;
  W_in_ = sparseRandom(R, input_dim_, params_.input_density, params_.input_range, random);
  W_rec_ = sparseRandom(R, R, params_.recurrent_density, params_.recurrent_range, random);
  W_out_ = Eigen::MatrixXd(sparseRandom(output_dim_, R, params_.output_density, params_.output_range, random));
  gain_ = Eigen::VectorXd::Ones(R);
  bias_ = Eigen::VectorXd::Zero(R);
  epochs_ = 0;
  history_.clear();
  trained_ = false;
}

void Bpdc::settle(const Eigen::VectorXd& x_normalized, Eigen::VectorXd& s, Eigen::VectorXd& h) const {
  const Eigen::VectorXd input = W_in_ * x_normalized;
  h.setZero(params_.reservoir);
  s.setZero(params_.reservoir);
  for (int step = 0; step < params_.settle_steps; ++step) {
    // Eq. 3.4 with Δt = 1: s(k + 1) = W_in x + W_rec h(k); Eq. 3.5: h = f(s).
    s = input + W_rec_ * h;
    for (Eigen::Index i = 0; i < s.size(); ++i) h[i] = logistic(gain_[i] * s[i] + bias_[i]);
  }
}

void Bpdc::fit(const TrainingSet& data, const CancellationToken& cancel) {
  data.validate();
  if (data.inputDim() != input_dim_ || data.outputDim() != output_dim_) {
    throw std::invalid_argument("BPDC fit: expected data with " + std::to_string(input_dim_) + " inputs and " +
                                std::to_string(output_dim_) + " outputs");
  }
  initialize();
  normalization_ = InputNormalization::fromData(data.X);
  normalization_.scale /= params_.input_scale;
  const Eigen::MatrixXd X = normalization_.applyColumns(data.X);
  const int R = params_.reservoir;
  Eigen::VectorXd s(R), h(R), error(output_dim_);
  const auto evaluate = [&] {
    double sum = 0.0;
    for (Eigen::Index l = 0; l < data.size(); ++l) {
      settle(X.col(l), s, h);
      sum += (W_out_ * h - data.Y.col(l)).squaredNorm();
    }
    return sum / static_cast<double>(data.size());
  };
  double best = std::numeric_limits<double>::infinity();
  int stale = 0;
  trained_ = true;
  while (epochs_ < params_.max_epochs && stale < params_.patience) {
    cancel.throwIfCancelled();
    // Training sweep in recording order (the reservoir's input is a time series).
    for (Eigen::Index l = 0; l < data.size(); ++l) {
      settle(X.col(l), s, h);
      // Eq. 3.6: Δw_ij = η / ‖h‖² h_j (y_i − ŷ_i).
      error = data.Y.col(l) - W_out_ * h;
      W_out_.noalias() += (params_.eta / std::max(h.squaredNorm(), 1e-12)) * error * h.transpose();
      // Eq. 3.7–3.8: intrinsic plasticity of every reservoir neuron.
      for (Eigen::Index i = 0; i < R; ++i) {
        const double delta_b = params_.eta_ip * (1.0 - (2.0 + 1.0 / params_.mu_ip) * h[i] + h[i] * h[i] / params_.mu_ip);
        const double delta_a = params_.eta_ip / gain_[i] + s[i] * delta_b;
        bias_[i] += delta_b;
        gain_[i] = std::max(gain_[i] + delta_a, 1e-3);
      }
    }
    // Evaluation sweep.
    const double mse = evaluate();
    ++epochs_;
    if (!std::isfinite(mse)) throw std::runtime_error("BPDC fit diverged; lower eta");
    history_.push_back(mse);
    if (params_.on_epoch) params_.on_epoch(epochs_, mse);
    if (mse <= params_.target_mse) break;
    stale = mse < best * (1.0 - params_.tolerance) ? 0 : stale + 1;
    best = std::min(best, mse);
  }
}

void Bpdc::predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
  checkPredictArguments(x, y.size());
  Eigen::VectorXd s, h;
  settle(normalization_.apply(x), s, h);
  y.noalias() = W_out_ * h;
}

void Bpdc::write(ModelWriter& writer) const {
  if (!trained_) throw std::logic_error("BPDC: cannot save an untrained model");
  writer.set("input_dim", input_dim_);
  writer.set("output_dim", output_dim_);
  writer.set("reservoir", params_.reservoir);
  writer.set("input_density", params_.input_density);
  writer.set("input_range", params_.input_range);
  writer.set("recurrent_density", params_.recurrent_density);
  writer.set("recurrent_range", params_.recurrent_range);
  writer.set("output_density", params_.output_density);
  writer.set("output_range", params_.output_range);
  writer.set("eta", params_.eta);
  writer.set("eta_ip", params_.eta_ip);
  writer.set("mu_ip", params_.mu_ip);
  writer.set("input_scale", params_.input_scale);
  writer.set("settle_steps", params_.settle_steps);
  writer.set("max_epochs", params_.max_epochs);
  writer.set("target_mse", params_.target_mse);
  writer.set("tolerance", params_.tolerance);
  writer.set("patience", params_.patience);
  writer.set("seed", std::to_string(params_.seed));
  writer.set("epochs", epochs_);
  normalization_.write(writer);
  writer.setMatrix("W_in", Eigen::MatrixXd(W_in_));
  writer.setMatrix("W_rec", Eigen::MatrixXd(W_rec_));
  writer.setMatrix("W_out", W_out_);
  writer.setMatrix("gain", gain_);
  writer.setMatrix("bias", bias_);
}

Bpdc Bpdc::read(const ModelReader& reader) {
  reader.expectKind("bpdc");
  const int M = static_cast<int>(reader.integer("input_dim", 1, kMaxInputDim));
  const int N = static_cast<int>(reader.integer("output_dim", 1, kMaxOutputDim));
  BpdcParams p;
  p.reservoir = static_cast<int>(reader.integer("reservoir", 1, 5000));
  p.input_density = reader.number("input_density");
  p.input_range = reader.number("input_range");
  p.recurrent_density = reader.number("recurrent_density");
  p.recurrent_range = reader.number("recurrent_range");
  p.output_density = reader.number("output_density");
  p.output_range = reader.number("output_range");
  p.eta = reader.number("eta");
  p.eta_ip = reader.number("eta_ip");
  p.mu_ip = reader.number("mu_ip");
  p.input_scale = reader.number("input_scale");
  p.settle_steps = static_cast<int>(reader.integer("settle_steps", 1, 1000));
  p.max_epochs = static_cast<int>(reader.integer("max_epochs", 1, 1000000));
  p.target_mse = reader.number("target_mse");
  p.tolerance = reader.number("tolerance");
  p.patience = static_cast<int>(reader.integer("patience", 1, 1000000));
  p.seed = reader.unsignedInteger("seed");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    reader.fail(e.what());
  }
  Bpdc net(M, N, p);
  net.epochs_ = static_cast<int>(reader.integer("epochs", 0, 1000000));
  net.normalization_ = InputNormalization::read(reader, M);
  net.W_in_ = reader.matrix("W_in", p.reservoir, M).sparseView();
  net.W_rec_ = reader.matrix("W_rec", p.reservoir, p.reservoir).sparseView();
  net.W_out_ = reader.matrix("W_out", N, p.reservoir);
  net.gain_ = reader.matrix("gain", p.reservoir, 1);
  net.bias_ = reader.matrix("bias", p.reservoir, 1);
  if (net.gain_.minCoeff() <= 0.0) reader.fail("BPDC gains must be > 0");
  net.trained_ = true;
  return net;
}

}  // namespace flexirob::learning
