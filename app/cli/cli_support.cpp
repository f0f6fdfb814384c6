#include "app/cli/cli_support.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <limits>
#include <optional>
#include <set>

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <iostream>

#include "app/file_output.hpp"
#include "app/mesh_digest.hpp"
#include "app/session_schema.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"

namespace flexirob::cli {

CLI::Validator seedValidator() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        const bool digits = !input.empty() && input.size() <= 20 &&
                            std::all_of(input.begin(), input.end(), [](char c) { return c >= '0' && c <= '9'; });
        // 20 digits may still exceed 2^64 - 1 = 18446744073709551615; a leading zero would make
        // the number octal to CLI11 (010 is seed 8).
        const bool plain = digits && (input[0] != '0' || input.size() == 1);
        if (plain && (input.size() < 20 || input <= "18446744073709551615")) return {};
        return "a seed is a whole number from 0 to 18446744073709551615 without leading zeros, got " + input.substr(0, 64);
      },
      "");
}

int jsonInteger(const Json& value, const std::string& what) {
  if (value.is_number_unsigned() && value.get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
    return value.get<int>();
  }
  if (value.is_number_integer() && !value.is_number_unsigned()) {
    const auto number = value.get<std::int64_t>();
    if (number >= std::numeric_limits<int>::min() && number <= std::numeric_limits<int>::max()) return static_cast<int>(number);
  }
  throw InputError(what + ": expected a whole number, got " + value.dump().substr(0, 64));
}

bool startsAsJson(std::istream& in) {
  // Skipping the blanks needs no seek, so a pipe works too; JSON does not mind them gone.
  // A JSON value of another kind (null, a number) is still JSON, and told so by the JSON reader,
  // rather than called "not an SQLite database".
  const auto next = (in >> std::ws).peek();
  return next == '{' || next == '[' || next == 'n' || next == '"' || next == '-' || (next >= '0' && next <= '9');
}

Json toJson(const Eigen::VectorXd& v) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::isfinite(v[i])) {
      array.push_back(v[i]);
    } else {
      array.push_back(nullptr);
    }
  }
  return array;
}

Json itmParametersJson(const planning::ItmParameters& parameters) {
  return {{"e_max", parameters.e_max},           {"delta", parameters.delta}, {"d_theta_max", parameters.d_theta_max},
          {"d_c_max", parameters.d_c_max},       {"eta", parameters.eta},     {"alpha", parameters.alpha}};
}

Json toJsonRows(const Eigen::MatrixXd& m) {
  Json rows = Json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) rows.push_back(toJson(m.row(r).transpose()));
  return rows;
}

void checkOutputPath(const std::string& option, const std::string& path,
                     const std::vector<std::pair<std::string, std::string>>& inputs, bool output_is_a_session) {
  namespace fs = std::filesystem;
  if (path.empty()) throw InputError(option + ": expected a file path");
  std::error_code error;
  if (fs::is_directory(path, error)) throw InputError(option + ": '" + path + "' is a directory; expected a file path");
  const bool in_place = app::writtenInPlace(path);
  if (fs::exists(path, error) && !fs::is_regular_file(path, error) && (output_is_a_session || !in_place)) {
    throw InputError(option + ": '" + path + "' is not a regular file (" +
                     (output_is_a_session ? "a device, a pipe or a socket" : "a device other than a terminal or /dev/null, or a socket") +
                     "); expected a file path");
  }
  app::refuseStandardStreams(option, path);
  for (const auto& [input_option, input] : inputs) {
    if (app::isExistingFile(path, input)) {
      throw InputError(option + ": '" + path + "' is the " + input_option + " file the run reads; give another file");
    }
  }
  if (!output_is_a_session && app::isSessionDatabase(path)) {
    throw InputError(option + ": '" + path + "' is a recorded session, which this output would replace; give another file");
  }
  if (in_place) {
    // Written as it is: /dev/null or a terminal lies in a folder only root may write in.
    if (::access(path.c_str(), W_OK) != 0) throw InputError(option + ": cannot write '" + path + "': " + std::strerror(errno));
    return;
  }
  // The folder of the file written: through a symbolic link, the folder of the file it names.
  const fs::path written = app::followLinks(path);
  const fs::path folder = written.parent_path().empty() ? fs::path(".") : written.parent_path();
  if (!fs::is_directory(folder, error)) {
    throw InputError(option + (fs::exists(folder, error) ? ": '" + folder.string() + "' is a file, not a folder"
                                                          : ": the folder '" + folder.string() + "' does not exist"));
  }
  if (::access(folder.c_str(), W_OK) != 0) {
    throw InputError(option + ": cannot write in '" + folder.string() + "': " + std::strerror(errno));
  }
}

robot::Scene loadSceneNoting(const std::string& name_or_path) {
  robot::Scene scene = robot::loadScene(name_or_path);
  static std::set<std::string> noted;
  if (noted.insert(name_or_path).second) {
    for (const std::string& note : robot::sceneNotes(scene)) std::fprintf(stderr, "note: %s\n", note.c_str());
  }
  return scene;
}

namespace {

// A robot's notes on stderr, once per robot and tip and process (eval and plan read a session's
// robot more than once).
robot::RobotModel noted(robot::RobotModel model, const std::string& name_or_path, const std::string& tip) {
  static std::set<std::string> said;
  if (said.insert(name_or_path + '\n' + tip).second) {
    for (const std::string& note : model.notes()) std::fprintf(stderr, "note: %s\n", printable(note, 400).c_str());
  }
  return model;
}

}  // namespace

robot::RobotModel loadRobotNoting(const std::string& name_or_path, const std::string& tip) {
  return noted(robot::RobotModel::fromUrdfFile(resolveRobotPath(name_or_path), tip), name_or_path, tip);
}

namespace {

// The whole file, or nullopt when it cannot be read (moved or deleted since teaching).
std::optional<std::string> fileText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

robot::RobotModel loadSessionRobot(const std::string& reference, const std::string& stored_urdf, const std::string& tip,
                                   const std::string& named) {
  if (!named.empty()) {
    robot::RobotModel model = loadRobotNoting(named, tip);
    if (!stored_urdf.empty() && fileText(resolveRobotPath(named)) != stored_urdf) {
      std::fprintf(stderr, "note: the robot '%s' differs from the copy the session stores; it is used as --robot asks\n", named.c_str());
    }
    return model;
  }
  if (stored_urdf.empty()) return loadRobotNoting(reference, tip);
  // A session stores a file robot by its absolute path (portableReference), so its folder is known
  // even after the file has gone.
  const std::filesystem::path file = robotFileOf(reference);
  const std::optional<std::string> on_disk = fileText(file);
  try {
    robot::RobotModel stored = robot::RobotModel::fromUrdfString(stored_urdf, file.parent_path(), tip);
    if (on_disk != stored_urdf) {
      std::fprintf(stderr, "note: the robot '%s' differs from the copy the session stores (changed or missing since, or the stored copy edited); the stored copy is used\n",
                   reference.c_str());
    }
    return noted(std::move(stored), reference, tip);
  } catch (const InputError& damaged) {
    // A damaged session file: the robot's own file, where it still reads, is the next best.
    if (!on_disk) {
      throw InputError(std::string("robot stored in the session: ") + damaged.what() + ", and '" + reference +
                       "' cannot be read (if the robot's files moved since teaching, --robot names its URDF where it lies now)");
    }
    std::fprintf(stderr, "note: the robot stored in the session does not read (%s); '%s' is used instead\n", damaged.what(),
                 reference.c_str());
    return noted(robot::RobotModel::fromUrdfString(*on_disk, file.parent_path(), tip), reference, tip);
  }
}

namespace {

// A scene as sceneToYaml writes it, with each file it names (a mesh, a robot's URDF) reduced to
// the file's name: the same scene moved to another folder reads the same.
std::string withFilesNamedOnly(const std::string& scene_yaml) {
  std::istringstream lines(scene_yaml);
  std::string result;
  for (std::string line; std::getline(lines, line);) {
    for (const std::string key : {"file: ", "robot: "}) {
      const std::size_t at = line.find(key);
      if (at == std::string::npos || line.find_first_not_of(" -") != at) continue;
      std::string value = line.substr(at + key.size());
      if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') && value.back() == value.front()) {
        value = value.substr(1, value.size() - 2);
      }
      line = line.substr(0, at + key.size()) + std::filesystem::path(value).filename().string();
    }
    result += line + "\n";
  }
  return result;
}

}  // namespace

robot::Scene loadSessionScene(const std::string& reference, const std::string& stored_scene_text, const std::string& named) {
  if (!named.empty()) {
    robot::Scene scene = loadSceneNoting(named);
    if (!stored_scene_text.empty() && withFilesNamedOnly(robot::sceneToYaml(scene)) != withFilesNamedOnly(stored_scene_text)) {
      std::fprintf(stderr, "note: the scene '%s' differs from the copy the session stores; it is used as --scene asks\n", named.c_str());
    }
    return scene;
  }
  if (stored_scene_text.empty()) return loadSceneNoting(reference);
  const std::filesystem::path file = sceneFileOf(reference);
  // The session stores the scene as sceneToYaml wrote it, so the file is compared in that form.
  std::optional<std::string> on_disk;
  std::string on_disk_error;
  try {
    on_disk = robot::sceneToYaml(robot::loadScene(reference));
  } catch (const InputError& error) {
    // Moved, deleted or no longer valid: the stored copy is all there is.
    on_disk_error = error.what();
  }
  const std::filesystem::path base_dir = file.empty() ? std::filesystem::current_path() : file.parent_path();
  robot::Scene scene;
  try {
    scene = robot::parseScene(stored_scene_text, base_dir, "scene stored in the session", robot::SceneText::kSessionCopy);
  } catch (const InputError& damaged) {
    // A damaged session file: the scene file, where it still reads, is the next best.
    // Both reasons: the same missing mesh fails both, and the file named alone would be blamed.
    if (!on_disk) {
      throw InputError(std::string(damaged.what()) + "; the scene file does not read either: " + on_disk_error +
                       " (if the scene's files moved since teaching, --scene names the scene file where it lies now)");
    }
    std::fprintf(stderr, "note: the scene stored in the session does not read (%s); '%s' is used instead\n", damaged.what(),
                 reference.c_str());
    return loadSceneNoting(reference);
  }
  if (on_disk != stored_scene_text) {
    std::fprintf(stderr, "note: the scene '%s' differs from the copy the session stores (changed or missing since, or the stored copy edited); the stored copy is used\n",
                 reference.c_str());
  }
  for (const std::string& note : robot::sceneNotes(scene)) std::fprintf(stderr, "note: %s\n", note.c_str());
  return scene;
}

std::string robotFileOf(const std::string& robot_argument) {
  const auto& builtins = builtinRobotNames();
  const bool builtin = std::find(builtins.begin(), builtins.end(), robot_argument) != builtins.end();
  return builtin ? resolveRobotPath(robot_argument).string() : robot_argument;
}

std::string sceneFileOf(const std::string& scene_argument) {
  if (scene_argument.empty() || scene_argument == "empty") return {};
  const auto& builtins = robot::builtinSceneNames();
  const bool builtin = std::find(builtins.begin(), builtins.end(), scene_argument) != builtins.end();
  return builtin ? (resourceDir() / "scenes" / (scene_argument + ".yaml")).string() : scene_argument;
}

void refuseOutputsOverMeshes(const std::vector<std::pair<std::string, std::string>>& outputs, const robot::RobotModel& model,
                             const robot::Scene& scene) {
  const auto meshes = app::meshFiles(model, scene);
  for (const auto& [option, path] : outputs) {
    if (path.empty()) continue;
    for (const auto& [part, mesh] : meshes) {
      if (app::isExistingFile(path, mesh)) {
        throw InputError(option + ": '" + path + "' is the mesh of " + printable(part, 200) + ", which the run reads; give another file");
      }
    }
  }
}

void noteMeshesChangedSinceTeaching(const std::string& recorded, const robot::RobotModel& model, const robot::Scene& scene) {
  static std::set<std::string> said;  // eval and plan load a session's robot and scene more than once
  for (const std::string& part : app::meshesChanged(app::parseMeshDigests(recorded), model, scene)) {
    if (!said.insert(part).second) continue;
    std::fprintf(stderr, "note: the mesh of %s differs from the one the session was taught with (changed since); it is used as it is now\n",
                 printable(part, 400).c_str());
  }
}

bool progressShown() {
  static const bool enabled = isatty(STDERR_FILENO) != 0 || std::getenv("FLEXIROB_PROGRESS") != nullptr;
  return enabled;
}

namespace {
// A progress line not ended yet: a line said after it starts on a line of its own.
bool g_progress_line_open = false;
}  // namespace

void addMovedFilesOptions(CLI::App& command, std::string& robot_file, std::string& scene_file) {
  command.add_option("--robot", robot_file,
                     "the URDF the session was taught with, read in place of the copy the session stores (when the robot's files moved since teaching)");
  command.add_option("--scene", scene_file,
                     "the scene file the session was taught in, read in place of the copy the session stores (when the scene's files moved since teaching)");
}

void endProgressLine() {
  if (!g_progress_line_open) return;
  std::fputc('\n', stderr);
  g_progress_line_open = false;
}

void reportProgress(const std::string& what, double fraction) {
  if (!progressShown()) return;
  const int percent = static_cast<int>(std::lround(std::clamp(fraction, 0.0, 1.0) * 100.0));
  std::fprintf(stderr, "\r%s: %3d%%%s", what.c_str(), percent, percent >= 100 ? "\n" : "");
  g_progress_line_open = percent < 100;
  std::fflush(stderr);
}

void reportStatus(const std::string& status, bool done) {
  if (!progressShown()) return;
  // Spaces over what a longer line before left on the right (no terminal codes: the line may
  // go to a log).
  static std::size_t shown_length = 0;
  const std::string padding(shown_length > status.size() ? shown_length - status.size() : 0, ' ');
  std::fprintf(stderr, "\r%s%s%s", status.c_str(), padding.c_str(), done ? "\n" : "");
  shown_length = done ? 0 : status.size();
  g_progress_line_open = !done;
  std::fflush(stderr);
}

namespace {

// " (did you mean --areas?)" where an argument left over names an option of the command given
// with a slip of a letter or two (`teach --area 2`); CLI11 names only what it did not expect.
// The innermost command the arguments named (`app` itself when they named none).
const CLI::App* commandGiven(const CLI::App& app) {
  const CLI::App* command = &app;
  for (std::vector<const CLI::App*> parsed = command->get_subcommands({}); !parsed.empty();) {
    const auto given = std::find_if(parsed.begin(), parsed.end(), [](const CLI::App* sub) { return sub->parsed(); });
    if (given == parsed.end()) break;
    command = *given;
    parsed = command->get_subcommands({});
  }
  return command;
}

// In place of CLI11's "A subcommand is required": the word given where a command was expected
// (a slip of a letter or two named), or that none was, and the commands there are.
std::string commandMissing(const CLI::App& app) {
  const CLI::App* command = commandGiven(app);
  std::vector<std::string> names;
  std::string listed;
  for (const CLI::App* sub : command->get_subcommands({})) {
    names.push_back(sub->get_name());
    listed += (listed.empty() ? "" : ", ") + sub->get_name();
  }
  const std::string where = command == &app ? "" : command->get_name() + ": ";
  // The word where the command was expected, right after the command given: a later one is an
  // option's value (`eval --session s.flexirob`, the command left out).
  const std::vector<std::string> rest = app.remaining(true);
  const std::string word = !rest.empty() && !rest.front().empty() && rest.front().front() != '-' ? rest.front() : std::string();
  if (word.empty()) return where + "a command is needed (" + listed + ")";
  const std::string guess = closestName(word, names, std::max<std::size_t>(1, word.size() / 3));
  return where + "unknown command '" + printable(word) + "'" + (guess.empty() ? "" : " (did you mean " + guess + "?)") +
         "; the commands are " + listed;
}

std::string optionMeant(const CLI::App& app) {
  const CLI::App* command = commandGiven(app);
  std::vector<std::string> names;
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back(name);
  }
  std::string meant;
  for (const std::string& extra : app.remaining(true)) {
    if (extra.rfind("--", 0) != 0) continue;
    const std::string typed = extra.substr(2, extra.find('=') == std::string::npos ? std::string::npos : extra.find('=') - 2);
    const std::string guess = closestName(typed, names, std::max<std::size_t>(1, typed.size() / 3));
    if (!guess.empty()) meant += (meant.empty() ? " (" : "; ") + printable("--" + typed) + ": did you mean --" + guess + "?";
  }
  return meant.empty() ? "" : meant + ")";
}

}  // namespace

int runCli(int argc, const char* const* argv) {
  CLI::App app{"FlexIRob headless tools: every command prints one JSON object on stdout", "flexirob-cli"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(FLEXIROB_VERSION_STRING));
  CommandRunner runner;
  registerRobotCommands(app, runner);
  registerRenderCommand(app, runner);
  registerLearnCommands(app, runner);
  registerItmCommands(app, runner);
  registerBenchCommand(app, runner);
  registerReachCommand(app, runner);
  registerFriCommands(app, runner);
  registerReviewCommands(app, runner);
  registerTeachCommands(app, runner);
  registerEvalCommands(app, runner);
  registerSweepCommand(app, runner);
  registerExportCommand(app, runner);
  try {
    app.parse(argc, argv);
    if (!runner.hasAction()) throw InputError("no command given; see --help");
    const Json result = runner.run();
    std::cout << result.dump(2) << std::endl;
    if (!std::cout) {
      // A full disk or a closed descriptor: the command's result is lost, which is no success.
      std::cerr << "error: cannot write the result to standard output" << std::endl;
      return 1;
    }
    return 0;
  } catch (const CommandFailed& e) {
    std::cout << e.result().dump(2) << std::endl;
    endProgressLine();
    std::cerr << "error: " << e.what() << std::endl;
    return e.exitCode();
  } catch (const CLI::Success& e) {
    // --help and --version: CLI11 prints them itself.
    return app.exit(e);
  } catch (const CLI::RequiredError& e) {
    const bool command_missing = std::string(e.what()).find("subcommand") != std::string::npos;
    std::cerr << "error: " << (command_missing ? commandMissing(app) : e.what() + optionMeant(app)) << std::endl;
    return 2;
  } catch (const CLI::ParseError& e) {
    std::cerr << "error: " << e.what() << optionMeant(app) << std::endl;
    return 2;
  } catch (const std::bad_alloc&) {
    endProgressLine();
    std::cerr << "error: out of memory (the input is too large)" << std::endl;
    return 2;
  } catch (const std::exception& e) {
    endProgressLine();
    std::string message = e.what();
    for (char& c : message) {
      if (c == '\n' || c == '\r') c = ' ';
    }
    std::cerr << "error: " << message << std::endl;
    return 2;
  }
}

CLI::Option* addApproachOption(CLI::App& command, std::string& approach) {
  return command
      .add_option("--approach", approach,
                  "where the arm starts for each target: the posture it stood in with its tip nearest the target, "
                  "at a target reached or a sample of the demonstration (visited, the default); the same without "
                  "the demonstration (nearest); the previous target's end (previous); the home posture (start); "
                  "the learned posture at the target (learned)")
      ->check(CLI::IsMember({"visited", "nearest", "previous", "start", "learned"}));
}

}  // namespace flexirob::cli
