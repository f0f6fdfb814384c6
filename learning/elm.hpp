#pragma once
// Extreme learning machine (Sect. 3.2.1, Eq. 3.9–3.13) and its online sequential variant
// OS-ELM (Sect. 6.2, Eq. 6.3–6.5). Both share the fixed random hidden layer below, so an
// OS-ELM that has seen the same samples equals the batch ridge ELM.
#include <Eigen/Core>
#include <cstdint>

#include "learning/learner.hpp"

namespace flexirob::learning {

/// Hyper-parameters of the random hidden layer and the read-out.
/// Random draws (all uniform, from UniformRandom(seed), in this order):
///   W_in(i, j) ~ U(−input_weight_range, input_weight_range)   row by row, R x M
///   a_i        ~ U(gain_min, gain_max)                        slope of neuron i
///   b_i        ~ U(−bias_range, bias_range)                   bias of neuron i
/// Inputs are normalized first (InputNormalization, about [−1, 1] over the training data).
struct ElmParams {
  int hidden = 100;                 ///< R: see docs/LEARNING.md for the measurement behind it
  double epsilon = 0.01;            ///< ridge ε of Eq. 3.12/3.13 (thesis default, Tab. 3.4)
  std::uint64_t seed = 1;
  double input_weight_range = 0.5;  ///< smoother maps between and beyond the areas: docs/LEARNING.md
  double gain_min = 1.0;
  double gain_max = 2.0;
  double bias_range = 1.0;

  /// Throws std::invalid_argument naming the first parameter out of range.
  void validate() const;
  void write(ModelWriter& writer) const;
  static ElmParams read(const ModelReader& reader);
};

/// h(x) = f(W_in x̃), f_i(s) = 1 / (1 + exp(−a_i s − b_i)) (Eq. 3.9) with x̃ the normalized input.
class RandomFeatures {
 public:
  RandomFeatures() = default;
  /// Draws W_in, a, b from params.seed.
  RandomFeatures(int input_dim, const ElmParams& params, InputNormalization normalization);

  int inputDim() const { return static_cast<int>(W_in_.cols()); }
  int hiddenDim() const { return static_cast<int>(W_in_.rows()); }
  const InputNormalization& normalization() const { return normalization_; }

  /// h(x) into h (R).
  void compute(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> h) const;
  /// H = (h_1, ..., h_L), R x L, for the columns of X (M x L).
  Eigen::MatrixXd computeColumns(const Eigen::MatrixXd& X) const;

  void write(ModelWriter& writer) const;
  static RandomFeatures read(const ModelReader& reader, int input_dim, int hidden);

 private:
  InputNormalization normalization_;
  Eigen::MatrixXd W_in_;  // R x M
  Eigen::VectorXd gain_;  // a, R
  Eigen::VectorXd bias_;  // b, R
};

/// W_out = Y Hᵀ (H Hᵀ + εI)⁻¹ (Eq. 3.13), solved by Cholesky (LDLᵀ) of the R x R system, or of
/// the equivalent L x L system Y (HᵀH + εI)⁻¹ Hᵀ when there are fewer samples than neurons.
/// H: R x L, Y: N x L; returns N x R.
Eigen::MatrixXd ridgeReadout(const Eigen::MatrixXd& H, const Eigen::MatrixXd& Y, double epsilon);

/// Batch ELM: one fit on all samples.
class Elm final : public Learner {
 public:
  Elm(int input_dim, int output_dim, ElmParams params = {});

  std::string kind() const override { return "elm"; }
  int inputDim() const override { return input_dim_; }
  int outputDim() const override { return output_dim_; }
  bool trained() const override { return trained_; }

  /// Normalization from the data's bounding box, features from the seed, then Eq. 3.13.
  void fit(const TrainingSet& data, const CancellationToken& cancel = CancellationToken::never()) override;
  /// As fit() with a given normalization (e.g. to share features with an OS-ELM).
  void fit(const TrainingSet& data, const InputNormalization& normalization,
           const CancellationToken& cancel = CancellationToken::never());
  using Learner::predict;
  void predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const override;
  Eigen::MatrixXd predictColumns(const Eigen::MatrixXd& X) const override;

  const ElmParams& params() const { return params_; }
  const RandomFeatures& features() const { return features_; }
  const Eigen::MatrixXd& outputWeights() const { return W_out_; }  ///< N x R

  void write(ModelWriter& writer) const override;
  static Elm read(const ModelReader& reader);

 private:
  int input_dim_;
  int output_dim_;
  ElmParams params_;
  RandomFeatures features_;
  Eigen::MatrixXd W_out_;
  bool trained_ = false;
};

/// OS-ELM: recursive least squares on the read-out from the very first sample,
/// W_0 = 0, P_0 = (εI)⁻¹ (Sect. 6.2), so after L samples P_L = (H Hᵀ + εI)⁻¹ and W_out equals
/// Eq. 3.13.
class OsElm final : public Learner {
 public:
  /// `normalization` fixes the input scaling for online learning before any data is seen
  /// (e.g. InputNormalization::fromBox of the workspace).
  OsElm(int input_dim, int output_dim, InputNormalization normalization, ElmParams params = {});

  std::string kind() const override { return "oselm"; }
  int inputDim() const override { return features_.inputDim(); }
  int outputDim() const override { return output_dim_; }
  bool trained() const override { return samples_ > 0; }

  /// Resets, takes the normalization from the data's bounding box (the whole batch is known
  /// here) and feeds every sample in order through update().
  void fit(const TrainingSet& data, const CancellationToken& cancel = CancellationToken::never()) override;
  bool supportsOnlineUpdate() const override { return true; }
  /// Eq. 6.4–6.5, O(R² + N R) per sample.
  void update(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y) override;
  using Learner::predict;
  void predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const override;

  /// Back to W_0 = 0, P_0 = (εI)⁻¹ with the current features.
  void reset();
  std::int64_t samples() const { return samples_; }
  const ElmParams& params() const { return params_; }
  const RandomFeatures& features() const { return features_; }
  const Eigen::MatrixXd& outputWeights() const { return W_out_; }

  void write(ModelWriter& writer) const override;
  static OsElm read(const ModelReader& reader);

 private:
  int output_dim_;
  ElmParams params_;
  RandomFeatures features_;
  Eigen::MatrixXd W_out_;  // N x R
  Eigen::MatrixXd P_;      // R x R, symmetric; only the lower triangle is maintained
  std::int64_t samples_ = 0;
  // Scratch of update() so the online path does not allocate.
  Eigen::VectorXd h_, Ph_, residual_;
};

}  // namespace flexirob::learning
