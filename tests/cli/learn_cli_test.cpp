// CLI-level tests of `learn fit` and `learn predict`: the built flexirob-cli is run as a user
// would run it; results are checked in its JSON, failures by exit code 2 and a one-line error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/cli/cli_support.hpp"

namespace {

namespace fs = std::filesystem;
using flexirob::cli::Json;

struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class LearnCli : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() / ("flexirob_learn_cli_" + std::to_string(getpid()) + "_" +
                                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  fs::path path(const std::string& name) const { return directory_ / name; }

  fs::path write(const std::string& name, const std::string& content) const {
    std::ofstream(path(name), std::ios::binary) << content;
    return path(name);
  }

  CliRun invoke(const std::string& arguments) const {
    const std::string command = std::string(FLEXIROB_CLI_EXECUTABLE) + " " + arguments + " > " + path("stdout").string() +
                                " 2> " + path("stderr").string();
    const int status = std::system(command.c_str());
    CliRun run;
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.out = slurp(path("stdout"));
    run.err = slurp(path("stderr"));
    return run;
  }

  // Exit code 2 and exactly one line "error: ..." on stderr.
  static void expectInputError(const CliRun& run, const std::string& fragment) {
    EXPECT_EQ(run.exit_code, 2) << run.out << run.err;
    ASSERT_FALSE(run.err.empty());
    EXPECT_EQ(run.err.rfind("error: ", 0), 0u) << run.err;
    EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << run.err;
    EXPECT_NE(run.err.find(fragment), std::string::npos) << run.err;
  }

  fs::path directory_;
};

// q_j(x) of a smooth known map, 7 joints.
double joint(int j, double x, double y, double z) { return 0.4 * std::sin(1.5 * x + 0.7 * j) + 0.3 * std::cos(2.0 * y) + 0.5 * z; }

// Four samples per area (fewer than five, as in Tab. 3.4) in six areas.
std::string trainingCsv(bool with_area) {
  const double centres[6][3] = {{-0.7, -0.4, 0.3}, {-0.7, 0.4, 0.3}, {-0.3, -0.4, 0.6},
                                {-0.3, 0.4, 0.6},  {-0.5, 0.0, 0.15}, {-0.5, 0.0, 0.7}};
  std::ostringstream csv;
  csv.precision(17);
  csv << (with_area ? "area," : "") << "x,y,z,q1,q2,q3,q4,q5,q6,q7\n";
  for (int k = 0; k < 6; ++k) {
    for (int l = 0; l < 4; ++l) {
      const double x = centres[k][0] + 0.04 * std::cos(2.0 * l), y = centres[k][1] + 0.04 * std::sin(2.0 * l),
                   z = centres[k][2] + 0.02 * l;
      if (with_area) csv << k << ",";
      csv << x << "," << y << "," << z;
      for (int j = 0; j < 7; ++j) csv << "," << joint(j, x, y, z);
      csv << "\n";
    }
  }
  return csv.str();
}

// Points between the areas, with their true postures.
std::string betweenCsv() {
  std::ostringstream csv;
  csv.precision(17);
  csv << "x,y,z,q1,q2,q3,q4,q5,q6,q7\n";
  const double points[4][3] = {{-0.7, 0.0, 0.3}, {-0.3, 0.0, 0.6}, {-0.5, -0.4, 0.45}, {-0.5, 0.0, 0.42}};
  for (const auto& p : points) {
    csv << p[0] << "," << p[1] << "," << p[2];
    for (int j = 0; j < 7; ++j) csv << "," << joint(j, p[0], p[1], p[2]);
    csv << "\n";
  }
  return csv.str();
}

TEST_F(LearnCli, FitsAndPredictsAKnownSmoothMapWithEveryLearner) {
  const fs::path data = write("train.csv", trainingCsv(true));
  const fs::path between = write("between.csv", betweenCsv());
  for (const std::string learner : {"elm", "oselm", "llm"}) {
    const fs::path model = path(learner + ".model");
    const CliRun fit = invoke("learn fit --learner " + learner + " --data " + data.string() + " --out " + model.string());
    ASSERT_EQ(fit.exit_code, 0) << fit.err;
    const Json fitted = Json::parse(fit.out);
    EXPECT_EQ(fitted.at("learner"), learner);
    EXPECT_EQ(fitted.at("samples"), 24);
    EXPECT_EQ(fitted.at("areas"), 6);
    EXPECT_LT(fitted.at("train_mse").get<double>(), 7 * 0.02 * 0.02) << learner;
    EXPECT_GE(fitted.at("seconds").get<double>(), 0.0);
    ASSERT_TRUE(fs::exists(model));

    const CliRun predict = invoke("learn predict --model " + model.string() + " --data " + between.string());
    ASSERT_EQ(predict.exit_code, 0) << predict.err;
    const Json predicted = Json::parse(predict.out);
    ASSERT_EQ(predicted.at("predictions").size(), 4u);
    ASSERT_EQ(predicted.at("predictions")[0].size(), 7u);
    // The reported error agrees with the printed predictions and the known map.
    double sum = 0.0;
    double joint_sums[7] = {};
    const double points[4][3] = {{-0.7, 0.0, 0.3}, {-0.3, 0.0, 0.6}, {-0.5, -0.4, 0.45}, {-0.5, 0.0, 0.42}};
    for (int r = 0; r < 4; ++r) {
      for (int j = 0; j < 7; ++j) {
        const double e = predicted["predictions"][static_cast<std::size_t>(r)][static_cast<std::size_t>(j)].get<double>() -
                         joint(j, points[r][0], points[r][1], points[r][2]);
        sum += e * e;
        joint_sums[j] += e * e;
      }
    }
    EXPECT_NEAR(predicted.at("mse").get<double>(), sum / 4.0, 1e-9);
    ASSERT_EQ(predicted.at("rmse_per_joint").size(), 7u);
    for (std::size_t j = 0; j < 7; ++j) {
      EXPECT_NEAR(predicted["rmse_per_joint"][j].get<double>(), std::sqrt(joint_sums[j] / 4.0), 1e-9) << learner << " q" << j + 1;
    }
    ASSERT_EQ(fitted.at("train_rmse_per_joint").size(), 7u);
    double fitted_sum = 0.0;
    for (const auto& rmse : fitted.at("train_rmse_per_joint")) fitted_sum += 4 * 6 * rmse.get<double>() * rmse.get<double>();
    EXPECT_NEAR(fitted.at("train_mse").get<double>(), fitted_sum / 24.0, 1e-12) << learner;
    EXPECT_LT(predicted.at("rmse_rad").get<double>(), 0.05) << learner;
  }
}

TEST_F(LearnCli, InfersAreasWhenTheAreaColumnIsOmitted) {
  const fs::path data = write("train.csv", trainingCsv(false));
  const CliRun fit = invoke("learn fit --learner llm --data " + data.string() + " --out " + path("m").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const Json fitted = Json::parse(fit.out);
  EXPECT_EQ(fitted.at("areas"), 6);
  EXPECT_TRUE(fitted.at("areas_inferred").get<bool>());
  // Predict accepts inputs without q columns.
  const CliRun predict = invoke("learn predict --model " + path("m").string() + " --data " +
                          write("inputs.csv", "x,y,z\n-0.5,0.1,0.4\n-0.6,0.0,0.3\n").string());
  ASSERT_EQ(predict.exit_code, 0) << predict.err;
  EXPECT_EQ(Json::parse(predict.out).at("predictions").size(), 2u);
}

TEST_F(LearnCli, ExposesHyperParametersAndRecordsThemInTheModel) {
  const fs::path data = write("train.csv", trainingCsv(true));
  const CliRun fit = invoke("learn fit --learner elm --hidden 37 --epsilon 0.5 --seed 9 --data " + data.string() + " --out " +
                      path("m").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const std::string model = slurp(path("m"));
  EXPECT_NE(model.find("\nhidden 37\n"), std::string::npos);
  EXPECT_NE(model.find("\nepsilon 0.5\n"), std::string::npos);
  EXPECT_NE(model.find("\nseed 9\n"), std::string::npos);
  expectInputError(invoke("learn fit --learner elm --hidden 0 --data " + data.string() + " --out " + path("m").string()), "hidden");
  expectInputError(invoke("learn fit --learner perceptron --data " + data.string() + " --out " + path("m").string()), "learner");
}

TEST_F(LearnCli, RefusesBrokenCsvWithExitCodeTwoAndOneLine) {
  struct Case {
    std::string content;
    std::string fragment;
  };
  const std::vector<Case> cases = {
      {"", "empty file"},
      {"area,x,y,z,q1\n", "no data rows"},
      {"a,b,c\n1,2,3\n", "expected the header"},
      {"x,y,z,q1,q2\n0.1,0.2,0.3,0.4\n", "line 2: expected 5 values, got 4"},
      {"x,y,z,q1\n0.1,abc,0.3,0.4\n", "column 'y': 'abc' is not a finite number"},
      {"x,y,z,q1\n0.1,nan,0.3,0.4\n", "is not a finite number"},
      {"x,y,z,q1\n0.1,1e999,0.3,0.4\n", "is not a finite number"},
      {"x,y,z,q1\n0.1,0.2,0.3,1e300\n", "column 'q1': '1e300' is beyond ±1e6"},
      {"x,y,z,q1\n0.1,0x1p-2,0.3,0.4\n", "column 'y': '0x1p-2' is not a finite number"},
      {"x,y,z,q1\r0.1,0.2,0.3,0.4\r", "lines end in a carriage return alone"},
      {std::string("x,y,z,q1\n0.1,0.2,0.3,0.4\0\n", 25), "'0.4?' is not a finite number"},
      {"x,y,z,q2\n0.1,0.2,0.3,0.4\n", "expected column 'q1'"},
      {"x,y,z\n0.1,0.2,0.3\n", "no joint columns"},
      {"area,x,y,z,q1\n-1,0.1,0.2,0.3,0.4\n", "area '-1' is not an integer"},
      {"area,x,y,z,q1\n1.5,0.1,0.2,0.3,0.4\n", "is not an integer"},
      {"x,y,z,q1\n0.1,0.2,0.3,\n", "'' is not a finite number"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path data = write("bad" + std::to_string(i) + ".csv", cases[i].content);
    SCOPED_TRACE(cases[i].content);
    expectInputError(invoke("learn fit --learner elm --data " + data.string() + " --out " + path("m").string()), cases[i].fragment);
  }
  expectInputError(invoke("learn fit --data " + path("missing.csv").string() + " --out " + path("m").string()), "does not exist");
  // The LLM keeps a local model per area: 10 001 areas are refused before an hour of fitting.
  std::string many = "area,x,y,z,q1\n";
  for (int a = 0; a <= 10000; ++a) many += std::to_string(a) + "," + std::to_string(0.0001 * a) + ",0.2,0.3,0.4\n";
  expectInputError(invoke("learn fit --learner llm --data " + write("many.csv", many).string() + " --out " + path("m").string()),
                   "the data hold 10001 areas");
  // A spreadsheet's byte order mark before the header is read past.
  const fs::path marked = write("bom.csv", "\xEF\xBB\xBF" + trainingCsv(true));
  EXPECT_EQ(invoke("learn fit --learner elm --data " + marked.string() + " --out " + path("m").string()).exit_code, 0);
}

TEST_F(LearnCli, RefusesBrokenOrMismatchedModelFilesWithExitCodeTwoAndOneLine) {
  const fs::path data = write("train.csv", trainingCsv(true));
  ASSERT_EQ(invoke("learn fit --learner elm --data " + data.string() + " --out " + path("good.model").string()).exit_code, 0);
  const std::string model = slurp(path("good.model"));
  const fs::path inputs = write("inputs.csv", "x,y,z\n-0.5,0.1,0.4\n");
  const auto predictWith = [&](const fs::path& file) {
    return invoke("learn predict --model " + file.string() + " --data " + inputs.string());
  };
  expectInputError(predictWith(write("truncated.model", model.substr(0, model.size() / 2))), "truncated");
  std::string corrupted = model;
  corrupted[corrupted.size() / 2] = corrupted[corrupted.size() / 2] == '1' ? '2' : '1';
  expectInputError(predictWith(write("corrupted.model", corrupted)), "checksum mismatch");
  expectInputError(predictWith(data), "not a FlexIRob model file");
  expectInputError(predictWith(path("absent.model")), "does not exist");
  expectInputError(predictWith(write("empty.model", "")), "not a FlexIRob model file");
  // A 6-D input file against a 3-D model, and q columns that do not match the model.
  expectInputError(invoke("learn predict --model " + path("good.model").string() + " --data " +
                       write("six.csv", "x,y,z,rx,ry,rz\n0,0,0,0,0,0\n").string()),
                   "expects 3 inputs");
  expectInputError(invoke("learn predict --model " + path("good.model").string() + " --data " +
                       write("nine.csv", "x,y,z,q1,q2\n0,0,0,0,0\n").string()),
                   "predicts 7 joints");
}

TEST_F(LearnCli, AcceptsJointsNumberedFromZero) {
  const fs::path data = write("zero.csv", "x,y,z,q0,q1\n0.1,0.2,0.3,1,2\n0.2,0.2,0.3,1.1,2.1\n");
  const CliRun fit = invoke("learn fit --learner elm --data " + data.string() + " --out " + path("m").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_EQ(Json::parse(fit.out).at("output_dim"), 2);
  expectInputError(invoke("learn fit --data " + write("gap.csv", "x,y,z,q0,q2\n0,0,0,1,2\n").string() + " --out " +
                          path("m").string()),
                   "expected column 'q1', got 'q2'");
}

TEST_F(LearnCli, LearnsSixDimensionalInputs) {
  std::ostringstream csv;
  csv << "area,x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6,q7,q8,q9\n";
  for (int l = 0; l < 12; ++l) {
    csv << l / 4 << "," << -0.5 + 0.1 * (l / 4) << "," << 0.01 * l << ",0.4," << 0.1 * std::sin(l) << ",0,0.2";
    for (int j = 0; j < 9; ++j) csv << "," << 0.1 * j + 0.05 * l;
    csv << "\n";
  }
  const CliRun fit = invoke("learn fit --learner oselm --data " + write("six.csv", csv.str()).string() + " --out " + path("m").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const Json fitted = Json::parse(fit.out);
  EXPECT_EQ(fitted.at("input_dim"), 6);
  EXPECT_EQ(fitted.at("output_dim"), 9);
}

}  // namespace
