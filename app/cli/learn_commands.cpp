// `learn fit` and `learn predict`: re-learn recorded demonstrations offline and query models.
//
// Data files are CSV with a header row: an optional `area` column (integer >= 0), then the
// inputs `x,y,z` [m], optionally followed by orientation inputs (e.g. `rx,ry,rz`, a rotation
// vector [rad]), then the outputs `q1,...,qN` [rad]. `learn predict` needs only the inputs; if
// the q columns are present it also reports the prediction error.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "app/cli/cli_support.hpp"
#include "app/file_output.hpp"
#include "app/table_text.hpp"
#include "learning/bpdc.hpp"
#include "learning/clustering.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "robot/errors.hpp"

namespace flexirob::cli {
namespace {

constexpr std::uintmax_t kMaxCsvBytes = 512ULL * 1024 * 1024;

struct LearningCsv {
  learning::TrainingSet data;  // Y has zero rows when the file has no q columns
  bool has_area = false;
  std::vector<std::string> input_names;
};

// Each q column's root mean square error in that column's own unit. The file does not say which
// joints slide, so one RMSE over all columns mixes metres with radians when one does.
Json rmsePerJoint(const Eigen::MatrixXd& error) {
  Json per_joint = Json::array();
  const double samples = static_cast<double>(error.cols());
  for (Eigen::Index j = 0; j < error.rows(); ++j) per_joint.push_back(std::sqrt(error.row(j).squaredNorm() / samples));
  return per_joint;
}

bool isOutputName(const std::string& name) {
  return name.size() >= 2 && name[0] == 'q' && name.find_first_not_of("0123456789", 1) == std::string::npos;
}

// Reads and validates a learning CSV; every problem is an InputError naming file, line and column.
LearningCsv readLearningCsv(const std::string& path, bool outputs_required) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) throw InputError("data file '" + path + "' is a directory");
  if (!std::filesystem::is_regular_file(path, error)) throw InputError("data file '" + path + "' does not exist");
  if (std::filesystem::file_size(path, error) > kMaxCsvBytes) throw InputError("data file '" + path + "' is larger than 512 MiB");
  std::ifstream in(path);
  if (!in) throw InputError("cannot open data file '" + path + "'");

  std::string line;
  std::size_t line_number = 0;
  // Header.
  do {
    if (!std::getline(in, line)) throw InputError(path + ": empty file (expected a header row)");
    ++line_number;
  } while (app::trimmed(line).empty());
  if (line_number == 1) app::prepareFirstLine(line, path);
  std::vector<std::string> header = app::splitCommaFields(line);
  for (auto& name : header) name = app::lowercase(name);
  const std::string where = path + " line " + std::to_string(line_number);
  std::size_t column = 0;
  LearningCsv csv;
  if (header[0] == "area") {
    csv.has_area = true;
    column = 1;
  }
  if (header.size() < column + 3 || header[column] != "x" || header[column + 1] != "y" || header[column + 2] != "z") {
    throw InputError(where + ": expected the header 'area,x,y,z,q1,...,qN' (area optional), got '" + printable(app::trimmed(line)) + "'");
  }
  const std::size_t input_begin = column;
  std::size_t output_begin = input_begin + 3;
  while (output_begin < header.size() && !isOutputName(header[output_begin])) {
    if (header[output_begin].empty()) throw InputError(where + ": empty column name");
    ++output_begin;
  }
  const std::size_t inputs = output_begin - input_begin;
  const std::size_t outputs = header.size() - output_begin;
  if (inputs > static_cast<std::size_t>(learning::kMaxInputDim)) throw InputError(where + ": too many input columns");
  if (outputs > static_cast<std::size_t>(learning::kMaxOutputDim)) throw InputError(where + ": too many q columns");
  // Joints numbered q1..qN (q0..qN-1 is accepted too).
  const std::size_t first_joint = outputs > 0 && header[output_begin] == "q0" ? 0 : 1;
  for (std::size_t j = 0; j < outputs; ++j) {
    const std::string expected = "q" + std::to_string(j + first_joint);
    if (header[output_begin + j] != expected) {
      throw InputError(where + ": expected column '" + expected + "', got '" + printable(header[output_begin + j]) + "'");
    }
  }
  if (outputs_required && outputs == 0) throw InputError(where + ": no joint columns q1,...,qN");
  for (std::size_t i = input_begin; i < output_begin; ++i) csv.input_names.push_back(header[i]);

  // Rows.
  std::vector<double> values;
  std::vector<int>& areas = csv.data.area;
  Eigen::Index rows = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (app::trimmed(line).empty()) continue;
    const std::vector<std::string> fields = app::splitCommaFields(line);
    const std::string at = path + " line " + std::to_string(line_number);
    if (fields.size() != header.size()) {
      throw InputError(at + ": expected " + std::to_string(header.size()) + " values, got " + std::to_string(fields.size()));
    }
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const std::optional<double> parsed = app::parseDecimal(fields[i]);
      if (!parsed) {
        throw InputError(at + ", column '" + printable(header[i]) + "': '" + printable(fields[i]) + "' is not a finite number");
      }
      const double value = *parsed;
      if (std::abs(value) > app::kLargestTableValue) {
        throw InputError(at + ", column '" + printable(header[i]) + "': '" + printable(fields[i]) + "' is beyond ±1e6");
      }
      if (csv.has_area && i == 0) {
        if (value < 0 || value != std::floor(value)) {
          throw InputError(at + ": area '" + printable(fields[i]) + "' is not an integer in 0...1000000");
        }
        areas.push_back(static_cast<int>(value));
      } else {
        values.push_back(value);
      }
    }
    ++rows;
  }
  if (rows == 0) throw InputError(path + ": no data rows after the header");
  const auto width = static_cast<Eigen::Index>(inputs + outputs);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor>> table(values.data(), width, rows);
  csv.data.X = table.topRows(static_cast<Eigen::Index>(inputs));
  csv.data.Y = table.bottomRows(static_cast<Eigen::Index>(outputs));
  return csv;
}

struct FitOptions {
  std::string learner = "elm";
  std::string data;
  std::string out;
  int hidden = learning::ElmParams{}.hidden;
  double epsilon = learning::ElmParams{}.epsilon;
  std::int64_t seed = 1;
  double eta = learning::LlmParams{}.eta;
  int max_epochs = learning::LlmParams{}.max_epochs;
  double tolerance = learning::LlmParams{}.tolerance;
  int patience = learning::LlmParams{}.patience;
  double area_radius = 0.15;
};

Json fit(const FitOptions& options) {
  checkOutputPath("--out", options.out, {{"--data", options.data}});
  LearningCsv csv = readLearningCsv(options.data, true);
  learning::TrainingSet& data = csv.data;
  const bool areas_inferred = !csv.has_area;
  if (areas_inferred) data.area = learning::inferAreas(data.X, options.area_radius);
  const int M = data.inputDim();
  const int N = data.outputDim();

  learning::ElmParams elm_params;
  elm_params.hidden = options.hidden;
  elm_params.epsilon = options.epsilon;
  elm_params.seed = static_cast<std::uint64_t>(options.seed);
  learning::LlmParams llm_params;
  llm_params.eta = options.eta;
  llm_params.max_epochs = options.max_epochs;
  llm_params.tolerance = options.tolerance;
  llm_params.patience = options.patience;
  llm_params.seed = static_cast<std::uint64_t>(options.seed);
  // The LLM and the BPDC learn in epochs until the fit stops improving: how long is not known
  // beforehand, and a large file takes minutes, so each epoch is shown (at most once a second).
  const auto fit_start = std::chrono::steady_clock::now();
  auto last_shown = fit_start;  // a fit done within a second shows nothing
  bool shown = false;
  int epochs_done = 0;
  // The learner keeps this observer: it must not outlive this function's locals (it does not:
  // it is made, fitted and saved here).
  const learning::EpochObserver show_epoch = [&last_shown, &shown, &epochs_done, fit_start, max_epochs = options.max_epochs,
                                              learner_name = options.learner](int epochs, double mse) {
    epochs_done = epochs;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_shown < std::chrono::seconds(1)) return;
    last_shown = now;
    shown = true;
    std::ostringstream status;
    status << "learn fit (" << learner_name << "): epoch " << epochs << " of at most " << max_epochs
           << ", training MSE " << std::setprecision(4) << mse << " rad², "
           << std::fixed << std::setprecision(0) << std::chrono::duration<double>(now - fit_start).count() << " s";
    reportStatus(status.str());
  };
  llm_params.on_epoch = show_epoch;

  std::unique_ptr<learning::Learner> learner;
  Json parameters;
  try {
    if (options.learner == "elm" || options.learner == "oselm") {
      parameters = {{"hidden", elm_params.hidden}, {"epsilon", elm_params.epsilon}, {"seed", options.seed}};
      if (options.learner == "elm") {
        learner = std::make_unique<learning::Elm>(M, N, elm_params);
      } else {
        learner = std::make_unique<learning::OsElm>(M, N, learning::InputNormalization::identity(M), elm_params);
      }
    } else if (options.learner == "llm") {
      // One local model per area, each epoch comparing every sample with every centre: a
      // file of a sample per area (200 000) would run for hours.
      constexpr std::size_t kMaxLlmAreas = 10000;
      const std::size_t areas = std::set<int>(data.area.begin(), data.area.end()).size();
      if (areas > kMaxLlmAreas) {
        throw InputError("--learner llm: the data hold " + std::to_string(areas) + " areas; the LLM keeps one local model per area, at most " +
                         std::to_string(kMaxLlmAreas));
      }
      parameters = {{"eta", llm_params.eta}, {"max_epochs", llm_params.max_epochs}, {"tolerance", llm_params.tolerance},
                    {"patience", llm_params.patience}, {"seed", options.seed}};
      learner = std::make_unique<learning::Llm>(M, N, llm_params);
    } else {
      learning::BpdcParams bpdc_params;
      bpdc_params.max_epochs = options.max_epochs;
      bpdc_params.seed = static_cast<std::uint64_t>(options.seed);
      bpdc_params.on_epoch = show_epoch;
      parameters = {{"reservoir", bpdc_params.reservoir}, {"max_epochs", bpdc_params.max_epochs}, {"seed", options.seed}};
      learner = std::make_unique<learning::Bpdc>(M, N, bpdc_params);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }

  const auto start = std::chrono::steady_clock::now();
  try {
    learner->fit(data);
  } catch (...) {
    // The error that follows gets a line of its own.
    if (shown) reportStatus("learn fit (" + options.learner + "): stopped after " + std::to_string(epochs_done) + " epochs", true);
    throw;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (shown) reportStatus("learn fit (" + options.learner + "): done after " + std::to_string(epochs_done) + " epochs", true);
  const Eigen::MatrixXd training_error = learner->predictColumns(data.X) - data.Y;
  const double mse = training_error.colwise().squaredNorm().mean();  // Eq. 3.3
  app::writeFileReplacing(options.out, learner->modelText(), "--out");

  Json result = {{"learner", learner->kind()},
                 {"samples", data.size()},
                 {"areas", data.samplesByArea().size()},
                 {"areas_inferred", areas_inferred},
                 {"input_dim", M},
                 {"output_dim", N},
                 {"train_mse", mse},
                 {"train_rmse_rad", std::sqrt(mse / N)},
                 {"train_rmse_per_joint", rmsePerJoint(training_error)},
                 {"seconds", seconds},
                 {"model", options.out},
                 {"parameters", parameters}};
  if (const auto* llm = dynamic_cast<const learning::Llm*>(learner.get())) {
    result["epochs"] = llm->epochs();
    result["width_normalized"] = llm->width();
  } else if (const auto* bpdc = dynamic_cast<const learning::Bpdc*>(learner.get())) {
    result["epochs"] = bpdc->epochs();
  }
  return result;
}

Json predict(const std::string& model_path, const std::string& data_path) {
  const std::unique_ptr<learning::Learner> learner = learning::loadLearner(model_path);
  const LearningCsv csv = readLearningCsv(data_path, false);
  const learning::TrainingSet& data = csv.data;
  if (data.inputDim() != learner->inputDim()) {
    throw InputError("model '" + model_path + "' expects " + std::to_string(learner->inputDim()) + " inputs, data file '" +
                     data_path + "' has " + std::to_string(data.inputDim()));
  }
  if (data.outputDim() != 0 && data.outputDim() != learner->outputDim()) {
    throw InputError("model '" + model_path + "' predicts " + std::to_string(learner->outputDim()) + " joints, data file '" +
                     data_path + "' has " + std::to_string(data.outputDim()) + " q columns");
  }
  const auto start = std::chrono::steady_clock::now();
  const Eigen::MatrixXd Y = learner->predictColumns(data.X);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Json result = {{"learner", learner->kind()},
                 {"samples", data.size()},
                 {"output_dim", learner->outputDim()},
                 {"seconds", seconds},
                 {"predictions", toJsonRows(Y.transpose())}};
  if (data.outputDim() != 0) {
    const Eigen::MatrixXd error = Y - data.Y;
    const double mse = error.colwise().squaredNorm().mean();
    result["mse"] = mse;
    result["rmse_rad"] = std::sqrt(mse / learner->outputDim());
    result["max_abs_error_rad"] = error.cwiseAbs().maxCoeff();
    result["rmse_per_joint"] = rmsePerJoint(error);
  }
  return result;
}

}  // namespace

void registerLearnCommands(CLI::App& app, CommandRunner& runner) {
  auto* learn = app.add_subcommand("learn", "fit redundancy-resolution learners on recorded data, and query them");
  learn->require_subcommand(1);
  {
    auto* fit_command = learn->add_subcommand("fit", "fit a learner on a CSV file (area,x,y,z,q1..qN) and save the model");
    auto options = std::make_shared<FitOptions>();
    fit_command->add_option("--learner", options->learner, "elm | oselm | llm | bpdc (proof of concept)")
        ->check(CLI::IsMember({"elm", "oselm", "llm", "bpdc"}))
        ->capture_default_str();
    fit_command->add_option("--data", options->data, "training data CSV with header area,x,y,z[,rx,ry,rz],q1,...,qN")->required();
    fit_command->add_option("--out", options->out, "model file to write")->required();
    fit_command->add_option("--hidden", options->hidden, "ELM/OS-ELM hidden neurons R")->check(finiteRange(1, 5000))->capture_default_str();
    fit_command->add_option("--epsilon", options->epsilon, "ELM/OS-ELM ridge regularization (Eq. 3.13)")
        ->check(finiteRange(1e-12, 1e12))
        ->capture_default_str();
    fit_command->add_option("--seed", options->seed, "random seed (ELM features, LLM sample order, BPDC weights)")
        ->check(finiteRange(std::int64_t{0}, std::numeric_limits<std::int64_t>::max()))
        ->capture_default_str();
    fit_command->add_option("--eta", options->eta, "LLM learning rate (Eq. 3.19)")->check(finiteRange(1e-9, 10.0))->capture_default_str();
    fit_command->add_option("--max-epochs", options->max_epochs, "LLM/BPDC epoch limit")->check(finiteRange(1, 1000000))->capture_default_str();
    fit_command->add_option("--tolerance", options->tolerance, "LLM stopping rule: relative MSE improvement that counts as progress")
        ->check(finiteRange(0.0, 1.0))
        ->capture_default_str();
    fit_command->add_option("--patience", options->patience, "LLM stopping rule: epochs without progress before stopping")
        ->check(finiteRange(1, 1000000))
        ->capture_default_str();
    fit_command->add_option("--area-radius", options->area_radius,
                            "without an area column: samples within this distance [m] of an area's first sample join it")
        ->check(finiteRange(1e-6, 100.0))
        ->capture_default_str();
    fit_command->callback([&runner, options] { runner.select([options] { return fit(*options); }); });
  }
  {
    auto* predict_command = learn->add_subcommand("predict", "predict joint values for the inputs of a CSV file");
    auto model = std::make_shared<std::string>();
    auto data = std::make_shared<std::string>();
    predict_command->add_option("--model", *model, "model file written by learn fit")->required();
    predict_command->add_option("--data", *data, "CSV with header [area,]x,y,z[,...][,q1,...,qN]")->required();
    predict_command->callback([&runner, model, data] { runner.select([model, data] { return predict(*model, *data); }); });
  }
}

}  // namespace flexirob::cli
