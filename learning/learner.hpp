#pragma once
// The learner interface shared by ELM, OS-ELM, LLM and BPDC, the training data they consume,
// the input normalization they store, and cooperative cancellation of long fits.
//
// Notation follows the thesis (Sect. 3.1): inputs x ∈ R^M are task-space positions [m]
// (M = 3) optionally followed by an orientation as a rotation vector [rad] (M = 6); outputs
// y = q ∈ R^N are joint values [rad]. Sample l is column l of X (M x L) and Y (N x L).
#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "learning/model_file.hpp"

namespace flexirob::learning {

/// Largest supported input / output dimension (a guard against absurd files and data).
inline constexpr int kMaxInputDim = 64;
inline constexpr int kMaxOutputDim = 256;

/// Told after each epoch of an iterative fit (LLM, BPDC): the epochs done and the training MSE
/// [rad²] after the last one. Runs on the fitting thread, so it must be quick (a progress line).
using EpochObserver = std::function<void(int epochs, double training_mse)>;

/// Thrown by a fit that saw its cancellation token set.
class TrainingCancelled : public std::runtime_error {
 public:
  TrainingCancelled() : std::runtime_error("training was cancelled") {}
};

/// Set from any thread; long fits poll it between steps and throw TrainingCancelled.
class CancellationToken {
 public:
  void cancel() { cancelled_.store(true, std::memory_order_relaxed); }
  bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }
  void throwIfCancelled() const {
    if (cancelled()) throw TrainingCancelled();
  }
  /// A token nobody cancels (the default argument of fit()).
  static const CancellationToken& never();

 private:
  std::atomic<bool> cancelled_{false};
};

/// Demonstration data D (Eq. 3.1): samples as columns, each tagged with its training area.
struct TrainingSet {
  Eigen::MatrixXd X;      ///< M x L inputs
  Eigen::MatrixXd Y;      ///< N x L targets
  std::vector<int> area;  ///< L area indices >= 0 (empty: every sample in area 0)

  Eigen::Index size() const { return X.cols(); }
  int inputDim() const { return static_cast<int>(X.rows()); }
  int outputDim() const { return static_cast<int>(Y.rows()); }
  /// Area of sample l (0 when no areas are given).
  int areaOf(Eigen::Index l) const { return area.empty() ? 0 : area[static_cast<std::size_t>(l)]; }
  /// Sample indices per area, areas in order of first appearance; each list in sample order.
  std::vector<std::vector<Eigen::Index>> samplesByArea() const;
  /// Throws std::invalid_argument unless non-empty, consistent in size, finite and within
  /// the dimension limits.
  void validate() const;
};

/// Affine input scaling x̃ = (x − offset) ./ scale stored in every model. Positions (the first
/// three inputs) share one scale so that distances keep their geometry (the LLM's Thales rule
/// and the sigmoids see isotropic space); orientation inputs share another.
struct InputNormalization {
  Eigen::VectorXd offset;  ///< M
  Eigen::VectorXd scale;   ///< M, > 0

  /// Centre of the training data's bounding box; scale = half of its largest extent in the
  /// group, but at least `position_floor` [m] / `orientation_floor` [rad], so that data from
  /// a single small area is not blown up.
  static InputNormalization fromData(const Eigen::MatrixXd& X, double position_floor = 0.1,
                                     double orientation_floor = 0.5);
  /// The identity on R^M.
  static InputNormalization identity(int input_dim);
  /// A fixed box [lower, upper] mapped to [-1, 1] with the same grouping rules (used when
  /// learning online before any data is known).
  static InputNormalization fromBox(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

  int dim() const { return static_cast<int>(offset.size()); }
  /// Normalized inputs are clamped to ±kLimit: every learner saturates long before, and it
  /// keeps huge (finite) inputs from overflowing to inf − inf = NaN downstream.
  static constexpr double kLimit = 1e6;
  Eigen::VectorXd apply(const Eigen::Ref<const Eigen::VectorXd>& x) const {
    return (x - offset).cwiseQuotient(scale).cwiseMax(-kLimit).cwiseMin(kLimit);
  }
  Eigen::MatrixXd applyColumns(const Eigen::MatrixXd& X) const;

  void write(ModelWriter& writer) const;
  static InputNormalization read(const ModelReader& reader, int input_dim);
};

/// A learned map ŷ(x): R^M -> R^N.
class Learner {
 public:
  virtual ~Learner() = default;

  /// "elm", "oselm", "llm" or "bpdc" (also the model file's learner field).
  virtual std::string kind() const = 0;
  virtual int inputDim() const = 0;
  virtual int outputDim() const = 0;
  virtual bool trained() const = 0;

  /// Batch training on all of `data`, replacing what was learned before. Long fits poll
  /// `cancel`. Throws std::invalid_argument for inconsistent data.
  virtual void fit(const TrainingSet& data, const CancellationToken& cancel = CancellationToken::never()) = 0;
  /// Whether update() learns one more sample without refitting.
  virtual bool supportsOnlineUpdate() const { return false; }
  /// Learns one sample online (x: M, y: N). Throws std::logic_error if unsupported.
  virtual void update(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y);

  /// ŷ(x) for one input (M) into y (N). Finite for every finite x once trained; throws
  /// std::logic_error before training and std::invalid_argument for a wrong size.
  virtual void predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const = 0;
  Eigen::VectorXd predict(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// Predictions for the columns of X (M x P) as N x P.
  virtual Eigen::MatrixXd predictColumns(const Eigen::MatrixXd& X) const;

  /// Mean squared error of Eq. 3.3 (sum over outputs, mean over samples) on `data`.
  double meanSquaredError(const TrainingSet& data) const;

  /// Writes the whole model (hyper-parameters, dimensions, normalization, seed, weights).
  virtual void write(ModelWriter& writer) const = 0;
  /// The model file's content (ModelReader reads it back; loadLearner reads a file of it).
  std::string modelText() const;

 protected:
  /// Throws unless trained, x has M finite entries and y_size == N.
  void checkPredictArguments(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index y_size) const;
  /// As above for the columns of X.
  void checkPredictColumns(const Eigen::MatrixXd& X) const;
};

/// Loads any learner from a model file; throws ModelFileError for unreadable, damaged or
/// inconsistent files.
std::unique_ptr<Learner> loadLearner(const std::filesystem::path& file);
std::unique_ptr<Learner> readLearner(const ModelReader& reader);

/// Portable uniform random numbers: std::mt19937_64's sequence is fixed by the standard, but
/// std::uniform_real_distribution is not, so the draws below are the same on every platform.
class UniformRandom {
 public:
  explicit UniformRandom(std::uint64_t seed);
  ~UniformRandom();
  UniformRandom(const UniformRandom&) = delete;
  UniformRandom& operator=(const UniformRandom&) = delete;
  /// U[0, 1) with 53 random bits.
  double unit();
  double uniform(double low, double high) { return low + (high - low) * unit(); }
  /// A point of the box [low, high) (same sizes), one draw per coordinate in order.
  Eigen::VectorXd uniform(const Eigen::VectorXd& low, const Eigen::VectorXd& high) {
    if (high.size() != low.size()) throw std::invalid_argument("UniformRandom::uniform: bounds of different sizes");
    Eigen::VectorXd point(low.size());
    for (Eigen::Index i = 0; i < point.size(); ++i) point[i] = uniform(low[i], high[i]);
    return point;
  }
  /// An index in [0, n).
  std::size_t index(std::size_t n);

 private:
  struct Engine;
  std::unique_ptr<Engine> engine_;
};

}  // namespace flexirob::learning
