// `export --session F`: a recorded session as the files the offline tools read (docs/SESSIONS.md):
// --samples (learn fit), --stream (itm build), --model (learn predict), --graph (itm path).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "app/cli/cli_support.hpp"
#include "app/file_output.hpp"
#include "app/session_export.hpp"
#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "app/session_write_lock.hpp"
#include "app/workflow.hpp"
#include "learning/elm.hpp"
#include "learning/llm.hpp"
#include "learning/model_file.hpp"
#include "learning/learner.hpp"
#include "planning/itm_file.hpp"
#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/scene.hpp"

namespace flexirob::cli {
namespace {

struct ExportOptions {
  std::string session;
  std::string samples, stream, model, graph;
  double sample_period = 0.02;
  std::string robot_file, scene_file;  ///< where the session's robot and scene files lie now (addMovedFilesOptions)
  bool accept_damage = false;  ///< export from a file SQLite's quick check finds damaged
};

// A session driven over FRI (the real robot, or teach --backend fri-sim): the workflow saw no
// contacts and fed its ITM every position. `parameters` are the session's metadata; the GUI
// records its backend as "sim" or "fri://HOST:PORT", teach as "sim" or "fri-sim".
bool drivenOverFri(const Json& parameters) {
  if (!parameters.is_object() || !parameters.contains("backend") || !parameters.at("backend").is_string()) return false;
  return parameters.at("backend").get<std::string>().rfind("fri", 0) == 0;
}

std::string bytesText(const std::vector<std::uint8_t>& bytes) { return std::string(bytes.begin(), bytes.end()); }

// The shortest spelling that reads back as the same double.
std::string exactNumber(double value) {
  char text[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

// The `learn fit` options that learn the session's model (read from the session) again from
// the exported samples, byte for byte, or null with the reason why none do.
void describeRefit(const std::unique_ptr<learning::Learner>& learner, Json& entry) {
  entry["learn_fit_arguments"] = nullptr;
  if (const auto* elm = dynamic_cast<const learning::Elm*>(learner.get())) {
    const learning::ElmParams& p = elm->params();
    const learning::ElmParams defaults;
    if (p.input_weight_range != defaults.input_weight_range || p.gain_min != defaults.gain_min ||
        p.gain_max != defaults.gain_max || p.bias_range != defaults.bias_range) {
      entry["learn_fit_note"] = "its random features were drawn with ranges learn fit has no option for";
      return;
    }
    entry["learn_fit_arguments"] = "--learner elm --hidden " + std::to_string(p.hidden) + " --epsilon " + exactNumber(p.epsilon) +
                                   " --seed " + std::to_string(p.seed);
  } else if (const auto* llm = dynamic_cast<const learning::Llm*>(learner.get())) {
    const learning::LlmParams& p = llm->params();
    if (p.target_mse != learning::LlmParams{}.target_mse) {
      entry["learn_fit_note"] = "it stopped at a target error learn fit has no option for";
      return;
    }
    entry["learn_fit_arguments"] = "--learner llm --eta " + exactNumber(p.eta) + " --max-epochs " + std::to_string(p.max_epochs) +
                                   " --tolerance " + exactNumber(p.tolerance) + " --patience " + std::to_string(p.patience) +
                                   " --seed " + std::to_string(p.seed);
  } else if (learner->kind() == "oselm") {
    entry["learn_fit_note"] =
        "an OS-ELM learned online scales its inputs to a fixed box about the arm's shoulder, learn fit to its data: "
        "the refit is an OS-ELM of the same samples, not this model";
  } else {
    entry["learn_fit_note"] = "learn fit does not learn a '" + learner->kind() + "' model as the session did";
  }
}

Json exportSession(const ExportOptions& options) {
  const std::vector<std::pair<std::string, std::string>> outputs = {
      {"--samples", options.samples}, {"--stream", options.stream}, {"--model", options.model}, {"--graph", options.graph}};
  // The session and the files SQLite and the recorder keep beside it (an interrupted session's
  // log holds what the database does not yet): none of them is an output.
  std::map<std::string, std::string> chosen;
  // As given and, for a session reached through a symbolic link, as resolved: SQLite keeps its
  // log beside the file the link names.
  for (const std::string& session : {options.session, sameFileKey(options.session)}) {
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) chosen.emplace(sameFileKey(session + suffix), "--session");
    chosen.emplace(sameFileKey(app::SessionWriteLock::lockFileFor(session).string()), "--session");
  }
  // The robot and scene files read in place of the session's copies are inputs as well; a
  // built-in name reads its file among the resources, not one of that name here.
  if (!options.robot_file.empty()) chosen.emplace(sameFileKey(robotFileOf(options.robot_file)), "--robot");
  if (const std::string file = sceneFileOf(options.scene_file); !file.empty()) chosen.emplace(sameFileKey(file), "--scene");
  bool any = false;
  for (const auto& [option, path] : outputs) {
    if (path.empty()) continue;
    any = true;
    checkOutputPath(option, path, {{"--session", options.session}});
    if (app::isNullDevice(path)) continue;  // takes any number of outputs
    if (const auto [where, added] = chosen.emplace(sameFileKey(path), option); !added) {
      throw InputError(where->second == "--session"
                           ? option + ": '" + path + "' is the session or a file SQLite keeps beside it; give another file"
                           : option + ": '" + path + "' is the file " + where->second + " names; give each output its own file");
    }
  }
  if (!any) throw InputError("export: nothing to write; give --samples, --stream, --model or --graph");
  {
    std::ifstream in(options.session);
    if (!in) throw InputError("--session: cannot read '" + options.session + "'");
    if (startsAsJson(in)) {
      // Told apart from any other text that starts as JSON might (a scene's "name: ...").
      const Json json = Json::parse(in, nullptr, false);
      if (!json.is_object() || !json.contains("format") || json.at("format") != "flexirob-session-json") {
        throw InputError("--session: '" + options.session + "' is not a session file (neither a recorded session nor a JSON session)");
      }
      throw InputError("--session: '" + options.session +
                       "' is a JSON session, which holds its areas as text already; export reads the sessions teach and the GUI record");
    }
  }
  const app::SessionReader reader(options.session);
  // Damage need not stop a read: rows on pages that still read can hold wrong values, and a
  // table of them, learned from without a word, would pass for the teaching.
  const std::string damage = reader.damage();
  if (!damage.empty() && !options.accept_damage) {
    throw InputError("--session: session file " + options.session + " is damaged (" + printable(damage, 200) +
                     "); what reads from it may hold wrong values, so nothing is written (--accept-damage writes what still reads)");
  }
  if (!damage.empty()) {
    std::fprintf(stderr, "note: the session file is damaged (%s); what is written may hold wrong values (eval checks each sample against the robot)\n",
                 printable(damage, 200).c_str());
  }
  // The graph is read only where it is asked for: a damaged snapshot does not stand in the way
  // of the samples.
  const app::RecordedTeaching teaching = app::readRecordedTeaching(reader, false);
  // The robot and scene files the session names are its cell's own (the session keeps copies,
  // their owner does not): no output replaces them. teach names a file by its absolute path; the
  // GUI names a robot or scene by the name it gives itself, which is no file here.
  for (const auto& [what, file] : {std::pair<std::string, std::string>{"the robot's URDF", robotFileOf(teaching.robot)},
                                   {"the scene file", sceneFileOf(teaching.scene)}}) {
    if (file.empty() || !std::filesystem::path(file).is_absolute()) continue;
    for (const auto& [option, path] : outputs) {
      if (!path.empty() && app::isExistingFile(path, file)) {
        throw InputError(option + ": '" + path + "' is " + what + " the session was taught with; give another file");
      }
    }
  }
  const Json stored_parameters = Json::parse(reader.metadata().parameters, nullptr, false);
  // The last ITM snapshot, read once for --stream and --graph.
  const std::optional<app::ItmRecord> snapshot =
      options.stream.empty() && options.graph.empty() ? std::nullopt : reader.lastItmSnapshot();
  Json result;
  result["session"] = options.session;
  result["robot"] = teaching.robot;
  result["scene"] = teaching.scene;

  // Every output is prepared before the first is written: a session that lacks one writes none.
  std::vector<app::OutputFile> files;

  if (!options.samples.empty()) {
    std::string csv = app::trainingSamplesCsv(teaching);
    Json areas = Json::array();
    std::int64_t rows = 0;
    for (const app::RecordedArea& area : teaching.areas) {
      if (!area.complete || area.X.cols() == 0) continue;
      areas.push_back({{"area", area.index}, {"name", area.name}, {"samples", area.X.cols()}});
      rows += area.X.cols();
    }
    result["samples"] = {{"file", options.samples}, {"rows", rows}, {"areas", areas}};
    files.push_back({"--samples", options.samples, std::move(csv)});
  }

  if (!options.stream.empty()) {
    std::unique_ptr<robot::RobotModel> model;
    std::unique_ptr<robot::Scene> scene;
    std::unique_ptr<robot::CollisionWorld> world;
    const bool over_fri = drivenOverFri(stored_parameters);
    if (!over_fri) {
      model = std::make_unique<robot::RobotModel>(loadSessionRobot(teaching.robot, teaching.robot_urdf, teaching.tip, options.robot_file));
      scene = std::make_unique<robot::Scene>(loadSessionScene(teaching.scene, teaching.scene_text, options.scene_file));
      noteMeshesChangedSinceTeaching(teaching.mesh_digests, *model, *scene);
      world = std::make_unique<robot::CollisionWorld>(*model, *scene);
      // The meshes the robot and the scene read are inputs too: an output in their place would
      // replace a cell's geometry with a table.
      refuseOutputsOverMeshes(outputs, *model, *scene);
    }
    const app::ConfigurationStream stream = app::configurationStream(
        reader, options.sample_period, world.get(), [](double fraction) { reportProgress("export: replaying the configuration stage", fraction); });
    reportStatus("export: replaying the configuration stage", true);
    if (stream.X.cols() == 0) throw InputError("--stream: the session recorded no position in CONFIGURATION");
    Json entry = {{"file", options.stream},
                  {"rows", stream.X.cols()},
                  {"sample_period_s", options.sample_period},
                  {"states_read", stream.states_read},
                  {"left_out_in_contact", stream.left_out_in_contact},
                  {"contacts_checked", !over_fri}};
    // The session's graph and what itm build needs to map the stream as the session did. The
    // stream rebuilds it exactly where the recording holds every state the workflow read and
    // its contacts: a simulated teach run that ended cleanly, replayed at the workflow's own
    // sample period (teach keeps the default; another period feeds the map other positions).
    const bool written_by_teach = stored_parameters.is_object() && stored_parameters.contains("seed");
    const bool workflows_period = std::abs(options.sample_period - app::WorkflowOptions{}.sample_period) < 1e-12;
    entry["rebuilds_session_graph"] = false;
    try {
      if (snapshot) {
        entry["rebuilds_session_graph"] = written_by_teach && !over_fri && teaching.closed_cleanly && workflows_period;
        const planning::Itm graph = planning::itmFromBytes(snapshot->bytes.data(), snapshot->bytes.size(), "session graph");
        const planning::ItmParameters& parameters = graph.parameters();
        entry["session_graph"] = {{"nodes", graph.nodeCount()},
                                  {"edges", graph.edgeCount()},
                                  {"variant", parameters.variant == planning::ItmVariant::kPlain ? "plain" : "hybrid"},
                                  {"parameters", itmParametersJson(parameters)},
                                  // As learn_fit_arguments for the model: the session's values
                                  // (scaled to the arm), which itm build's defaults are not.
                                  {"itm_build_arguments",
                                   "--emax " + exactNumber(parameters.e_max) + " --delta " + std::to_string(parameters.delta) +
                                       " --dthetamax " + exactNumber(parameters.d_theta_max) + " --dcmax " +
                                       exactNumber(parameters.d_c_max) + " --alpha " + exactNumber(parameters.alpha) + " --eta " +
                                       exactNumber(parameters.eta) + " --variant " +
                                       (parameters.variant == planning::ItmVariant::kPlain ? "plain" : "hybrid")}};
      }
    } catch (const planning::ItmFileError& error) {
      std::fprintf(stderr, "note: the session's ITM snapshot is damaged (%s); the stream is written without its parameters\n", error.what());
      entry["rebuilds_session_graph"] = false;
    }
    result["stream"] = entry;
    files.push_back({"--stream", options.stream, app::configurationStreamCsv(stream)});
  }

  if (!options.model.empty()) {
    const std::vector<app::ModelRecord> models = reader.models();
    if (models.empty()) throw InputError("--model: the session recorded no learned model (learning runs after finished_configuration)");
    const app::ModelRecord& last = models.back();
    // Read as learn predict will read it: a damaged model is not handed on (as --graph).
    std::unique_ptr<learning::Learner> learner;
    try {
      learner = learning::readLearner(learning::ModelReader(bytesText(last.bytes), options.session + " (learned model)"));
    } catch (const learning::ModelFileError& error) {
      throw InputError(std::string("--model: the session's last model does not read: ") + error.what());
    }
    result["model"] = {{"file", options.model}, {"learner", last.learner_kind}, {"samples", last.samples}, {"time_s", last.time}};
    describeRefit(learner, result["model"]);
    files.push_back({"--model", options.model, bytesText(last.bytes)});
  }

  if (!options.graph.empty()) {
    if (!snapshot) throw InputError("--graph: the session recorded no ITM graph");
    // The snapshot is checked as itm path will read it; a damaged one is not handed on.
    const planning::Itm graph = planning::itmFromBytes(snapshot->bytes.data(), snapshot->bytes.size(), options.session + " (ITM snapshot)");
    result["graph"] = {{"file", options.graph}, {"nodes", graph.nodeCount()}, {"edges", graph.edgeCount()}, {"time_s", snapshot->time}};
    files.push_back({"--graph", options.graph, bytesText(snapshot->bytes)});
  }

  if (!teaching.closed_cleanly) {
    std::fprintf(stderr, "note: the session '%s' was not closed cleanly (interrupted, or still being written); export writes what was recorded\n",
                 options.session.c_str());
  }
  result["closed_cleanly"] = teaching.closed_cleanly;
  result["damage"] = damage.empty() ? Json(nullptr) : Json(damage);
  // Through a symbolic link to the file it points at, keeping the link; all of them or none.
  app::writeFilesTogether(files);
  return result;
}

}  // namespace

void registerExportCommand(CLI::App& app, CommandRunner& runner) {
  auto* command = app.add_subcommand(
      "export", "Write a recorded session's training samples, configuration stream, model or ITM graph as the files learn and itm read");
  auto options = std::make_shared<ExportOptions>();
  command->add_option("--session", options->session, "session database written by teach or the GUI")->required();
  command->add_option("--samples", options->samples, "training samples CSV (area,x,y,z,q1..qN) for learn fit");
  command->add_option("--stream", options->stream, "positions the configuration stage fed the ITM, CSV (x,y,z,q1..qN) for itm build");
  command->add_option("--model", options->model, "the last learned model, for learn predict");
  command->add_option("--graph", options->graph, "the last ITM graph, for itm path");
  command->add_option("--sample-period", options->sample_period, "with --stream: seconds between positions (the workflow's sample period)")
      ->check(finiteRange(1e-4, 10.0))
      ->capture_default_str();
  addMovedFilesOptions(*command, options->robot_file, options->scene_file);
  command->add_flag("--accept-damage", options->accept_damage,
                    "export from a session file SQLite finds damaged (refused otherwise): what still reads, which may hold wrong values");
  command->callback([&runner, options] { runner.select([options] { return readingSession(options->session, [options] { return exportSession(*options); }); }); });
}

}  // namespace flexirob::cli
