// Learners fed degenerate and extreme (but finite) data: predictions stay finite for every
// finite input, whether the data were learned in one batch or sample by sample (OS-ELM).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

/// A random finite value whose magnitude ranges from 1e-300 to 1e300, or an exact zero.
double extremeValue(UniformRandom& random) {
  if (random.unit() < 0.1) return 0.0;
  const double magnitude = std::pow(10.0, random.uniform(-300.0, 300.0));
  return random.unit() < 0.5 ? -magnitude : magnitude;
}

Eigen::Vector3d extremeInput(UniformRandom& random) {
  return {extremeValue(random), extremeValue(random), extremeValue(random)};
}

void expectFiniteEverywhere(const Learner& learner, UniformRandom& random, const char* what) {
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3d x = trial % 2 == 0 ? extremeInput(random) : Eigen::Vector3d::Random().eval();
    ASSERT_TRUE(learner.predict(x).allFinite()) << learner.kind() << " (" << what << ") at " << x.transpose();
  }
}

/// Training sets that stress normalization and the least-squares solves.
std::vector<std::pair<const char*, TrainingSet>> degenerateSets() {
  std::vector<std::pair<const char*, TrainingSet>> sets;
  TrainingSet single;  // one sample
  single.X = Eigen::MatrixXd::Constant(3, 1, 0.4);
  single.Y = Eigen::MatrixXd::Constant(7, 1, 0.2);
  sets.emplace_back("one sample", single);
  TrainingSet repeated;  // one point repeated: zero input variance
  repeated.X = Eigen::MatrixXd::Constant(3, 50, 0.4);
  repeated.Y = Eigen::MatrixXd::Constant(7, 50, -1.0);
  sets.emplace_back("repeated point", repeated);
  TrainingSet collinear;  // inputs on a line: rank 1
  collinear.X.resize(3, 40);
  collinear.Y.resize(7, 40);
  for (int l = 0; l < 40; ++l) {
    collinear.X.col(l) = Eigen::Vector3d(1.0, 2.0, 3.0) * (l * 0.01);
    collinear.Y.col(l) = Eigen::VectorXd::Constant(7, std::sin(l * 0.1));
  }
  sets.emplace_back("collinear inputs", collinear);
  TrainingSet tiny_scale = collinear;  // micrometre-sized workspace
  tiny_scale.X *= 1e-6;
  sets.emplace_back("micrometre scale", tiny_scale);
  TrainingSet huge_scale = collinear;  // kilometre-sized workspace, huge targets
  huge_scale.X *= 1e3;
  huge_scale.Y *= 1e6;
  sets.emplace_back("kilometre scale", huge_scale);
  return sets;
}

TEST(LearnerProperty, DegenerateTrainingDataStillGiveFinitePredictions) {
  UniformRandom random(5);
  for (const auto& [what, data] : degenerateSets()) {
    std::vector<std::unique_ptr<Learner>> learners;
    learners.push_back(std::make_unique<Elm>(3, 7));
    learners.push_back(std::make_unique<OsElm>(3, 7, InputNormalization::identity(3)));
    learners.push_back(std::make_unique<Llm>(3, 7));
    for (auto& learner : learners) {
      learner->fit(data);
      expectFiniteEverywhere(*learner, random, what);
    }
  }
}

TEST(LearnerProperty, OnlineUpdatesWithExtremeFiniteSamplesKeepPredictionsFinite) {
  const TrainingSet start = testing::helixAreas(testing::sixAreaCentres(), 4, 7);
  OsElm learner(3, 7, InputNormalization::identity(3));
  learner.fit(start);
  ASSERT_TRUE(learner.supportsOnlineUpdate());
  UniformRandom random(17);
  for (int k = 0; k < 500; ++k) {
    // Mostly samples near the workspace, every fifth one extreme in input or target.
    Eigen::Vector3d x = start.X.col(k % start.size()) + 0.01 * Eigen::Vector3d::Random();
    Eigen::VectorXd y = start.Y.col(k % start.size());
    if (k % 5 == 0) x = extremeInput(random);
    if (k % 5 == 1) y = Eigen::VectorXd::Constant(7, extremeValue(random) * 1e-10);
    learner.update(x, y);
    ASSERT_TRUE(learner.predict(start.X.col(0)).allFinite()) << "after update " << k;
  }
  expectFiniteEverywhere(learner, random, "after extreme online updates");
}

}  // namespace
}  // namespace flexirob::learning
