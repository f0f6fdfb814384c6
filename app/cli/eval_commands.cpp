// `eval reachable` (Sect. 3.3.2, Tab. 3.3) and `plan` (Sect. 8.3) on a session written by
// `teach` (DESIGN §6). The map q_c(x) is learned again from the session's samples with the
// requested learner; the ITM graph is the session's. Sessions are SQLite recordings (the session
// recorder) or the JSON files `teach --out F.json` writes.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <iomanip>
#include <limits>
#include <map>
#include <unistd.h>

#include "app/cli/cli_support.hpp"
#include "app/evaluation.hpp"
#include "app/experiments.hpp"
#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "planning/itm_file.hpp"
#include "app/workflow.hpp"
#include "planning/itm.hpp"
#include "planning/path_postures.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"

namespace flexirob::cli {
namespace {

Eigen::VectorXd vectorOf(const Json& array, Eigen::Index size, const std::string& what) {
  if (!array.is_array() || static_cast<Eigen::Index>(array.size()) != size) {
    throw InputError("session: " + what + ": expected " + std::to_string(size) + " numbers");
  }
  Eigen::VectorXd v(size);
  for (Eigen::Index i = 0; i < size; ++i) {
    const Json& value = array[static_cast<std::size_t>(i)];
    if (!value.is_number()) throw InputError("session: " + what + ": expected numbers");
    v[i] = value.get<double>();
  }
  if (!v.allFinite()) throw InputError("session: " + what + ": non-finite number");
  return v;
}

struct Session {
  std::string robot, tip, scene;
  std::unique_ptr<robot::RobotModel> model;
  robot::Scene scene_data;
  learning::TrainingSet data;
  std::vector<Eigen::VectorXd> q_fixed;
  std::vector<std::string> area_names;  ///< how messages name area k: as the file counts it
  /// Area k's name as teach gave it ("I1", "auto_3"), which the drawn trajectories' regions
  /// carry; as the file counts it where the file keeps no name (version 1 sessions).
  std::vector<std::string> taught_names;
  std::unique_ptr<planning::Itm> itm;
  std::string learner = "elm";  ///< the learner the session was taught with (what eval and plan use by default)
};

// A posture the robot cannot take would be learned and planned with as if it could (a hand-edited
// or damaged file): every recorded posture must lie within the hardware limits, up to what a
// joint overshot them in sessions simulated before the limit stops held (up to 0.11 rad
// measured in the 9-DoF and setup_II sessions; a prismatic slide 0.09 m), which stay readable.
void checkPosturesWithinLimits(const Session& session) {
  constexpr double kOvershootRad = 0.25;
  constexpr double kOvershootM = 0.1;
  const robot::RobotModel& model = *session.model;
  const auto check = [&](const Eigen::VectorXd& q, const std::string& what) {
    model.checkWithinLimits(q, "session: " + what, kOvershootRad, kOvershootM);
  };
  for (std::size_t k = 0; k < session.q_fixed.size(); ++k) check(session.q_fixed[k], "q_fixed of area " + session.area_names[k]);
  for (Eigen::Index l = 0; l < session.data.Y.cols(); ++l) check(session.data.Y.col(l), "training sample " + std::to_string(l + 1));
  if (session.itm) {
    for (const int id : session.itm->nodeIds()) check(session.itm->joints(id), "ITM node " + std::to_string(id));
  }
}

// teach writes each sample's tip position as the forward kinematics of its posture: a JSON
// session whose positions disagree was edited or belongs to another robot, and its map would
// be learned from pairs that never were (positions 5 m away were evaluated without a word).
// So is an SQLite session teach recorded in the simulation (its stored robot edited to another
// geometry was planned with). A session from the real robot, or over FRI, keeps the
// controller's own Cartesian measurement, which a tool frame set on the robot may offset; it
// is not held to this.
void checkTipPositionsMatchPostures(const Session& session) {
  constexpr double kToleranceM = 0.01;
  robot::Kinematics kinematics(*session.model);
  for (Eigen::Index l = 0; l < session.data.X.cols(); ++l) {
    kinematics.update(session.data.Y.col(l));
    const double gap = (kinematics.p_WT() - session.data.X.col(l)).norm();
    if (!(gap <= kToleranceM)) {
      std::ostringstream message;
      message << std::setprecision(3) << "session: training sample " << l + 1 << ": its tip position lies " << gap
              << " m from where its joint values put the tip of '" << session.model->name() << "' (at most " << kToleranceM << " m)";
      throw InputError(message.str());
    }
  }
}

// The learner a session names, where eval and plan can learn with it; the ELM otherwise (a
// BPDC model of the GUI, a hand-edited name), said in a note.
std::string evaluableLearner(const std::string& named, const std::string& file) {
  if (named == "elm" || named == "oselm" || named == "llm") return named;
  std::fprintf(stderr, "note: the session '%s' was taught with the learner '%s', which eval and plan do not learn with; the ELM is used (--learner chooses another)\n",
               file.c_str(), printable(named).c_str());
  return "elm";
}

// Two areas of one name would have their figures merged under it (eval trajectories' regions)
// and messages could not say which one they mean: teach and the GUI never write such a file.
void checkAreaNamesDiffer(const Session& session) {
  for (std::size_t k = 0; k < session.taught_names.size(); ++k) {
    for (std::size_t l = 0; l < k; ++l) {
      if (session.taught_names[k] == session.taught_names[l]) {
        throw InputError("session: two areas are named '" + printable(session.taught_names[k], 200) + "' (areas " + session.area_names[l] +
                         " and " + session.area_names[k] + ")");
      }
    }
  }
}

// A session recorded in SQLite by the session recorder: the complete areas' latest takes.
Session loadRecordedSession(const std::string& file, const std::string& robot_file, const std::string& scene_file) {
  const app::SessionReader reader(file);
  app::RecordedTeaching teaching = app::readRecordedTeaching(reader);
  Session session;
  // teach records its options as JSON (`parameters`); the GUI's sessions name the learner of
  // their last model.
  const Json parameters = Json::parse(reader.metadata().parameters, nullptr, false);
  if (parameters.is_object() && parameters.contains("learner") && parameters.at("learner").is_string()) {
    session.learner = parameters.at("learner").get<std::string>();
  } else if (const std::vector<app::ModelRecord> models = reader.models(); !models.empty()) {
    session.learner = models.back().learner_kind;
  }
  session.learner = evaluableLearner(session.learner, file);
  session.robot = teaching.robot;
  session.tip = teaching.tip;
  session.scene = teaching.scene;
  session.model = std::make_unique<robot::RobotModel>(loadSessionRobot(session.robot, teaching.robot_urdf, session.tip, robot_file));
  session.scene_data = loadSessionScene(session.scene, teaching.scene_text, scene_file);
  noteMeshesChangedSinceTeaching(teaching.mesh_digests, *session.model, session.scene_data);
  robot::checkPosturesFit(session.scene_data, *session.model, robot_file.empty() ? session.robot : robot_file);
  if (!teaching.closed_cleanly) {
    std::fprintf(stderr, "note: the session '%s' was not closed cleanly (interrupted, or still being written); the evaluation covers what was recorded\n",
                 file.c_str());
  }
  const int n = session.model->dof();
  // The complete areas with samples, labelled by their position here: q_fixed[k] is area k's.
  std::vector<const app::RecordedArea*> taught;
  Eigen::Index count = 0;
  for (const app::RecordedArea& area : teaching.areas) {
    if (!area.complete || area.X.cols() == 0) continue;  // a RECORDING the session ended in taught nothing
    if (area.q_fixed.size() != n || area.Q.rows() != n) {
      throw InputError("session: area " + std::to_string(area.index) + " does not fit the robot's " + std::to_string(n) + " joints");
    }
    taught.push_back(&area);
    session.q_fixed.push_back(area.q_fixed);
    session.area_names.push_back(std::to_string(area.index));
    session.taught_names.push_back(area.name.empty() ? std::to_string(area.index) : area.name);
    count += area.X.cols();
  }
  if (count == 0) {
    throw InputError(teaching.closed_cleanly ? "session: no training samples"
                                             : "session: '" + file + "' was interrupted before any area was finished; nothing to evaluate");
  }
  session.data.X.resize(3, count);
  session.data.Y.resize(n, count);
  Eigen::Index l = 0;
  for (std::size_t k = 0; k < taught.size(); ++k) {
    const app::RecordedArea& area = *taught[k];
    session.data.X.middleCols(l, area.X.cols()) = area.X;
    session.data.Y.middleCols(l, area.X.cols()) = area.Q;
    session.data.area.insert(session.data.area.end(), static_cast<std::size_t>(area.X.cols()), static_cast<int>(k));
    l += area.X.cols();
  }
  if (!teaching.itm) throw InputError("session: no ITM graph recorded");
  session.itm = std::make_unique<planning::Itm>(std::move(*teaching.itm));
  checkAreaNamesDiffer(session);
  checkPosturesWithinLimits(session);
  if (parameters.is_object() && parameters.value("backend", Json()) == Json("sim")) checkTipPositionsMatchPostures(session);
  return session;
}

Session loadSession(const std::string& file, const std::string& robot_file, const std::string& scene_file) {
  std::ifstream in(file);
  if (!in) throw InputError("--session: cannot read '" + file + "'");
  if (!startsAsJson(in)) return readingSession(file, [&] { return loadRecordedSession(file, robot_file, scene_file); });
  Json json;
  try {
    json = Json::parse(in);
  } catch (const std::exception& e) {
    throw InputError("--session: '" + file + "' is not a session file (" + std::string(e.what()) + ")");
  }
  if (!json.is_object() || json.value("format", "") != "flexirob-session-json") {
    throw InputError("--session: '" + file + "' is not a flexirob session (format flexirob-session-json)");
  }
  if (!json.contains("version") || json.at("version") != 1) {
    throw InputError("--session: '" + file + "' has version " + (json.contains("version") ? json.at("version").dump() : "none") +
                     "; this build reads version 1");
  }
  Session session;
  try {
    session.robot = json.at("robot").get<std::string>();
    session.tip = json.value("tip", "");
    session.scene = json.at("scene").get<std::string>();
    session.learner = evaluableLearner(json.value("learner", "elm"), file);
    session.model = std::make_unique<robot::RobotModel>(
        loadSessionRobot(session.robot, json.value("robot_urdf", ""), session.tip, robot_file));
    session.scene_data = loadSessionScene(session.scene, json.value("scene_text", ""), scene_file);
    noteMeshesChangedSinceTeaching(json.value("mesh_digests", ""), *session.model, session.scene_data);
    robot::checkPosturesFit(session.scene_data, *session.model, robot_file.empty() ? session.robot : robot_file);
    const int n = session.model->dof();
    // teach writes the robot's joint count; one edited to another count or type says the file
    // was changed by hand, and whose postures then fit is not to be guessed.
    if (json.contains("dof") && (!json.at("dof").is_number_integer() || json.at("dof").get<long long>() != n)) {
      throw InputError("session: dof is " + json.at("dof").dump() + ", but the robot '" + session.robot + "' has " + std::to_string(n) +
                       " joints");
    }
    std::vector<Eigen::VectorXd> xs, qs;
    int k = 0;
    for (const Json& area : json.at("areas")) {
      session.q_fixed.push_back(vectorOf(area.at("q_fixed"), n, "q_fixed"));
      session.area_names.push_back(std::to_string(k + 1));
      const std::string taught_name = area.value("name", "");
      session.taught_names.push_back(taught_name.empty() ? std::to_string(k + 1) : taught_name);
      const Json& x = area.at("x");
      const Json& q = area.at("q");
      if (x.size() != q.size()) throw InputError("session: area samples x and q differ in count");
      // teach writes an area once it holds samples: an empty one was emptied by hand, and the
      // result would read as an evaluation of one area more than taught.
      if (x.empty()) throw InputError("session: area '" + printable(session.taught_names.back(), 200) + "' holds no samples");
      for (std::size_t l = 0; l < x.size(); ++l) {
        xs.push_back(vectorOf(x[l], 3, "x"));
        qs.push_back(vectorOf(q[l], n, "q"));
        session.data.area.push_back(k);
      }
      ++k;
    }
    if (xs.empty()) throw InputError("session: no training samples");
    session.data.X.resize(3, static_cast<Eigen::Index>(xs.size()));
    session.data.Y.resize(n, static_cast<Eigen::Index>(qs.size()));
    for (std::size_t l = 0; l < xs.size(); ++l) {
      session.data.X.col(static_cast<Eigen::Index>(l)) = xs[l];
      session.data.Y.col(static_cast<Eigen::Index>(l)) = qs[l];
    }
    // As the workflow that recorded it: the ITM's distances are the arm's.
    session.itm = std::make_unique<planning::Itm>(app::itmParametersForArm({}, app::armScale(*session.model)), n);
    const Json& nodes = json.at("itm").at("nodes");
    for (const Json& node : nodes) session.itm->addNode(vectorOf(node.at("x"), 3, "itm x"), vectorOf(node.at("q"), n, "itm q"));
    for (const Json& edge : json.at("itm").at("edges")) {
      const int a = jsonInteger(edge.at(0), "session: ITM edge");
      const int b = jsonInteger(edge.at(1), "session: ITM edge");
      if (a < 0 || b < 0 || a >= static_cast<int>(nodes.size()) || b >= static_cast<int>(nodes.size()) || a == b) {
        throw InputError("session: ITM edge with a bad node index");
      }
      if (!session.itm->hasEdge(a, b)) session.itm->addEdge(a, b);
    }
  } catch (const Json::exception& e) {
    throw InputError("--session: malformed session (" + std::string(e.what()) + ")");
  }
  checkAreaNamesDiffer(session);
  checkPosturesWithinLimits(session);
  checkTipPositionsMatchPostures(session);
  return session;
}

std::unique_ptr<learning::Learner> learnMap(const Session& session, const std::string& learner_name) {
  app::WorkflowOptions options;
  options.learner = app::learnerKindFromString(learner_name);
  std::unique_ptr<learning::Learner> learner = app::makeLearner(options, session.model->dof());
  learner->fit(session.data);
  return learner;
}

Eigen::VectorXd startPosture(const Session& session) {
  const auto& home = session.scene_data.home_posture;
  if (home && home->size() == session.model->dof()) return *home;
  return session.q_fixed.empty() ? session.model->midPosture() : session.q_fixed.front();
}

// Points as [[x, y, z], ...] [m, W], for pictures (render --reachable, --scene-model).
Json pointsJson(const std::vector<Eigen::Vector3d>& points) {
  Json out = Json::array();
  for (const Eigen::Vector3d& p : points) out.push_back({p.x(), p.y(), p.z()});
  return out;
}

struct EvalOptions {
  std::string session;
  std::string learner;  ///< empty: the session's
  double spacing = 0.0;
  std::string postures = "demonstrated";
  int goals = 10;
  std::uint64_t seed = 1;
  int per_area = 25;
  double speed = 0.1;
  std::string approach = "visited";  ///< reachable / scene-model: where each target is approached from
  std::string source = "auto";  ///< trajectories: the scene's, or drawn around the training data
  std::string robot_file, scene_file;  ///< where the session's robot and scene files lie now (addMovedFilesOptions)
};

// The learner asked for, else the one the session was taught with.
std::string learnerOf(const EvalOptions& options, const Session& session) {
  return options.learner.empty() ? session.learner : app::toString(app::learnerKindFromString(options.learner));
}

// Which session, robot and scene a result belongs to: `render` draws a result over a session
// and says so where they differ.
void nameTheSession(Json& json, const EvalOptions& options, const Session& session) {
  json["session"] = options.session;
  json["robot"] = session.model->name();
  json["scene"] = session.scene_data.name;
}

// A grid without targets has no reachability to report (0 of 0 is not 0 %): `command` fails
// saying why each point was left out, with `json` as its result.
void requireTargets(const std::string& command, const app::ReachableResult& result, Json json) {
  if (result.targets > 0) return;
  throw CommandFailed(command + ": none of the grid's " + std::to_string(result.grid_points) + " points is a target (" +
                          std::to_string(result.out_of_reach) + " out of reach, " + std::to_string(result.in_obstacles) +
                          " inside obstacles, " + std::to_string(result.excluded) + " excluded, " +
                          std::to_string(result.inaccessible) + " inaccessible)",
                      std::move(json));
}

Json runReachable(const EvalOptions& options) {
  const Session session = loadSession(options.session, options.robot_file, options.scene_file);
  const robot::EvaluationGrid grid = app::sceneGrid(session.scene_data, options.spacing);
  const auto learner = learnMap(session, learnerOf(options, session));
  const robot::ParameterSet parameters = app::sceneParameters(session.scene_data);
  const app::ApproachFrom approach = app::parseApproach(options.approach);
  const app::ReachableResult result =
      app::evaluateReachable(*session.model, session.scene_data, parameters, *learner, startPosture(session), grid,
                             session.data, [](double f) { reportProgress("eval reachable", f); }, approach);
  // Without targets there is no fraction (0 of 0 is not 0 %).
  const auto fraction = [&result](double value) { return result.targets > 0 ? Json(value) : Json(nullptr); };
  Json json = {{"targets", result.targets},
               {"reached", result.reached},
               {"reachable_fraction", fraction(result.reachable_fraction)},
               {"explored_fraction", fraction(result.explored_fraction)},
               {"collided", result.collided},
               {"missed_without_contact", result.targets - result.reached - result.collided},
               {"resolved_free", result.resolved_free},
               {"resolved_fraction", fraction(result.resolved_fraction)},
               {"grid_points", result.grid_points},
               {"out_of_reach", result.out_of_reach},
               {"in_obstacles", result.in_obstacles},
               {"spacing_m", grid.spacing},
               {"tolerance_m", grid.tolerance},
               {"learner", learnerOf(options, session)},
               {"areas", session.q_fixed.size()},
               {"samples", session.data.size()},
               {"inaccessible", result.inaccessible},
               {"excluded", result.excluded},
               {"contacts", result.contacts},
               {"approach", options.approach},
               {"target_points", pointsJson(result.target_points)},
               {"target_reached", result.target_reached},
               {"target_resolved_free", result.target_resolved_free},
               {"target_contact", result.target_contact}};
  // The scene's single targets, reached within the grid's tolerance without a contact on the
  // way, each started as the grid's targets are: `visited` from the posture the arm stood in
  // with its tip nearest it, at a grid target reached or at a sample of the demonstration;
  // `nearest` from the posture at the grid target reached nearest it (the demonstration left
  // out, as for the grid's targets); `learned` from q_c(x), `start` from the start posture;
  // `previous`, whose start is wherever the grid's tour ended, from the taught posture of the
  // area whose sample lies nearest. The start posture where there is no demonstration and no
  // target was reached.
  Json scene_targets = Json::array();
  int scene_targets_reached = 0;
  robot::CollisionWorld world(*session.model, session.scene_data);
  const app::ArmReach arm_reach = app::armReach(*session.model);
  for (const Eigen::Vector3d& target : session.scene_data.targets) {
    Eigen::VectorXd q_start = startPosture(session);
    if (approach == app::ApproachFrom::kNearestVisited || approach == app::ApproachFrom::kNearestReached) {
      // Where the grid's run left the arm standing, as the grid's own targets start: the
      // targets it reached, and under `visited` the demonstration's samples.
      q_start = app::nearestStandingPosture(result.standing_postures, target, q_start);
    } else if (approach == app::ApproachFrom::kLearnedPosture) {
      q_start = app::learnedPosture(*session.model, *learner, target);
    } else if (approach != app::ApproachFrom::kStartPosture && session.data.size() > 0) {
      Eigen::Index nearest = 0;
      (session.data.X.colwise() - target).colwise().squaredNorm().minCoeff(&nearest);
      const int area = session.data.areaOf(nearest);
      if (area >= 0 && area < static_cast<int>(session.q_fixed.size())) q_start = session.q_fixed[static_cast<std::size_t>(area)];
    }
    const app::MotionOutcome outcome = app::approachTarget(*session.model, parameters, *learner, q_start, target, &world);
    const bool reached = !outcome.collided && outcome.final_error_m <= grid.tolerance;
    scene_targets_reached += reached ? 1 : 0;
    const robot::Obstacle* inside = robot::obstacleAt(session.scene_data, target);
    // As a grid target out of reach is left out of T: a target no posture reaches is said to be
    // one, not reported as a miss of the learned map with whatever the arm met on its way.
    const double beyond_reach = arm_reach.fromShoulder(target) - arm_reach.reach;
    if (beyond_reach > 0.0) {
      std::fprintf(stderr, "note: scene target (%.3f, %.3f, %.3f) m lies %.2f m beyond the arm's reach (%.2f m from the shoulder, reach %.2f m)\n",
                   target.x(), target.y(), target.z(), beyond_reach, arm_reach.fromShoulder(target), arm_reach.reach);
    }
    scene_targets.push_back({{"target_m", {target.x(), target.y(), target.z()}},
                             {"reached", reached},
                             {"error_m", outcome.final_error_m},
                             {"contact", outcome.contact},
                             {"inside_obstacle", inside != nullptr ? Json(inside->name) : Json(nullptr)},
                             {"beyond_reach_m", beyond_reach > 0.0 ? Json(beyond_reach) : Json(nullptr)}});
  }
  json["scene_targets"] = scene_targets;
  json["scene_targets_reached"] = scene_targets_reached;
  nameTheSession(json, options, session);
  requireTargets("eval reachable", result, json);
  return json;
}

// The session's areas with their samples, for the trajectory evaluation.
std::vector<app::EvaluatedArea> sessionAreas(const Session& session) {
  std::vector<app::EvaluatedArea> areas;
  for (std::size_t k = 0; k < session.q_fixed.size(); ++k) {
    std::vector<Eigen::Index> columns;
    for (Eigen::Index l = 0; l < session.data.size(); ++l) {
      if (session.data.areaOf(l) == static_cast<int>(k)) columns.push_back(l);
    }
    if (columns.empty()) continue;
    app::EvaluatedArea area;
    area.q_fixed = session.q_fixed[k];
    area.name = session.taught_names[k];
    area.samples.resize(3, static_cast<Eigen::Index>(columns.size()));
    for (std::size_t i = 0; i < columns.size(); ++i) area.samples.col(static_cast<Eigen::Index>(i)) = session.data.X.col(columns[i]);
    areas.push_back(area);
  }
  return areas;
}

Json runSceneModel(const EvalOptions& options) {
  const Session session = loadSession(options.session, options.robot_file, options.scene_file);
  const robot::EvaluationGrid grid = app::sceneGrid(session.scene_data, options.spacing);
  const auto learner = learnMap(session, learnerOf(options, session));
  const robot::ParameterSet parameters = app::sceneParameters(session.scene_data);
  // Eq. 4.1 uses the postures the reachability evaluation ends in (Sect. 4.2.2).
  const app::ReachableResult reachable =
      app::evaluateReachable(*session.model, session.scene_data, parameters, *learner, startPosture(session), grid,
                             session.data, [](double f) { reportProgress("eval scene-model", f); },
                             app::parseApproach(options.approach));
  // Without targets the reachability run ended in no posture, M is empty and every point of T
  // would count as model: the same failure as `eval reachable` on this session.
  requireTargets("eval scene-model", reachable,
                 {{"targets", reachable.targets},
                  {"grid_points", reachable.grid_points},
                  {"out_of_reach", reachable.out_of_reach},
                  {"in_obstacles", reachable.in_obstacles},
                  {"excluded", reachable.excluded},
                  {"inaccessible", reachable.inaccessible},
                  {"spacing_m", grid.spacing},
                  {"learner", learnerOf(options, session)},
                  {"areas", session.q_fixed.size()}});
  const app::SceneModelResult model = app::evaluateSceneModel(*session.model, session.scene_data, grid, reachable.final_postures);
  Json json = {{"workspace_points", model.workspace_points},
          {"model_points", model.model_points},
          {"obstacle_points", model.obstacle_points},
          {"obstacle_points_enclosed", model.obstacle_points_enclosed},
          // Without obstacle points there is no fraction of them enclosed (0 of 0 is not 0 %).
          {"obstacle_enclosed_fraction",
           model.obstacle_points > 0 ? Json(model.obstacle_enclosed_fraction) : Json(nullptr)},
          {"free_points_in_model", model.free_points_in_model},
          {"reachable_fraction", reachable.reachable_fraction},
          {"spacing_m", grid.spacing},
          {"learner", learnerOf(options, session)},
          {"areas", session.q_fixed.size()},
          {"model", pointsJson(model.model)}};
  nameTheSession(json, options, session);
  return json;
}

}  // namespace

Json trajectoryRegionJson(const app::TrajectoryRegionResult& region) {
  // Null where no trajectory's start was reached: no error was measured, which 0 would hide.
  const auto measured = [&](double value) { return region.e_task_trajectories > 0 ? Json(value) : Json(nullptr); };
  Json collided = Json::array();
  for (const auto& trajectory : region.collided) {
    collided.push_back({{"name", trajectory.name},
                        {"contact", trajectory.contact},
                        {"contact_time_s", trajectory.contact_time},
                        {"target_m", toJson(trajectory.target)},
                        {"on_way_to_start", trajectory.on_way_to_start}});
  }
  return {{"region", region.name},
          {"trajectories", region.trajectories},
          {"e_task_trajectories", region.e_task_trajectories},
          {"e_task_until_contact", region.e_task_until_contact},
          {"e_task_mean_mm", measured(region.e_task_mean_mm)},
          {"e_task_std_mm", measured(region.e_task_std_mm)},
          {"e_task_max_mm", measured(region.e_task_max_mm)},
          {"e_task_max_trajectory", region.e_task_max_trajectory},
          {"e_task_max_time_s", region.e_task_max_time},
          {"e_coll", region.collisions},
          {"contacts", region.contacts},
          {"collided_trajectories", collided},
          {"start_contact", region.start_contact},
          {"starts_placed", region.starts_placed},
          {"impossible_trajectories", region.impossible}};
}

namespace {

Json trajectoryJson(const app::TrajectoryResult& result) {
  Json regions = Json::array();
  for (const auto& region : result.regions) regions.push_back(trajectoryRegionJson(region));
  // As --source names them.
  return {{"source", result.from_scene ? "scene" : "training-data"}, {"regions", regions}};
}

Json runTrajectories(const EvalOptions& options) {
  const Session session = loadSession(options.session, options.robot_file, options.scene_file);
  const auto learner = learnMap(session, learnerOf(options, session));
  const robot::ParameterSet parameters = app::sceneParameters(session.scene_data);
  const app::TrajectoryResult result =
      app::evaluateTrajectories(*session.model, session.scene_data, parameters, *learner, sessionAreas(session),
                                options.per_area, options.speed, options.seed,
                                [](double f) { reportProgress("eval trajectories", f); },
                                app::parseTrajectorySource(options.source));
  // A scene in the wrong units would name every trajectory: the first few, then how many more.
  constexpr std::size_t kNotesOnStderr = 10;
  std::size_t impossible = 0;
  for (const auto& region : result.regions) {
    for (const auto& why : region.impossible) {
      if (++impossible <= kNotesOnStderr) {
        std::cerr << "note: trajectory " << printable(why, 200) << " (the tip cannot follow it there; counted with the others)\n";
      }
    }
  }
  if (impossible > kNotesOnStderr) {
    std::cerr << "note: ... and " << impossible - kNotesOnStderr << " more (\"impossible_trajectories\" in the JSON)\n";
  }
  Json out = trajectoryJson(result);
  out["learner"] = learnerOf(options, session);
  out["speed_m_s"] = options.speed;
  out["areas"] = session.q_fixed.size();
  nameTheSession(out, options, session);
  return out;
}

Json runPlan(const EvalOptions& options) {
  const Session session = loadSession(options.session, options.robot_file, options.scene_file);
  const auto learner = learnMap(session, learnerOf(options, session));
  const robot::ParameterSet parameters = app::sceneParameters(session.scene_data);
  const Eigen::VectorXd start = session.q_fixed.empty() ? startPosture(session) : session.q_fixed.front();
  const app::PlanningResult result =
      app::evaluatePlanning(*session.model, session.scene_data, parameters, *learner, *session.itm, start, options.goals,
                            options.seed, [](double f) { reportProgress("plan", f); },
                            planning::planPosturesFromString(options.postures));
  Json motions = Json::array();
  for (const app::PlannedMotion& motion : result.motions) {
    motions.push_back({{"start", toJson(motion.start_W)},
                       {"goal", toJson(motion.goal_W)},
                       {"found", motion.found},
                       {"collided", motion.collided},
                       {"reached_1cm", motion.reached_1cm},
                       {"contact", motion.contact},
                       {"contact_time_s", motion.contact_time},
                       {"contact_path_error_m", motion.contact_path_error},
                       {"ended_in_contact", motion.ended_in_contact},
                       {"final", toJson(motion.final_W)},
                       {"final_error_m", motion.final_error_m},
                       {"tracking_error_max_m", motion.tracking_error_max_m},
                       {"path", pointsJson(motion.planned_W)}});
  }
  Json json = {{"goals", result.goals},
          {"postures", options.postures},
          {"found", result.found},
          {"collision_free", result.collision_free},
          {"reached_1cm", result.reached_1cm},
          {"final_error_max_m", result.final_error_max_m},
          {"tracking_error_max_m", result.tracking_error_max_m},
          {"mean_plan_ms", result.mean_plan_ms},
          {"contacts", result.contacts},
          {"itm_nodes", session.itm->nodeCount()},
          {"disconnected_nodes", result.disconnected_nodes},
          {"learner", learnerOf(options, session)},
          {"motions", motions}};
  nameTheSession(json, options, session);
  return json;
}

}  // namespace

void registerEvalCommands(CLI::App& app, CommandRunner& runner) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* eval = app.add_subcommand("eval", "evaluate a taught session in simulation");
  eval->require_subcommand(1);
  CLI::App* reachable = eval->add_subcommand("reachable", "reachable workspace on the evaluation grid (Sect. 3.3.2)");
  reachable->add_option("--session", options->session, "session file written by teach")->required();
  reachable->add_option("--learner", options->learner, "elm, oselm or llm (default: the one the session was taught with)");
  reachable->add_option("--spacing", options->spacing, "grid spacing [m] (default: the scene's)")->check(finiteRange(0.01, 1.0));
  addApproachOption(*reachable, options->approach);
  addMovedFilesOptions(*reachable, options->robot_file, options->scene_file);
  reachable->callback([&runner, options] { runner.select([options] { return runReachable(*options); }); });
  CLI::App* scene_model = eval->add_subcommand("scene-model", "implicit scene model S of Eq. 4.1 and how much of the obstacles it encloses");
  scene_model->add_option("--session", options->session, "session file written by teach")->required();
  scene_model->add_option("--learner", options->learner, "elm, oselm or llm (default: the one the session was taught with)");
  scene_model->add_option("--spacing", options->spacing, "grid spacing [m] (default: the scene's)")->check(finiteRange(0.01, 1.0));
  addApproachOption(*scene_model, options->approach);
  addMovedFilesOptions(*scene_model, options->robot_file, options->scene_file);
  scene_model->callback([&runner, options] { runner.select([options] { return runSceneModel(*options); }); });
  CLI::App* trajectories = eval->add_subcommand("trajectories", "E_task and E_coll along straight trajectories per area (Tab. 3.2)");
  trajectories->add_option("--session", options->session, "session file written by teach")->required();
  trajectories->add_option("--learner", options->learner, "elm, oselm or llm (default: the one the session was taught with)");
  trajectories->add_option("--source", options->source,
                           "the scene's trajectories (scene), trajectories drawn in the boxes around each area's "
                           "training data and between them, as the thesis defines its regions (training-data), or "
                           "the scene's where it lists any (auto, the default)")
      ->check(CLI::IsMember({"auto", "scene", "training-data"}));
  trajectories->add_option("--per-area", options->per_area, "trajectories per training area where they are drawn (between areas taught one after the other: twice)")->check(finiteRange(1, 10000))->capture_default_str();
  trajectories->add_option("--speed", options->speed, "tip speed [m/s]")->check(finiteRange(0.01, 1.0))->capture_default_str();
  trajectories->add_option("--seed", options->seed, "random seed for drawn trajectories")->check(seedValidator())->capture_default_str();
  addMovedFilesOptions(*trajectories, options->robot_file, options->scene_file);
  trajectories->callback([&runner, options] { runner.select([options] { return runTrajectories(*options); }); });

  CLI::App* plan = app.add_subcommand("plan", "plan to random ITM nodes and execute (Sect. 8.3)");
  plan->add_option("--session", options->session, "session file written by teach")->required();
  plan->add_option("--goals", options->goals, "number of goals")->check(finiteRange(1, 10000))->capture_default_str();
  plan->add_option("--seed", options->seed, "random seed")->check(seedValidator())->capture_default_str();
  plan->add_option("--learner", options->learner, "elm, oselm or llm (default: the one the session was taught with)");
  plan->add_option("--postures", options->postures,
                   "null-space posture along a path: the postures shown along it in CONFIGURATION (demonstrated) "
                   "or the learned map alone, as in the thesis (learned)")
      ->check(CLI::IsMember({"demonstrated", "learned"}))
      ->capture_default_str();
  addMovedFilesOptions(*plan, options->robot_file, options->scene_file);
  plan->callback([&runner, options] { runner.select([options] { return runPlan(*options); }); });
}

}  // namespace flexirob::cli
