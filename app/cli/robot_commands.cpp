// `robot info` and `fk`: what a robot description says, and where its tip is.
#include <Eigen/Geometry>
#include <cmath>
#include <iostream>

#include "app/cli/cli_support.hpp"
#include "app/evaluation.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::cli {
namespace {

struct RobotOptions {
  std::string robot = "lwr4";
  std::string tip;
};

void addRobotOptions(CLI::App& command, RobotOptions& options) {
  command.add_option("--robot", options.robot, "built-in robot (lwr4, arm9) or a URDF file")->capture_default_str();
  command.add_option("--tip", options.tip, kTipHelp);
}

robot::RobotModel loadRobot(const RobotOptions& options) {
  return loadRobotNoting(options.robot, options.tip);
}

Json limitValue(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

Json robotInfo(const robot::RobotModel& model) {
  Json joints = Json::array();
  for (const auto& joint : model.joints()) {
    joints.push_back({{"name", joint.name},
                      {"type", robot::toString(joint.type)},
                      {"lower", limitValue(joint.limits.lower)},
                      {"upper", limitValue(joint.limits.upper)},
                      {"soft_lower", limitValue(joint.limits.soft_lower)},
                      {"soft_upper", limitValue(joint.limits.soft_upper)},
                      {"velocity", joint.limits.velocity},
                      {"velocity_from_urdf", joint.limits.velocity_from_urdf},
                      {"effort", joint.limits.effort}});
  }
  Json links = Json::array();
  for (const auto& body : model.bodies()) links.push_back(body.name);
  // What the tutor and the evaluations take as within reach: a sphere about the shoulder.
  const app::ArmReach reach = app::armReach(model);
  double total_mass = 0.0;
  Json assumed = Json::array();
  Json held = Json::array();
  for (const auto& body : model.bodies()) {
    total_mass += body.mass;
    if (body.inertia_assumed) assumed.push_back(body.name);
    for (const auto& link : body.held_links) held.push_back({{"link", link}, {"moves_with", body.name}});
  }
  return {{"name", model.name()},
          {"dof", model.dof()},
          {"urdf", model.urdfPath().string()},
          {"base_link", model.baseLink()},
          {"tip_link", model.tipLink()},
          {"joints", joints},
          {"bodies", links},
          {"mass_kg", total_mass},
          {"bodies_with_assumed_mass", assumed},
          {"links_held_still", held},
          {"reach", {{"shoulder", toJson(reach.shoulder)}, {"radius_m", reach.reach}, {"base_column_radius_m", reach.base_radius}}}};
}

Json forwardKinematics(const robot::RobotModel& model, const Eigen::VectorXd& q) {
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  robot::Matrix6Xd J_WT;
  kinematics.tipJacobian(J_WT);
  const Eigen::Isometry3d& X_WT = kinematics.X_WT();
  const Eigen::Quaterniond quaternion(X_WT.linear());
  Eigen::Vector4d wxyz(quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z());
  if (wxyz[0] < 0) wxyz = -wxyz;  // one of the two equal quaternions, w >= 0
  // The pose beyond a stop is still well defined (a user may ask where the tip would be), but
  // the arm can never stand there: said in the result and once on stderr, not refused.
  Json beyond_limits = Json::array();
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const auto& joint = model.joints()[static_cast<std::size_t>(i)];
    if (q[i] >= joint.limits.lower && q[i] <= joint.limits.upper) continue;
    beyond_limits.push_back({{"joint", joint.name},
                             {"value", q[i]},
                             {"lower", limitValue(joint.limits.lower)},
                             {"upper", limitValue(joint.limits.upper)}});
  }
  if (!beyond_limits.empty()) {
    const Json& first = beyond_limits.front();
    std::cerr << "warning: " << beyond_limits.size() << " joint value(s) beyond the robot's limits, first "
              << first["joint"].get<std::string>() << " = " << first["value"].get<double>() << " outside ["
              << first["lower"].dump() << ", " << first["upper"].dump() << "]; the pose is computed all the same\n";
  }
  return {{"robot", model.name()},
          {"tip_link", model.tipLink()},
          {"q", toJson(q)},
          {"beyond_limits", beyond_limits},
          {"position", toJson(X_WT.translation())},
          {"quaternion", toJson(wxyz)},
          {"rotation", toJsonRows(X_WT.linear())},
          {"jacobian", toJsonRows(J_WT)}};
}

}  // namespace

void registerRobotCommands(CLI::App& app, CommandRunner& runner) {
  auto* robot_group = app.add_subcommand("robot", "robot descriptions");
  robot_group->require_subcommand(1);
  {
    auto* info = robot_group->add_subcommand("info", "joints, limits and links of a robot description");
    auto options = std::make_shared<RobotOptions>();
    addRobotOptions(*info, *options);
    info->callback([&runner, options] { runner.select([options] { return robotInfo(loadRobot(*options)); }); });
  }
  {
    auto* fk = app.add_subcommand("fk", "forward kinematics and Jacobian of the tip");
    auto options = std::make_shared<RobotOptions>();
    auto q_text = std::make_shared<std::string>();
    addRobotOptions(*fk, *options);
    fk->add_option("--q", *q_text, "joint values q1,...,qN [rad or m]")->required();
    fk->callback([&runner, options, q_text] {
      runner.select([options, q_text] {
        const auto model = loadRobot(*options);
        const Eigen::VectorXd q = parseNumberList(*q_text, "--q", model.dof());
        return forwardKinematics(model, q);
      });
    });
  }
}

}  // namespace flexirob::cli
