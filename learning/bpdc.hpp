#pragma once
// Backpropagation-decorrelation reservoir network with intrinsic plasticity (Sect. 3.2.1,
// Eq. 3.4–3.8, parameters of Tab. 3.1): the learner of the thesis' first prototype, kept as
// a proof of concept. It is slower and less accurate than the ELM; use the ELM or LLM.
//
// The map x -> y is static, so every query runs the reservoir from rest (s = 0) for
// `settle_steps` steps of Eq. 3.4 (Δt = 1) with the input held constant and reads the output
// from the last hidden state. Output feedback W_fdb is left out (zero): a static map has no
// output history to feed back, and it keeps predict() a function of x alone.
// Weights and rates follow Tab. 3.1; see BpdcParams::input_scale for the one addition.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>

#include "learning/learner.hpp"

namespace flexirob::learning {

struct BpdcParams {
  int reservoir = 300;               ///< R (Tab. 3.1)
  double input_density = 0.2;        ///< share of non-zero input weights (Tab. 3.1)
  double input_range = 0.1;          ///< W_in ~ U(−0.1, 0.1) where non-zero
  double recurrent_density = 0.02;   ///< reservoir-reservoir (Tab. 3.1)
  double recurrent_range = 0.02;
  double output_density = 0.2;       ///< initial read-out (Tab. 3.1 "reservoir-output")
  double output_range = 0.1;
  double eta = 0.015;                ///< BPDC rate, Eq. 3.6 (Tab. 3.1)
  double eta_ip = 0.00015;           ///< IP rate, Eq. 3.7–3.8 (Tab. 3.1)
  double mu_ip = 0.2;                ///< desired mean activity of IP (not given in the thesis)
  /// Normalized inputs span ±input_scale. With the small input weights of Tab. 3.1 the
  /// neurons then see pre-activations of order one; at ±1 they are almost linear and the
  /// read-out learns little beyond the mean (measured: MSE 0.34 vs 0.005 after 300 epochs).
  double input_scale = 10.0;
  int settle_steps = 5;              ///< reservoir steps per query
  int max_epochs = 1000;             ///< N_E (Sect. 3.3.1)
  double target_mse = 1e-4;          ///< [rad²] stop below this training MSE
  double tolerance = 1e-4;           ///< relative improvement that counts as progress
  int patience = 20;                 ///< epochs without progress before stopping
  std::uint64_t seed = 1;
  EpochObserver on_epoch;            ///< told after each epoch (empty: nobody)

  void validate() const;
};

class Bpdc final : public Learner {
 public:
  Bpdc(int input_dim, int output_dim, BpdcParams params = {});

  std::string kind() const override { return "bpdc"; }
  int inputDim() const override { return input_dim_; }
  int outputDim() const override { return output_dim_; }
  bool trained() const override { return trained_; }

  /// Epochs of one sweep with BPDC (Eq. 3.6) and IP (Eq. 3.7–3.8) per sample, then an
  /// evaluation sweep; stops at target_mse, after `patience` epochs without progress, or
  /// after max_epochs.
  void fit(const TrainingSet& data, const CancellationToken& cancel = CancellationToken::never()) override;
  using Learner::predict;
  void predict(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y) const override;

  int epochs() const { return epochs_; }
  /// Training MSE after each epoch (the learning curve).
  const std::vector<double>& history() const { return history_; }

  void write(ModelWriter& writer) const override;
  static Bpdc read(const ModelReader& reader);

 private:
  void initialize();
  // Runs the reservoir for x̃ from rest; leaves the last activations s and states h.
  void settle(const Eigen::VectorXd& x_normalized, Eigen::VectorXd& s, Eigen::VectorXd& h) const;

  int input_dim_;
  int output_dim_;
  BpdcParams params_;
  InputNormalization normalization_;
  Eigen::SparseMatrix<double> W_in_;   // R x M
  Eigen::SparseMatrix<double> W_rec_;  // R x R
  Eigen::MatrixXd W_out_;              // N x R
  Eigen::VectorXd gain_, bias_;        // a, b of the logistic neurons
  bool trained_ = false;
  int epochs_ = 0;
  std::vector<double> history_;
};

}  // namespace flexirob::learning
