// `review --session F`: the study metrics of one recorded session (DESIGN §5, §6; thesis
// Sect. 3.3, 4.3.3, 5.2.2). Fields: duration_s, areas, samples, e_task, e_coll and the details
// they come from.
// `review --study DIR`: every session in DIR: per-participant table, k-means clusters of the
// q_fixed postures per area (App. B.4), MDS coordinates, the consistent combinations (Tab. 4.1);
// --csv-dir writes every table as CSV, --plot the MDS scatter plot as PNG (docs/STUDY.md).
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "app/cli/cli_support.hpp"
#include "app/file_output.hpp"
#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "app/study.hpp"
#include "app/study_metrics.hpp"
#include "render/offscreen.hpp"
#include "robot/errors.hpp"

namespace flexirob::cli {
namespace {

using app::SessionReader;
using app::TrajectoryKind;
using app::TrajectoryRecord;

const char* kindName(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::TeachIn: return "teach_in";
    case TrajectoryKind::Target: return "target";
    case TrajectoryKind::Executed: return "executed";
  }
  return "";
}

Json numberOrNull(const std::optional<double>& value) {
  return value && std::isfinite(*value) ? Json(*value) : Json(nullptr);
}

// Shape metrics of a trajectory against its target (Sect. 5.2.2) and its jerk.
Json trajectoryMetrics(const TrajectoryRecord& trajectory, const TrajectoryRecord* target) {
  Json entry;
  entry["id"] = trajectory.id;
  entry["kind"] = kindName(trajectory.kind);
  entry["name"] = trajectory.name;
  entry["points"] = trajectory.times.size();
  entry["duration_s"] = trajectory.times.size() > 0 ? trajectory.times(trajectory.times.size() - 1) - trajectory.times(0) : 0.0;
  std::optional<double> jerk_mean;
  try {
    jerk_mean = app::jerk(trajectory.times, trajectory.positions).mean;
  } catch (const std::invalid_argument&) {
    // Fewer than four points or repeated times: no jerk.
  }
  entry["jerk_mean"] = numberOrNull(jerk_mean);
  if (target && target->positions.cols() > 0 && trajectory.positions.cols() > 0) {
    entry["reference_id"] = target->id;
    entry["max_deviation_m"] = app::maxDeviation(trajectory.positions, target->positions);
    entry["procrustes_m"] = app::procrustesDistance(trajectory.positions, target->positions).distance;
  }
  return entry;
}

Json review(const std::string& file) {
  const SessionReader reader(file);
  Json out;
  out["session"] = file;
  out["schema_version"] = reader.schemaVersion();
  out["robot"] = reader.metadata().robot_name;
  out["scene"] = reader.metadata().scene_name;
  out["participant"] = reader.metadata().participant;
  out["software_version"] = reader.metadata().software_version;
  out["start_time_utc"] = reader.metadata().start_time_utc;
  // A session closed by its recorder has an end time; a killed one does not.
  out["closed_cleanly"] = !reader.meta("end_time_utc").empty();
  // Damage where this review does not read (a stored model's pages) still makes the file suspect.
  const std::string damage = reader.damage();
  out["damage"] = damage.empty() ? Json(nullptr) : Json(damage);
  const auto [first_time, last_time] = reader.recordedTimeSpan();
  out["duration_s"] = last_time - first_time;
  out["states"] = reader.stateCount();
  if (reader.stateCount() == 0) {
    std::cerr << "note: the session holds no robot states (none recorded, or deleted since): duration_s spans its events, and no posture is replayed\n";
  }

  // Training areas and samples: each area's latest take (a re-taught area counts once), and the
  // samples of a RECORDING the session ended in apart (app/session_teaching.hpp).
  const app::RecordedTeaching teaching = app::readRecordedTeaching(reader, /*read_graph=*/false);
  std::int64_t samples = 0;
  std::int64_t unfinished = 0;
  Json per_area = Json::object();
  Json taught_areas = Json::array();  // with the names teach, export and the GUI give the areas
  for (const app::RecordedArea& area : teaching.areas) {
    samples += area.X.cols();
    unfinished += area.unfinished_X.cols();
    if (!area.complete) continue;
    per_area[std::to_string(area.index)] = area.X.cols();
    taught_areas.push_back({{"index", area.index}, {"name", area.name.empty() ? Json() : Json(area.name)}, {"samples", area.X.cols()}});
  }
  out["areas"] = std::count_if(teaching.areas.begin(), teaching.areas.end(), [](const app::RecordedArea& a) { return a.complete; });
  out["samples"] = samples;
  out["samples_per_area"] = per_area;
  out["taught_areas"] = taught_areas;
  out["unfinished_recording_samples"] = unfinished;

  // E_task (Eq. 3.20) over every executed motion that names its reference trajectory.
  const auto trajectories = reader.trajectories();
  const app::TrajectoryReferences references(trajectories);
  double error_sum = 0.0;
  std::int64_t error_points = 0;
  Json executed = Json::array();
  Json teach_in = Json::array();
  for (const auto& t : trajectories) {
    if (t.kind == TrajectoryKind::Executed) {
      Json entry = trajectoryMetrics(t, references.referenceOf(t));
      entry["outcome"] = t.outcome;
      if (const auto error = references.executionError(t)) {
        entry["e_task"] = error->first;
        error_sum += error->first * static_cast<double>(error->second);
        error_points += error->second;
      }
      const double t0 = t.times.size() > 0 ? t.times(0) : 0.0;
      const double t1 = t.times.size() > 0 ? t.times(t.times.size() - 1) : -1.0;
      entry["collisions"] = reader.collisions(t0, t1).size();
      executed.push_back(entry);
    } else if (t.kind == TrajectoryKind::TeachIn) {
      teach_in.push_back(trajectoryMetrics(t, references.targetOf(t)));
    }
  }
  out["e_task"] = error_points > 0 ? Json(error_sum / static_cast<double>(error_points)) : Json(nullptr);
  // E_coll: collisions recorded during the session (contacts the simulator reported).
  const auto collisions = reader.collisions();
  out["e_coll"] = collisions.size();
  std::int64_t colliding_motions = 0;
  for (const auto& entry : executed) colliding_motions += entry["collisions"].get<std::int64_t>() > 0 ? 1 : 0;
  out["colliding_motions"] = colliding_motions;
  out["executed_motions"] = executed;
  out["teach_in"] = teach_in;

  // Time per phase (Sect. 4.3.3: efficiency).
  Json phases = Json::object();
  for (const auto& [phase, seconds] : app::timePerPhase(reader.stages(), last_time)) phases[phase] = seconds;
  out["time_per_phase_s"] = phases;
  std::int64_t triggers = 0;
  std::int64_t buttons = 0;
  for (const auto& s : reader.signals()) (s.kind == app::SignalKind::Button ? buttons : triggers) += 1;
  out["triggers"] = triggers;
  out["buttons"] = buttons;

  const auto models = reader.models();
  out["models"] = models.size();
  if (!models.empty()) {
    out["last_model"] = {{"learner", models.back().learner_kind},
                         {"samples", models.back().samples},
                         {"train_seconds", models.back().train_seconds},
                         {"bytes", models.back().bytes.size()}};
  }
  out["itm_snapshots"] = reader.itmSnapshotCount();
  if (const auto graph = reader.lastItmSnapshot()) out["itm"] = {{"nodes", graph->nodes}, {"edges", graph->edges}};
  // Written at close; a killed session has none (null).
  const auto count = [&reader](const std::string& key) -> Json {
    const std::string text = reader.meta(key);
    try {
      return text.empty() ? Json(nullptr) : Json(std::stoll(text));
    } catch (const std::exception&) {
      return Json(nullptr);
    }
  };
  out["recorder_states_dropped"] = count("states_dropped");
  out["recorder_events_dropped"] = count("events_dropped");
  // E_coll by replay: the recorded postures against the recorded scene in the collision world.
  const app::ParticipantResult replayed = app::analyseSession(reader, 0.01);
  out["e_coll_replayed"] = replayed.e_coll ? Json(*replayed.e_coll) : Json(nullptr);
  out["colliding_samples_replayed"] = replayed.e_coll ? Json(replayed.colliding_samples) : Json(nullptr);
  out["replayed_samples"] = replayed.replayed_samples;
  if (!replayed.replay_note.empty()) {
    out["replay_note"] = replayed.replay_note;
    // Said where a person reads, as the missing states are: a null E_coll in the JSON alone
    // would pass unnoticed.
    if (reader.stateCount() > 0) std::cerr << "note: E_coll was not replayed: " << replayed.replay_note << "\n";
  }
  return out;
}

Json optionalNumber(const std::optional<double>& value) { return value ? Json(*value) : Json(nullptr); }

struct StudyArguments {
  std::string folder;
  std::string csv_dir;
  std::string plot;
  std::string centres;
  double success_e_task = 0.01;
  double replay_interval = 0.01;
};

Json reviewStudy(const StudyArguments& arguments) {
  app::StudyOptions options;
  if (!arguments.centres.empty()) {
    options.seeds = app::loadClusterSeeds(arguments.centres);
    options.seeds_robot.clear();
  }
  options.success_e_task = arguments.success_e_task;
  options.replay_interval = arguments.replay_interval;
  options.progress = [](const std::string& what, double fraction) { reportProgress("review " + what, fraction); };
  // A study runs for a while: a --plot path that cannot be written, or that names a file the run
  // reads, is refused before it.
  std::vector<std::pair<std::string, std::string>> inputs{{"--centres", arguments.centres}};
  // The sessions and the logs SQLite keeps beside them.
  for (const std::filesystem::path& session : app::studySessionFiles(arguments.folder)) {
    for (const char* suffix : {"", "-wal", "-shm", "-journal"}) inputs.emplace_back("--study", session.string() + suffix);
  }
  if (!arguments.plot.empty()) checkOutputPath("--plot", arguments.plot, inputs);
  const app::StudyResult study = app::analyseStudy(arguments.folder, options);

  Json out;
  out["study"] = arguments.folder;
  Json participants = Json::array();
  for (const auto& p : study.participants) {
    Json clusters = Json::object();
    for (const auto& [area, name] : p.cluster) clusters[std::to_string(area)] = name;
    Json phases = Json::object();
    for (const auto& [phase, seconds] : p.time_per_phase) phases[phase] = seconds;
    participants.push_back({{"participant", p.participant},
                            {"file", p.file},
                            {"robot", p.robot},
                            {"scene", p.scene},
                            {"closed_cleanly", p.closed_cleanly},
                            {"duration_s", p.duration_s},
                            {"areas", p.areas},
                            {"samples", p.samples},
                            {"e_task", optionalNumber(p.e_task)},
                            {"max_deviation_m", optionalNumber(p.max_deviation)},
                            {"procrustes_m", optionalNumber(p.procrustes)},
                            {"jerk_mean", optionalNumber(p.jerk_mean)},
                            {"e_coll", p.e_coll ? Json(*p.e_coll) : Json(nullptr)},
                            {"colliding_samples", p.colliding_samples},
                            {"replayed_samples", p.replayed_samples},
                            {"e_coll_recorded", p.e_coll_recorded},
                            {"clusters", clusters},
                            {"time_per_phase_s", phases}});
    if (!p.replay_note.empty()) participants.back()["replay_note"] = p.replay_note;
  }
  out["participants"] = participants;
  out["skipped"] = study.skipped;
  out["not_clustered"] = study.not_clustered;
  out["clustering_note"] = study.clustering_note.empty() ? Json() : Json(study.clustering_note);
  if (!study.clustering_note.empty()) std::cerr << "note: not clustered: " << study.clustering_note << "\n";
  for (const std::string& line : study.not_clustered) std::cerr << "note: not clustered: " << line << "\n";
  Json clusterings = Json::array();
  for (const auto& c : study.clusterings) {
    Json clusters = Json::array();
    for (std::size_t k = 0; k < c.names.size(); ++k) {
      clusters.push_back({{"name", c.names[k]},
                          {"users", c.kmeans.sizes[k]},
                          {"centre", toJson(c.kmeans.centres.col(static_cast<Eigen::Index>(k)))}});
    }
    Json members = Json::array();
    for (std::size_t m = 0; m < c.participants.size(); ++m) {
      const auto column = static_cast<Eigen::Index>(m);
      members.push_back({{"participant", c.participants[m]},
                         {"cluster", c.names[static_cast<std::size_t>(c.kmeans.labels[m])]},
                         {"mds", {c.mds(0, column), c.mds(1, column)}}});
    }
    clusterings.push_back({{"area", c.area},
                           {"iterations", c.kmeans.iterations},
                           {"converged", c.kmeans.converged},
                           {"clusters", clusters},
                           {"members", members}});
  }
  out["clusterings"] = clusterings;
  Json combinations = Json::array();
  for (const auto& c : study.combinations) {
    combinations.push_back({{"combination", c.name},
                            {"users", c.users},
                            {"successful", c.successful},
                            {"median_e_task", optionalNumber(c.median_e_task)},
                            {"median_e_coll", optionalNumber(c.median_e_coll)},
                            {"consistent", c.consistent}});
  }
  out["combinations"] = combinations;
  std::vector<app::OutputFile> plot;
  // Nothing clustered is nothing to draw: a blank picture named in the JSON would pass for one.
  const bool plotted = !arguments.plot.empty() && !study.clusterings.empty();
  if (!arguments.plot.empty() && !plotted) std::cerr << "note: --plot: no area was clustered, so no picture was written (a file already there is left as it was)\n";
  if (plotted) {
    // Room for the legend below each frame: a row per used cluster at most, and the ring's and
    // the scale bar's.
    std::size_t most_used = 0;
    for (const app::AreaClustering& clustering : study.clusterings) {
      most_used = std::max<std::size_t>(most_used, std::count_if(clustering.kmeans.sizes.begin(), clustering.kmeans.sizes.end(), [](int size) { return size > 0; }));
    }
    const int height = std::min(8192, 360 + 18 * static_cast<int>(most_used + 2));
    const app::ScatterImage scatter = app::renderMdsScatter(study, 360 * std::max<int>(1, static_cast<int>(study.clusterings.size())), height);
    render::Image image;
    image.width = scatter.width;
    image.height = scatter.height;
    image.rgba = scatter.rgba;
    std::vector<render::PlacedLabel> labels;
    for (const app::ScatterLabel& label : scatter.labels) {
      labels.push_back({label.text, static_cast<float>(label.x), static_cast<float>(label.baseline), static_cast<float>(label.max_width)});
    }
    plot.push_back({"--plot", arguments.plot, render::encodePng(render::printLabels(image, labels))});
  }
  // The tables and the plot together: all of them or none.
  if (!arguments.csv_dir.empty()) {
    Json files = Json::array();
    std::vector<std::pair<std::string, std::filesystem::path>> read;
    for (const auto& [option, file] : inputs) read.emplace_back(option, file);
    for (const auto& file : app::writeStudyCsv(study, arguments.csv_dir, plot, read)) files.push_back(file.string());
    out["csv_files"] = files;
  } else {
    app::writeFilesTogether(plot);
  }
  if (!arguments.plot.empty()) out["plot"] = plotted ? Json(arguments.plot) : Json(nullptr);
  return out;
}

}  // namespace

void registerReviewCommands(CLI::App& app, CommandRunner& runner) {
  auto* command = app.add_subcommand("review", "Study metrics of a recorded session or of a folder of sessions");
  auto session = std::make_shared<std::string>();
  auto study = std::make_shared<StudyArguments>();
  auto* session_option = command->add_option("--session", *session, "session database written by teach or the GUI");
  auto* study_option = command->add_option("--study", study->folder, "folder of session databases (*.flexirob as the GUI writes them, *.db, *.sqlite, *.session)");
  session_option->excludes(study_option);
  command->add_option("--csv-dir", study->csv_dir, "with --study: write every table as CSV into this folder");
  command->add_option("--plot", study->plot, "with --study: write the MDS scatter plot of the postures (PNG)");
  command->add_option("--centres", study->centres,
                      "with --study: initial k-means centres, CSV lines area,name,q1,...,q6 (default: thesis Tab. B.1)");
  command->add_option("--success-e-task", study->success_e_task, "with --study: E_task [m] a successful teaching stays within")
      ->check(finiteRange(0.0, 10.0));
  command->add_option("--replay-interval", study->replay_interval, "with --study: seconds between replayed states for E_coll")
      ->check(finiteRange(0.0, 10.0));
  command->callback([&runner, session, study, session_option, study_option] {
    if (session_option->count() == 0 && study_option->count() == 0) {
      throw InputError("review: expected --session FILE or --study DIR");
    }
    if (session_option->count() > 0) {
      if (!study->csv_dir.empty() || !study->plot.empty() || !study->centres.empty()) {
        throw InputError("review: --csv-dir, --plot and --centres go with --study");
      }
      runner.select([session] { return readingSession(*session, [session] { return review(*session); }); });
    } else {
      runner.select([study] { return reviewStudy(*study); });
    }
  });
}

}  // namespace flexirob::cli
