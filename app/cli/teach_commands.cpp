// `teach`: the simulated tutor teaches a robot in a scene through the workflow (DESIGN §6) and
// writes the session through the SQLite session recorder (states at control rate, stages, triggers,
// buttons, areas, samples, model, ITM), or as JSON when the path ends in .json.
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <iostream>
#include <mutex>
#include <sstream>
#include <unistd.h>

#include "app/backend_factory.hpp"
#include "app/evaluation.hpp"
#include "app/experiments.hpp"
#include "app/file_output.hpp"
#include "app/cli/cli_support.hpp"
#include "app/mesh_digest.hpp"
#include "app/session_recorder.hpp"
#include "app/session_write_lock.hpp"
#include "planning/itm_file.hpp"
#include "app/simulated_tutor.hpp"
#include "app/workflow.hpp"
#include "app/workflow_session.hpp"
#include "robot/errors.hpp"
#include "robot/fri_simulated_controller.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::cli {
namespace {

struct TeachOptions {
  std::string robot;  ///< empty: the scene's robot
  std::string tip;
  std::string scene = "empty";
  int areas = 2;
  std::uint64_t seed = 1;
  std::string out;
  bool realtime = false;
  bool overwrite = false;
  std::string learner = "elm";
  double diameter = app::TutorOptions{}.circle_diameter;  // the tutor's default
  int candidates = 24;
  int check_points = app::TutorOptions{}.check_points;
  std::string backend = "sim";
  bool scene_postures = false;
};

Json matrixColumns(const Eigen::MatrixXd& m) { return toJsonRows(m.transpose()); }

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Case-insensitive: `S.JSON` is as much a JSON file as `s.json`.
bool endsWith(const std::string& text, const std::string& suffix) {
  if (text.size() < suffix.size()) return false;
  return std::equal(suffix.begin(), suffix.end(), text.end() - static_cast<std::ptrdiff_t>(suffix.size()),
                    [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b)); });
}

// A recording, a scene or anything else already at --out is data a run must not destroy; the
// scene, the URDF and the meshes the run reads (as resolved: a built-in name, the scene's own
// robot) never, --overwrite or not.
void checkNoInputIsAt(const std::filesystem::path& output, const robot::Scene& scene, const robot::RobotModel& model,
                      const std::string& named) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(output, error)) return;
  const std::pair<fs::path, const char*> inputs[] = {{scene.source, "the scene"}, {model.urdfPath(), "the robot's URDF"}};
  for (const auto& [input, what] : inputs) {
    if (!input.empty() && fs::equivalent(input, output, error)) {
      throw InputError("--out: " + named + " is " + what + " the run reads; give another file");
    }
  }
  refuseOutputsOverMeshes({{"--out", output.string()}}, model, scene);
}

void checkNothingIsOverwritten(const TeachOptions& options, const robot::Scene& scene, const robot::RobotModel& model) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(options.out, error)) return;
  checkNoInputIsAt(options.out, scene, model, "'" + options.out + "'");
  if (!options.overwrite) {
    throw InputError("--out: '" + options.out + "' exists; teach does not write over a file (give --overwrite to replace it)");
  }
}

constexpr std::size_t kWarningsOnStderr = 20;

// SIGINT or SIGTERM during a run: the tutor stops at its next control cycle (after the
// computation in hand: a fit or a posture search can take seconds) and what was recorded is
// written as usual. The handler gives both signals back their defaults, so a second one ends the
// process at once. Lock-free atomic: the signal may land on any of the run's threads.
std::atomic<int> g_stop_signal{0};

static_assert(std::atomic<int>::is_always_lock_free);

// A file of this run's own in the temporary directory (created exclusively, never through a
// link another user planted there), for a session its --out could not take.
std::string newTemporaryFile(const std::string& suffix) {
  std::string name = (std::filesystem::temp_directory_path() / ("flexirob-teach-XXXXXX" + suffix)).string();
  const int fd = ::mkstemps(name.data(), static_cast<int>(suffix.size()));
  if (fd < 0) throw InputError("cannot create a file in " + std::filesystem::temp_directory_path().string() + ": " + std::strerror(errno));
  ::close(fd);
  return name;
}

extern "C" void stopOnSignal(int signal_number) {
  g_stop_signal.store(signal_number);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

// Installs the handler for one run and puts the previous handlers back afterwards. A signal the
// caller ignores (SIGINT for a job a script started in the background) stays ignored.
class StopOnSignal {
 public:
  StopOnSignal() {
    g_stop_signal.store(0);
    previous_int_ = std::signal(SIGINT, stopOnSignal);
    if (previous_int_ == SIG_IGN) std::signal(SIGINT, SIG_IGN);
    previous_term_ = std::signal(SIGTERM, stopOnSignal);
    if (previous_term_ == SIG_IGN) std::signal(SIGTERM, SIG_IGN);
  }
  ~StopOnSignal() {
    std::signal(SIGINT, previous_int_);
    std::signal(SIGTERM, previous_term_);
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;

 private:
  void (*previous_int_)(int) = SIG_DFL;
  void (*previous_term_)(int) = SIG_DFL;
};

Json runTeach(TeachOptions options) {
  // From the start: a signal before the tutor's first cycle stops it there.
  const StopOnSignal stop_on_signal;
  // A session is SQLite's, kept open through the run, or a JSON file: a regular file either way.
  checkOutputPath("--out", options.out, {}, true);
  // Held to the end of the run: a second teach into the same file is refused at its start.
  const app::SessionWriteLock out_lock(options.out, "--out");
  const app::LearnerKind learner = app::learnerKindFromString(options.learner);
  options.learner = app::toString(learner);  // as the session records it and eval reads it
  const robot::Scene scene = loadSceneNoting(options.scene);
  const std::string robot_name = robot::robotFor(options.robot, scene);
  const auto model = loadRobotNoting(robot_name, options.tip);
  checkNothingIsOverwritten(options, scene, model);
  robot::checkPosturesFit(scene, model, robot_name);
  // The session names robot and scene so that they resolve from any working directory.
  const std::string robot_reference = portableReference(robot_name, builtinRobotNames());
  const std::string scene_reference = portableReference(options.scene, robot::builtinSceneNames());
  const robot::ParameterSet parameters = app::sceneParameters(scene);

  if (options.backend != "sim" && options.backend != "fri-sim") {
    throw InputError("--backend: expected sim or fri-sim, got '" + options.backend + "'");
  }
  auto owned_sim = std::make_unique<robot::Simulation>(model, &scene, parameters);
  robot::Simulation& sim = *owned_sim;
  const Eigen::VectorXd home = app::homePosture(model, scene);
  if (!home.isApprox(model.midPosture())) sim.reset(home);
  // Joints too weak to hold the arm at its start posture let it sag before any hand touches it,
  // into the table or an obstacle, and every later failure would read as a contact.
  robot::RobotState start_state;
  sim.readState(start_state);
  const robot::Simulation::GravityLoad start_load = sim.gravityLoad(start_state.q);
  std::string start_sags;
  if (start_load.ratio > 1.0) {
    start_sags = "the arm cannot hold itself up at its start posture: it needs " + sim.describe(start_load) +
                 " (the URDF's <limit effort>)";
    std::fprintf(stderr, "warning: %s\n", start_sags.c_str());
  }
  // fri-sim: the same Bullet arm behind the FRI controller stand-in in lockstep, in-process; the
  // workflow drives it through RobotConnection and the FRI backend over UDP loopback, as it
  // drives the real LWR IV, while the tutor's hands push the arm behind the stand-in.
  std::unique_ptr<robot::FriSimulatedController> controller;
  std::unique_ptr<app::RobotConnection> connection;
  robot::RobotBackend* backend = owned_sim.get();
  if (options.backend == "fri-sim") {
    if (model.dof() != robot::fri::kJoints) throw InputError("--backend fri-sim: needs the 7-joint LWR IV (--robot lwr4)");
    robot::UdpSocket socket("127.0.0.1", 0);
    robot::FriSimulatedControllerConfig stand_in;
    stand_in.peer = socket.localEndpoint();
    stand_in.cycle = sim.cycleTime();
    stand_in.lockstep = true;
    controller = std::make_unique<robot::FriSimulatedController>(model, stand_in, std::move(owned_sim));
    app::BackendChoice choice;
    choice.kind = app::BackendKind::kFri;
    choice.fri.robot = controller->localEndpoint();
    choice.fri.lockstep = true;
    choice.text = "fri-sim";
    connection = std::make_unique<app::RobotConnection>(
        choice, std::make_unique<robot::FriBackend>(model, choice.fri, std::move(socket)));
    controller->start();
    for (int i = 0; i < 1000 && !connection->status().commanding; ++i) connection->step();
    if (!connection->status().commanding) {
      throw InputError("--backend fri-sim: the link did not reach command mode (" + connection->status().summary() + ")");
    }
    backend = connection.get();
  }

  app::WorkflowOptions workflow_options;
  workflow_options.learner = learner;
  workflow_options.elm.seed = options.seed;
  workflow_options.llm.seed = options.seed;
  workflow_options.check_scene = &scene;
  app::Workflow workflow(*backend, parameters, workflow_options);

  app::TutorOptions tutor_options;
  tutor_options.seed = options.seed;
  tutor_options.home = home;
  tutor_options.realtime = options.realtime;
  tutor_options.circle_diameter = options.diameter;
  tutor_options.posture_candidates = options.candidates;
  tutor_options.follow_scene_postures = options.scene_postures;
  tutor_options.check_points = options.check_points;
  tutor_options.progress = [](const std::string& what, double fraction) { reportProgress(what, fraction); };
  tutor_options.stop_requested = [] { return g_stop_signal.load() != 0; };
  if (controller) tutor_options.arm_mutex = &controller->armMutex();  // the stand-in's thread steps the arm

  // The session: SQLite through the session recorder, or JSON for a path ending in .json.
  const bool json_session = endsWith(options.out, ".json");
  // --overwrite: the run records beside the file it replaces (through a symbolic link, the file
  // it names), and takes its place only once it has taught something. A mistaken re-run stopped
  // with Ctrl-C, or one that taught no area, leaves the earlier recording as it was.
  std::error_code out_status;
  const std::filesystem::path out_file = app::followLinks(options.out);
  const bool replacing = std::filesystem::is_regular_file(out_file, out_status);
  const std::string recording_path = replacing ? out_file.string() + ".new" : options.out;
  std::optional<app::SessionWriteLock> recording_lock;
  if (replacing) {
    // The file beside is written as --out is: never by two runs, never over what the run reads.
    recording_lock.emplace(recording_path, "--out");
    checkNoInputIsAt(recording_path, scene, model, "the file '" + recording_path + "', where the run records before replacing --out,");
  }
  std::unique_ptr<app::SessionRecorder> recorder;
  std::unique_ptr<app::WorkflowSessionWriter> writer;
  if (!json_session) {
    app::SessionMetadata metadata;
    metadata.robot_name = robot_reference;
    metadata.robot_urdf = readText(model.urdfPath());
    metadata.tip_link = model.tipLink();
    metadata.scene_name = scene_reference;
    metadata.software_version = FLEXIROB_VERSION_STRING;
    metadata.scene_text = robot::sceneToYaml(scene);
    metadata.mesh_digests = app::meshDigestsText(app::meshDigests(model, scene));
    metadata.parameters = Json{{"seed", options.seed}, {"learner", options.learner}, {"areas", options.areas},
                               {"diameter_m", options.diameter}, {"backend", options.backend}}.dump();
    app::RecorderOptions recorder_options;
    recorder_options.overwrite = true;
    recorder = std::make_unique<app::SessionRecorder>(recording_path, metadata, recorder_options);
    // Written as it happens (areas, samples, models, ITM snapshots, collisions): a crash or
    // kill -9 loses at most the last second.
    writer = std::make_unique<app::WorkflowSessionWriter>(*recorder, workflow, &sim);
    app::SessionRecorder* sink = recorder.get();
    app::WorkflowSessionWriter* events = writer.get();
    tutor_options.on_cycle = [sink, events, cycles = std::uint64_t{0}, reported = false](const robot::RobotState& state) mutable {
      sink->recordState(state);
      events->poll();
      // A full disk or an unwritable location: say so once, when it happens; the run goes on
      // and the recording continues in memory.
      if (++cycles % 1000 == 0 && !reported) {
        const app::RecorderStatus status = sink->status();
        if (!status.message.empty()) {
          reported = true;
          std::cerr << "warning: session: " << status.message << " (recording goes on in memory)\n";
        }
      }
    };
  }
  if (recorder) {
    // The state the workflow reads in its first cycle: the tutor records each state after a
    // cycle, and without this one the session would lack the posture its stage starts in (the
    // ITM's first input, which export --stream replays).
    robot::RobotState first;
    first.resize(model.dof());
    backend->readState(first);
    recorder->recordState(first);
  }
  app::SimulatedTutor tutor(sim, workflow, scene, parameters, tutor_options);

  const auto wall_start = std::chrono::steady_clock::now();
  app::TutorReport report;
  try {
    report = tutor.configure(options.areas);
  } catch (const InputError&) {
    // Refused before configuration began (the start posture in an obstacle): nothing was taught,
    // and a file left behind would only stand in the way of the corrected run (--out exists).
    if (workflow.stage() == app::Stage::kIdle && workflow.areas().empty() && recorder) {
      writer.reset();
      recorder.reset();
      app::removeDatabaseFiles(recording_path);
    }
    throw;
  }
  const double wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  // The session file.
  Json areas = Json::array();
  Eigen::Index samples = 0;
  for (const auto& area : workflow.areas()) {
    samples += area.X.cols();
    areas.push_back({{"name", area.name},
                     {"centre", toJson(area.centre)},
                     {"q_fixed", toJson(area.q_fixed)},
                     {"x", matrixColumns(area.X)},
                     {"q", matrixColumns(area.Q)}});
  }
  Json events = Json::array();
  for (const auto& event : workflow.events()) {
    events.push_back({{"time_s", event.time},
                      {"kind", app::toString(event.kind)},
                      {"name", event.name},
                      {"detail", event.detail},
                      {"area", event.area}});
  }
  const planning::Itm& itm = workflow.itm();
  Json nodes = Json::array();
  Json edges = Json::array();
  std::map<int, int> index;
  for (const int id : itm.nodeIds()) {
    index[id] = static_cast<int>(nodes.size());
    nodes.push_back({{"x", toJson(Eigen::VectorXd(itm.prototype(id)))}, {"q", toJson(Eigen::VectorXd(itm.joints(id)))}});
  }
  for (const int id : itm.nodeIds()) {
    for (const int other : itm.neighbors(id)) {
      if (other > id) edges.push_back({index[id], index[other]});
    }
  }
  Json checks = Json::array();
  // `from` and `to` index the taught areas ("areas" of the session), not the tutor's list of
  // attempts; the names say which they are.
  const auto areaName = [&workflow](int area) {
    return area >= 0 && area < static_cast<int>(workflow.areas().size()) ? workflow.areas()[static_cast<std::size_t>(area)].name
                                                                         : std::string();
  };
  for (const auto& check : workflow.transitionChecks()) {
    checks.push_back({{"from", check.from},
                      {"to", check.to},
                      {"from_name", areaName(check.from)},
                      {"to_name", areaName(check.to)},
                      {"mean_error_m", check.mean_error_m},
                      {"max_error_m", check.max_error_m},
                      {"final_error_m", check.final_error_m},
                      {"posture_error_rad", check.posture_error_rad},
                      {"colliding_samples", check.colliding_samples},
                      {"first_contact", check.first_contact},
                      {"first_contact_along_m", check.first_contact_along_m},
                      {"ok", check.ok}});
  }
  Json tutor_areas = Json::array();
  for (const auto& area : report.areas) {
    tutor_areas.push_back({{"name", area.name},
                           {"target", toJson(area.target)},
                           {"taught", area.taught},
                           {"posture", area.q_chosen.size() > 0 ? toJson(area.q_chosen) : Json()},
                           {"scene_posture_offset_rad", area.q_chosen.size() > 0 && area.q_chosen.size() == area.q_suggested.size()
                                                            ? Json((area.q_chosen - area.q_suggested).norm())
                                                            : Json()},
                           // null: not taught (no posture shown), or nothing within 0.5 m of the arm.
                           {"clearance_m", area.taught && std::isfinite(area.clearance) ? Json(area.clearance) : Json()},
                           {"failure", area.failure},
                           {"automatic", area.automatic},
                           {"map_failures_before", area.map_failures_before},
                           {"map_failures_with", area.map_failures_with},
                           {"helix_diameter_m", area.helix_diameter},
                           {"samples", area.samples},
                           {"span_m", area.span},
                           {"assistance_lead_m", area.assistance_lead}});
  }
  const Json session = {{"format", "flexirob-session-json"},
                        {"version", 1},
                        {"robot", robot_reference},
                        {"tip", options.tip},
                        {"scene", scene_reference},
                        {"robot_urdf", readText(model.urdfPath())},
                        {"scene_text", robot::sceneToYaml(scene)},
                        {"mesh_digests", app::meshDigestsText(app::meshDigests(model, scene))},
                        {"seed", options.seed},
                        {"learner", options.learner},
                        {"dof", model.dof()},
                        {"areas", areas},
                        {"events", events},
                        {"itm", {{"nodes", nodes}, {"edges", edges}}},
                        {"transition_checks", checks},
                        {"tutor", tutor_areas},
                        {"collisions", report.collisions},
                        {"simulated_time_s", report.simulated_time}};
  // Contacts during teaching (E_coll): the first events with the bodies involved.
  Json collision_events = Json::array();
  std::unique_lock<std::mutex> arm_lock;  // fri-sim: the stand-in's thread steps the arm
  if (controller) arm_lock = std::unique_lock(controller->armMutex());
  robot::CollisionWorld* world = sim.collisionWorld();
  for (const auto& event : sim.collisions().eventLog()) {
    if (world == nullptr) break;
    const std::string body = world->bodyName(event.contact.body);
    const std::string other = world->otherName(event.contact);
    if (collision_events.size() < 20) {
      collision_events.push_back({{"time_s", event.time}, {"link", body}, {"other", other}, {"depth_m", event.contact.depth}});
    }
  }
  std::uint64_t states_dropped = 0;
  std::string session_error, session_copy;
  // Where the session is when the run ends: --out, or beside it where the run replaced nothing.
  std::string session_path = options.out;
  std::string kept_note;
  const bool keep_earlier = replacing && samples == 0;
  // Stopped before anything was taught: no file, which would only stand in the way of the run
  // started again (an --out that exists is refused).
  const bool stopped_untaught = report.interrupted && samples == 0;
  if (json_session) {
    if (stopped_untaught) {
      session_path.clear();
    } else {
      if (keep_earlier) session_path = recording_path;
      const std::string text = session.dump();
      try {
        app::writeFileReplacing(session_path, text, "--out");
      } catch (const InputError& error) {
        // The folder removed or the disk full at the end of the run: what was taught is kept
        // in the temporary directory, as for an SQLite session that failed, and said.
        session_error = error.what();
        try {
          const std::string copy = newTemporaryFile(".json");
          app::writeFileReplacing(copy, text, "the session's copy");
          session_copy = copy;
        } catch (const InputError& also) {
          session_error += std::string("; no copy either: ") + also.what();
        }
      }
    }
  } else {
    writer->finish();
    recorder->close();
    const app::RecorderStatus status = recorder->status();
    states_dropped = status.states_dropped;
    if (stopped_untaught) {
      // Nothing taught to keep, whether or not the file failed meanwhile.
      app::removeDatabaseFiles(recording_path);
      session_path.clear();
    } else if (!status.message.empty()) {
      // The file failed during the run: keep the whole session (file content + what followed
      // in memory) in the temporary directory, and say where.
      session_error = status.message;
      try {
        const std::string copy = newTemporaryFile(".flexirob");
        recorder->saveCopy(copy);
        session_copy = copy;
      } catch (const InputError& e) {
        session_error += std::string("; no copy either: ") + e.what();
      }
    } else if (replacing) {
      std::error_code error;
      if (keep_earlier) {
        session_path = recording_path;
      } else {
        // The earlier file's journal would be read as the new file's own: set aside, and put
        // back should the file stay (a killed run's journal holds its last commits).
        const std::string journal = out_file.string() + "-wal";
        const std::string set_aside = journal + ".replaced";
        std::error_code ignored;
        const bool had_journal = std::filesystem::exists(journal, ignored);
        if (had_journal) std::filesystem::rename(journal, set_aside, error);
        if (!error) std::filesystem::rename(recording_path, out_file, error);
        if (error) {
          if (had_journal) std::filesystem::rename(set_aside, journal, ignored);
          session_error = "cannot replace '" + options.out + "' with the new recording: " + error.message();
          session_copy = recording_path;  // whole, beside it
        } else {
          std::filesystem::remove(set_aside, ignored);
          std::filesystem::remove(out_file.string() + "-shm", ignored);  // an index of the journal set aside
        }
      }
    }
  }
  if (!session_error.empty()) {
    // What --out names (gone with its folder, cut short, or an earlier run's file) is not this
    // run's session: the copy, where there is one, is the whole of it.
    session_path.clear();
  } else if (session_path.empty() && !replacing) {
    kept_note = " (nothing was taught)";
  } else if (session_path != options.out) {
    if (keep_earlier) {
      kept_note = "; '" + options.out + "' was left as it was (nothing was taught" +
                  (session_path.empty() ? std::string() : ", the new recording is '" + session_path + "'") + ")";
    } else {
      kept_note = "; '" + options.out + "' was left as it was (the new recording is '" + session_path + "')";
    }
  }
  // The tutor's feedback (joint limits, transition checks) is what a person would have read on
  // the screen: said on stderr too, each distinct line once, not only counted in the JSON.
  // Only the last map's transition warnings stand (app::standingWarnings): an OS-ELM session had
  // listed one pair once per refit.
  const std::vector<std::string> standing = app::standingWarnings(workflow.events());
  endProgressLine();  // an interrupted run left its progress line open
  Json warning_lines = Json::array();
  if (!start_sags.empty()) warning_lines.push_back(start_sags);  // said on stderr at the start
  for (std::size_t i = 0; i < standing.size(); ++i) {
    warning_lines.push_back(standing[i]);
    if (i < kWarningsOnStderr) std::fprintf(stderr, "warning: %s\n", standing[i].c_str());
  }
  if (standing.size() > kWarningsOnStderr) {
    std::fprintf(stderr, "warning: ... and %zu more (\"warning_lines\" in the JSON)\n", standing.size() - kWarningsOnStderr);
  }
  // A place the scene lists and the tutor gave up is the scene's author's to know about (a
  // place inside an obstacle, out of reach, a scene in the wrong units), even where the tutor
  // made the count up with places of its own. Where nothing was taught, the one-line error
  // below says why the first place failed.
  std::size_t given_up = 0;
  for (const auto& area : report.areas) {
    if (area.automatic || area.taught || workflow.areas().empty()) continue;
    const std::string line = "the scene's area '" + printable(area.name) + "' was not taught: " + area.failure;
    warning_lines.push_back(line);
    if (++given_up <= kWarningsOnStderr) std::fprintf(stderr, "warning: %s\n", line.c_str());
  }
  if (given_up > kWarningsOnStderr) {
    std::fprintf(stderr, "warning: ... and %zu more of the scene's areas not taught (\"warning_lines\" in the JSON)\n", given_up - kWarningsOnStderr);
  }
  // An arm so light that even the most physics steps per cycle do not keep its impedance law
  // stable shakes in the simulation: what was taught with it is not what a robot would do.
  const int max_substeps = sim.maxSubsteps();
  if (sim.substepCapReached()) {
    const std::string too_light = "the arm's links are too light for the simulation: even " + std::to_string(max_substeps) +
                                  " physics steps per 1 ms cycle did not keep its joint impedance stable, so it may have "
                                  "shaken; its masses and inertias are worth a check";
    warning_lines.push_back(too_light);
    std::fprintf(stderr, "warning: %s\n", too_light.c_str());
  }
  const std::size_t warnings = warning_lines.size();
  if (static_cast<int>(workflow.areas().size()) < options.areas && !workflow.areas().empty() && !report.interrupted) {
    std::fprintf(stderr, "note: %zu of the %d areas asked for %s taught; \"tutor\" in the JSON says why the others were not\n",
                 workflow.areas().size(), options.areas, workflow.areas().size() == 1 ? "was" : "were");
  }
  // The scene's suggested postures are where the search starts; the tutor shows the posture
  // nearest the areas taught before, which may be another: said, so that a scene's author does
  // not take the shown posture for the one written.
  if (!options.scene_postures) {
    int shown_elsewhere = 0, suggested = 0;
    constexpr double kElsewhere = 0.5;  // [rad] joint-space distance
    for (const auto& area : report.areas) {
      if (!area.taught || area.q_suggested.size() != area.q_chosen.size() || area.q_chosen.size() == 0) continue;
      ++suggested;
      shown_elsewhere += (area.q_chosen - area.q_suggested).norm() > kElsewhere ? 1 : 0;
    }
    if (shown_elsewhere > 0) {
      std::fprintf(stderr,
                   "note: %d of the %d taught areas with a posture in the scene were shown in another (more than %.1f rad from it, "
                   "nearer the start posture or the areas taught before; \"scene_posture_offset_rad\" in the JSON); --scene-postures shows the scene's\n",
                   shown_elsewhere, suggested, kElsewhere);
    }
  }
  Json link = nullptr;
  if (connection) {
    const app::LinkStatus status = connection->status();
    const robot::FriSimulatedControllerStats krc = controller->stats();
    link = {{"link", status.link},
            {"quality", status.quality},
            {"measurements", status.measurements},
            {"lost_measurements", status.lost_measurements},
            {"watchdog_trips", status.watchdog_trips},
            {"commands_rejected", status.commands_rejected},
            {"commands_rate_limited", connection->fri()->status().counters.commands_rate_limited},
            {"commands_refused_by_controller", krc.commands_refused},
            {"commands_applied_by_controller", krc.commands_applied}};
    controller->stop();
  }
  Json result = {{"areas", workflow.areas().size()},
                 {"backend", options.backend},
                 {"fri_link", link},
                 {"samples", samples},
                 {"collisions", report.collisions},
                 {"colliding_steps", report.colliding_steps},
                 {"collision_events", collision_events},
                 {"approach_max_lead_rad", report.max_approach_lead},
                 {"session", session_path.empty() ? Json(nullptr) : Json(session_path)},
                 {"session_format", json_session ? "json" : "sqlite"},
                 {"states_dropped", states_dropped},
                 {"session_error", session_error},
                 {"session_copy", session_copy},
                 {"learner", options.learner},
                 {"model_learned", workflow.model() != nullptr},
                 {"itm_nodes", itm.nodeCount()},
                 {"itm_edges", itm.edgeCount()},
                 {"transition_checks", checks},
                 {"warnings", warnings},
                 {"warning_lines", warning_lines},
                 {"tutor", tutor_areas},
                 {"simulated_time_s", report.simulated_time},
                 {"max_substeps", max_substeps},
                 {"start_gravity_load", start_load.ratio},
                 {"wall_time_s", wall_seconds},
                 {"interrupted", report.interrupted}};
  if (report.interrupted) {
    const int signal_number = g_stop_signal.load();
    std::ostringstream message;
    message << "teach: stopped by " << (signal_number == SIGTERM ? "SIGTERM" : "SIGINT") << " after " << std::fixed
            << std::setprecision(1) << wall_seconds << " s (" << report.simulated_time << " s of simulated teaching); what was recorded (" << workflow.areas().size()
            << " of " << options.areas << " areas, " << samples << " samples) ";
    if (!session_error.empty()) {
      message << "was not written to " << options.out << ": " << session_error
              << (session_copy.empty() ? std::string() : "; the whole session was saved to " + session_copy);
    } else if (session_path.empty()) {
      message << "was not written" << kept_note;
    } else {
      message << "was written to " << session_path << kept_note;
    }
    throw CommandFailed(message.str(), std::move(result), 128 + signal_number);
  }
  if (!session_error.empty()) {
    throw CommandFailed("teach: the session file failed: " + session_error +
                            (session_copy.empty() ? std::string() : "; the whole session was saved to " + session_copy),
                        std::move(result));
  }
  if (workflow.areas().empty()) {
    // The session is written all the same (events, the ITM of the attempts): nothing is lost.
    const std::string reason = report.areas.empty() ? std::string("none was tried") : report.areas.front().failure;
    // Counted by kind: the first reason alone may be a minor one (a cramped listed place) where
    // most attempts failed otherwise.
    const std::string kinds = report.areas.size() > 1 ? ": " + app::failureKinds(report.areas) : std::string();
    throw CommandFailed("teach: no training area could be taught" + (start_sags.empty() ? "" : ": " + start_sags) + " (" +
                            std::to_string(report.areas.size()) + " tried" + kinds + "; the first: " + reason +
                            "); the session was written to " + session_path + kept_note,
                        std::move(result));
  }
  return result;
}

}  // namespace

void registerTeachCommands(CLI::App& app, CommandRunner& runner) {
  auto options = std::make_shared<TeachOptions>();
  CLI::App* teach = app.add_subcommand("teach", "simulated tutor teaches the robot in a scene; writes a session");
  teach->add_option("--robot", options->robot, "lwr4, arm9 or a URDF path (default: the scene's robot)");
  teach->add_option("--tip", options->tip, kTipHelp);
  teach->add_option("--scene", options->scene, "built-in scene name or scene file")->capture_default_str();
  teach->add_option("--areas", options->areas, "number of training areas: the scene's first ones, then places of the tutor's own")
      ->check(finiteRange(1, 200))
      ->capture_default_str();
  teach->add_option("--seed", options->seed, "random seed")->check(seedValidator())->capture_default_str();
  teach->add_option("--out", options->out, "session file (SQLite; JSON if it ends in .json)")->required();
  teach->add_flag("--realtime", options->realtime, "pace the simulation at wall-clock speed");
  teach->add_flag("--overwrite", options->overwrite, "replace an existing --out file (without it, an existing file is refused)");
  teach->add_option("--learner", options->learner, "elm, oselm or llm")->capture_default_str();
  // Below 1 cm even the fastest turns leave the joints under the still speed: on_converged would
  // end the recording within 2 s (a 5 mm helix recorded 101 samples).
  teach->add_option("--diameter", options->diameter, "largest diameter of the deflection helix [m], 0.01-0.5")
      ->check(finiteRange(app::kSmallestCircleDiameter, app::kLargestCircleDiameter))
      ->capture_default_str();
  teach->add_option("--candidates", options->candidates, "IK postures tried per area")->check(finiteRange(1, 1000))->capture_default_str();
  teach->add_flag("--scene-postures", options->scene_postures,
                  "show each area in the posture nearest the one the scene suggests (default: nearest the areas already taught, "
                  "the scene's posture only where the search starts)");
  teach->add_option("--check-points", options->check_points,
                    "points on which areas beyond the scene's list are checked and taken back if the map got worse (0: random places, kept)")
      ->check(finiteRange(0, 10000))
      ->capture_default_str();
  teach->add_option("--backend", options->backend,
                    "sim (the Bullet simulation) or fri-sim (the same arm behind the FRI controller stand-in, "
                    "driven over UDP loopback through the FRI backend)")
      ->capture_default_str();
  teach->callback([&runner, options] { runner.select([options] { return runTeach(*options); }); });
}

}  // namespace flexirob::cli
