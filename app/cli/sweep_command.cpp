// `sweep`: the thesis' tables reproduced headless with the simulated tutor (issue #6, DESIGN §6):
// Tab. 3.2 (setups A-D and D* with a third area: E_task and E_coll per region), Tab. 3.3
// (setup I with 1/2/4/6/12 areas, setup II with 1/2/4/6/21: explored and reachable workspace,
// plus the implicit scene model of Eq. 4.1), Tab. 3.4 (ELM ε × LLM η × sub-sampling s over
// seeds: E_coll), Tab. 7.1 (ITM statistics for δ = 0, 2, 3, 4, 5) and Sect. 8.3 (9-DoF arm,
// 8 areas, 100 planned goals). JSON on stdout, a markdown table with `--markdown F`, progress
// on stderr.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "app/cli/cli_support.hpp"
#include "app/file_output.hpp"
#include "app/experiments.hpp"
#include "planning/path_postures.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::cli {
namespace {

struct SweepOptions {
  std::vector<std::string> tables{"3.2", "3.3", "3.4", "7.1", "8.3"};
  double spacing = 0.0;        ///< Tab. 3.3 grid spacing (0: the scene's, 5 cm)
  double spacing_34 = 0.15;    ///< Tab. 3.4 grid spacing
  int seeds = 10;              ///< Tab. 3.4 network initializations
  int goals = 100;             ///< Sect. 8.3
  int max_areas = 1000;        ///< Tab. 3.3 rows with more areas are skipped
  std::string approach = "visited";  ///< Tab. 3.3 / 3.4: where each target is approached from
  std::vector<std::string> only;     ///< Tab. 3.3 rows to run ("setup_I:4"), empty: all
  std::string markdown;        ///< markdown table file, or empty
  std::string json_out;        ///< JSON file, or empty
};

// One write per line, so that a line is never cut by what comes between its parts.
void log(const std::string& line) { std::cerr << ("sweep: " + line + "\n") << std::flush; }

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

struct Loaded {
  robot::RobotModel model;
  robot::Scene scene;
};

Loaded load(const std::string& scene_name) {
  robot::Scene scene = loadSceneNoting(scene_name);
  const std::string robot_name = robot::robotFor("", scene);
  robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot_name), "");
  robot::checkPosturesFit(scene, model, robot_name);
  return {std::move(model), std::move(scene)};
}

app::TeachSpec teachSpec(int areas) {
  app::TeachSpec spec;
  spec.areas = areas;
  spec.seed = 1;
  spec.workflow.background_learning = false;
  return spec;
}

// A region's E_task "mean ± sd (max)" in mm, or why there is none.
std::string regionError(const app::TrajectoryRegionResult& region) {
  if (region.e_task_trajectories == 0) return "n/a (no start reached)";
  return fixed(region.e_task_mean_mm, 1) + " ± " + fixed(region.e_task_std_mm, 1) + " (" + fixed(region.e_task_max_mm, 1) + ")";
}

std::string regionCollisions(const app::TrajectoryRegionResult& region) {
  return std::to_string(region.collisions) + "/" + std::to_string(region.trajectories);
}

// Tab. 3.2: two areas (three for D*), the regions' E_task and E_coll, twice: along the scene's
// stored trajectories (0.2 m boxes around the areas' centres), and along trajectories drawn in
// the boxes around the training data the tutor recorded, which is how the thesis defines its
// regions (Sect. 3.3.1: "axis-aligned bounding boxes around each of the two training data
// trajectories", the interpolation area between them).
Json table32(std::ostream& md) {
  const std::vector<std::tuple<std::string, std::string, int>> rows{
      {"A", "setup_A", 2}, {"B", "setup_B", 2}, {"C", "setup_C", 2}, {"D", "setup_D", 2}, {"D*", "setup_D", 3}};
  // Thesis Tab. 3.2 (left / right / interp.): E_task mm, E_coll.
  const std::map<std::string, std::string> thesis{{"A", "2.0 / 1.6 / 1.9 mm; 0 / 0 / 0"},
                                                  {"B", "1.8 / 2.0 / 1.9 mm; 0 / 0 / 0"},
                                                  {"C", "2.0 / 1.6 / 1.7 mm; 0 / 0 / 0"},
                                                  {"D", "1.9 / 1.6 / 1.6 mm; 0 / 0 / 16"},
                                                  {"D*", "E_coll interp. 3 (Sect. 3.3.1: 16 → 3 with the third area)"}};
  std::ostringstream scene_md, drawn_md;
  scene_md << "\n## Tab. 3.2 — E_task and E_coll per region, the scene's trajectories (ELM, tutor seed 1)\n\n"
           << "| setup | areas | samples | E_task left / right / interp. [mm] (mean ± sd, max) | E_coll left / right / interp. | thesis |\n|---|---|---|---|---|---|\n";
  drawn_md << "\n## Tab. 3.2 — the same sessions, trajectories drawn around the training data (the thesis' regions)\n\n"
           << "| setup | E_task left / right / interp. [mm] (mean ± sd, max) | E_coll left / right / interp. | further regions | thesis |\n|---|---|---|---|---|\n";
  Json out = Json::array();
  for (const auto& [label, scene_name, areas] : rows) {
    log("Tab. 3.2 setup " + label);
    const Loaded loaded = load(scene_name);
    const app::TaughtSystem taught = app::teachInSimulation(loaded.model, loaded.scene, teachSpec(areas));
    const auto map = app::fitMap(taught.data, loaded.model.dof(), app::LearnerKind::kElm, {}, {});
    const auto evaluate = [&, row = label](app::TrajectorySource source, const std::string& what) {
      const app::TrajectoryResult result = app::evaluateTrajectories(
          loaded.model, loaded.scene, app::sceneParameters(loaded.scene), *map, app::evaluatedAreas(taught), 25, 0.1, 1,
          [&](double f) { reportProgress("Tab. 3.2 " + row + " (" + what + ")", f); }, source);
      for (const auto& region : result.regions) {
        for (const auto& trajectory : region.collided) {
          log("Tab. 3.2 " + row + " (" + what + ") " + region.name + ": " + trajectory.name + " " + trajectory.contact + " at " +
              fixed(trajectory.contact_time, 2) + " s" + (trajectory.on_way_to_start ? " on the way to its start" : ""));
        }
      }
      return result;
    };
    const app::TrajectoryResult scene_result = evaluate(app::TrajectorySource::kScene, "scene");
    const app::TrajectoryResult drawn_result = evaluate(app::TrajectorySource::kTrainingData, "training data");
    std::string errors, collisions;
    Json scene_regions = Json::array(), drawn_regions = Json::array();
    for (const auto& region : scene_result.regions) {
      errors += (errors.empty() ? "" : " / ") + regionError(region);
      collisions += (collisions.empty() ? "" : " / ") + regionCollisions(region);
      scene_regions.push_back(trajectoryRegionJson(region));
    }
    scene_md << "| " << label << " | " << taught.areas.size() << " | " << taught.data.size() << " | " << errors << " | "
             << collisions << " | " << thesis.at(label) << " |\n";
    // The thesis' three columns are the areas left and right and the box between them; D*'s
    // third area and the box between it and the area taught before it are listed beside them.
    std::string further;
    std::map<std::string, const app::TrajectoryRegionResult*> by_name;
    for (const auto& region : drawn_result.regions) {
      drawn_regions.push_back(trajectoryRegionJson(region));
      by_name[region.name] = &region;
      if (region.name != "left" && region.name != "right" && region.name != "between left and right") {
        further += (further.empty() ? "" : "; ") + region.name + ": " + regionError(region) + ", " + regionCollisions(region);
      }
    }
    errors.clear();
    collisions.clear();
    for (const std::string name : {"left", "right", "between left and right"}) {
      const auto it = by_name.find(name);
      errors += (errors.empty() ? "" : " / ") + (it == by_name.end() ? std::string("n/a") : regionError(*it->second));
      collisions += (collisions.empty() ? "" : " / ") + (it == by_name.end() ? std::string("n/a") : regionCollisions(*it->second));
    }
    drawn_md << "| " << label << " | " << errors << " | " << collisions << " | " << (further.empty() ? "—" : further) << " | "
             << thesis.at(label) << " |\n";
    out.push_back({{"setup", label}, {"scene", scene_name}, {"areas", taught.areas.size()}, {"samples", taught.data.size()},
                   {"teaching_contacts", taught.tutor.collisions}, {"regions", scene_regions},
                   {"regions_around_training_data", drawn_regions}});
  }
  md << scene_md.str() << drawn_md.str();
  return out;
}

// Tab. 3.3's rows: scene, areas, the thesis' explored / reachable %.
const std::vector<std::tuple<std::string, int, std::string>>& tab33Rows() {
  static const std::vector<std::tuple<std::string, int, std::string>> rows{
      {"setup_I", 1, "4.9 / 51.3"},   {"setup_I", 2, "9.2 / 47.3"},   {"setup_I", 4, "23.7 / 89.7"},
      {"setup_I", 6, "31.0 / 93.0"},  {"setup_I", 12, "36.5 / 97.1"}, {"setup_II", 1, "7.1 / 51.6"},
      {"setup_II", 2, "9.7 / 64.8"},  {"setup_II", 4, "19.1 / 73.5"}, {"setup_II", 6, "31.6 / 80.8"},
      {"setup_II", 21, "56.5 / 94.1"}};
  return rows;
}

// Tab. 3.3 (and Eq. 4.1 on the same evaluation).
Json table33(const SweepOptions& options, std::ostream& md) {
  const auto& rows = tab33Rows();
  const app::ApproachFrom approach = app::parseApproach(options.approach);
  md << "\n## Tab. 3.3 — reachable workspace (ELM, tutor seed 1, targets approached from: " << options.approach
     << "), with the implicit scene model (Eq. 4.1)\n\n"
     << "| setup | areas (taught / given up) | samples | targets in T | explored % | reachable % | resolved posture free % | collided targets | S encloses obstacle points | free points in S | thesis explored / reachable % | wall s |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  Json out = Json::array();
  for (const auto& [scene_name, areas, thesis] : rows) {
    if (areas > options.max_areas) continue;
    if (!options.only.empty() &&
        std::find(options.only.begin(), options.only.end(), scene_name + ":" + std::to_string(areas)) == options.only.end()) {
      continue;
    }
    log("Tab. 3.3 " + scene_name + " with " + std::to_string(areas) + " areas");
    const auto start = std::chrono::steady_clock::now();
    const Loaded loaded = load(scene_name);
    const app::TaughtSystem taught = app::teachInSimulation(loaded.model, loaded.scene, teachSpec(areas));
    const auto map = app::fitMap(taught.data, loaded.model.dof(), app::LearnerKind::kElm, {}, {});
    const robot::EvaluationGrid grid = app::sceneGrid(loaded.scene, options.spacing);
    const app::ReachableResult reachable =
        app::evaluateReachable(loaded.model, loaded.scene, app::sceneParameters(loaded.scene), *map, taught.home, grid,
                               taught.data, [&, row = scene_name](double f) { reportProgress("Tab. 3.3 " + row, f); }, approach);
    const app::SceneModelResult model = app::evaluateSceneModel(loaded.model, loaded.scene, grid, reachable.final_postures);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    md << "| " << scene_name << " | " << taught.areas.size() << " / " << taught.areas_given_up << " | " << taught.data.size() << " | "
       << reachable.targets << " | " << fixed(100.0 * reachable.explored_fraction, 1) << " | "
       << fixed(100.0 * reachable.reachable_fraction, 1) << " | " << fixed(100.0 * reachable.resolved_fraction, 1) << " | "
       << reachable.collided << " | " << model.obstacle_points_enclosed
       << " / " << model.obstacle_points << " | " << model.free_points_in_model << " | " << thesis << " | " << fixed(wall, 0) << " |\n";
    md.flush();
    out.push_back({{"scene", scene_name}, {"areas_requested", areas}, {"areas", taught.areas.size()},
                   {"areas_given_up", taught.areas_given_up}, {"samples", taught.data.size()},
                   {"teaching_contacts", taught.tutor.collisions}, {"targets", reachable.targets},
                   {"inaccessible", reachable.inaccessible}, {"reached", reachable.reached}, {"collided", reachable.collided},
                   {"explored_fraction", reachable.explored_fraction}, {"reachable_fraction", reachable.reachable_fraction},
                   {"resolved_fraction", reachable.resolved_fraction},
                   {"scene_model_points", model.model_points}, {"obstacle_points", model.obstacle_points},
                   {"obstacle_points_enclosed", model.obstacle_points_enclosed},
                   {"free_points_in_model", model.free_points_in_model}, {"contacts", reachable.contacts},
                   {"spacing_m", grid.spacing}, {"wall_s", wall}, {"approach", options.approach}});
    std::string contacts;
    for (const auto& [contact, count] : reachable.contacts) contacts += " " + contact + " x" + std::to_string(count);
    log("Tab. 3.3 " + scene_name + " " + std::to_string(areas) + " areas: reachable " + fixed(100.0 * reachable.reachable_fraction, 1) +
        " %, explored " + fixed(100.0 * reachable.explored_fraction, 1) + " %, contacts:" + contacts);
  }
  return out;
}

// Tab. 3.4: E_coll over ELM ε / LLM η × sub-sampling s, averaged over seeds. The thesis ran one
// target trajectory through the workspace; here the collided targets of the reachability
// evaluation on a coarse grid take its place (the same question: does the map generalize
// collision-free beyond the data?).
Json table34(const SweepOptions& options, std::ostream& md) {
  md << "\n## Tab. 3.4 — E_coll (targets with a contact, mean over " << options.seeds << " seeds) and reachable %, 4 areas, grid "
     << fixed(options.spacing_34, 2) << " m\n\n| setup | learner | parameter | s = 1 | s = 5 | s = 80 |\n|---|---|---|---|---|---|\n";
  Json out = Json::array();
  for (const std::string scene_name : {"setup_I", "setup_II"}) {
    const Loaded loaded = load(scene_name);
    log("Tab. 3.4 " + scene_name + ": teaching 4 areas");
    const app::TaughtSystem taught = app::teachInSimulation(loaded.model, loaded.scene, teachSpec(4));
    const robot::EvaluationGrid grid = app::sceneGrid(loaded.scene, options.spacing_34);
    const robot::ParameterSet parameters = app::sceneParameters(loaded.scene);
    for (const auto kind : {app::LearnerKind::kElm, app::LearnerKind::kLlm}) {
      const bool elm = kind == app::LearnerKind::kElm;
      for (const double value : elm ? std::vector<double>{1.0, 0.01, 0.0001} : std::vector<double>{1.0, 0.1, 0.01}) {
        md << "| " << scene_name << " | " << (elm ? "ELM" : "LLM") << " | " << (elm ? "ε = " : "η = ") << value;
        for (const int s : {1, 5, 80}) {
          const learning::TrainingSet data = app::subsample(taught.data, s);
          double collided = 0.0, reachable = 0.0;
          for (int seed = 1; seed <= options.seeds; ++seed) {
            learning::ElmParams elm_params;
            learning::LlmParams llm_params;
            elm_params.seed = llm_params.seed = static_cast<std::uint64_t>(seed);
            if (elm) elm_params.epsilon = value; else llm_params.eta = value;
            const auto map = app::fitMap(data, loaded.model.dof(), kind, elm_params, llm_params);
            const app::ReachableResult result =
                app::evaluateReachable(loaded.model, loaded.scene, parameters, *map, taught.home, grid, taught.data, {},
                                       app::parseApproach(options.approach));
            collided += result.collided;
            reachable += result.reachable_fraction;
          }
          collided /= options.seeds;
          reachable /= options.seeds;
          log("Tab. 3.4 " + scene_name + (elm ? " ELM eps=" : " LLM eta=") + fixed(value, 4) + " s=" + std::to_string(s) +
              ": E_coll " + fixed(collided, 1) + ", reachable " + fixed(100 * reachable, 1) + " %");
          md << " | " << fixed(collided, 1) << " (" << fixed(100.0 * reachable, 0) << " %)";
          out.push_back({{"scene", scene_name}, {"learner", elm ? "elm" : "llm"}, {elm ? "epsilon" : "eta", value}, {"s", s},
                         {"samples", data.size()}, {"seeds", options.seeds}, {"e_coll_mean", collided},
                         {"reachable_fraction_mean", reachable}});
        }
        md << " |\n";
        md.flush();
      }
    }
  }
  return out;
}

// Tab. 7.1: graph statistics of the ITM fed during the same teaching session, per δ.
Json table71(std::ostream& md) {
  md << "\n## Tab. 7.1 — ITM statistics per δ (setup_I, 4 areas, e_max = 0.10 m)\n\n"
     << "| δ | nodes | edges | max ν | mean ν | max ε [m] | mean ε [m] |\n|---|---|---|---|---|---|---|\n";
  Json out = Json::array();
  const Loaded loaded = load("setup_I");
  for (const int delta : {0, 2, 3, 4, 5}) {
    log("Tab. 7.1 delta = " + std::to_string(delta));
    app::TeachSpec spec = teachSpec(4);
    spec.workflow.itm.delta = delta;
    const app::TaughtSystem taught = app::teachInSimulation(loaded.model, loaded.scene, spec);
    const planning::ItmStatistics stats = taught.itm->statistics();
    const bool bootstrapped = stats.bootstrapped_nodes > 0;
    md << "| " << delta << " | " << stats.nodes << " | " << stats.edges << " | " << stats.max_valence << " | "
       << fixed(stats.mean_valence, 2) << " | " << (bootstrapped ? fixed(stats.bootstrap_error_max, 4) : "n.a.") << " | "
       << (bootstrapped ? fixed(stats.bootstrap_error_mean, 4) : "n.a.") << " |\n";
    out.push_back({{"delta", delta}, {"nodes", stats.nodes}, {"edges", stats.edges}, {"max_valence", stats.max_valence},
                   {"mean_valence", stats.mean_valence}, {"bootstrapped_nodes", stats.bootstrapped_nodes},
                   {"bootstrap_error_max", bootstrapped ? Json(stats.bootstrap_error_max) : Json()},
                   {"bootstrap_error_mean", bootstrapped ? Json(stats.bootstrap_error_mean) : Json()},
                   {"components", stats.components}});
  }
  md << "\nThesis (its own session, Fig. 7.5): δ = 0: 175 nodes, 330 edges, max ν 10, mean ν 3.76; δ = 2: 177 / 388 / 13 / 4.37, ε 0.026 / 0.0208.\n";
  return out;
}

// Sect. 8.3: the 9-DoF arm, 8 areas, planned paths to random graph nodes.
Json section83(const SweepOptions& options, std::ostream& md) {
  log("Sect. 8.3: arm9, 8 areas");
  const Loaded loaded = load("arm9_areas");
  const app::TaughtSystem taught = app::teachInSimulation(loaded.model, loaded.scene, teachSpec(8));
  const auto map = app::fitMap(taught.data, loaded.model.dof(), app::LearnerKind::kElm, {}, {});
  const Eigen::VectorXd start = taught.areas.empty() ? taught.home : taught.areas.front().q_fixed;
  md << "\n## Sect. 8.3 — 9-DoF arm (arm9_areas), 8 areas, " << options.goals << " goals\n\n"
     << "| null-space posture along the path | areas (taught / given up) | ITM nodes | paths found | collision-free | within 1 cm | final error max mm | tracking error max mm | mean plan ms | thesis |\n|---|---|---|---|---|---|---|---|---|---|\n";
  Json rows = Json::array();
  // Both executions to the same goals: the postures shown along the paths, and the thesis' q_c alone.
  for (const planning::PlanPostures postures : {planning::PlanPostures::kDemonstrated, planning::PlanPostures::kLearned}) {
    const std::string name = planning::toString(postures);
    const app::PlanningResult result = app::evaluatePlanning(
        loaded.model, loaded.scene, app::sceneParameters(loaded.scene), *map, *taught.itm, start, options.goals, 1,
        [&name](double f) { reportProgress("Sect. 8.3 " + name, f); }, postures);
    for (const auto& [contact, count] : result.contacts) log("Sect. 8.3 " + name + " contact " + contact + " x" + std::to_string(count));
    md << "| " << name << " | " << taught.areas.size() << " / " << taught.areas_given_up << " | " << taught.itm->nodeCount()
       << " | " << result.found << " | " << result.collision_free << " | " << result.reached_1cm << " | "
       << fixed(1e3 * result.final_error_max_m, 3) << " | " << fixed(1e3 * result.tracking_error_max_m, 1) << " | "
       << fixed(result.mean_plan_ms, 2) << " | 100/100 collision-free, 99 within 1 cm |\n";
    rows.push_back({{"postures", name}, {"goals", result.goals}, {"found", result.found},
                    {"collision_free", result.collision_free}, {"reached_1cm", result.reached_1cm},
                    {"final_error_max_m", result.final_error_max_m}, {"tracking_error_max_m", result.tracking_error_max_m},
                    {"mean_plan_ms", result.mean_plan_ms}, {"contacts", result.contacts},
                    {"disconnected_nodes", result.disconnected_nodes}});
  }
  return {{"areas", taught.areas.size()}, {"areas_given_up", taught.areas_given_up}, {"teaching_contacts", taught.tutor.collisions},
          {"itm_nodes", taught.itm->nodeCount()}, {"executions", rows}};
}

Json runSweep(const SweepOptions& options) {
  const std::set<std::string> known{"3.2", "3.3", "3.4", "7.1", "8.3"};
  for (const auto& table : options.tables) {
    if (known.count(table) == 0) throw InputError("--tables: unknown table '" + table + "' (3.2, 3.3, 3.4, 7.1, 8.3)");
  }
  // --only names rows of Tab. 3.3: one that is not there, or without Tab. 3.3, would run nothing.
  if (!options.only.empty()) {
    std::string known_rows;
    std::set<std::string> known_row_names;
    for (const auto& [scene_name, areas, thesis] : tab33Rows()) {
      known_row_names.insert(scene_name + ":" + std::to_string(areas));
      known_rows += (known_rows.empty() ? "" : ", ") + scene_name + ":" + std::to_string(areas);
    }
    for (const auto& row : options.only) {
      if (known_row_names.count(row) == 0) throw InputError("--only: Tab. 3.3 has no row '" + row + "' (" + known_rows + ")");
    }
    if (std::find(options.tables.begin(), options.tables.end(), "3.3") == options.tables.end()) {
      throw InputError("--only: selects rows of Tab. 3.3, which --tables leaves out");
    }
  }
  // A sweep runs for minutes: an output that cannot be written is refused before it starts.
  for (const auto& [option, path] : {std::pair{"--json", options.json_out}, std::pair{"--markdown", options.markdown}}) {
    if (path.empty()) continue;
    checkOutputPath(option, path);
  }
  if (!options.json_out.empty() && !options.markdown.empty() && !app::isNullDevice(options.json_out) &&
      sameFileKey(options.json_out) == sameFileKey(options.markdown)) {
    throw InputError("--markdown: '" + options.markdown + "' is the file --json names; give each output its own file");
  }
  // The tables are kept until the sweep ends and only then written: a sweep stopped or failed
  // half-way leaves the files of the last one whole (progress is on stderr meanwhile).
  std::ostringstream md;
  md << "# flexirob-cli sweep\n";
  Json out = Json::object();
  const auto wanted = [&](const std::string& t) { return std::find(options.tables.begin(), options.tables.end(), t) != options.tables.end(); };
  if (wanted("3.2")) out["tab_3_2"] = table32(md);
  if (wanted("3.3")) out["tab_3_3"] = table33(options, md);
  if (wanted("3.4")) out["tab_3_4"] = table34(options, md);
  if (wanted("7.1")) out["tab_7_1"] = table71(md);
  if (wanted("8.3")) out["sect_8_3"] = section83(options, md);
  std::vector<app::OutputFile> outputs;
  if (!options.json_out.empty()) outputs.push_back({"--json", options.json_out, out.dump(2) + "\n"});
  if (!options.markdown.empty()) outputs.push_back({"--markdown", options.markdown, md.str()});
  app::writeFilesTogether(outputs);
  return out;
}

}  // namespace

void registerSweepCommand(CLI::App& app, CommandRunner& runner) {
  auto options = std::make_shared<SweepOptions>();
  CLI::App* sweep = app.add_subcommand("sweep", "reproduce the thesis' tables with the simulated tutor (Tab. 3.2, 3.3, 3.4, 7.1, Sect. 8.3)");
  sweep->add_option("--tables", options->tables, "subset of 3.2 3.3 3.4 7.1 8.3")->delimiter(',');
  sweep->add_option("--spacing", options->spacing, "Tab. 3.3 grid spacing [m] (default: the scene's)")->check(finiteRange(0.01, 1.0));
  sweep->add_option("--spacing-34", options->spacing_34, "Tab. 3.4 grid spacing [m]")->check(finiteRange(0.01, 1.0))->capture_default_str();
  sweep->add_option("--seeds", options->seeds, "Tab. 3.4 network initializations")->check(finiteRange(1, 100))->capture_default_str();
  sweep->add_option("--goals", options->goals, "Sect. 8.3 goals")->check(finiteRange(1, 10000))->capture_default_str();
  sweep->add_option("--max-areas", options->max_areas, "skip Tab. 3.3 rows with more areas (default: none skipped)")->check(finiteRange(1, 1000));
  addApproachOption(*sweep, options->approach);  // Tab. 3.3 and 3.4
  sweep->add_option("--only", options->only, "Tab. 3.3 rows to run, e.g. setup_I:4,setup_II:1")->delimiter(',');
  sweep->add_option("--markdown", options->markdown, "write the tables as markdown to this file");
  sweep->add_option("--json", options->json_out, "write the JSON result to this file as well");
  sweep->callback([&runner, options] { runner.select([options] { return runSweep(*options); }); });
}

}  // namespace flexirob::cli
