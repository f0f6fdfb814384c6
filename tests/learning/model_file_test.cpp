// Model files: exact round trips, and damaged or mismatched files refused with clear errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cstdio>

#include "learning/bpdc.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "learning/model_file.hpp"
#include "tests/learning/test_maps.hpp"

namespace flexirob::learning {
namespace {

using testing::helixAreas;
using testing::sixAreaCentres;

std::string modelText(const Learner& learner) { return learner.modelText(); }

// Message of the ModelFileError thrown while reading `text`, or "" if it was accepted.
std::string readError(const std::string& text) {
  try {
    readLearner(ModelReader(text, "test.model"));
  } catch (const ModelFileError& e) {
    return e.what();
  }
  return "";
}

Elm trainedElm() {
  Elm elm(3, 7);
  elm.fit(helixAreas(sixAreaCentres(), 4, 7));
  return elm;
}

void expectSamePredictions(const Learner& a, const Learner& b) {
  ASSERT_EQ(a.kind(), b.kind());
  for (const Eigen::Vector3d& x : sixAreaCentres()) {
    const Eigen::Vector3d probe = x + Eigen::Vector3d(0.013, -0.021, 0.007);
    EXPECT_EQ(a.predict(probe), b.predict(probe));  // bit for bit: values are written exactly
  }
}

TEST(ModelFile, RoundTripReproducesEveryLearnerExactly) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 4, 7);
  const auto directory = std::filesystem::temp_directory_path() / "flexirob_model_file_test";
  std::filesystem::create_directories(directory);
  std::vector<std::unique_ptr<Learner>> learners;
  learners.push_back(std::make_unique<Elm>(3, 7));
  learners.push_back(std::make_unique<OsElm>(3, 7, InputNormalization::identity(3)));
  learners.push_back(std::make_unique<Llm>(3, 7));
  BpdcParams bpdc;
  bpdc.reservoir = 40;
  bpdc.max_epochs = 3;
  learners.push_back(std::make_unique<Bpdc>(3, 7, bpdc));
  for (auto& learner : learners) {
    learner->fit(data);
    const auto file = directory / (learner->kind() + ".model");
    std::ofstream(file, std::ios::binary) << learner->modelText();
    const auto loaded = loadLearner(file);
    expectSamePredictions(*learner, *loaded);
    EXPECT_EQ(loaded->inputDim(), 3);
    EXPECT_EQ(loaded->outputDim(), 7);
  }
  std::filesystem::remove_all(directory);
}

TEST(ModelFile, LoadedOsElmContinuesLearningOnline) {
  const TrainingSet data = helixAreas(sixAreaCentres(), 10, 7);
  OsElm whole(3, 7, InputNormalization::fromData(data.X));
  OsElm first_half(3, 7, InputNormalization::fromData(data.X));
  for (Eigen::Index l = 0; l < data.size(); ++l) whole.update(data.X.col(l), data.Y.col(l));
  for (Eigen::Index l = 0; l < 30; ++l) first_half.update(data.X.col(l), data.Y.col(l));
  OsElm resumed = OsElm::read(ModelReader(modelText(first_half), "half"));
  for (Eigen::Index l = 30; l < data.size(); ++l) resumed.update(data.X.col(l), data.Y.col(l));
  EXPECT_EQ(resumed.samples(), data.size());
  EXPECT_LT((resumed.outputWeights() - whole.outputWeights()).norm(), 1e-9 * whole.outputWeights().norm());
}

TEST(ModelFile, FileIsSelfDescribing) {
  const std::string text = modelText(trainedElm());
  for (const char* field : {"flexirob-model 1\n", "learner elm\n", "input_dim 3\n", "output_dim 7\n", "hidden 100\n",
                            "epsilon 0.01\n", "seed 1\n", "matrix input_offset 3 1\n", "matrix input_scale 3 1\n",
                            "matrix W_out 7 100\n", "checksum "}) {
    EXPECT_NE(text.find(field), std::string::npos) << field;
  }
}

TEST(ModelFile, RefusesTruncatedModelFile) {
  const std::string text = modelText(trainedElm());
  for (const std::size_t length : {std::size_t{0}, std::size_t{10}, std::size_t{17}, text.size() / 3, text.size() / 2,
                                   text.size() - 30, text.size() - 1}) {
    const std::string message = readError(text.substr(0, length));
    EXPECT_FALSE(message.empty()) << length;
    EXPECT_EQ(message.find('\n'), std::string::npos);  // one line
  }
  EXPECT_NE(readError(text.substr(0, text.size() / 2)).find("truncated"), std::string::npos);
}

TEST(ModelFile, RefusesCorruptedModelFile) {
  std::string text = modelText(trainedElm());
  const std::size_t digit = text.find_first_of("123456789", text.find("matrix W_out"));
  text[digit] = text[digit] == '9' ? '8' : static_cast<char>(text[digit] + 1);
  EXPECT_NE(readError(text).find("checksum mismatch"), std::string::npos);
}

TEST(ModelFile, RefusesForeignFilesAndNewerVersions) {
  EXPECT_NE(readError("area,x,y,z,q1\n0,1,2,3,4\n").find("not a FlexIRob model file"), std::string::npos);
  std::string text = modelText(trainedElm());
  text.replace(0, std::string("flexirob-model 1").size(), "flexirob-model 9");
  EXPECT_NE(readError(text).find("version 9 is not supported"), std::string::npos);
}

TEST(ModelFile, RefusesMismatchedLearnerKindAndDimensions) {
  const std::string elm_text = modelText(trainedElm());
  try {
    Llm::read(ModelReader(elm_text, "elm.model"));
    FAIL() << "an ELM file was read as an LLM";
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("holds a 'elm' model, expected 'llm'"), std::string::npos) << e.what();
  }
  // A well-formed file (valid checksum) whose read-out does not fit its declared dimensions.
  const Elm elm = trainedElm();
  ModelWriter writer("elm");
  writer.set("input_dim", 3);
  writer.set("output_dim", 9);  // the matrices below are for 7 outputs
  elm.params().write(writer);
  elm.features().write(writer);
  writer.setMatrix("W_out", elm.outputWeights());
  EXPECT_NE(readError(writer.text()).find("matrix 'W_out' is 7 x 100, expected 9 x 100"), std::string::npos)
      << readError(writer.text());
}

TEST(ModelFile, RefusesImplausibleSizesBeforeAllocating) {
  // Hand-made body claiming a 100000 x 100000 matrix, with a correct checksum.
  std::string body = "flexirob-model 1\nlearner elm\nmatrix W_out 100000 100000\n1 2 3\n";
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(fnv1a64(body.data(), body.size())));
  EXPECT_NE(readError(body + "checksum " + hex + "\n").find("implausible size"), std::string::npos);
  body = "flexirob-model 1\nlearner elm\nmatrix W_out 1000 1000\n1 2 3\n";
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(fnv1a64(body.data(), body.size())));
  EXPECT_NE(readError(body + "checksum " + hex + "\n").find("claims more entries than the file holds"), std::string::npos);
  // Absurd hyper-parameters are refused as well.
  body = "flexirob-model 1\nlearner elm\ninput_dim 3\noutput_dim 7\nhidden 999999999\n";
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(fnv1a64(body.data(), body.size())));
  EXPECT_NE(readError(body + "checksum " + hex + "\n").find("'hidden'"), std::string::npos);
}

TEST(ModelFile, RefusesMissingFileAndUnknownLearner) {
  EXPECT_THROW(loadLearner("/nonexistent/dir/model.txt"), ModelFileError);
  ModelWriter writer("perceptron");
  EXPECT_NE(readError(writer.text()).find("unknown learner 'perceptron'"), std::string::npos);
}

}  // namespace
}  // namespace flexirob::learning
