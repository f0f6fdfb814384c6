// `itm build` and `itm path`: learn an instantaneous topological map (hybrid ITM, thesis
// Chap. 7) from a recorded stream and plan paths through it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "app/cli/cli_support.hpp"
#include "app/file_output.hpp"
#include "app/table_text.hpp"
#include "planning/itm.hpp"
#include "planning/itm_file.hpp"
#include "planning/path_planner.hpp"
#include "robot/errors.hpp"

namespace flexirob::cli {
namespace {

using planning::Itm;
using planning::ItmParameters;
using planning::TaskSpace;
using Clock = std::chrono::steady_clock;


/// Reads an ITM stream (header x,y,z[,qw,qx,qy,qz],q1..qN; one sample per row, in time order)
/// and hands each row to `consume` as it is read, so that learning is online.
class StreamReader {
 public:
  explicit StreamReader(const std::string& path) : path_(path), file_(path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error) || !file_) throw InputError("cannot read stream file '" + path + "'");
    bytes_ = std::filesystem::file_size(path, error);
    std::string header;
    if (!std::getline(file_, header)) throw InputError(path + ": empty file (expected a header x,y,z,q1,...)");
    ++line_number_;
    app::prepareFirstLine(header, path);
    std::vector<std::string> names = app::splitCommaFields(header);
    for (auto& name : names) name = app::lowercase(name);
    if (names.size() < 4 || names[0] != "x" || names[1] != "y" || names[2] != "z") {
      throw InputError(path + " line 1: expected a header starting with x,y,z and then joint columns, got '" + printable(app::trimmed(header)) + "'");
    }
    std::size_t joints_from = 3;
    if (names.size() >= 7 && names[3] == "qw" && names[4] == "qx" && names[5] == "qy" && names[6] == "qz") {
      space_ = TaskSpace::kPose;
      joints_from = 7;
    }
    columns_ = static_cast<int>(names.size());
    joints_ = columns_ - static_cast<int>(joints_from);
    if (joints_ < 1) throw InputError(path + " line 1: no joint columns after the task-space columns");
    if (joints_ > 64) throw InputError(path + " line 1: more than 64 joint columns");
  }

  TaskSpace space() const { return space_; }
  int joints() const { return joints_; }
  std::uintmax_t bytes() const { return bytes_; }

  /// Next sample, false at the end of the file. Throws InputError naming the line.
  bool next(Eigen::VectorXd& xi, Eigen::VectorXd& q) {
    std::string line;
    while (std::getline(file_, line)) {
      ++line_number_;
      consumed_ += line.size() + 1;
      if (app::trimmed(line).empty()) continue;
      xi.resize(planning::storedSize(space_));
      q.resize(joints_);
      // Fields read in place (a stream holds hundreds of thousands of lines); the messages are
      // built only for a line that fails.
      const auto column_text = [](int column, std::string_view field) {
        return "column " + std::to_string(column + 1) + " ('" + printable(std::string(field)) + "')";
      };
      const std::string_view text(line);
      std::size_t start = 0;
      for (int column = 0; column < columns_; ++column) {
        const std::size_t comma = text.find(',', start);
        if (comma == std::string_view::npos && column + 1 < columns_) {
          fail("expected " + std::to_string(columns_) + " values, got " + std::to_string(column + 1));
        }
        if (comma != std::string_view::npos && column + 1 == columns_) fail("expected " + std::to_string(columns_) + " values, got more");
        const std::string_view field = app::trimmedView(text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
        start = comma + 1;
        const std::optional<double> parsed = app::parseDecimal(field);
        if (!parsed) fail(column_text(column, field) + " is not a finite number");
        const double value = *parsed;
        if (std::abs(value) > app::kLargestTableValue) fail(column_text(column, field) + " is beyond ±1e6");
        if (column < xi.size()) {
          xi[column] = value;
        } else {
          q[column - xi.size()] = value;
        }
      }
      if (space_ == TaskSpace::kPose && !(xi.tail<4>().norm() > 1e-9)) fail("quaternion of zero length");
      if (xi.head<3>().cwiseAbs().maxCoeff() > 1e5) fail("position beyond 100 km");
      return true;
    }
    return false;
  }

  double fraction() const { return bytes_ > 0 ? static_cast<double>(consumed_) / static_cast<double>(bytes_) : 1.0; }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_ + " line " + std::to_string(line_number_) + ": " + what);
  }

 private:
  std::string path_;
  std::ifstream file_;
  std::uintmax_t bytes_ = 0;
  std::uintmax_t consumed_ = 0;
  long line_number_ = 0;
  int columns_ = 0;
  int joints_ = 0;
  TaskSpace space_ = TaskSpace::kPosition;
};

Json numberOrNull(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

struct BuildOptions {
  std::string data;
  std::string out;
  std::string variant = "hybrid";
  ItmParameters parameters;
};

Json buildMap(const BuildOptions& options) {
  checkOutputPath("--out", options.out, {{"--data", options.data}});
  ItmParameters parameters = options.parameters;
  if (options.variant == "plain") {
    parameters.variant = planning::ItmVariant::kPlain;
  } else if (options.variant != "hybrid") {
    throw InputError("--variant: expected plain or hybrid, got '" + options.variant + "'");
  }
  StreamReader reader(options.data);
  parameters.task_space = reader.space();
  try {
    parameters.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  Itm itm(parameters, reader.joints());

  // Online: each sample is learned as soon as it is read; only insert() is timed.
  Eigen::VectorXd xi, q;
  std::int64_t samples = 0;
  double insert_seconds = 0.0, max_insert_seconds = 0.0;
  const auto started = Clock::now();
  while (reader.next(xi, q)) {
    const auto before = Clock::now();
    itm.insert(xi, q);
    const double seconds = std::chrono::duration<double>(Clock::now() - before).count();
    insert_seconds += seconds;
    max_insert_seconds = std::max(max_insert_seconds, seconds);
    if (++samples % 20000 == 0) reportProgress("itm build", reader.fraction());
  }
  if (samples == 0) throw InputError(options.data + ": no samples after the header");
  if (samples >= 20000) reportProgress("itm build", 1.0);
  const std::vector<std::uint8_t> bytes = planning::itmToBytes(itm);
  app::writeFileReplacing(options.out, std::string(bytes.begin(), bytes.end()), "--out");
  const double total_seconds = std::chrono::duration<double>(Clock::now() - started).count();

  const auto stats = itm.statistics();
  return {{"samples", samples},
          {"nodes", stats.nodes},
          {"edges", stats.edges},
          {"max_valence", stats.max_valence},
          {"mean_valence", stats.mean_valence},
          {"mean_insert_us", 1e6 * insert_seconds / static_cast<double>(samples)},
          {"max_insert_us", 1e6 * max_insert_seconds},
          {"bootstrapped_nodes", stats.bootstrapped_nodes},
          {"bootstrap_error_max_m", numberOrNull(stats.bootstrap_error_max)},
          {"bootstrap_error_mean_m", numberOrNull(stats.bootstrap_error_mean)},
          {"bootstrap_samples", stats.bootstrap_samples},
          {"components", stats.components},
          {"variant", options.variant},
          {"task_space", reader.space() == TaskSpace::kPose ? "pose" : "position"},
          {"joints", reader.joints()},
          {"parameters", itmParametersJson(parameters)},
          {"out", options.out},
          {"seconds", total_seconds}};
}

struct PathCommandOptions {
  std::string graph;
  std::string from;
  std::string to;
  planning::PathOptions path;
  double sample_period = 0.0;
  double max_gap = -1.0;  ///< [m]; negative: the graph's e_max
};

Json planOnMap(const PathCommandOptions& options) {
  const Itm itm = planning::loadItm(options.graph);
  const std::size_t max_values = static_cast<std::size_t>(itm.taskSize());
  const auto parsePoint = [&](const std::string& text, const std::string& what) {
    Eigen::VectorXd point = parseNumberList(text, what, max_values);
    if (point.size() != 3 && point.size() != itm.taskSize()) {
      throw InputError(what + ": expected x,y,z" + std::string(itm.taskSize() == 7 ? " or x,y,z,qw,qx,qy,qz" : "") + ", got " +
                       std::to_string(point.size()) + " values");
    }
    if (point.size() == 7 && !(point.tail<4>().norm() > 1e-9)) throw InputError(what + ": quaternion of zero length");
    return point;
  };
  const Eigen::VectorXd from = parsePoint(options.from, "--from");
  const Eigen::VectorXd to = parsePoint(options.to, "--to");
  try {
    options.path.limits.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }

  const auto started = Clock::now();
  planning::PlannedPath path = planning::planPath(itm, from, to, options.path);
  const double plan_ms = 1e3 * std::chrono::duration<double>(Clock::now() - started).count();

  // A node stands for the explored positions within e_max of it (the ITM's insertion threshold,
  // Sect. 7.3.1); a start or goal farther from every node lies in space the tutor never showed,
  // and the straight leg to it would cross unexplored space: no path, as the workflow's planner
  // refuses such a goal.
  const double max_gap = options.max_gap >= 0.0 ? options.max_gap : itm.parameters().e_max;
  std::string reason;
  if (itm.nodeCount() == 0) {
    reason = "the graph has no nodes";
  } else if (path.start_gap > max_gap || path.goal_gap > max_gap) {
    const bool start = path.start_gap > max_gap;
    std::ostringstream text;
    text << (start ? "the start is " : "the goal is ") << (start ? path.start_gap : path.goal_gap)
         << " m from the nearest explored position (at most " << max_gap << " m, --max-gap)";
    reason = text.str();
    path.found = false;
    path.nodes.clear();
    path.trajectory.reset();
  } else if (!path.found) {
    reason = "start and goal lie in different components of the graph";
  }

  Json result{{"found", path.found}};
  if (!reason.empty()) result["reason"] = reason;
  result["waypoints"] = path.found ? toJsonRows(path.waypoints.transpose()) : Json::array();
  result["length_m"] = path.found ? Json(path.length) : Json(nullptr);
  result["graph_nodes"] = itm.nodeCount();
  result["start_node"] = path.start_node;
  result["goal_node"] = path.goal_node;
  result["start_gap_m"] = path.start_node >= 0 ? Json(path.start_gap) : Json(nullptr);
  result["goal_gap_m"] = path.goal_node >= 0 ? Json(path.goal_gap) : Json(nullptr);
  result["nodes"] = path.nodes;
  result["node_joint_configurations"] = path.found ? toJsonRows(path.node_joints.transpose()) : Json::array();
  result["max_joint_step_rad"] = path.found ? Json(path.max_joint_step) : Json(nullptr);
  if (itm.taskSize() == 7 && path.found) result["orientations"] = toJsonRows(path.orientations.transpose());
  result["expanded"] = path.expanded;
  result["plan_ms"] = plan_ms;
  if (path.trajectory) {
    const auto& trajectory = *path.trajectory;
    result["duration_s"] = trajectory.duration();
    result["knot_times_s"] = trajectory.knotTimes();
    result["max_speed"] = trajectory.maxSpeed();
    result["max_acceleration"] = trajectory.maxAcceleration();
    result["limits"] = {{"max_speed", options.path.limits.max_speed}, {"max_acceleration", options.path.limits.max_acceleration}};
    if (options.sample_period > 0.0) {
      const auto samples = trajectory.sample(options.sample_period);
      result["trajectory"] = {{"period_s", options.sample_period},
                              {"times_s", samples.times},
                              {"positions", toJsonRows(samples.positions.transpose())},
                              {"velocities", toJsonRows(samples.velocities.transpose())}};
    }
  }
  return result;
}

}  // namespace

void registerItmCommands(CLI::App& app, CommandRunner& runner) {
  auto* itm = app.add_subcommand("itm", "instantaneous topological map of the taught free space (hybrid ITM)");
  itm->require_subcommand(1);
  {
    auto* build = itm->add_subcommand("build", "learn a map from a stream x,y,z[,qw,qx,qy,qz],q1..qN and save it");
    auto options = std::make_shared<BuildOptions>();
    auto& p = options->parameters;
    build->add_option("--data", options->data, "CSV stream with a header, in time order")->required();
    build->add_option("--out", options->out, "graph file to write")->required();
    build->add_option("--emax", p.e_max, "maximum quantization error e_max [m]")->capture_default_str();
    build->add_option("--delta", p.delta, "local bootstrapping depth delta [edges] (0 = off)")->capture_default_str();
    build->add_option("--dthetamax", p.d_theta_max, "maximum joint distance of an edge [rad]")->capture_default_str();
    build->add_option("--dcmax", p.d_c_max, "global bootstrapping radius d_Cmax [m] (0 = off)")->capture_default_str();
    build->add_option("--alpha", p.alpha, "rotational weight of the pose metric (Eq. 7.5)")->capture_default_str();
    build->add_option("--eta", p.eta, "winner adaptation rate (plain ITM only)")->capture_default_str();
    build->add_option("--variant", options->variant, "hybrid (Alg. 7.2) or plain (Alg. 7.1)")->capture_default_str();
    build->callback([&runner, options] { runner.select([options] { return buildMap(*options); }); });
  }
  {
    auto* path = itm->add_subcommand("path", "plan a path through a saved map (A* and a limited spline)");
    auto options = std::make_shared<PathCommandOptions>();
    path->add_option("--graph", options->graph, "graph file written by itm build")->required();
    path->add_option("--from", options->from, "start x,y,z [m] (or x,y,z,qw,qx,qy,qz on a pose map)")->required();
    path->add_option("--to", options->to, "goal x,y,z [m] (or x,y,z,qw,qx,qy,qz on a pose map)")->required();
    path->add_option("--vmax", options->path.limits.max_speed, "speed limit of the spline [m/s]")->capture_default_str();
    path->add_option("--amax", options->path.limits.max_acceleration, "acceleration limit of the spline [m/s^2]")->capture_default_str();
    path->add_option("--dt", options->sample_period, "also print the trajectory sampled every dt seconds")->check(CLI::PositiveNumber);
    path->add_option("--max-gap", options->max_gap,
                     "no path when start or goal lies farther than this from every node [m] (default: the graph's e_max)")
        ->check(finiteRange(0.0, 1e3));
    path->callback([&runner, options] { runner.select([options] { return planOnMap(*options); }); });
  }
}

}  // namespace flexirob::cli
