#include "learning/learner.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "learning/bpdc.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"

namespace flexirob::learning {

const CancellationToken& CancellationToken::never() {
  static const CancellationToken token;
  return token;
}

// ---------------------------------------------------------------------------------------------
std::vector<std::vector<Eigen::Index>> TrainingSet::samplesByArea() const {
  std::vector<std::vector<Eigen::Index>> groups;
  std::map<int, std::size_t> group_of_area;
  for (Eigen::Index l = 0; l < size(); ++l) {
    const auto [it, inserted] = group_of_area.emplace(areaOf(l), groups.size());
    if (inserted) groups.emplace_back();
    groups[it->second].push_back(l);
  }
  return groups;
}

void TrainingSet::validate() const {
  if (X.cols() == 0) throw std::invalid_argument("training data: no samples");
  if (Y.cols() != X.cols()) {
    throw std::invalid_argument("training data: " + std::to_string(X.cols()) + " inputs but " + std::to_string(Y.cols()) +
                                " targets");
  }
  if (X.rows() < 1 || X.rows() > kMaxInputDim) {
    throw std::invalid_argument("training data: expected 1..." + std::to_string(kMaxInputDim) + " input dimensions, got " +
                                std::to_string(X.rows()));
  }
  if (Y.rows() < 1 || Y.rows() > kMaxOutputDim) {
    throw std::invalid_argument("training data: expected 1..." + std::to_string(kMaxOutputDim) +
                                " output dimensions, got " + std::to_string(Y.rows()));
  }
  if (!area.empty() && static_cast<Eigen::Index>(area.size()) != X.cols()) {
    throw std::invalid_argument("training data: " + std::to_string(area.size()) + " area labels for " +
                                std::to_string(X.cols()) + " samples");
  }
  for (int a : area) {
    if (a < 0) throw std::invalid_argument("training data: area indices must be >= 0, got " + std::to_string(a));
  }
  if (!X.allFinite() || !Y.allFinite()) throw std::invalid_argument("training data: non-finite values");
}

// ---------------------------------------------------------------------------------------------
namespace {

// Inputs 0..2 are positions, 3.. orientation; each group gets one common scale.
void groupScale(const Eigen::VectorXd& half_extent, Eigen::VectorXd& scale, double position_floor,
                double orientation_floor) {
  const Eigen::Index M = half_extent.size();
  const Eigen::Index positions = std::min<Eigen::Index>(3, M);
  const double position_scale = std::max(half_extent.head(positions).maxCoeff(), position_floor);
  scale.resize(M);
  scale.head(positions).setConstant(position_scale);
  if (M > positions) {
    const double orientation_scale = std::max(half_extent.tail(M - positions).maxCoeff(), orientation_floor);
    scale.tail(M - positions).setConstant(orientation_scale);
  }
}

}  // namespace

InputNormalization InputNormalization::fromData(const Eigen::MatrixXd& X, double position_floor, double orientation_floor) {
  if (X.cols() == 0 || X.rows() == 0) throw std::invalid_argument("input normalization: no data");
  if (!(position_floor > 0.0) || !(orientation_floor > 0.0)) throw std::invalid_argument("input normalization: floors must be > 0");
  const Eigen::VectorXd lower = X.rowwise().minCoeff();
  const Eigen::VectorXd upper = X.rowwise().maxCoeff();
  InputNormalization n;
  n.offset = 0.5 * (lower + upper);
  groupScale(0.5 * (upper - lower), n.scale, position_floor, orientation_floor);
  return n;
}

InputNormalization InputNormalization::identity(int input_dim) {
  return {Eigen::VectorXd::Zero(input_dim), Eigen::VectorXd::Ones(input_dim)};
}

InputNormalization InputNormalization::fromBox(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  if (lower.size() != upper.size() || lower.size() == 0 || !lower.allFinite() || !upper.allFinite() ||
      (upper - lower).minCoeff() <= 0.0) {
    throw std::invalid_argument("input normalization: expected a box with lower < upper in every dimension");
  }
  InputNormalization n;
  n.offset = 0.5 * (lower + upper);
  groupScale(0.5 * (upper - lower), n.scale, 1e-9, 1e-9);
  return n;
}

Eigen::MatrixXd InputNormalization::applyColumns(const Eigen::MatrixXd& X) const {
  return ((X.colwise() - offset).array().colwise() / scale.array()).cwiseMax(-kLimit).cwiseMin(kLimit);
}

void InputNormalization::write(ModelWriter& writer) const {
  writer.setMatrix("input_offset", offset);
  writer.setMatrix("input_scale", scale);
}

InputNormalization InputNormalization::read(const ModelReader& reader, int input_dim) {
  InputNormalization n;
  n.offset = reader.matrix("input_offset", input_dim, 1);
  n.scale = reader.matrix("input_scale", input_dim, 1);
  if (n.scale.minCoeff() <= 0.0) reader.fail("input_scale must be > 0");
  return n;
}

// ---------------------------------------------------------------------------------------------
void Learner::update(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&) {
  throw std::logic_error(kind() + ": online update is not supported; use fit()");
}

void Learner::checkPredictArguments(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index y_size) const {
  if (!trained()) throw std::logic_error(kind() + ": predict before training");
  const Eigen::Index x_size = x.size();
  if (x_size != inputDim() || y_size != outputDim()) {
    throw std::invalid_argument(kind() + " predict: expected input of size " + std::to_string(inputDim()) +
                                " and output of size " + std::to_string(outputDim()) + ", got " + std::to_string(x_size) +
                                " and " + std::to_string(y_size));
  }
  if (!x.allFinite()) throw std::invalid_argument(kind() + " predict: non-finite input");
}

void Learner::checkPredictColumns(const Eigen::MatrixXd& X) const {
  if (!trained()) throw std::logic_error(kind() + ": predict before training");
  if (X.rows() != inputDim()) {
    throw std::invalid_argument(kind() + " predict: expected inputs of size " + std::to_string(inputDim()) + ", got " +
                                std::to_string(X.rows()));
  }
  if (!X.allFinite()) throw std::invalid_argument(kind() + " predict: non-finite input");
}

Eigen::VectorXd Learner::predict(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::VectorXd y(outputDim());
  predict(x, y);
  return y;
}

Eigen::MatrixXd Learner::predictColumns(const Eigen::MatrixXd& X) const {
  checkPredictColumns(X);
  Eigen::MatrixXd Y(outputDim(), X.cols());
  Eigen::VectorXd y(outputDim());
  for (Eigen::Index l = 0; l < X.cols(); ++l) {
    predict(X.col(l), y);
    Y.col(l) = y;
  }
  return Y;
}

double Learner::meanSquaredError(const TrainingSet& data) const {
  data.validate();
  // Eq. 3.3: mean over samples of the squared Euclidean error.
  return (predictColumns(data.X) - data.Y).colwise().squaredNorm().mean();
}

std::string Learner::modelText() const {
  ModelWriter writer(kind());
  write(writer);
  return writer.text();
}

std::unique_ptr<Learner> readLearner(const ModelReader& reader) {
  const std::string& kind = reader.learnerKind();
  if (kind == "elm") return std::make_unique<Elm>(Elm::read(reader));
  if (kind == "oselm") return std::make_unique<OsElm>(OsElm::read(reader));
  if (kind == "llm") return std::make_unique<Llm>(Llm::read(reader));
  if (kind == "bpdc") return std::make_unique<Bpdc>(Bpdc::read(reader));
  reader.fail("unknown learner '" + kind + "' (expected elm, oselm, llm or bpdc)");
}

std::unique_ptr<Learner> loadLearner(const std::filesystem::path& file) { return readLearner(ModelReader::fromFile(file)); }

// ---------------------------------------------------------------------------------------------
struct UniformRandom::Engine {
  std::mt19937_64 generator;
};

UniformRandom::UniformRandom(std::uint64_t seed) : engine_(std::make_unique<Engine>()) { engine_->generator.seed(seed); }
UniformRandom::~UniformRandom() = default;

double UniformRandom::unit() { return static_cast<double>(engine_->generator() >> 11) * 0x1.0p-53; }

std::size_t UniformRandom::index(std::size_t n) {
  if (n == 0) throw std::invalid_argument("UniformRandom::index: empty range");
  return static_cast<std::size_t>(unit() * static_cast<double>(n)) % n;
}

}  // namespace flexirob::learning
