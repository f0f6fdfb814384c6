// `render`: a picture of a robot posture in a scene, drawn offscreen through OSMesa (no X
// server needed).
#include <chrono>
#include <cmath>

#include "app/cli/cli_support.hpp"
#include "render/camera.hpp"
#include "render/offscreen.hpp"
#include "render/world.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::cli {
namespace {

struct RenderOptions {
  std::string robot = "lwr4";
  std::string tip;
  std::string scene;
  std::string out;
  std::string q;
  std::string camera;
  int width = 1024;
  int height = 768;
  int supersampling = 2;
  bool no_grid = false;
};

Json renderPicture(const RenderOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath(options.robot), options.tip);
  const robot::Scene scene = robot::loadScene(options.scene);

  // Posture: --q, else the scene's home posture if it fits this robot, else the middle of the
  // software limits.
  Eigen::VectorXd q = model.midPosture();
  if (!options.q.empty()) {
    q = parseNumberList(options.q, "--q", model.dof());
  } else if (scene.home_posture && scene.home_posture->size() == model.dof()) {
    q = *scene.home_posture;
  }
  model.checkPosture(q);

  render::World world;
  world.setRobot(model);
  world.setScene(scene);
  world.setGridVisible(!options.no_grid);
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  world.robot()->setPosture(kinematics);

  const double aspect = static_cast<double>(options.width) / options.height;
  const render::CameraPose camera =
      options.camera.empty() ? world.defaultCamera(aspect) : render::parseCamera(options.camera);
  render::OffscreenRenderer renderer(options.width, options.height, options.supersampling);
  const Eigen::Vector4f background = render::Palette::background();
  const render::Image image =
      renderer.render(world.root(), camera, {background[0], background[1], background[2], background[3]});
  render::writePng(image, options.out);

  const std::optional<Eigen::Vector2d> tip_pixel =
      render::projectToPixel(camera, options.width, options.height, kinematics.p_WT());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {{"width", image.width},
          {"height", image.height},
          {"file", options.out},
          {"robot", model.name()},
          {"scene", scene.name.empty() ? std::string("empty") : scene.name},
          {"q", toJson(q)},
          {"tip_position", toJson(kinematics.p_WT())},
          {"tip_pixel", tip_pixel ? toJson(*tip_pixel) : Json(nullptr)},
          {"camera",
           {{"eye", toJson(camera.eye_W)}, {"center", toJson(camera.center_W)}, {"fovy_deg", camera.fovy_deg}}},
          {"seconds", seconds}};
}

}  // namespace

void registerRenderCommand(CLI::App& app, CommandRunner& runner) {
  auto options = std::make_shared<RenderOptions>();
  auto* command = app.add_subcommand("render", "render a robot posture in a scene to a PNG file, offscreen");
  command->add_option("--robot", options->robot, "built-in robot (lwr4, arm9) or a URDF file")->capture_default_str();
  command->add_option("--tip", options->tip, "tip link (default: the last link of the longest serial chain)");
  command->add_option("--scene", options->scene, "built-in scene name or a scene file (default: empty)");
  command->add_option("--out", options->out, "PNG file to write")->required();
  command->add_option("--q", options->q, "joint values q1,...,qN [rad] (default: the scene's home posture, else mid-range)");
  command->add_option("--width", options->width, "image width [px]")->capture_default_str()->check(CLI::Range(1, 8192));
  command->add_option("--height", options->height, "image height [px]")->capture_default_str()->check(CLI::Range(1, 8192));
  command->add_option("--camera", options->camera,
                      "eye and look-at point in the world frame [m], optionally the vertical field of view "
                      "[deg]: ex,ey,ez,cx,cy,cz[,fovy] (default: front-left, framing robot and scene)");
  command->add_option("--supersample", options->supersampling, "anti-aliasing: render at this multiple and average")
      ->capture_default_str()
      ->check(CLI::Range(1, 4));
  command->add_flag("--no-grid", options->no_grid, "hide the ground grid and the world axes");
  command->callback([options, &runner] { runner.select([options] { return renderPicture(*options); }); });
}

}  // namespace flexirob::cli
