// `reach`: drive the tip of a simulated robot to a target with the hierarchical controller
// (Eq. 2.11), the null space pulled towards a posture, and report accuracy, collisions and
// clamps (DESIGN §6).
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli/cli_support.hpp"
#include "app/evaluation.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"

namespace flexirob::cli {
namespace {

struct ReachOptions {
  std::string robot;  ///< empty: the scene's robot, else lwr4
  std::string tip;
  std::string scene;
  std::string target;
  std::string posture;
  std::string from;
  double tolerance = 1e-4;
  double max_time = 30.0;
};

Json runReach(const ReachOptions& options) {
  // Without --scene the empty scene (loadScene("")), as documented: the same table and the same
  // free start as `--scene empty`.
  const robot::Scene scene = loadSceneNoting(options.scene);
  const std::string robot_name = robot::robotFor(options.robot, scene);
  const auto model = loadRobotNoting(robot_name, options.tip);
  robot::checkPosturesFit(scene, model, robot_name);
  const Eigen::Vector3d target = parseNumberList(options.target, "--target", 3);
  // As scene files: a coordinate beyond 1 km is a mistake (units, a missing decimal point).
  if (target.cwiseAbs().maxCoeff() > 1000.0) throw InputError("--target: coordinates beyond 1000 m");
  // The robot stands on the table top z = 0 (as in scene files, docs/SCENES.md): a target under
  // it could only be reached through it.
  if (target.z() < 0.0) {
    std::ostringstream z;
    z << target.z();
    throw InputError("--target: lies below the table top or mount the robot stands on, z = 0 (z = " + z.str() + " m)");
  }
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  parameters.applyOverrides(scene.parameters, robot::sceneOrigin(scene));

  robot::ReachRequest request;
  request.target = target;
  if (!options.from.empty()) {
    request.start = parseNumberList(options.from, "--from", model.dof());
    model.checkWithinLimits(request.start, "--from");
  } else {
    request.start = app::homePosture(model, scene);
  }
  if (!options.posture.empty()) {
    request.posture = parseNumberList(options.posture, "--posture", model.dof());
    model.checkWithinLimits(request.posture, "--posture");
  }
  if (!(options.tolerance > 0.0) || !std::isfinite(options.tolerance)) throw InputError("--tolerance: expected a positive number");
  if (!(options.max_time > 0.0) || !(options.max_time <= 3600.0)) throw InputError("--max-time: expected a value in (0, 3600] s");
  request.tolerance = options.tolerance;
  request.max_time = options.max_time;

  // Scene files say when their places lie tens of metres away; a target typed in millimetres
  // would otherwise end as "unreachable" with an error of hundreds of metres and no word why.
  const app::ArmReach arm = app::armReach(model);
  const double from_shoulder = (target - arm.shoulder).norm();
  if (arm.reach > 0.0 && from_shoulder > 10.0 * arm.reach) {
    std::fprintf(stderr, "note: the target lies %.0f m from the arm's shoulder, %.0f times its reach of %.2f m; --target is read in metres (%s?)\n",
                 from_shoulder, from_shoulder / arm.reach, arm.reach, from_shoulder > 100.0 * arm.reach ? "millimetres" : "centimetres");
  }
  const robot::ReachResult result = robot::reach(model, &scene, parameters, request);
  // As `eval` says of a scene target: reached or not, the tip is in the obstacle there.
  const robot::Obstacle* inside = robot::obstacleAt(scene, target);
  if (inside != nullptr && inside->shape == robot::Obstacle::Shape::kMesh && result.status == "reached" && result.collisions == 0) {
    // An open mesh's inside is free air to the simulation: say what the run showed.
    std::fprintf(stderr,
                 "note: the target lies inside obstacle '%s' as areas and evaluations read it (an open mesh counts as the "
                 "solid it surrounds), though the simulated tip met none of its surface on the way\n",
                 printable(inside->name, 100).c_str());
  } else if (inside != nullptr) {
    std::fprintf(stderr, "note: the target lies inside obstacle '%s': the tip cannot get there without touching it\n",
                 printable(inside->name, 100).c_str());
  }
  if (result.status == "unreachable" && !result.joints_at_limits.empty()) {
    std::string joints;
    for (const auto& name : result.joints_at_limits) joints += (joints.empty() ? "" : ", ") + name;
    std::fprintf(stderr, "note: the controller stalled %.3f m from the target with %s on %s limits; another start (--from) may reach it\n",
                 result.error_m, joints.c_str(), result.joints_at_limits.size() == 1 ? "its" : "their");
  }
  if (!result.gravity_overload.empty()) {
    std::fprintf(stderr, "warning: the joints cannot hold the arm up: %s (the URDF's <limit effort>)\n", result.gravity_overload.c_str());
  }
  if (result.status == "reached" && result.collisions > 0) {
    // The target is reached (within the tolerance), but not as `eval reachable` counts it.
    std::string touched;
    std::vector<std::string> named;
    for (const auto& event : result.collision_events) {
      const std::string pair = event.link + " on " + event.other;
      if (std::find(named.begin(), named.end(), pair) != named.end()) continue;
      named.push_back(pair);
      touched += (touched.empty() ? "" : ", ") + pair;
    }
    std::fprintf(stderr, "note: reached, but not free of contacts on the way: %s\n", touched.c_str());
  }
  Json events = Json::array();
  for (const auto& event : result.collision_events) {
    events.push_back({{"time_s", event.time}, {"link", event.link}, {"other", event.other}, {"self", event.self_collision}});
  }
  return {{"robot", model.name()},
          {"scene", scene.name},
          {"status", result.status},
          {"reached", result.status == "reached"},
          // As `eval reachable` counts a target: reached, and no contact on the way.
          {"reached_without_contact", result.status == "reached" && result.collisions == 0},
          {"inside_obstacle", inside != nullptr ? Json(inside->name) : Json(nullptr)},
          {"error_m", result.error_m},
          {"best_error_m", result.best_error_m},
          {"steps", result.steps},
          {"time_s", result.time_s},
          {"collisions", result.collisions},
          {"colliding_steps", result.colliding_steps},
          {"collision_events", events},
          {"clamped", result.clamps.total()},
          {"clamps",
           {{"position", result.clamps.position},
            {"velocity", result.clamps.velocity},
            {"acceleration", result.clamps.acceleration},
            {"rejected", result.clamps.rejected}}},
          {"null_space_scaled", result.null_space_scaled},
          {"torque_saturations", result.torque_saturations},
          {"max_substeps", result.max_substeps},
          {"gravity_overload", result.gravity_overload},
          {"joints_at_limits", result.joints_at_limits},
          {"rejected_commands", result.rejected_commands},
          {"target", toJson(target)},
          {"position", toJson(result.position)},
          {"q", toJson(result.q)},
          {"posture_error_rad", result.posture_error_rad}};
}

}  // namespace

void registerReachCommand(CLI::App& app, CommandRunner& runner) {
  auto* command = app.add_subcommand("reach", "drive the simulated tip to a target with the hierarchical controller");
  auto options = std::make_shared<ReachOptions>();
  command->add_option("--robot", options->robot, "built-in robot (lwr4, arm9) or a URDF file (default: the scene's, else lwr4)");
  command->add_option("--tip", options->tip, kTipHelp);
  command->add_option("--scene", options->scene, "built-in scene name or a scene file (default: empty)");
  command->add_option("--target", options->target, "tip target x,y,z [m] in the base frame")->required();
  command->add_option("--posture", options->posture, "null-space posture q1,...,qN [rad] (default: the start)");
  command->add_option("--from", options->from, "start posture q1,...,qN [rad] (default: the scene's home, else mid-range)");
  command->add_option("--tolerance", options->tolerance, "task error counted as reached [m]")->capture_default_str();
  command->add_option("--max-time", options->max_time, "simulated time limit [s]")->capture_default_str();
  command->callback([&runner, options] { runner.select([options] { return runReach(*options); }); });
}

}  // namespace flexirob::cli
