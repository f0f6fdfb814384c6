// Properties over many random inputs: finite predictions for every finite input, and every
// damaged model file refused with a ModelFileError (never a crash or another error).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "learning/bpdc.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

using testing::helixAreas;
using testing::sixAreaCentres;

std::vector<std::unique_ptr<Learner>> trainedLearners() {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  std::vector<std::unique_ptr<Learner>> learners;
  learners.push_back(std::make_unique<Elm>(3, 7));
  learners.push_back(std::make_unique<OsElm>(3, 7, InputNormalization::identity(3)));
  learners.push_back(std::make_unique<Llm>(3, 7));
  BpdcParams bpdc;
  bpdc.reservoir = 50;
  bpdc.max_epochs = 5;
  learners.push_back(std::make_unique<Bpdc>(3, 7, bpdc));
  for (auto& learner : learners) learner->fit(data);
  return learners;
}

TEST(LearnerProperty, PredictionsAreFiniteForEveryFiniteInput) {
  const auto learners = trainedLearners();
  UniformRandom random(11);
  for (int trial = 0; trial < 2000; ++trial) {
    // Magnitudes from 1e-300 to 1e300 with random signs, plus exact zeros.
    Eigen::Vector3d x;
    for (int i = 0; i < 3; ++i) {
      const double magnitude = std::pow(10.0, random.uniform(-300.0, 300.0));
      x[i] = trial % 7 == 0 ? 0.0 : (random.unit() < 0.5 ? -magnitude : magnitude);
    }
    for (const auto& learner : learners) {
      ASSERT_TRUE(learner->predict(x).allFinite()) << learner->kind() << " at " << x.transpose();
    }
  }
  const Eigen::Vector3d extreme(std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::denorm_min());
  for (const auto& learner : learners) EXPECT_TRUE(learner->predict(extreme).allFinite()) << learner->kind();
}

TEST(ModelFileProperty, EveryTruncationAndByteFlipIsRefusedAsModelFileError) {
  Llm llm(3, 2);
  llm.fit(helixAreas({{-0.5, -0.2, 0.3}, {-0.5, 0.2, 0.3}}, 3, 2));
  ModelWriter writer("llm");
  llm.write(writer);
  const std::string text = writer.text();
  ASSERT_NO_THROW(readLearner(ModelReader(text, "intact")));
  for (std::size_t length = 0; length < text.size(); ++length) {
    EXPECT_THROW(readLearner(ModelReader(text.substr(0, length), "truncated")), ModelFileError) << length;
  }
  UniformRandom random(5);
  for (int trial = 0; trial < 500; ++trial) {
    std::string damaged = text;
    const std::size_t position = random.index(damaged.size());
    const char replacement = static_cast<char>(32 + random.index(95));
    if (damaged[position] == replacement) continue;
    damaged[position] = replacement;
    EXPECT_THROW(readLearner(ModelReader(damaged, "damaged")), ModelFileError) << position;
  }
}

}  // namespace
}  // namespace flexirob::learning
