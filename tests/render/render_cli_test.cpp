// `flexirob-cli render`, run in-process: its JSON, its picture, its errors.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "app/cli/cli_support.hpp"
#include "render/camera.hpp"
#include "render/overlays.hpp"
#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::cli {
namespace {

struct Result {
  int exit_code = 0;
  std::string out;
  std::string err;
};

Result run(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "flexirob-cli");
  std::vector<const char*> argv;
  for (const auto& a : arguments) argv.push_back(a.c_str());
  std::ostringstream out;
  std::ostringstream err;
  std::streambuf* old_out = std::cout.rdbuf(out.rdbuf());
  std::streambuf* old_err = std::cerr.rdbuf(err.rdbuf());
  Result result;
  result.exit_code = runCli(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old_out);
  std::cerr.rdbuf(old_err);
  result.out = out.str();
  result.err = err.str();
  return result;
}

std::filesystem::path tempPng(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("flexirob-render-cli-" + std::to_string(::getpid()) + "-" + name);
}

TEST(RenderCommand, WritesThePictureAndReportsItsSizeAndTipPixel) {
  const auto file = tempPng("lwr4.png");
  const Result result = run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "320", "--height", "200",
                             "--q", "0.3,0.6,0,-1.2,0,0.8,0", "--supersample", "1"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("width"), 320);
  EXPECT_EQ(json.at("height"), 200);
  EXPECT_EQ(json.at("file"), file.string());
  ASSERT_TRUE(std::filesystem::exists(file));
  // PNG signature and the IHDR size match what was reported.
  std::ifstream in(file, std::ios::binary);
  std::vector<unsigned char> head(24);
  in.read(reinterpret_cast<char*>(head.data()), 24);
  EXPECT_EQ(head[1], 'P');
  EXPECT_EQ((head[16] << 24) | (head[17] << 16) | (head[18] << 8) | head[19], 320);
  EXPECT_EQ((head[20] << 24) | (head[21] << 16) | (head[22] << 8) | head[23], 200);
  const auto& tip = json.at("tip_pixel");
  EXPECT_GT(tip[0].get<double>(), 0.0);
  EXPECT_LT(tip[0].get<double>(), 320.0);
  EXPECT_GT(tip[1].get<double>(), 0.0);
  EXPECT_LT(tip[1].get<double>(), 200.0);
  std::filesystem::remove(file);
}

TEST(RenderCommand, RejectsBadInputWithExitCodeTwo) {
  const auto file = tempPng("bad.png");
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--q", "0,0,0"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "0"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--camera", "1,2"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "no_such_robot", "--out", file.string()}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--scene", "no_such_scene", "--out", file.string()}).exit_code, 2);
  const Result unwritable = run({"render", "--robot", "lwr4", "--width", "16", "--height", "16", "--out",
                                 "/nonexistent-folder/x.png"});
  EXPECT_EQ(unwritable.exit_code, 2);
  EXPECT_NE(unwritable.err.find("the folder '/nonexistent-folder' does not exist"), std::string::npos) << unwritable.err;
  EXPECT_FALSE(std::filesystem::exists(file));
}

// --- Overlays from files --------------------------------------------------------------------

// The RGBA PNG the renderer writes (8 bit, filter 0 on every line), decoded with zlib.
struct Picture {
  int width = 0;
  int height = 0;
  std::vector<unsigned char> rgba;
  std::array<int, 3> at(const Eigen::Vector2d& pixel) const {
    const int x = static_cast<int>(pixel.x());
    const int y = static_cast<int>(pixel.y());
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4;
    return {rgba[i], rgba[i + 1], rgba[i + 2]};
  }
};

Picture readPicture(const std::filesystem::path& file) {
  std::string bytes(std::filesystem::file_size(file), '\0');
  std::ifstream(file, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const auto u32 = [&](std::size_t at) {
    return (std::uint32_t{static_cast<unsigned char>(bytes[at])} << 24) |
           (std::uint32_t{static_cast<unsigned char>(bytes[at + 1])} << 16) |
           (std::uint32_t{static_cast<unsigned char>(bytes[at + 2])} << 8) | std::uint32_t{static_cast<unsigned char>(bytes[at + 3])};
  };
  Picture picture;
  picture.width = static_cast<int>(u32(16));
  picture.height = static_cast<int>(u32(20));
  std::string idat;
  for (std::size_t at = 8; at + 8 <= bytes.size();) {
    const std::uint32_t length = u32(at);
    if (bytes.substr(at + 4, 4) == "IDAT") idat += bytes.substr(at + 8, length);
    at += 12 + length;
  }
  const std::size_t stride = static_cast<std::size_t>(picture.width) * 4 + 1;
  std::vector<unsigned char> raw(stride * static_cast<std::size_t>(picture.height));
  uLongf raw_size = raw.size();
  if (uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) != Z_OK) return {};
  for (int y = 0; y < picture.height; ++y) {
    const auto* line = raw.data() + static_cast<std::size_t>(y) * stride;
    if (line[0] != 0) return {};
    picture.rgba.insert(picture.rgba.end(), line + 1, line + stride);
  }
  return picture;
}

render::CameraPose cameraOf(const nlohmann::json& json) {
  const auto vec = [](const nlohmann::json& v) { return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()); };
  render::CameraPose camera;
  camera.eye_W = vec(json.at("camera").at("eye"));
  camera.center_W = vec(json.at("camera").at("center"));
  camera.up_W = vec(json.at("camera").at("up"));
  camera.fovy_deg = json.at("camera").at("fovy_deg").get<double>();
  return camera;
}

std::array<int, 3> bytesOf(const Eigen::Vector4f& rgba) {
  return {static_cast<int>(std::lround(rgba[0] * 255.0F)), static_cast<int>(std::lround(rgba[1] * 255.0F)),
          static_cast<int>(std::lround(rgba[2] * 255.0F))};
}

// The colour at a pixel within `tolerance` per channel of the expected colour.
::testing::AssertionResult near(const std::array<int, 3>& actual, const std::array<int, 3>& expected, int tolerance = 4) {
  for (int c = 0; c < 3; ++c) {
    if (std::abs(actual[static_cast<std::size_t>(c)] - expected[static_cast<std::size_t>(c)]) > tolerance) {
      return ::testing::AssertionFailure() << "colour (" << actual[0] << ", " << actual[1] << ", " << actual[2]
                                           << "), expected (" << expected[0] << ", " << expected[1] << ", " << expected[2] << ")";
    }
  }
  return ::testing::AssertionSuccess();
}

void writeText(const std::filesystem::path& file, const std::string& text) { std::ofstream(file) << text; }

// A hand-made session: one area named "front" of samples in front of the LWR IV (in a 4 cm cube
// centred at (-0.5, 0, 0.4) m) and a three-node ITM graph (a chain) at another height.
std::string tinySession() {
  nlohmann::json x = nlohmann::json::array();
  for (int i = 0; i < 27; ++i) x.push_back({-0.5 + 0.02 * (i % 3 - 1), 0.02 * ((i / 3) % 3 - 1), 0.4 + 0.02 * (i / 9 - 1)});
  nlohmann::json session = {
      {"format", "flexirob-session-json"},
      {"version", 1},
      {"robot", "lwr4"},
      {"scene", "empty"},
      {"areas", {{{"name", "front"}, {"q_fixed", {0.0, 0.5, 0.0, -1.5, 0.0, 0.8, 0.0}}, {"x", x}, {"q", nlohmann::json::array()}}}},
      {"itm",
       {{"nodes", {{{"x", {-0.6, -0.3, 0.15}}}, {{"x", {-0.6, 0.0, 0.15}}}, {{"x", {-0.6, 0.3, 0.15}}}}},
        {"edges", {{0, 1}, {1, 2}}}}}};
  return session.dump();
}

// Looking at the front of the robot from far in front (-x), so that nothing of the arm stands
// between the eye and the overlays in front of it.
const char* kFrontCamera = "-3,0,0.4,-0.5,0,0.4,30";

TEST(RenderCommandOverlays, DrawsTheSessionsSamplesAndItmGraphWhereTheyProject) {
  const auto session = tempPng("session.json");
  const auto file = tempPng("session.png");
  writeText(session, tinySession());
  const Result result = run({"render", "--session", session.string(), "--out", file.string(), "--width", "320",
                             "--height", "240", "--supersample", "1", "--no-grid", "--hide", "ghosts", "--camera",
                             kFrontCamera, "--point-size", "8"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("overlays").at("samples"), 27);
  EXPECT_EQ(json.at("overlays").at("itm_nodes"), 3);
  EXPECT_EQ(json.at("overlays").at("itm_edges"), 2);
  const render::CameraPose camera = cameraOf(json);
  const Picture picture = readPicture(file);
  ASSERT_EQ(picture.width, 320);
  // The front sample (nearest to the eye) in the colour of area 1.
  const auto sample = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.52, 0.0, 0.4));
  ASSERT_TRUE(sample);
  EXPECT_TRUE(near(picture.at(*sample), bytesOf(render::OverlayPalette::area(0))));
  // The ITM nodes at their projections, an edge half-way between two of them.
  for (const double y : {-0.3, 0.3}) {
    const auto node = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, y, 0.15));
    ASSERT_TRUE(node);
    EXPECT_TRUE(near(picture.at(*node), bytesOf(render::OverlayPalette::itmNode()))) << "node at y = " << y;
  }
  const auto edge = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, 0.15, 0.15));
  ASSERT_TRUE(edge);
  EXPECT_TRUE(near(picture.at(*edge), bytesOf(render::OverlayPalette::itmEdge()), 40));
  // Away from everything: the background.
  EXPECT_TRUE(near(picture.at({5.5, 5.5}), bytesOf(render::Palette::background())));
  // The legend names the area as it was taught.
  const Result with_legend = run({"render", "--session", session.string(), "--out", file.string(), "--width", "320",
                                  "--height", "240", "--supersample", "1", "--legend"});
  ASSERT_EQ(with_legend.exit_code, 0) << with_legend.err;
  const auto legend = nlohmann::json::parse(with_legend.out).at("legend");
  ASSERT_FALSE(legend.empty());
  EXPECT_EQ(legend.at(0), "front samples");
  std::filesystem::remove(session);
  std::filesystem::remove(file);
}

TEST(RenderCommandOverlays, DrawsReachedTargetsGreenUnreachedRedAndTheSceneModel) {
  const auto reachable = tempPng("reachable.json");
  const auto model = tempPng("model.json");
  const auto file = tempPng("reachable.png");
  writeText(reachable, R"({"target_points": [[-0.6, -0.3, 0.3], [-0.6, 0.3, 0.3]], "target_reached": [true, false]})");
  writeText(model, R"({"model": [[-0.6, 0.0, 0.1]]})");
  const Result result = run({"render", "--reachable", reachable.string(), "--scene-model", model.string(), "--out",
                             file.string(), "--width", "320", "--height", "240", "--supersample", "1", "--no-grid",
                             "--camera", kFrontCamera, "--point-size", "8", "--legend"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("overlays").at("targets"), 2);
  EXPECT_EQ(json.at("overlays").at("reached"), 1);
  EXPECT_EQ(json.at("overlays").at("scene_model_points"), 1);
  EXPECT_EQ(json.at("legend").size(), 3U);
  const render::CameraPose camera = cameraOf(json);
  const Picture picture = readPicture(file);
  const auto green = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, -0.3, 0.3));
  const auto red = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, 0.3, 0.3));
  const auto dark = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, 0.0, 0.1));
  ASSERT_TRUE(green && red && dark);
  EXPECT_TRUE(near(picture.at(*green), bytesOf(render::OverlayPalette::reachable())));
  EXPECT_TRUE(near(picture.at(*red), bytesOf(render::OverlayPalette::unreachable())));
  EXPECT_TRUE(near(picture.at(*dark), bytesOf(render::OverlayPalette::sceneModel())));
  for (const auto& f : {reachable, model, file}) std::filesystem::remove(f);
}

// A scene's evaluation trajectories are target trajectories: near-black, named in the legend and
// hidden with them (drawn purple, unnamed and always, they had read as the first area's samples).
TEST(RenderCommandOverlays, TheScenesTrajectoriesAreNamedAndHiddenWithTheTrajectories) {
  const auto file = tempPng("scene-trajectories.png");
  const std::vector<std::string> common = {"render", "--scene", "setup_A", "--out", file.string(), "--width", "320",
                                           "--height", "240", "--supersample", "1", "--legend"};
  const Result shown = run(common);
  ASSERT_EQ(shown.exit_code, 0) << shown.err;
  const auto legend = nlohmann::json::parse(shown.out).at("legend");
  EXPECT_NE(std::find(legend.begin(), legend.end(), "Scene's evaluation trajectories"), legend.end()) << legend.dump();
  std::vector<std::string> hiding = common;
  hiding.insert(hiding.end(), {"--hide", "trajectories"});
  const Result hidden = run(hiding);
  ASSERT_EQ(hidden.exit_code, 0) << hidden.err;
  const auto hidden_legend = nlohmann::json::parse(hidden.out).at("legend");
  EXPECT_EQ(std::find(hidden_legend.begin(), hidden_legend.end(), "Scene's evaluation trajectories"), hidden_legend.end());
  EXPECT_EQ(render::Palette::trajectory(), render::OverlayPalette::targetTrajectory());  // apart from the areas: overlays_test
  std::filesystem::remove(file);
}

// A result measured in another scene or with another arm is drawn as asked, and said: its
// points mean nothing in this picture, which the picture alone would not show.
TEST(RenderCommandOverlays, SaysWhenAResultWasMeasuredInAnotherSceneOrWithAnotherRobot) {
  const auto reachable = tempPng("other-scene.json");
  const auto file = tempPng("other-scene.png");
  const auto drawWith = [&](const std::string& robot, const std::string& scene) {
    writeText(reachable, R"({"target_points": [[-0.6, -0.3, 0.3]], "target_reached": [true], "session": "taught.db", "robot": ")" +
                             robot + R"(", "scene": ")" + scene + R"("})");
    return run({"render", "--scene", "setup_I", "--reachable", reachable.string(), "--out", file.string(), "--width", "64",
                "--height", "48", "--supersample", "1"});
  };
  const Result same = drawWith("lwr4", "setup_I");
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_TRUE(nlohmann::json::parse(same.out).at("overlays").at("reachable_matches").get<bool>());
  EXPECT_EQ(same.err.find("was measured"), std::string::npos) << same.err;
  for (const auto& [robot, scene] : {std::pair{"lwr4", "setup_II"}, std::pair{"arm9", "setup_I"}}) {
    const Result other = drawWith(robot, scene);
    ASSERT_EQ(other.exit_code, 0) << other.err;
    EXPECT_FALSE(nlohmann::json::parse(other.out).at("overlays").at("reachable_matches").get<bool>());
    EXPECT_NE(other.err.find(std::string("was measured with robot '") + robot + "' in scene '" + scene + "' (session 'taught.db')"),
              std::string::npos)
        << other.err;
  }
  // The same name, another scene (a mirrored copy, say): a target lies inside an obstacle drawn.
  const Eigen::Vector3d in_box = robot::loadScene("setup_I").obstacles.front().X_WO.translation();
  writeText(reachable, R"({"target_points": [[-0.6, -0.3, 0.3], [)" + std::to_string(in_box.x()) + ", " + std::to_string(in_box.y()) +
                           ", " + std::to_string(in_box.z()) + R"(]], "target_reached": [true, false], "robot": "lwr4", "scene": "setup_I"})");
  const Result copy = run({"render", "--scene", "setup_I", "--reachable", reachable.string(), "--out", file.string(), "--width", "64",
                           "--height", "48", "--supersample", "1"});
  ASSERT_EQ(copy.exit_code, 0) << copy.err;
  EXPECT_FALSE(nlohmann::json::parse(copy.out).at("overlays").at("reachable_matches").get<bool>());
  EXPECT_NE(copy.err.find("1 of its 2 targets lie inside the drawn scene's obstacles"), std::string::npos) << copy.err;
  for (const auto& f : {reachable, file}) std::filesystem::remove(f);
}

TEST(RenderCommandOverlays, DrawsGoalsAndPlannedPathsWhereTheyProject) {
  const auto plan = tempPng("plan.json");
  const auto file = tempPng("plan.png");
  writeText(plan, R"({"motions": [{"goal": [-0.6, 0.3, 0.2], "collided": false,
      "path": [[-0.6, -0.3, 0.2], [-0.6, 0.0, 0.2], [-0.6, 0.3, 0.2]]}]})");
  const Result result = run({"render", "--plan", plan.string(), "--out", file.string(), "--width", "320", "--height",
                             "240", "--supersample", "1", "--no-grid", "--camera", kFrontCamera});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("overlays").at("paths"), 1);
  const render::CameraPose camera = cameraOf(json);
  const Picture picture = readPicture(file);
  // The path's line (unlit) a quarter of the way along; the goal sphere is lit, so only its hue
  // is checked: magenta, red and blue well above green.
  const auto line = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, -0.15, 0.2));
  const auto goal = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.6, 0.3, 0.2));
  ASSERT_TRUE(line && goal);
  EXPECT_TRUE(near(picture.at(*line), bytesOf(render::OverlayPalette::plannedPath()), 12));
  const auto g = picture.at(*goal);
  EXPECT_GT(g[0], g[1] + 60);
  EXPECT_GT(g[2], g[1] + 20);
  std::filesystem::remove(plan);
  std::filesystem::remove(file);
}

TEST(RenderCommandOverlays, ConfidenceSliceIsBrightAtTheAreaAndDarkFarFromIt) {
  const auto session = tempPng("confidence.json");
  const auto file = tempPng("confidence.png");
  writeText(session, tinySession());
  // Straight down onto the slice at the area's height, z = 0.4 m.
  const Result result = run({"render", "--session", session.string(), "--out", file.string(), "--width", "320",
                             "--height", "240", "--supersample", "1", "--no-grid", "--hide", "samples,ghosts,itm",
                             "--confidence-heights", "0.4", "--camera", "-0.5,0,3,-0.5,0,0.4,30"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  const auto& slice = json.at("overlays").at("confidence_slices").at(0);
  // C(x) = max_k g_k(x) reaches 1 at an area's mean (Eq. 6.9); the grid comes close to it.
  EXPECT_GT(slice.at("max").get<double>(), 0.9);
  EXPECT_LE(slice.at("max").get<double>(), 1.0);
  render::CameraPose camera = cameraOf(json);
  const Picture picture = readPicture(file);
  const auto centre = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.5, 0.0, 0.4));
  const auto far = render::projectToPixel(camera, 320, 240, Eigen::Vector3d(-0.85, -0.5, 0.4));
  ASSERT_TRUE(centre && far);
  // Blended over the background with alpha 0.65: yellow (C = 1) at the centre, dark violet
  // (C = 0) in the far corner of the slice.
  const Eigen::Vector4f background = render::Palette::background();
  const auto blend = [&](const Eigen::Vector4f& c) {
    return bytesOf(Eigen::Vector4f(0.65F * c + 0.35F * background));
  };
  EXPECT_TRUE(near(picture.at(*centre), blend(render::confidenceColor(1.0)), 20));
  EXPECT_TRUE(near(picture.at(*far), blend(render::confidenceColor(0.0)), 6));
  std::filesystem::remove(session);
  std::filesystem::remove(file);
}

// A session's postures belong to its robot: another arm with as many joints (here a copy of
// the LWR IV's description under another name) is refused instead of drawing them on it.
TEST(RenderCommandOverlays, DrawsASessionOnlyOnItsOwnRobot) {
  const auto session = tempPng("own_robot.json");
  const auto file = tempPng("own_robot.png");
  const auto other = tempPng("other_arm.urdf");
  writeText(session, tinySession());
  std::filesystem::copy_file(resolveRobotPath("lwr4"), other, std::filesystem::copy_options::overwrite_existing);
  const Result refused = run({"render", "--session", session.string(), "--robot", other.string(), "--out", file.string()});
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_NE(refused.err.find("is not the session's robot 'lwr4'"), std::string::npos) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  const Result same = run({"render", "--session", session.string(), "--robot", "lwr4", "--out", file.string(), "--width", "64",
                           "--height", "48"});
  EXPECT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(same.err.find("was taught in the scene"), std::string::npos) << same.err;
  // Drawn in another scene than the one it was taught in: said, once.
  const Result elsewhere = run({"render", "--session", session.string(), "--scene", "setup_I", "--out", file.string(), "--width", "64",
                                "--height", "48"});
  EXPECT_EQ(elsewhere.exit_code, 0) << elsewhere.err;
  EXPECT_NE(elsewhere.err.find("note: the session was taught in the scene 'empty'; drawn in 'setup_I' as --scene asks, with the session's robot"),
            std::string::npos)
      << elsewhere.err;
  const Result own_scene = run({"render", "--session", session.string(), "--scene", "empty", "--out", file.string(), "--width", "64",
                                "--height", "48"});
  EXPECT_EQ(own_scene.err.find("was taught in the scene"), std::string::npos) << own_scene.err;
  for (const auto& path : {session, file, other}) std::filesystem::remove(path);
}

TEST(RenderCommandOverlays, RejectsHostileOverlayFilesWithAOneLineErrorAndExitCodeTwo) {
  const auto file = tempPng("hostile.png");
  const auto input = tempPng("hostile.json");
  const auto expectRejected = [&](const std::string& content, const std::vector<std::string>& options) {
    writeText(input, content);
    std::vector<std::string> arguments{"render", "--out", file.string(), "--width", "16", "--height", "16"};
    for (const auto& option : options) arguments.push_back(option == "FILE" ? input.string() : option);
    const Result result = run(arguments);
    EXPECT_EQ(result.exit_code, 2) << content;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  };
  expectRejected("not json", {"--reachable", "FILE"});
  expectRejected("[]", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0, 0]]})", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0, 0]], "target_reached": [true, false]})", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0]], "target_reached": [true]})", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0, "a"]], "target_reached": [true]})", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0, 1e999]], "target_reached": [true]})", {"--reachable", "FILE"});
  expectRejected(R"({"target_points": [[0, 0, 0]], "target_reached": [1]})", {"--reachable", "FILE"});
  expectRejected(R"({"model": {"a": 1}})", {"--scene-model", "FILE"});
  expectRejected(R"({"motions": [{"path": []}]})", {"--plan", "FILE"});
  expectRejected(R"({"motions": [{"goal": [0, 0, 0]}]})", {"--plan", "FILE"});
  expectRejected(R"({"motions": [7]})", {"--plan", "FILE"});
  expectRejected(R"({"format": "something else"})", {"--session", "FILE"});
  expectRejected(R"({"format": "flexirob-session-json", "robot": "lwr4", "scene": "empty", "areas": [],
      "itm": {"nodes": [{"x": [0, 0, 0]}], "edges": [[0, 5]]}})", {"--session", "FILE"});
  expectRejected(R"({"format": "flexirob-session-json", "robot": "lwr4", "scene": "empty",
      "areas": [{"q_fixed": [0, 0], "x": [[0, 0, 0]]}], "itm": {"nodes": [], "edges": []}})", {"--session", "FILE"});
  expectRejected(R"({"format": "flexirob-session-json", "robot": "no_such_robot", "scene": "empty", "areas": [],
      "itm": {"nodes": [], "edges": []}})", {"--session", "FILE"});
  expectRejected("SQLite format 3 but not really", {"--session", "FILE"});
  // Options that do not make sense.
  expectRejected(tinySession(), {"--session", "FILE", "--confidence-heights", "0.3,abc"});
  expectRejected(tinySession(), {"--session", "FILE", "--hide", "samples,nonsense"});
  expectRejected("{}", {"--confidence-heights", "0.3"});
  expectRejected("{}", {"--view", "sideways"});
  const Result missing = run({"render", "--out", file.string(), "--reachable", "/nonexistent-folder/r.json"});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("cannot read"), std::string::npos) << missing.err;
  EXPECT_FALSE(std::filesystem::exists(file));
  std::filesystem::remove(input);
}

TEST(RenderCommandOverlays, DefaultAndNamedViewsFrameTheOverlays) {
  const auto reachable = tempPng("view.json");
  const auto file = tempPng("view.png");
  writeText(reachable, R"({"target_points": [[-1.5, 0.0, 0.3], [0.0, 1.5, 0.3]], "target_reached": [true, true]})");
  // "" is the default camera, which frames them as well.
  for (const std::string view : {"", "front-left", "front-right", "front", "back", "left", "right", "top"}) {
    std::vector<std::string> arguments = {"render", "--reachable", reachable.string(), "--out", file.string(),
                                          "--width", "200", "--height", "150", "--supersample", "1"};
    if (!view.empty()) arguments.insert(arguments.end(), {"--view", view});
    const Result result = run(arguments);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const render::CameraPose camera = cameraOf(nlohmann::json::parse(result.out));
    // Both targets lie far outside the robot's bounds, and still inside the picture.
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(-1.5, 0.0, 0.3), Eigen::Vector3d(0.0, 1.5, 0.3)}) {
      const auto pixel = render::projectToPixel(camera, 200, 150, p);
      ASSERT_TRUE(pixel) << view;
      EXPECT_GT(pixel->x(), 0.0) << view;
      EXPECT_LT(pixel->x(), 200.0) << view;
      EXPECT_GT(pixel->y(), 0.0) << view;
      EXPECT_LT(pixel->y(), 150.0) << view;
    }
  }
  std::filesystem::remove(reachable);
  std::filesystem::remove(file);
}

TEST(RenderCommandOverlays, NoRobotLeavesTheTipsPixelToTheBackground) {
  const auto file = tempPng("no-robot.png");
  for (const bool robot : {true, false}) {
    std::vector<std::string> arguments{"render", "--robot", "lwr4", "--out", file.string(), "--width", "160", "--height",
                                       "120", "--supersample", "1", "--no-grid", "--q", "0.3,0.6,0,-1.2,0,0.8,0"};
    if (!robot) arguments.push_back("--no-robot");
    const Result result = run(arguments);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto json = nlohmann::json::parse(result.out);
    const Eigen::Vector2d tip(json.at("tip_pixel")[0].get<double>(), json.at("tip_pixel")[1].get<double>());
    const Picture picture = readPicture(file);
    EXPECT_EQ(static_cast<bool>(near(picture.at(tip), bytesOf(render::Palette::background()), 2)), !robot) << (robot ? "with" : "without");
  }
  std::filesystem::remove(file);
}

// --- Posture and viewpoint -------------------------------------------------------------------

TEST(RenderCommand, WarnsOfAPostureBeyondTheJointLimitsAndDrawsItAllTheSame) {
  const auto file = tempPng("beyond.png");
  // A2 of the LWR IV stops at 120 degrees (2.094 rad).
  const Result beyond = run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "64", "--height", "48",
                             "--supersample", "1", "--q", "0,2.5,0,-1.6,0,0.9,0"});
  ASSERT_EQ(beyond.exit_code, 0) << beyond.err;
  EXPECT_TRUE(std::filesystem::exists(file));
  EXPECT_EQ(beyond.err.rfind("warning: ", 0), 0U) << beyond.err;
  EXPECT_NE(beyond.err.find("(A2)"), std::string::npos) << beyond.err;
  // One warning (the bent-back arm lies in the table, which a note says as well).
  EXPECT_EQ(beyond.err.find("warning: ", 1), std::string::npos) << beyond.err;
  EXPECT_NE(beyond.err.find("note: the posture puts "), std::string::npos) << beyond.err;
  EXPECT_EQ(nlohmann::json::parse(beyond.out).at("beyond_limits"), nlohmann::json::array({"A2"}));
  const Result within = run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "64", "--height", "48",
                             "--supersample", "1", "--q", "0,0.6,0,-1.6,0,0.9,0"});
  ASSERT_EQ(within.exit_code, 0) << within.err;
  EXPECT_EQ(within.err, "");
  EXPECT_TRUE(nlohmann::json::parse(within.out).at("beyond_limits").empty());
  std::filesystem::remove(file);
}

// A crate around the LWR IV's wrist: the links inside it are named and drawn red (the crate left
// out of the picture, so that they can be seen); without the crate the arm keeps its colours.
TEST(RenderCommand, NamesAndDrawsRedTheLinksAPostureSinksIntoAnObstacle) {
  const auto scene = tempPng("crate.yaml");
  const auto file = tempPng("crate.png");
  const std::string posture = "0,0.6,0,-1.6,0,0.9,0";
  const robot::RobotModel lwr4 = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  robot::Kinematics kinematics(lwr4);  // keeps a reference to the model
  Eigen::VectorXd q(7);
  q << 0, 0.6, 0, -1.6, 0, 0.9, 0;
  kinematics.update(q);
  const Eigen::Vector3d tip = kinematics.p_WT();
  std::ostringstream crate;
  crate << "name: crate\nrobot: lwr4\nobstacles:\n  - {name: crate, shape: box, size: [0.2, 0.2, 0.2], position: [" << tip.x() << ", "
        << tip.y() << ", " << tip.z() << "]}\n";
  writeText(scene, crate.str());
  const auto redPixels = [&](const Result& result) {
    const Picture picture = readPicture(file);
    int red = 0;
    for (std::size_t i = 0; i + 3 < picture.rgba.size(); i += 4) {
      if (picture.rgba[i] > 180 && picture.rgba[i + 1] < 70 && picture.rgba[i + 2] < 70) ++red;
    }
    EXPECT_GT(picture.width, 0) << result.err;
    return red;
  };
  const std::vector<std::string> common{"render", "--out", file.string(), "--width", "160", "--height", "120",
                                        "--supersample", "1", "--q", posture, "--no-obstacles", "--no-grid"};
  std::vector<std::string> inside = common;
  inside.insert(inside.end(), {"--scene", scene.string()});
  const Result sunk = run(inside);
  ASSERT_EQ(sunk.exit_code, 0) << sunk.err;
  const auto contacts = nlohmann::json::parse(sunk.out).at("contacts");
  ASSERT_FALSE(contacts.empty());
  EXPECT_EQ(contacts.at(0).at("other"), "crate");
  EXPECT_GT(contacts.at(0).at("depth_m").get<double>(), 0.0);
  EXPECT_NE(sunk.err.find("note: the posture puts "), std::string::npos) << sunk.err;
  EXPECT_GT(redPixels(sunk), 30);

  std::vector<std::string> empty = common;
  empty.insert(empty.end(), {"--scene", "empty"});
  const Result free = run(empty);
  ASSERT_EQ(free.exit_code, 0) << free.err;
  EXPECT_TRUE(nlohmann::json::parse(free.out).at("contacts").empty());
  EXPECT_EQ(free.err, "");
  EXPECT_EQ(redPixels(free), 0);
  std::filesystem::remove(scene);
  std::filesystem::remove(file);
}

TEST(RenderCommand, SeesTheArmPastAWallUnlessTheUserChoseTheCamera) {
  const auto scene = tempPng("wall.yaml");
  const auto file = tempPng("wall.png");
  // A wall between the default front-left eye and the arm.
  writeText(scene, "name: wall\nrobot: lwr4\nhome_posture: [0, 0.6, 0, -1.6, 0, 0.9, 0]\n"
                   "obstacles:\n  - {name: wall, shape: box, size: [0.04, 3.0, 1.6], position: [-0.85, 0, 0.8]}\n");
  const std::vector<std::string> common{"render", "--scene", scene.string(), "--out", file.string(), "--width", "160",
                                        "--height", "120", "--supersample", "1"};
  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> arguments = common;
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    const Result result = run(arguments);
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return nlohmann::json::parse(result.out);
  };
  const auto chosen = with({});
  EXPECT_NE(chosen.at("camera").at("view"), "front-left");
  EXPECT_LE(chosen.at("camera").at("robot_hidden_fraction").get<double>(), render::kAcceptableHiddenFraction);
  EXPECT_TRUE(chosen.at("see_through_obstacles").empty());
  const auto named = with({"--view", "front-left"});
  EXPECT_EQ(named.at("camera").at("view"), "front-left");
  EXPECT_EQ(named.at("see_through_obstacles"), nlohmann::json::array({"wall"}));
  const auto fixed = with({"--camera", "-3,-2,1.5,0,0,0.4"});
  EXPECT_EQ(fixed.at("camera").at("view"), "camera");
  EXPECT_EQ(fixed.at("camera").at("eye"), nlohmann::json::array({-3.0, -2.0, 1.5}));
  EXPECT_TRUE(fixed.at("see_through_obstacles").empty());
  EXPECT_GT(fixed.at("camera").at("robot_hidden_fraction").get<double>(), 0.5) << "the wall stands between";
  const auto behind = with({"--camera", "3,2,1.5,0,0,0.4"});
  EXPECT_LE(behind.at("camera").at("robot_hidden_fraction").get<double>(), render::kAcceptableHiddenFraction);
  std::filesystem::remove(scene);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace flexirob::cli
