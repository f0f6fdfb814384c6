#pragma once
// Shared plumbing of flexirob-cli's commands: how a command hands its JSON result back, and
// strict parsing of the numeric lists users type on the command line.
#include <CLI/CLI.hpp>
#include <sqlite3.h>
#include <Eigen/Core>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <istream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "app/cli/number_list.hpp"
#include "app/file_output.hpp"
#include "app/session_schema.hpp"
#include "planning/itm.hpp"
#include "robot/errors.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {
struct TrajectoryRegionResult;
}

namespace flexirob::cli {

using Json = nlohmann::ordered_json;

/// A command that ran but did not achieve what it is for (e.g. teach taught no area): its JSON
/// result still goes to stdout (what happened, where the data went), the message to stderr as
/// one line, and the exit code is 1 (128 + the signal for a run a signal stopped).
class CommandFailed : public std::runtime_error {
 public:
  CommandFailed(const std::string& message, Json result, int exit_code = 1)
      : std::runtime_error(message), result_(std::move(result)), exit_code_(exit_code) {}
  const Json& result() const { return result_; }
  int exitCode() const { return exit_code_; }

 private:
  Json result_;
  int exit_code_;
};

/// What a parsed command will do; it returns the JSON object printed on stdout.
using Action = std::function<Json()>;

/// Collects the action of whichever subcommand the user chose.
class CommandRunner {
 public:
  void select(Action action) { action_ = std::move(action); }
  bool hasAction() const { return static_cast<bool>(action_); }
  Json run() const { return action_(); }

 private:
  Action action_;
};

/// Registers subcommands on `app`. Each group lives in its own file.
void registerRobotCommands(CLI::App& app, CommandRunner& runner);   // robot info, fk
void registerRenderCommand(CLI::App& app, CommandRunner& runner);   // render
void registerLearnCommands(CLI::App& app, CommandRunner& runner);   // learn fit|predict
void registerItmCommands(CLI::App& app, CommandRunner& runner);     // itm build|path
void registerBenchCommand(CLI::App& app, CommandRunner& runner);    // bench
void registerReachCommand(CLI::App& app, CommandRunner& runner);    // reach
void registerFriCommands(CLI::App& app, CommandRunner& runner);     // fri probe|simulate
void registerReviewCommands(CLI::App& app, CommandRunner& runner);  // review
void registerTeachCommands(CLI::App& app, CommandRunner& runner);   // teach
void registerEvalCommands(CLI::App& app, CommandRunner& runner);    // eval reachable, plan
void registerSweepCommand(CLI::App& app, CommandRunner& runner);    // sweep
void registerExportCommand(CLI::App& app, CommandRunner& runner);   // export

/// CLI::Range lets "nan" through (every comparison with NaN is false), and an option left at
/// its default then meant "the scene's value": the range of every numeric option also refuses
/// numbers that are not finite.
template <typename T>
CLI::Validator finiteRange(T min, T max) {
  const CLI::Validator finite(
      [](std::string& input) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(input.c_str(), &end);
        if (end != input.c_str() && !std::isfinite(value)) return "expected a finite number, got " + input.substr(0, 64);
        return {};
      },
      "");
  return CLI::Range(min, max) & finite;
}

/// Seeds are unsigned 64-bit integers written in decimal; "-1" or a number beyond 2^64 - 1 is
/// refused (the C library would wrap or saturate it to a seed the user never gave).
CLI::Validator seedValidator();

/// A whole number from JSON, e.g. a node index: 0.7 or "1" is an error, not 0 or 1.
int jsonInteger(const Json& value, const std::string& what);

/// Whether a file is JSON text (its first non-blank character opens an object or an array),
/// as opposed to a recording in SQLite; leaves the stream at that character.
bool startsAsJson(std::istream& in);

/// Runs `read` on the recorded session `file`: an SQLite error while reading (a corrupt page,
/// a row of the wrong size: "is damaged") becomes a one-line InputError naming the file.
template <class Read>
auto readingSession(const std::string& file, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const app::SqliteError& error) {
    // A corrupt page or row is damage; a busy or unreadable file is not.
    const bool damaged = error.code() == SQLITE_CORRUPT || error.code() == SQLITE_NOTADB;
    throw InputError("session file " + file + (damaged ? " is damaged: " : ": ") + error.what());
  }
}

/// Runs the CLI on argv; prints the JSON result on stdout or a one-line error on stderr.
/// Returns the process exit code (0 success, 1 the command ran but failed, 2 bad input).
int runCli(int argc, const char* const* argv);

/// One region of `eval trajectories` (Tab. 3.2) as `eval trajectories` and `sweep` print it.
Json trajectoryRegionJson(const app::TrajectoryRegionResult& region);

Json toJson(const Eigen::VectorXd& v);
Json toJsonRows(const Eigen::MatrixXd& m);
/// The parameters of an ITM graph by the names itm build prints (its options: --emax, --delta,
/// --dthetamax, --dcmax, --eta, --alpha).
Json itmParametersJson(const planning::ItmParameters& parameters);

using app::sameFileKey;

/// Refuses (InputError naming `option`) an output path that is a directory, that is one of the
/// run's `inputs` ({option, path}: writing would destroy what is being read), that is where
/// standard output or error goes (app::refuseStandardStreams), or whose folder does not exist or
/// cannot be written, before any work is done. A block device or a socket is refused, a pipe or a
/// character device is written in place (app::writeFileReplacing) and must be writable. A
/// recorded session in the output's place is refused: a table or a picture written over it
/// would lose the recording. With `output_is_a_session` (teach's --out: SQLite keeps it open)
/// anything but a regular file is refused, and whether a session may be replaced is the
/// caller's to decide (teach --overwrite).
void checkOutputPath(const std::string& option, const std::string& path,
                     const std::vector<std::pair<std::string, std::string>>& inputs = {}, bool output_is_a_session = false);

/// robot::loadScene, and its sceneNotes on stderr ("note: ..."), once per scene and process.
robot::Scene loadSceneNoting(const std::string& name_or_path);
/// robot::RobotModel::fromUrdfFile of a built-in name or a file (resolveRobotPath), and its
/// notes on stderr ("note: ..."), once per robot and tip and process.
/// --tip's help, as robot::RobotModel chooses the tip when none is named.
inline constexpr const char* kTipHelp =
    "tip link (default: the last link of the longest chain, or the link equally long fingers of a gripper branch from)";

robot::RobotModel loadRobotNoting(const std::string& name_or_path, const std::string& tip = "");

/// The robot and the scene a session was taught with, parsed from the copies the session stores
/// (`stored_urdf`, `stored_scene_text`) so that editing or moving their files after teaching does
/// not change what is evaluated or drawn. Relative mesh paths resolve against the original file's
/// folder (the resources folder for built-in names). Without a stored copy (older sessions) the
/// file is read as before; a file that now differs from the stored copy is said in a "note:" line.
/// `named` is a file given on the command line (--robot, --scene) for a session whose files moved
/// since teaching, so that the stored copy's paths name files that are gone: it is read in place
/// of the stored copy, with a note where the two differ (a scene other than in where the files it
/// names lie; a URDF in any way).
robot::RobotModel loadSessionRobot(const std::string& reference, const std::string& stored_urdf, const std::string& tip,
                                   const std::string& named = "");
robot::Scene loadSessionScene(const std::string& reference, const std::string& stored_scene_text, const std::string& named = "");

/// The file a robot argument reads: a built-in's URDF among the resources, else the argument.
std::string robotFileOf(const std::string& robot_argument);
/// The file a scene argument reads: a built-in's among the resources, else the argument; empty
/// for the empty scene.
std::string sceneFileOf(const std::string& scene_argument);

/// Refuses (InputError naming the option) an output ({option, path}) that is a mesh `model` or
/// `scene` reads: the output would replace a cell's geometry.
void refuseOutputsOverMeshes(const std::vector<std::pair<std::string, std::string>>& outputs, const robot::RobotModel& model,
                             const robot::Scene& scene);

/// A note on stderr for each mesh `model` or `scene` reads that differs from the one the session
/// was taught with (`recorded`: SessionMetadata::mesh_digests; empty in older sessions, which
/// are not checked): the URDF and the scene the session stores name meshes, not their shapes.
void noteMeshesChangedSinceTeaching(const std::string& recorded, const robot::RobotModel& model, const robot::Scene& scene);

/// Adds --robot and --scene to a command reading a session, in the sense of loadSessionRobot's
/// and loadSessionScene's `named`.
void addMovedFilesOptions(CLI::App& command, std::string& robot_file, std::string& scene_file);

/// The --approach option of eval reachable, eval scene-model and sweep (app::ApproachFrom),
/// default "visited".
CLI::Option* addApproachOption(CLI::App& command, std::string& approach);

/// Whether progress is shown: stderr is a terminal, or FLEXIROB_PROGRESS is set.
bool progressShown();

/// Progress on stderr for long work ("what: 42%"); silent unless progressShown().
void reportProgress(const std::string& what, double fraction);

/// The same for work whose end is not known in advance (a fit that stops when it no longer
/// improves): `status` replaces the line shown before; `done` ends the line.
void reportStatus(const std::string& status, bool done = false);
/// Ends a progress line that reportProgress or reportStatus left open, so that an error or a
/// note said next starts a line of its own.
void endProgressLine();

}  // namespace flexirob::cli
