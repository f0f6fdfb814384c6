// Fuzz target: learner model files (learning/model_file.hpp) and the learners reading them.
// Anything malformed must end in a ModelFileError; accepted matrices hold finite numbers only.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "fuzz/fuzz_support.hpp"
#include "learning/learner.hpp"
#include "learning/model_file.hpp"

namespace {

void checkModel(const std::string& text) {
  std::unique_ptr<flexirob::learning::Learner> learner;
  try {
    const flexirob::learning::ModelReader reader(text, "fuzz input");
    // The file is well formed: the learners' own loaders judge its content.
    learner = flexirob::learning::readLearner(reader);
  } catch (const flexirob::learning::ModelFileError&) {
    return;
  }
  if (!learner) flexirob::fuzz::invariantBroken("readLearner returned nothing without an error");
  if (learner->trained()) {
    const Eigen::VectorXd x = Eigen::VectorXd::Zero(learner->inputDim());
    const Eigen::VectorXd y = learner->predict(x);
    if (y.size() != learner->outputDim()) flexirob::fuzz::invariantBroken("prediction of the wrong size");
    if (!y.allFinite()) flexirob::fuzz::invariantBroken("a loaded model predicts non-finite values for a finite input");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  checkModel(text);
  checkModel(flexirob::fuzz::withValidModelChecksum(text));
  return 0;
}
