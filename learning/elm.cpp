#include "learning/elm.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace flexirob::learning {
namespace {

void requirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("ELM parameter ") + name + ": expected a finite value > 0, got " +
                                std::to_string(value));
  }
}

// Logistic function written so that exp() never overflows for large |s|.
inline double logistic(double s) {
  if (s >= 0.0) return 1.0 / (1.0 + std::exp(-s));
  const double e = std::exp(s);
  return e / (1.0 + e);
}

void requireData(const TrainingSet& data, int input_dim, int output_dim, const char* who) {
  data.validate();
  if (data.inputDim() != input_dim || data.outputDim() != output_dim) {
    throw std::invalid_argument(std::string(who) + ": expected data with " + std::to_string(input_dim) + " inputs and " +
                                std::to_string(output_dim) + " outputs, got " + std::to_string(data.inputDim()) + " and " +
                                std::to_string(data.outputDim()));
  }
}

void requireDims(int input_dim, int output_dim) {
  if (input_dim < 1 || input_dim > kMaxInputDim || output_dim < 1 || output_dim > kMaxOutputDim) {
    throw std::invalid_argument("learner dimensions: expected 1..." + std::to_string(kMaxInputDim) + " inputs and 1..." +
                                std::to_string(kMaxOutputDim) + " outputs, got " + std::to_string(input_dim) + " and " +
                                std::to_string(output_dim));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
void ElmParams::validate() const {
  if (hidden < 1 || hidden > 5000) {
    throw std::invalid_argument("ELM parameter hidden: expected 1...5000 neurons, got " + std::to_string(hidden));
  }
  requirePositive(epsilon, "epsilon");
  requirePositive(input_weight_range, "input_weight_range");
  requirePositive(gain_min, "gain_min");
  requirePositive(bias_range, "bias_range");
  if (!(gain_max >= gain_min) || !std::isfinite(gain_max)) {
    throw std::invalid_argument("ELM parameter gain_max: expected >= gain_min, got " + std::to_string(gain_max));
  }
}

void ElmParams::write(ModelWriter& writer) const {
  writer.set("hidden", hidden);
  writer.set("epsilon", epsilon);
  writer.set("seed", std::to_string(seed));
  writer.set("input_weight_range", input_weight_range);
  writer.set("gain_min", gain_min);
  writer.set("gain_max", gain_max);
  writer.set("bias_range", bias_range);
}

ElmParams ElmParams::read(const ModelReader& reader) {
  ElmParams params;
  params.hidden = static_cast<int>(reader.integer("hidden", 1, 5000));
  params.epsilon = reader.number("epsilon");
  params.seed = reader.unsignedInteger("seed");
  params.input_weight_range = reader.number("input_weight_range");
  params.gain_min = reader.number("gain_min");
  params.gain_max = reader.number("gain_max");
  params.bias_range = reader.number("bias_range");
  try {
    params.validate();
  } catch (const std::invalid_argument& e) {
    reader.fail(e.what());
  }
  return params;
}

// ---------------------------------------------------------------------------------------------
RandomFeatures::RandomFeatures(int input_dim, const ElmParams& params, InputNormalization normalization)
    : normalization_(std::move(normalization)) {
  params.validate();
  if (normalization_.dim() != input_dim) {
    throw std::invalid_argument("random features: normalization has " + std::to_string(normalization_.dim()) +
                                " inputs, expected " + std::to_string(input_dim));
  }
  // Draw order is part of the documented seed contract (ElmParams).
  UniformRandom random(params.seed);
  W_in_.resize(params.hidden, input_dim);
  for (int i = 0; i < params.hidden; ++i) {
    for (int j = 0; j < input_dim; ++j) W_in_(i, j) = random.uniform(-params.input_weight_range, params.input_weight_range);
  }
  gain_.resize(params.hidden);
  bias_.resize(params.hidden);
  for (int i = 0; i < params.hidden; ++i) gain_[i] = random.uniform(params.gain_min, params.gain_max);
  for (int i = 0; i < params.hidden; ++i) bias_[i] = random.uniform(-params.bias_range, params.bias_range);
}

void RandomFeatures::compute(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> h) const {
  // Eq. 3.9: h = f(W_in x̃) with f_i(s) = 1 / (1 + exp(−a_i s − b_i)).
  h.noalias() = W_in_ * normalization_.apply(x);
  for (Eigen::Index i = 0; i < h.size(); ++i) h[i] = logistic(gain_[i] * h[i] + bias_[i]);
}

Eigen::MatrixXd RandomFeatures::computeColumns(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd H = W_in_ * normalization_.applyColumns(X);
  for (Eigen::Index l = 0; l < H.cols(); ++l) {
    for (Eigen::Index i = 0; i < H.rows(); ++i) H(i, l) = logistic(gain_[i] * H(i, l) + bias_[i]);
  }
  return H;
}

void RandomFeatures::write(ModelWriter& writer) const {
  normalization_.write(writer);
  writer.setMatrix("W_in", W_in_);
  writer.setMatrix("gain", gain_);
  writer.setMatrix("bias", bias_);
}

RandomFeatures RandomFeatures::read(const ModelReader& reader, int input_dim, int hidden) {
  RandomFeatures features;
  features.normalization_ = InputNormalization::read(reader, input_dim);
  features.W_in_ = reader.matrix("W_in", hidden, input_dim);
  features.gain_ = reader.matrix("gain", hidden, 1);
  features.bias_ = reader.matrix("bias", hidden, 1);
  return features;
}

// ---------------------------------------------------------------------------------------------
Eigen::MatrixXd ridgeReadout(const Eigen::MatrixXd& H, const Eigen::MatrixXd& Y, double epsilon) {
  if (H.cols() != Y.cols()) throw std::invalid_argument("ridgeReadout: H and Y differ in sample count");
  if (!(epsilon > 0.0)) throw std::invalid_argument("ridgeReadout: epsilon must be > 0");
  const Eigen::Index R = H.rows();
  const Eigen::Index L = H.cols();
  if (L >= R) {
    // Primal form, Eq. 3.13: (H Hᵀ + εI) W_outᵀ = H Yᵀ. H Hᵀ by a symmetric rank-L update.
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(R, R) * epsilon;
    A.selfadjointView<Eigen::Lower>().rankUpdate(H);
    const Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> solver(A);
    return solver.solve(H * Y.transpose()).transpose();
  }
  // Dual form with fewer samples than neurons: Y Hᵀ (H Hᵀ + εI)⁻¹ = Y (HᵀH + εI)⁻¹ Hᵀ.
  Eigen::MatrixXd G = Eigen::MatrixXd::Identity(L, L) * epsilon;
  G.selfadjointView<Eigen::Lower>().rankUpdate(H.transpose());
  const Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> solver(G);
  return solver.solve(Y.transpose()).transpose() * H.transpose();
}

// ---------------------------------------------------------------------------------------------
Elm::Elm(int input_dim, int output_dim, ElmParams params)
    : input_dim_(input_dim), output_dim_(output_dim), params_(params) {
  requireDims(input_dim, output_dim);
  params_.validate();
}

void Elm::fit(const TrainingSet& data, const CancellationToken& cancel) {
  requireData(data, input_dim_, output_dim_, "ELM fit");
  fit(data, InputNormalization::fromData(data.X), cancel);
}

void Elm::fit(const TrainingSet& data, const InputNormalization& normalization, const CancellationToken& cancel) {
  requireData(data, input_dim_, output_dim_, "ELM fit");
  cancel.throwIfCancelled();
  RandomFeatures features(input_dim_, params_, normalization);
  const Eigen::Index R = params_.hidden;
  const Eigen::Index L = data.size();
  Eigen::MatrixXd W_out;
  if (L < R) {
    W_out = ridgeReadout(features.computeColumns(data.X), data.Y, params_.epsilon);
  } else {
    // Eq. 3.13 with H Hᵀ and H Yᵀ accumulated over blocks of samples: memory stays O(R²)
    // however long the recording, and cancellation is polled between blocks.
    constexpr Eigen::Index kBlock = 2048;
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(R, R) * params_.epsilon;
    Eigen::MatrixXd HYt = Eigen::MatrixXd::Zero(R, output_dim_);
    for (Eigen::Index begin = 0; begin < L; begin += kBlock) {
      cancel.throwIfCancelled();
      const Eigen::Index count = std::min(kBlock, L - begin);
      const Eigen::MatrixXd H = features.computeColumns(data.X.middleCols(begin, count));
      A.selfadjointView<Eigen::Lower>().rankUpdate(H);
      HYt.noalias() += H * data.Y.middleCols(begin, count).transpose();
    }
    cancel.throwIfCancelled();
    const Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> solver(A);
    W_out = solver.solve(HYt).transpose();
  }
  if (!W_out.allFinite()) throw std::runtime_error("ELM fit: the ridge system is numerically singular; increase epsilon");
  features_ = std::move(features);
  W_out_ = std::move(W_out);
  trained_ = true;
}

void Elm::predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
  checkPredictArguments(x, y.size());
  Eigen::VectorXd h(W_out_.cols());
  features_.compute(x, h);
  y.noalias() = W_out_ * h;  // Eq. 3.10
}

Eigen::MatrixXd Elm::predictColumns(const Eigen::MatrixXd& X) const {
  checkPredictColumns(X);
  return W_out_ * features_.computeColumns(X);
}

void Elm::write(ModelWriter& writer) const {
  if (!trained_) throw std::logic_error("ELM: cannot save an untrained model");
  writer.set("input_dim", input_dim_);
  writer.set("output_dim", output_dim_);
  params_.write(writer);
  features_.write(writer);
  writer.setMatrix("W_out", W_out_);
}

Elm Elm::read(const ModelReader& reader) {
  reader.expectKind("elm");
  const int input_dim = static_cast<int>(reader.integer("input_dim", 1, kMaxInputDim));
  const int output_dim = static_cast<int>(reader.integer("output_dim", 1, kMaxOutputDim));
  Elm elm(input_dim, output_dim, ElmParams::read(reader));
  elm.features_ = RandomFeatures::read(reader, input_dim, elm.params_.hidden);
  elm.W_out_ = reader.matrix("W_out", output_dim, elm.params_.hidden);
  elm.trained_ = true;
  return elm;
}

// ---------------------------------------------------------------------------------------------
OsElm::OsElm(int input_dim, int output_dim, InputNormalization normalization, ElmParams params)
    : output_dim_(output_dim), params_(params) {
  requireDims(input_dim, output_dim);
  features_ = RandomFeatures(input_dim, params_, std::move(normalization));
  reset();
}

void OsElm::reset() {
  const int R = params_.hidden;
  W_out_ = Eigen::MatrixXd::Zero(output_dim_, R);                 // W_0 = 0
  P_ = Eigen::MatrixXd::Identity(R, R) / params_.epsilon;        // P_0 = (εI)⁻¹
  samples_ = 0;
  h_.resize(R);
  Ph_.resize(R);
  residual_.resize(output_dim_);
}

void OsElm::fit(const TrainingSet& data, const CancellationToken& cancel) {
  requireData(data, inputDim(), output_dim_, "OS-ELM fit");
  features_ = RandomFeatures(inputDim(), params_, InputNormalization::fromData(data.X));
  reset();
  for (Eigen::Index l = 0; l < data.size(); ++l) {
    if (l % 64 == 0) cancel.throwIfCancelled();
    update(data.X.col(l), data.Y.col(l));
  }
}

void OsElm::update(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (x.size() != inputDim() || y.size() != output_dim_) {
    throw std::invalid_argument("OS-ELM update: expected x of size " + std::to_string(inputDim()) + " and y of size " +
                                std::to_string(output_dim_));
  }
  if (!x.allFinite() || !y.allFinite()) throw std::invalid_argument("OS-ELM update: non-finite sample");
  features_.compute(x, h_);
  // Eq. 6.5: P_{k+1} = P_k − P_k h hᵀ P_k / (1 + hᵀ P_k h), on the lower triangle.
  Ph_.noalias() = P_.selfadjointView<Eigen::Lower>() * h_;
  const double denominator = 1.0 + h_.dot(Ph_);
  P_.selfadjointView<Eigen::Lower>().rankUpdate(Ph_, -1.0 / denominator);
  // Eq. 6.4: W_{k+1} = W_k + (y − W_k h) hᵀ P_{k+1}, where P_{k+1} h = P_k h / (1 + hᵀ P_k h).
  residual_.noalias() = y - W_out_ * h_;
  W_out_.noalias() += (residual_ / denominator) * Ph_.transpose();
  ++samples_;
}

void OsElm::predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const {
  checkPredictArguments(x, y.size());
  Eigen::VectorXd h(params_.hidden);
  features_.compute(x, h);
  y.noalias() = W_out_ * h;  // Eq. 6.3
}

void OsElm::write(ModelWriter& writer) const {
  writer.set("input_dim", inputDim());
  writer.set("output_dim", output_dim_);
  writer.set("samples", samples_);
  params_.write(writer);
  features_.write(writer);
  writer.setMatrix("W_out", W_out_);
  // The full P (not only its lower triangle) so that online learning resumes after loading.
  writer.setMatrix("P", Eigen::MatrixXd(P_.selfadjointView<Eigen::Lower>()));
}

OsElm OsElm::read(const ModelReader& reader) {
  reader.expectKind("oselm");
  const int input_dim = static_cast<int>(reader.integer("input_dim", 1, kMaxInputDim));
  const int output_dim = static_cast<int>(reader.integer("output_dim", 1, kMaxOutputDim));
  const ElmParams params = ElmParams::read(reader);
  OsElm model(input_dim, output_dim, InputNormalization::identity(input_dim), params);
  model.features_ = RandomFeatures::read(reader, input_dim, params.hidden);
  model.W_out_ = reader.matrix("W_out", output_dim, params.hidden);
  model.P_ = reader.matrix("P", params.hidden, params.hidden);
  model.samples_ = reader.integer("samples", 0, std::numeric_limits<std::int64_t>::max());
  return model;
}

}  // namespace flexirob::learning
