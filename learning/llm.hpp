#pragma once
// Local linear map adapted to the structured interaction (Sect. 3.2.2, Eq. 3.14–3.19): one
// linear model per training area, centred at the area's first sample.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "learning/learner.hpp"

namespace flexirob::learning {

/// Width d of Eq. 3.18: the largest distance ‖c_i − c_j‖ over all pairs of centres whose
/// Thales sphere (the sphere with diameter c_i c_j) holds no other centre, i.e.
/// (c_i − c_k)ᵀ(c_j − c_k) >= 0 for every k ≠ i, j. centres: D x K with K >= 2.
double thalesWidth(const Eigen::MatrixXd& centres);

/// Training parameters. Stopping rule: after every epoch (one sweep over all samples in a
/// random order drawn from `seed`) the training MSE of Eq. 3.3 is evaluated; training stops
/// when it is <= target_mse, or when the best MSE so far has not improved by a relative
/// `tolerance` for `patience` consecutive epochs, or after max_epochs.
struct LlmParams {
  double eta = 0.1;           ///< learning rate η of Eq. 3.19 (thesis default)
  int max_epochs = 1000;      ///< N_E, as for the BPDC in Sect. 3.3.1
  double tolerance = 1e-3;    ///< relative MSE improvement that counts as progress
  int patience = 10;          ///< epochs without progress before stopping
  double target_mse = 1e-10;  ///< [rad²] stop as soon as the fit is this good
  std::uint64_t seed = 1;     ///< presentation order of the samples
  EpochObserver on_epoch;     ///< told after each epoch (empty: nobody)

  void validate() const;
};

class Llm final : public Learner {
 public:
  Llm(int input_dim, int output_dim, LlmParams params = {});

  std::string kind() const override { return "llm"; }
  int inputDim() const override { return input_dim_; }
  int outputDim() const override { return output_dim_; }
  bool trained() const override { return centres_.cols() > 0; }

  /// One model per area of `data` (areas in order of first appearance): c_k = x_init,
  /// b_k = y_init, W_k = 0; d by Eq. 3.18 (for a single area: the largest distance of its
  /// samples from the centre); then gradient descent in epochs (Eq. 3.19).
  void fit(const TrainingSet& data, const CancellationToken& cancel = CancellationToken::never()) override;
  /// Eq. 3.14–3.17, evaluated with the soft-max shifted by the largest exponent so that far
  /// from every centre the map tends to the nearest model instead of 0/0.
  using Learner::predict;
  void predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const override;

  int models() const { return static_cast<int>(centres_.cols()); }
  /// Centres c_k (M x K) and biases b_k (N x K), in normalized input units.
  const Eigen::MatrixXd& centres() const { return centres_; }
  const Eigen::MatrixXd& biases() const { return b_; }
  /// d in normalized input units (positions: the common scale of InputNormalization).
  double width() const { return width_; }
  int epochs() const { return epochs_; }
  const LlmParams& params() const { return params_; }
  const InputNormalization& normalization() const { return normalization_; }

  void write(ModelWriter& writer) const override;
  static Llm read(const ModelReader& reader);

 private:
  // Responsibilities r_k = g_k / n (Eq. 3.15–3.16) and scaled offsets u_k = (x̃ − c_k) / d.
  void responsibilities(const Eigen::VectorXd& x_normalized, Eigen::VectorXd& r, Eigen::MatrixXd& u) const;

  int input_dim_;
  int output_dim_;
  LlmParams params_;
  InputNormalization normalization_;
  Eigen::MatrixXd centres_;  // M x K, normalized
  Eigen::MatrixXd W_;        // N x (K M): W_k in columns k M ... (k + 1) M − 1
  Eigen::MatrixXd b_;        // N x K
  double width_ = 1.0;
  int epochs_ = 0;
};

}  // namespace flexirob::learning
