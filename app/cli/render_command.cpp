// `render`: a picture of a robot posture in a scene, drawn offscreen through OSMesa (no X
// server needed), optionally with the overlays of a taught session and of the evaluations'
// results, in the style of the thesis' figures: reachable targets (Fig. 3.10), the implicit
// scene model (Fig. 4.6), confidence slices (Fig. 6.5), the ITM graph with planned paths
// (Fig. 7.7, 8.4).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <unistd.h>

#include "app/cli/cli_support.hpp"
#include "app/evaluation.hpp"
#include "app/file_output.hpp"
#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "learning/confidence.hpp"
#include "planning/itm.hpp"
#include "planning/itm_file.hpp"
#include "render/camera.hpp"
#include "render/offscreen.hpp"
#include "render/overlays.hpp"
#include "render/world.hpp"
#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::cli {
namespace {

struct RenderOptions {
  std::string robot;
  std::string tip;
  std::string scene;
  std::string out;
  std::string q;
  std::string camera;
  std::string view;
  int width = 1024;
  int height = 768;
  int supersampling = 2;
  bool no_grid = false;
  bool no_scene_areas = false;
  bool no_robot = false;
  bool no_obstacles = false;
  // Overlays from files.
  std::string session;
  std::string confidence_heights;
  int confidence_resolution = 60;
  std::string reachable;
  std::string scene_model;
  std::string plan;
  int plan_paths = -1;
  std::string hide;
  double point_size = 6.0;
  bool legend = false;
};

// --- Reading the overlays' files -----------------------------------------------------------

Json readJsonFile(const std::string& file, const std::string& option) {
  std::ifstream in(file);
  if (!in) throw InputError(option + ": cannot read '" + file + "'");
  try {
    return Json::parse(in);
  } catch (const std::exception& e) {
    throw InputError(option + ": '" + file + "' is not JSON (" + std::string(e.what()) + ")");
  }
}

// A result of eval or plan names the robot and scene it was measured in; drawn over another
// scene or arm its points mean nothing there, which the picture alone would not show. Returns
// whether it belongs (true where the file does not say).
bool belongsToTheDrawing(const Json& result, const std::string& option, const std::string& file, const robot::Scene& scene,
                         const robot::RobotModel& model) {
  if (!result.is_object()) return true;
  const auto named = [&result](const char* key) {
    return result.contains(key) && result.at(key).is_string() ? result.at(key).get<std::string>() : std::string();
  };
  const std::string robot = named("robot"), scene_name = named("scene"), session = named("session");
  if ((scene_name.empty() || scene_name == scene.name) && (robot.empty() || robot == model.name())) return true;
  const auto said = [](const std::string& name) { return name.empty() ? std::string("?") : "'" + printable(name, 80) + "'"; };
  std::cerr << "note: " << option << " '" << printable(file, 200) << "' was measured with robot " << said(robot) << " in scene "
            << said(scene_name) << (session.empty() ? "" : " (session '" + printable(session, 200) + "')")
            << ", not with the robot " << said(model.name()) << " in the scene " << said(scene.name) << " drawn\n";
  return false;
}

double finiteNumber(const Json& value, const std::string& what) {
  if (!value.is_number()) throw InputError(what + ": expected a number");
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw InputError(what + ": non-finite number");
  return v;
}

// A point the picture is framed around: one of 1e308 m (a hand-edited or damaged file) had the
// camera's arithmetic overflow and a blank picture written; a megametre is far beyond any cell.
constexpr double kFarthestPointM = 1e6;

Eigen::Vector3d withinFramingReach(const Eigen::Vector3d& p, const std::string& what) {
  if (!(p.cwiseAbs().maxCoeff() <= kFarthestPointM)) {
    std::ostringstream message;
    message << what << ": [" << p.x() << ", " << p.y() << ", " << p.z() << "] lies beyond ±1e6 m";
    throw InputError(message.str());
  }
  return p;
}

Eigen::Vector3d point3(const Json& value, const std::string& what) {
  if (!value.is_array() || value.size() != 3) throw InputError(what + ": expected [x, y, z]");
  return withinFramingReach({finiteNumber(value[0], what), finiteNumber(value[1], what), finiteNumber(value[2], what)}, what);
}

Eigen::VectorXd vectorN(const Json& value, Eigen::Index n, const std::string& what) {
  if (!value.is_array() || static_cast<Eigen::Index>(value.size()) != n) {
    throw InputError(what + ": expected " + std::to_string(n) + " numbers");
  }
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = finiteNumber(value[static_cast<std::size_t>(i)], what);
  return v;
}

// A field that must be an array of points.
std::vector<Eigen::Vector3d> pointList(const Json& object, const char* key, const std::string& what) {
  if (!object.is_object() || !object.contains(key) || !object.at(key).is_array()) {
    throw InputError(what + ": no '" + key + "' array (written by a current flexirob-cli)");
  }
  std::vector<Eigen::Vector3d> points;
  for (const Json& p : object.at(key)) points.push_back(point3(p, what + ": " + key));
  return points;
}

// What the pictures need of a session: the training samples per area, q_fixed per area, the
// final ITM graph (positions of the nodes, the edges).
struct SessionOverlay {
  std::string robot, tip, scene;
  std::string robot_urdf, scene_text;  ///< the copies taught with (empty in older sessions)
  std::string mesh_digests;            ///< SessionMetadata::mesh_digests
  std::vector<render::AreaSamples> areas;
  std::vector<std::string> area_names;  ///< areas[k]'s name as taught (empty where the file keeps none)
  std::vector<Eigen::VectorXd> q_fixed;
  std::vector<std::pair<int, Eigen::Vector3d>> nodes;
  std::vector<std::pair<int, int>> edges;
  std::string dof;  ///< the joint count a JSON session states, as written (empty: none stated)
};

SessionOverlay sessionFromJson(const Json& json, const std::string& file) {
  if (!json.is_object() || !json.contains("format") || json.at("format") != "flexirob-session-json") {
    throw InputError("--session: '" + file + "' is not a flexirob session (format flexirob-session-json)");
  }
  // As eval and plan read it: a version this build does not know is refused, not guessed at.
  if (!json.contains("version") || json.at("version") != 1) {
    throw InputError("--session: '" + file + "' has version " + (json.contains("version") ? json.at("version").dump() : "none") +
                     "; this build reads version 1");
  }
  SessionOverlay session;
  try {
    if (json.contains("dof")) session.dof = json.at("dof").dump();
    session.robot = json.at("robot").get<std::string>();
    if (json.contains("tip")) session.tip = json.at("tip").get<std::string>();
    session.scene = json.at("scene").get<std::string>();
    if (json.contains("robot_urdf")) session.robot_urdf = json.at("robot_urdf").get<std::string>();
    if (json.contains("scene_text")) session.scene_text = json.at("scene_text").get<std::string>();
    if (json.contains("mesh_digests")) session.mesh_digests = json.at("mesh_digests").get<std::string>();
    int k = 0;
    for (const Json& area : json.at("areas")) {
      render::AreaSamples samples;
      samples.area = k++;
      samples.points_W = pointList(area, "x", "--session: area");
      session.areas.push_back(std::move(samples));
      const auto name = area.find("name");
      session.area_names.push_back(name != area.end() && name->is_string() ? name->get<std::string>() : std::string());
      // q_fixed is checked against the robot once it is known.
      const Json& q = area.at("q_fixed");
      if (!q.is_array()) throw InputError("--session: q_fixed: expected numbers");
      session.q_fixed.push_back(vectorN(q, static_cast<Eigen::Index>(q.size()), "--session: q_fixed"));
    }
    const Json& nodes = json.at("itm").at("nodes");
    int id = 0;
    for (const Json& node : nodes) session.nodes.emplace_back(id++, point3(node.at("x"), "--session: itm x"));
    for (const Json& edge : json.at("itm").at("edges")) {
      const int a = jsonInteger(edge.at(0), "--session: ITM edge");
      const int b = jsonInteger(edge.at(1), "--session: ITM edge");
      if (a < 0 || b < 0 || a >= id || b >= id || a == b) throw InputError("--session: ITM edge with a bad node index");
      session.edges.emplace_back(a, b);
    }
  } catch (const Json::exception& e) {
    throw InputError("--session: malformed session (" + std::string(e.what()) + ")");
  }
  return session;
}

// A session recorded in SQLite (docs/SESSIONS.md): each area's latest take, and the samples of
// a RECORDING the session ended in.
SessionOverlay sessionFromRecording(const std::string& file) {
  const app::RecordedTeaching teaching = app::readRecordedTeaching(app::SessionReader(file));
  SessionOverlay session;
  session.robot = teaching.robot;
  session.tip = teaching.tip;
  session.scene = teaching.scene;
  session.robot_urdf = teaching.robot_urdf;
  session.scene_text = teaching.scene_text;
  session.mesh_digests = teaching.mesh_digests;
  Eigen::Index unfinished = 0;
  for (const app::RecordedArea& area : teaching.areas) unfinished += area.unfinished_X.cols();
  if (unfinished > 0) {
    std::cerr << "note: " << unfinished << (unfinished == 1 ? " sample" : " samples")
              << " of a RECORDING that no area record closed (the session ended in it, or its record is missing) "
              << (unfinished == 1 ? "is" : "are") << " drawn; eval and the learner leave them out\n";
  }
  for (const app::RecordedArea& area : teaching.areas) {
    render::AreaSamples cloud;
    cloud.area = area.index;
    for (Eigen::Index l = 0; l < area.X.cols(); ++l) cloud.points_W.push_back(withinFramingReach(area.X.col(l), "--session: area sample"));
    for (Eigen::Index l = 0; l < area.unfinished_X.cols(); ++l) {
      cloud.points_W.push_back(withinFramingReach(area.unfinished_X.col(l), "--session: area sample"));
    }
    session.areas.push_back(std::move(cloud));
    session.area_names.push_back(area.name);
    if (area.complete) session.q_fixed.push_back(area.q_fixed);
  }
  if (teaching.itm) {
    const planning::Itm& itm = *teaching.itm;
    for (const int id : itm.nodeIds()) {
      session.nodes.emplace_back(id, withinFramingReach(itm.prototype(id).head<3>(), "--session: ITM node"));
      for (const int other : itm.neighbors(id)) {
        if (other > id) session.edges.emplace_back(id, other);
      }
    }
  }
  return session;
}

SessionOverlay loadSessionOverlay(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError("--session: cannot read '" + file + "'");
  if (!startsAsJson(in)) return readingSession(file, [&file] { return sessionFromRecording(file); });
  in.close();
  return sessionFromJson(readJsonFile(file, "--session"), file);
}

// --- Composing the picture ------------------------------------------------------------------

// Grows a box by points (overlays lie outside the robot and the scene, e.g. a far goal).
void include(std::pair<Eigen::Vector3d, Eigen::Vector3d>& box, const std::vector<Eigen::Vector3d>& points) {
  for (const Eigen::Vector3d& p : points) {
    box.first = box.first.cwiseMin(p);
    box.second = box.second.cwiseMax(p);
  }
}

// A posture beyond the joint limits is still drawn (a picture of what a stop prevents can be
// wanted, as fk computes such a pose), but said once on stderr and in the result.
Json warnBeyondLimits(const robot::RobotModel& model, const Eigen::VectorXd& q) {
  Json beyond_limits = Json::array();
  std::ostringstream outside;
  outside << std::setprecision(4);
  for (int j = 0; j < model.dof(); ++j) {
    const robot::Joint& joint = model.joints()[static_cast<std::size_t>(j)];
    if (q[j] >= joint.limits.lower && q[j] <= joint.limits.upper) continue;
    outside << (beyond_limits.empty() ? "" : "; ") << "joint " << j + 1 << " (" << joint.name << ") at " << q[j]
            << " outside [" << joint.limits.lower << ", " << joint.limits.upper << "]";
    beyond_limits.push_back(joint.name);
  }
  if (!beyond_limits.empty()) std::cerr << "warning: --q beyond the joint limits, drawn all the same: " << outside.str() << "\n";
  return beyond_limits;
}

Json renderPicture(const RenderOptions& options) {
  checkOutputPath("--out", options.out,
                  {{"--session", options.session}, {"--scene", options.scene}, {"--robot", options.robot}, {"--reachable", options.reachable},
                   {"--scene-model", options.scene_model}, {"--plan", options.plan}});
  const auto start = std::chrono::steady_clock::now();
  std::optional<SessionOverlay> session;
  if (!options.session.empty()) session = loadSessionOverlay(options.session);
  // Scene and robot: the options', else the session's, else an empty scene and the scene's robot.
  const std::string scene_name = !options.scene.empty() ? options.scene : session ? session->scene : "";
  robot::Scene scene = options.scene.empty() && session ? loadSessionScene(session->scene, session->scene_text) : loadSceneNoting(scene_name);
  if (session && !options.scene.empty() && !session->scene.empty()) {
    // The session's areas and postures are drawn in another scene than the one they were taught
    // in: worth drawing (the same cell changed), not worth drawing unsaid.
    const std::string taught_in = std::filesystem::path(session->scene).stem().string();
    const bool same = options.scene == session->scene || std::filesystem::path(options.scene).stem().string() == taught_in ||
                      taught_in == scene.name;
    if (!same) {
      std::cerr << "note: the session was taught in the scene '" << printable(session->scene, 200) << "'; drawn in '"
                << printable(scene.name, 200) << "' as --scene asks" << (options.robot.empty() ? ", with the session's robot" : "") << "\n";
    }
  }
  const std::string robot_name = !options.robot.empty() ? options.robot : session ? session->robot : robot::robotFor("", scene);
  bool robot_is_the_sessions = options.robot.empty();
  if (session && !options.robot.empty()) {
    // The session's postures and samples belong to its robot: drawn on another arm of the same
    // joint count they would show postures that never put that arm's tip into the samples.
    // A session whose robot file has moved since may be drawn on the robot the user names.
    std::error_code error;
    const auto canonical = [&error](const std::string& name) { return std::filesystem::weakly_canonical(resolveRobotPath(name), error); };
    std::filesystem::path session_robot;
    try {
      session_robot = canonical(session->robot);
    } catch (const InputError&) {
    }
    robot_is_the_sessions = !session_robot.empty() && canonical(options.robot) == session_robot;
    if (!session_robot.empty() && canonical(options.robot) != session_robot) {
      throw InputError("--robot '" + options.robot + "' is not the session's robot '" + session->robot +
                       "'; leave --robot out to draw the session on its own robot");
    }
  }
  // The session's own robot, named again by --robot or not: its tip too.
  const std::string tip = !options.tip.empty() ? options.tip : session && robot_is_the_sessions ? session->tip : "";
  const robot::RobotModel model = options.robot.empty() && session ? loadSessionRobot(session->robot, session->robot_urdf, tip)
                                                                   : loadRobotNoting(robot_name, tip);
  // The session's own robot and scene: their meshes as they were taught with.
  if (session && robot_is_the_sessions && options.scene.empty()) noteMeshesChangedSinceTeaching(session->mesh_digests, model, scene);
  refuseOutputsOverMeshes({{"--out", options.out}}, model, scene);
  robot::checkPosturesFit(scene, model, robot_name);
  if (session && !session->dof.empty() && session->dof != std::to_string(model.dof())) {
    throw InputError("session: dof is " + printable(session->dof) + ", but the robot '" + session->robot + "' has " +
                     std::to_string(model.dof()) + " joints");
  }

  // Posture: --q, else where teaching starts (the scene's home posture, else a free one).
  Eigen::VectorXd q;
  if (!options.q.empty()) {
    q = parseNumberList(options.q, "--q", model.dof());
  } else {
    q = app::homePosture(model, scene);
  }
  model.checkPosture(q);
  const Json beyond_limits = options.q.empty() ? Json::array() : warnBeyondLimits(model, q);
  // Links the posture puts into an obstacle, the table or each other are drawn red and named:
  // a picture of an arm buried in a box must not look like a picture of a free arm.
  Json contacts = Json::array();
  std::vector<std::string> touching_links;
  {
    robot::CollisionWorld collisions(model, scene);
    collisions.update(q);
    std::ostringstream said;
    for (const robot::Contact& contact : collisions.contacts()) {
      const std::string& link = collisions.bodyName(contact.body);
      const std::string other = collisions.otherName(contact);
      contacts.push_back({{"link", link}, {"other", other}, {"depth_m", contact.depth}});
      // Both links of a contact between two links are drawn red.
      for (const std::string& touching : {link, contact.isSelfCollision() ? other : std::string()}) {
        if (!touching.empty() && std::find(touching_links.begin(), touching_links.end(), touching) == touching_links.end()) {
          touching_links.push_back(touching);
        }
      }
      if (contacts.size() <= 3) {
        said << (contacts.size() > 1 ? ", " : "") << printable(link) << " in " << printable(other) << " (" << std::fixed << std::setprecision(1)
             << 1000.0 * contact.depth << " mm)";
      }
    }
    if (!contacts.empty()) {
      std::cerr << "note: the posture puts " << said.str() << (contacts.size() > 3 ? " and more" : "")
                << (options.no_robot ? "" : "; drawn red") << "\n";
    }
  }

  std::set<render::OverlayLayer> hidden;
  if (!options.hide.empty()) {
    std::size_t begin = 0;
    while (begin <= options.hide.size()) {
      const std::size_t comma = std::min(options.hide.find(',', begin), options.hide.size());
      hidden.insert(render::parseOverlayLayer(options.hide.substr(begin, comma - begin)));
      begin = comma + 1;
    }
  }
  const auto shown = [&](render::OverlayLayer layer) { return hidden.count(layer) == 0; };

  // The scene's suggested training areas would be mistaken for the taught ones.
  const robot::EvaluationGrid grid = scene.grid.value_or(robot::EvaluationGrid{});
  if (options.no_scene_areas) scene.training_areas.clear();
  // Fig. 4.6 shows the implicit scene model on its own, where the obstacles would hide it.
  if (options.no_obstacles) scene.obstacles.clear();
  // The scene's evaluation trajectories are target trajectories: hidden with them.
  if (!shown(render::OverlayLayer::kTrajectories)) scene.trajectories.clear();

  render::World world;
  if (!options.no_robot) world.setRobot(model);
  // Without the arm the picture is still about its workspace: far obstacles stay out of it.
  const auto [reach_center_W, reach] = render::reachSphere(model);
  if (options.no_robot) world.setFocusSphere(reach_center_W, 1.25 * reach + 0.25);
  world.setScene(scene);
  world.setGridVisible(!options.no_grid);
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  if (world.robot() != nullptr) {
    world.robot()->setPosture(kinematics);
    if (!touching_links.empty()) render::showCollisions(*world.robot(), touching_links);
  }
  // What the views frame: the robot, the scene's areas and targets and the obstacles near the
  // robot (World::focusBox), grown by every overlay drawn (empty at first when there is neither
  // robot nor scene, so that the overlays alone are framed).
  std::pair<Eigen::Vector3d, Eigen::Vector3d> box = world.focusBox().value_or(
      std::make_pair(Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
                     Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())));

  render::Overlays& overlays = world.overlays();
  std::vector<render::LegendEntry> legend;
  if (!touching_links.empty() && !options.no_robot) legend.push_back({"Link in contact", render::OverlayPalette::collision()});
  if (!scene.trajectories.empty()) legend.push_back({"Scene's evaluation trajectories", render::Palette::trajectory()});
  // Point sizes and line widths are pixels of the render target: with supersampling they scale
  // with it, so that they keep their size in the picture.
  const auto scale = static_cast<float>(options.supersampling);
  const auto size = static_cast<float>(options.point_size) * scale;
  render::ItmGraphOverlay graph(5.0F * scale, 1.5F * scale);
  Json drawn = Json::object();

  if (session) {
    if (shown(render::OverlayLayer::kTrainingSamples)) {
      overlays.setContent(render::OverlayLayer::kTrainingSamples, render::makeTrainingSamples(session->areas, size));
      int samples = 0;
      for (std::size_t k = 0; k < session->areas.size(); ++k) {
        const render::AreaSamples& area = session->areas[k];
        samples += static_cast<int>(area.points_W.size());
        include(box, area.points_W);
        const std::string& name = session->area_names[k];
        legend.push_back({(name.empty() ? "Area " + std::to_string(area.area + 1) : name) + " samples",
                          render::OverlayPalette::area(area.area)});
      }
      drawn["samples"] = samples;
    }
    if (shown(render::OverlayLayer::kGhostArms)) {
      for (const Eigen::VectorXd& q_fixed : session->q_fixed) {
        if (q_fixed.size() != model.dof()) throw InputError("--session: a q_fixed does not fit the robot");
        overlays.addContent(render::OverlayLayer::kGhostArms, render::makeGhostArm(model, q_fixed));
      }
      if (!session->q_fixed.empty()) legend.push_back({"q_fixed (ghost arms)", render::OverlayPalette::ghost()});
      drawn["ghosts"] = session->q_fixed.size();
    }
    if (shown(render::OverlayLayer::kItmGraph) && !session->nodes.empty()) {
      graph.setGraph(session->nodes, session->edges);
      overlays.addContent(render::OverlayLayer::kItmGraph, graph.node());
      std::vector<Eigen::Vector3d> nodes;
      for (const auto& node : session->nodes) nodes.push_back(node.second);
      include(box, nodes);
      legend.push_back({"ITM nodes", render::OverlayPalette::itmNode()});
      legend.push_back({"ITM edges", render::OverlayPalette::itmEdge()});
      drawn["itm_nodes"] = session->nodes.size();
      drawn["itm_edges"] = session->edges.size();
    }
    if (!options.confidence_heights.empty() && shown(render::OverlayLayer::kConfidence)) {
      // Eq. 6.6-6.9: one Gaussian per area, d = 15 as in Fig. 6.5.
      learning::ConfidenceModel confidence(15.0);
      for (const auto& area : session->areas) {
        if (area.points_W.empty()) continue;
        Eigen::MatrixXd samples(3, static_cast<Eigen::Index>(area.points_W.size()));
        for (std::size_t l = 0; l < area.points_W.size(); ++l) samples.col(static_cast<Eigen::Index>(l)) = area.points_W[l];
        confidence.addArea(samples);
      }
      // The slices span the evaluation grid's x-y extent (the scene's workspace), grown to
      // hold every sample.
      Eigen::Vector2d lower = grid.lower.head<2>();
      Eigen::Vector2d upper = grid.upper.head<2>();
      for (const auto& area : session->areas) {
        for (const Eigen::Vector3d& p : area.points_W) {
          lower = lower.cwiseMin(p.head<2>() - Eigen::Vector2d::Constant(0.1));
          upper = upper.cwiseMax(p.head<2>() + Eigen::Vector2d::Constant(0.1));
        }
      }
      const Eigen::VectorXd heights = parseNumberList(options.confidence_heights, "--confidence-heights", std::size_t{16});
      Json slices = Json::array();
      for (const double z : heights) {
        if (!std::isfinite(z) || std::abs(z) > 10.0) throw InputError("--confidence-heights: expected heights within 10 m");
        const render::ConfidenceGrid slice = render::sampleConfidence(
            [&](const Eigen::Vector3d& p) { return confidence.evaluate(p); }, lower, upper, z,
            options.confidence_resolution);
        overlays.addContent(render::OverlayLayer::kConfidence, render::makeConfidenceSlice(slice));
        include(box, {Eigen::Vector3d(lower.x(), lower.y(), z), Eigen::Vector3d(upper.x(), upper.y(), z)});
        slices.push_back({{"z", z}, {"max", slice.values.maxCoeff()}, {"mean", slice.values.mean()}});
      }
      legend.push_back({"Confidence C = 0", render::confidenceColor(0.0)});
      legend.push_back({"C = 0.5", render::confidenceColor(0.5)});
      legend.push_back({"C = 1", render::confidenceColor(1.0)});
      drawn["confidence_slices"] = slices;
      drawn["confidence_extent"] = {{"lower", toJson(lower)}, {"upper", toJson(upper)}};
    }
  } else if (!options.confidence_heights.empty()) {
    throw InputError("--confidence-heights needs --session (the confidence model is learned from its samples)");
  }

  if (!options.reachable.empty() && shown(render::OverlayLayer::kReachability)) {
    const Json json = readJsonFile(options.reachable, "--reachable");
    drawn["reachable_matches"] = belongsToTheDrawing(json, "--reachable", options.reachable, scene, model);
    const std::vector<Eigen::Vector3d> points = pointList(json, "target_points", "--reachable");
    // Targets lie outside the obstacles of the scene they were measured in: targets inside the
    // drawn scene's obstacles were measured in another scene of the same name (a mirrored copy).
    const auto inside = std::count_if(points.begin(), points.end(),
                                      [&scene](const Eigen::Vector3d& p) { return robot::obstacleAt(scene, p) != nullptr; });
    if (inside > 0 && drawn["reachable_matches"].get<bool>()) {
      std::cerr << "note: --reachable '" << printable(options.reachable, 200) << "': " << inside << " of its " << points.size()
                << " targets lie inside the drawn scene's obstacles; it was measured in another scene of the name '"
                << printable(scene.name, 80) << "'\n";
      drawn["reachable_matches"] = false;
    }
    if (!json.contains("target_reached") || !json.at("target_reached").is_array() ||
        json.at("target_reached").size() != points.size()) {
      throw InputError("--reachable: 'target_reached' must be an array as long as 'target_points'");
    }
    std::vector<bool> reached;
    for (const Json& r : json.at("target_reached")) {
      if (!r.is_boolean()) throw InputError("--reachable: 'target_reached' must hold true or false");
      reached.push_back(r.get<bool>());
    }
    overlays.addContent(render::OverlayLayer::kReachability, render::makeReachability(points, reached, size));
    include(box, points);
    const auto count = std::count(reached.begin(), reached.end(), true);
    legend.push_back({"Reached target", render::OverlayPalette::reachable()});
    legend.push_back({"Not reached", render::OverlayPalette::unreachable()});
    drawn["targets"] = points.size();
    drawn["reached"] = count;
  }
  if (!options.scene_model.empty() && shown(render::OverlayLayer::kReachability)) {
    const Json json = readJsonFile(options.scene_model, "--scene-model");
    drawn["scene_model_matches"] = belongsToTheDrawing(json, "--scene-model", options.scene_model, scene, model);
    const std::vector<Eigen::Vector3d> points = pointList(json, "model", "--scene-model");
    overlays.addContent(render::OverlayLayer::kReachability, render::makePoints(points, render::OverlayPalette::sceneModel(), size));
    include(box, points);
    legend.push_back({"Scene model S (Eq. 4.1)", render::OverlayPalette::sceneModel()});
    drawn["scene_model_points"] = points.size();
  }
  if (!options.plan.empty() && shown(render::OverlayLayer::kGoalAndPath)) {
    const Json json = readJsonFile(options.plan, "--plan");
    drawn["plan_matches"] = belongsToTheDrawing(json, "--plan", options.plan, scene, model);
    if (!json.is_object() || !json.contains("motions") || !json.at("motions").is_array()) {
      throw InputError("--plan: no 'motions' array (written by a current flexirob-cli plan)");
    }
    int paths = 0;
    int collided = 0;
    const double marker_scale = render::robotSizeScale(model);  // 2 cm on the LWR IV
    for (const Json& motion : json.at("motions")) {
      if (options.plan_paths >= 0 && paths >= options.plan_paths) break;
      if (!motion.is_object()) throw InputError("--plan: a motion is not an object");
      const Eigen::Vector3d goal = point3(motion.contains("goal") ? motion.at("goal") : Json(), "--plan: goal");
      const std::vector<Eigen::Vector3d> path = pointList(motion, "path", "--plan");
      const bool hit = motion.contains("collided") && motion.at("collided").is_boolean() && motion.at("collided").get<bool>();
      collided += hit ? 1 : 0;
      overlays.addContent(render::OverlayLayer::kGoalAndPath, render::makeGoalMarker(goal, 0.02 * marker_scale));
      overlays.addContent(render::OverlayLayer::kGoalAndPath,
                          render::makePolyline(path, hit ? render::OverlayPalette::collidedPath()
                                                         : render::OverlayPalette::plannedPath(), 3.0F * scale));
      include(box, path);
      include(box, {goal});
      ++paths;
    }
    legend.push_back({"Goal and planned path", render::OverlayPalette::plannedPath()});
    if (collided > 0) legend.push_back({"Path with a contact", render::OverlayPalette::collidedPath()});
    drawn["paths"] = paths;
    drawn["paths_with_contact"] = collided;
  }

  const double aspect = static_cast<double>(options.width) / options.height;
  render::CameraPose camera;
  std::string view = "camera";
  double hidden_fraction = 0.0;
  std::vector<std::string> see_through;
  if (!options.camera.empty()) {
    camera = render::parseCamera(options.camera);
    // A camera the user places is kept as it is; how much of the arm it sees is still reported.
    hidden_fraction = world.hiddenFraction(camera);
  } else {
    // Without a view the picture is taken from the front-left, as the GUI's home view, unless
    // obstacles hide the arm from there (a ceiling, a wall in front): then from the first side of
    // defaultViewOrder() that sees it. It frames the overlays too, since a picture that crops the
    // targets it was asked to show is wrong. A view the user names is kept.
    if (!(box.first.array() <= box.second.array()).all()) box = {Eigen::Vector3d(-1.0, -1.0, 0.0), Eigen::Vector3d(1.0, 1.0, 1.0)};
    const render::ViewChoice choice = world.chooseView(
        box, aspect, options.view.empty() ? render::defaultViewOrder() : std::vector<std::string>{options.view}, 0.04);
    camera = choice.camera;
    view = choice.view;
    hidden_fraction = choice.hidden_fraction;
    // Where no side sees the arm, the obstacles in the way are drawn see-through.
    see_through = world.revealRobot(camera);
  }
  if (options.legend && !legend.empty() && shown(render::OverlayLayer::kLegend)) {
    overlays.setContent(render::OverlayLayer::kLegend, render::makeLegend(legend, options.width, options.height));
  }

  render::OffscreenRenderer renderer(options.width, options.height, options.supersampling);
  const Eigen::Vector4f background = render::Palette::background();
  const render::Image image =
      renderer.render(world.root(), camera, {background[0], background[1], background[2], background[3]});
  app::writeFileReplacing(options.out, render::encodePng(image), "--out");

  const std::optional<Eigen::Vector2d> tip_pixel =
      render::projectToPixel(camera, options.width, options.height, kinematics.p_WT());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Json legend_json = Json::array();
  if (options.legend) {
    for (const auto& entry : legend) legend_json.push_back(entry.label);
  }
  return {{"width", image.width},
          {"height", image.height},
          {"file", options.out},
          {"robot", model.name()},
          {"scene", scene.name.empty() ? std::string("empty") : scene.name},
          {"q", toJson(q)},
          {"beyond_limits", beyond_limits},
          {"contacts", contacts},
          {"tip_position", toJson(kinematics.p_WT())},
          {"tip_pixel", tip_pixel ? toJson(*tip_pixel) : Json(nullptr)},
          {"camera",
           {{"eye", toJson(camera.eye_W)},
            {"center", toJson(camera.center_W)},
            {"up", toJson(camera.up_W)},
            {"fovy_deg", camera.fovy_deg},
            {"view", view},
            {"robot_hidden_fraction", hidden_fraction}}},
          {"see_through_obstacles", see_through},
          {"overlays", drawn},
          {"legend", legend_json},
          {"seconds", seconds}};
}

}  // namespace

void registerRenderCommand(CLI::App& app, CommandRunner& runner) {
  auto options = std::make_shared<RenderOptions>();
  auto* command = app.add_subcommand("render", "render a robot posture in a scene to a PNG file, offscreen");
  command->add_option("--robot", options->robot, "built-in robot (lwr4, arm9) or a URDF file (default: the session's, else the scene's)");
  command->add_option("--tip", options->tip, kTipHelp);
  command->add_option("--scene", options->scene, "built-in scene name or a scene file (default: the session's, else empty)");
  command->add_option("--out", options->out, "PNG file to write")->required();
  command->add_option("--q", options->q, "joint values q1,...,qN [rad] (default: the scene's home posture, else the free posture nearest mid-range)");
  command->add_option("--width", options->width, "image width [px]")->capture_default_str()->check(finiteRange(1, 8192));
  command->add_option("--height", options->height, "image height [px]")->capture_default_str()->check(finiteRange(1, 8192));
  command->add_option("--camera", options->camera,
                      "eye and look-at point in the world frame [m], optionally the vertical field of view "
                      "[deg]: ex,ey,ez,cx,cy,cz[,fovy] (default: the first side of --view's order from which obstacles do not hide the arm)");
  command->add_option("--view", options->view,
                      "front-left, front-left-low, front-right, front, back, back-left, back-right, left, right or top: frames "
                      "robot, scene and overlays from that side of the robot (it works towards -x; its left is -y) (default: front-left, or "
                      "another side where obstacles hide the arm)");
  command->add_option("--supersample", options->supersampling, "anti-aliasing: render at this multiple and average")
      ->capture_default_str()
      ->check(finiteRange(1, 4));
  command->add_flag("--no-grid", options->no_grid, "hide the ground grid and the world axes");
  command->add_flag("--no-scene-areas", options->no_scene_areas, "hide the scene file's suggested training areas");
  command->add_flag("--no-robot", options->no_robot, "leave the robot out (e.g. to look down onto a confidence slice)");
  command->add_flag("--no-obstacles", options->no_obstacles, "leave the scene's obstacles out (e.g. to see the scene model S)");
  command->add_option("--session", options->session,
                      "session written by teach (JSON or SQLite): training samples per area, q_fixed ghosts, ITM graph");
  command->add_option("--confidence-heights", options->confidence_heights,
                      "heights z1,z2,... [m] of confidence slices (Fig. 6.5) from the session's areas");
  command->add_option("--confidence-resolution", options->confidence_resolution, "grid points per side of a slice")
      ->capture_default_str()
      ->check(finiteRange(2, 400));
  command->add_option("--reachable", options->reachable, "JSON of eval reachable: reached targets green, others red (Fig. 3.10)");
  command->add_option("--scene-model", options->scene_model, "JSON of eval scene-model: the points of S (Eq. 4.1, Fig. 4.6)");
  command->add_option("--plan", options->plan, "JSON of plan: goals and planned paths (Fig. 7.7, 8.4)");
  command->add_option("--plan-paths", options->plan_paths, "draw only the first N planned paths")->check(finiteRange(0, 100000));
  command->add_option("--hide", options->hide, "overlay layers not to draw: samples,ghosts,confidence,itm,path,trajectories (also the scene's),reachability,force,legend");
  command->add_option("--point-size", options->point_size, "size of points [px]")
      ->capture_default_str()
      ->check(finiteRange(1.0, 64.0));
  command->add_flag("--legend", options->legend, "draw a legend of the overlays in the top-left corner");
  command->callback([options, &runner] { runner.select([options] { return renderPicture(*options); }); });
}

}  // namespace flexirob::cli
