#include "robot/scene.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <string_view>
#include <system_error>

#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/mesh.hpp"
#include "robot/mesh_solid.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/parameters.hpp"

namespace flexirob::robot {
namespace fs = std::filesystem;

namespace {

// Limits that keep a hostile or mistaken file from exhausting memory or time. They are far
// above anything a real workcell needs; docs/SCENES.md lists them.
constexpr std::uintmax_t kMaxFileBytes = 16U * 1024U * 1024U;
constexpr std::size_t kMaxObstacles = 100000;
constexpr std::size_t kMaxAreas = 10000;
constexpr std::size_t kMaxTargets = 500000;
constexpr std::size_t kMaxTrajectories = 100000;
constexpr std::size_t kMaxWaypoints = 500000;  // summed over all trajectories
constexpr std::size_t kMaxParameters = 10000;
constexpr std::size_t kMaxJoints = 64;
constexpr std::size_t kMaxNameLength = 200;
constexpr std::size_t kMaxTextLength = 20000;
constexpr std::size_t kMaxExcludedBoxes = 1000;
constexpr double kMaxGridTolerance = 0.05;  // [m]
constexpr double kMaxLength = 1000.0;  // [m]: any coordinate or size beyond this is a mistake
// Every scalar the reader visits costs one unit; YAML aliases can make a small file name the
// same large list many times, and this budget bounds the work regardless.
constexpr std::size_t kMaxVisitedNodes = 20000000;
// Values (scalars, lists, mappings, aliases) a file may hold: 100 000 boxes with name, size and
// position need 1.5 million.
constexpr std::size_t kMaxYamlValues = 3000000;
constexpr double kPi = 3.14159265358979323846;

bool isValidUtf8(const std::string& text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    std::size_t extra = 0;
    if (c < 0x80) {
      extra = 0;
    } else if ((c & 0xE0U) == 0xC0U && c >= 0xC2U) {
      extra = 1;
    } else if ((c & 0xF0U) == 0xE0U) {
      extra = 2;
    } else if ((c & 0xF8U) == 0xF0U && c <= 0xF4U) {
      extra = 3;
    } else {
      return false;
    }
    if (i + extra >= text.size()) return false;
    for (std::size_t k = 1; k <= extra; ++k) {
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0U) != 0x80U) return false;
    }
    i += extra + 1;
  }
  return true;
}

Eigen::Matrix3d rotationFromRpy(double roll, double pitch, double yaw) {
  // URDF convention: fixed axes X, then Y, then Z, i.e. R = Rz(yaw) Ry(pitch) Rx(roll).
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// One parsed YAML document in a compact form. yaml-cpp's own node tree costs about 0.5 kB per
// value (a 16 MB file would need several GB), so the reader builds this flat tree from the
// parser's events instead and stops as soon as a file holds more values than any sane scene.
struct RawNode {
  enum class Kind : std::uint8_t { kNull, kScalar, kSequence, kMap };
  Kind kind = Kind::kNull;
  bool quoted = false;  // a quoted scalar is text, never a number
  int line = -1;        // 0-based, -1 if unknown
  std::string text;     // scalars
  std::vector<std::uint32_t> children;  // sequences: items; maps: key, value, key, value, ...
};

constexpr std::uint32_t kNoNode = std::numeric_limits<std::uint32_t>::max();

struct RawDocument {
  std::vector<RawNode> nodes;
  std::uint32_t root = kNoNode;
};

// Thrown by the builder to stop the parser; parseScene turns it into an InputError.
struct BuildStop {
  std::string reason;
  int line = -1;
};

class DocumentBuilder : public YAML::EventHandler {
 public:
  DocumentBuilder(RawDocument& document, std::size_t max_values) : document_(document), max_values_(max_values) {}

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) throw BuildStop{"expected one YAML document, found a second one", mark.line};
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { add(RawNode::Kind::kNull, mark, anchor, false); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    count(mark);
    const auto found = anchors_.find(anchor);
    // Anchors are registered when their node is complete, so an alias inside its own anchored
    // node (a cycle) is not found here.
    if (found == anchors_.end()) throw BuildStop{"an alias refers to a node that encloses it", mark.line};
    attach(found->second);
  }
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor, const std::string& value) override {
    const std::uint32_t index = add(RawNode::Kind::kScalar, mark, anchor, true);
    document_.nodes[index].text = value;
    document_.nodes[index].quoted = tag == "!";
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(RawNode::Kind::kSequence, mark, anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, YAML::EmitterStyle::value) override {
    open(RawNode::Kind::kMap, mark, anchor);
  }
  void OnMapEnd() override { close(); }

 private:
  void count(const YAML::Mark& mark) {
    if (++values_ > max_values_) {
      throw BuildStop{"more than " + std::to_string(max_values_) + " YAML values; a scene file holds fewer", mark.line};
    }
  }
  std::uint32_t add(RawNode::Kind kind, const YAML::Mark& mark, YAML::anchor_t anchor, bool complete) {
    count(mark);
    const auto index = static_cast<std::uint32_t>(document_.nodes.size());
    RawNode node;
    node.kind = kind;
    node.line = mark.line;
    document_.nodes.push_back(std::move(node));
    attach(index);
    if (anchor != YAML::NullAnchor && complete) anchors_[anchor] = index;
    return index;
  }
  void open(RawNode::Kind kind, const YAML::Mark& mark, YAML::anchor_t anchor) {
    const std::uint32_t index = add(kind, mark, anchor, false);
    open_.push_back({index, anchor});
  }
  void close() {
    if (open_.empty()) return;
    const auto [index, anchor] = open_.back();
    open_.pop_back();
    if (anchor != YAML::NullAnchor) anchors_[anchor] = index;
  }
  void attach(std::uint32_t index) {
    if (open_.empty()) {
      document_.root = index;
    } else {
      document_.nodes[open_.back().first].children.push_back(index);
    }
  }

  RawDocument& document_;
  std::size_t max_values_;
  std::size_t values_ = 0;
  int documents_ = 0;
  std::vector<std::pair<std::uint32_t, YAML::anchor_t>> open_;
  std::map<YAML::anchor_t, std::uint32_t> anchors_;
};

// A read-only view of one node of a RawDocument, with the few queries the reader needs. A
// missing map entry is an undefined Node (false in a condition).
class Node {
 public:
  Node() = default;
  Node(const RawDocument* document, std::uint32_t index) : document_(document), index_(index) {}

  bool IsDefined() const { return document_ != nullptr && index_ != kNoNode; }
  explicit operator bool() const { return IsDefined(); }
  bool IsNull() const { return !IsDefined() || raw().kind == RawNode::Kind::kNull; }
  bool IsScalar() const { return IsDefined() && raw().kind == RawNode::Kind::kScalar; }
  bool IsSequence() const { return IsDefined() && raw().kind == RawNode::Kind::kSequence; }
  bool IsMap() const { return IsDefined() && raw().kind == RawNode::Kind::kMap; }
  bool quoted() const { return IsScalar() && raw().quoted; }
  const std::string& Scalar() const { return raw().text; }
  int line() const { return IsDefined() ? raw().line : -1; }
  /// Items of a sequence, entries of a map.
  std::size_t size() const {
    if (!IsDefined()) return 0;
    return IsMap() ? raw().children.size() / 2 : raw().children.size();
  }
  Node operator[](std::size_t i) const { return {document_, raw().children[i]}; }
  Node key(std::size_t i) const { return {document_, raw().children[2 * i]}; }
  Node value(std::size_t i) const { return {document_, raw().children[2 * i + 1]}; }
  /// The value of the first entry whose key is the plain text `name`.
  Node operator[](std::string_view name) const {
    if (!IsMap()) return {};
    for (std::size_t i = 0; i < size(); ++i) {
      const Node k = key(i);
      if (k.IsScalar() && k.Scalar() == name) return value(i);
    }
    return {};
  }
  Node operator[](const char* name) const { return (*this)[std::string_view(name)]; }
  Node operator[](const std::string& name) const { return (*this)[std::string_view(name)]; }

 private:
  const RawNode& raw() const { return document_->nodes[index_]; }
  const RawDocument* document_ = nullptr;
  std::uint32_t index_ = kNoNode;
};

// Walks the YAML tree of one scene, checking every value on the way; each failure throws
// InputError "<origin>:<line>: <key path>: <reason>".
class SceneReader {
 public:
  SceneReader(std::string origin, fs::path base_dir, SceneText source = SceneText::kFile)
      : origin_(std::move(origin)), base_dir_(std::move(base_dir)), source_(source) {}

  Scene read(const Node& root) {
    if (!root.IsDefined() || root.IsNull()) fail(root, "", "the file holds no scene (it is empty)");
    if (!root.IsMap()) fail(root, "", "expected a mapping of scene keys (name, obstacles, ...) at the top level");
    checkKeys(root, "",
              {"version", "name", "description", "robot", "home_posture", "obstacles", "table",
               "training_areas", "working_areas", "grid", "targets", "trajectories", "parameters"});
    Scene scene;
    if (const auto node = root["version"]) {
      const double version = number(node, "version");
      if (version != 1.0) fail(node, "version", "this program reads scene format version 1, got " + printable(node.Scalar()));
    }
    if (const auto node = root["name"]) scene.name = name(node, "name");
    if (const auto node = root["description"]) scene.description = text(node, "description", kMaxTextLength);
    if (const auto node = root["robot"]) scene.robot = robot(node, "robot", scene.robot_unreadable);
    if (const auto node = root["home_posture"]) {
      scene.home_posture = posture(node, "home_posture");
      scene.home_posture_in_degrees = inDegrees(node);
      scene.home_posture_line = node.line() + 1;
    }
    if (const auto node = root["obstacles"]) {
      const auto& items = sequence(node, "obstacles", kMaxObstacles);
      std::set<std::string> names;
      for (std::size_t i = 0; i < items.size(); ++i) {
        const std::string path = "obstacles[" + std::to_string(i) + "]";
        scene.obstacles.push_back(obstacle(items[i], path, i));
        if (!names.insert(scene.obstacles.back().name).second) {
          fail(items[i], path, "duplicate obstacle name '" + printable(scene.obstacles.back().name) + "'");
        }
      }
    }
    if (const auto node = root["table"]) scene.table = boolean(node, "table");
    if (const auto node = root["training_areas"]) scene.training_areas = areas(node, "training_areas");
    if (const auto node = root["working_areas"]) scene.working_areas = areas(node, "working_areas");
    if (const auto node = root["grid"]) scene.grid = grid(node, "grid");
    if (const auto node = root["targets"]) {
      const auto& items = sequence(node, "targets", kMaxTargets);
      for (std::size_t i = 0; i < items.size(); ++i) {
        scene.targets.push_back(placeAboveTable(items[i], "targets[" + std::to_string(i) + "]"));
      }
    }
    if (const auto node = root["trajectories"]) scene.trajectories = trajectories(node, "trajectories");
    if (const auto node = root["parameters"]) scene.parameters = parameters(node, "parameters");
    scene.ignored_parameters = ignored_parameters_;
    return scene;
  }

  // "<file>:<line>: <path>: <reason>"
  std::string located(const Node& node, const std::string& path, const std::string& reason) const {
    std::string where = origin_;
    if (node.line() >= 0) where += ":" + std::to_string(node.line() + 1);
    return where + ": " + (path.empty() ? "" : path + ": ") + reason;
  }

  [[noreturn]] void fail(const Node& node, const std::string& path, const std::string& reason) const {
    throw InputError(located(node, path, reason));
  }

 private:
  void visit(const Node& node, const std::string& path) {
    if (++visited_ > kMaxVisitedNodes) {
      fail(node, path, "the file is too large to process (more than " + std::to_string(kMaxVisitedNodes) + " values, aliases included)");
    }
  }

  // The node must be a mapping whose keys are all in `allowed` and appear once each.
  void checkKeys(const Node& node, const std::string& path, std::initializer_list<const char*> allowed) {
    if (!node.IsMap()) fail(node, path, "expected a mapping of keys, got " + kind(node));
    std::set<std::string> seen;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const Node key_node = node.key(i);
      visit(key_node, path);
      if (!key_node.IsScalar()) fail(key_node, path, "expected a plain key, got " + kind(key_node));
      const std::string& key = key_node.Scalar();
      const bool known = std::any_of(allowed.begin(), allowed.end(), [&](const char* k) { return key == k; });
      if (!known) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(key_node, path, "unknown key '" + printable(key) + "' (expected one of: " + list + ")");
      }
      if (!seen.insert(key).second) fail(key_node, path, "key '" + key + "' appears twice");
    }
  }

  static std::string kind(const Node& node) {
    if (node.IsScalar()) return "'" + printable(node.Scalar()) + "'";
    if (node.IsSequence()) return "a list";
    if (node.IsMap()) return "a mapping";
    return "nothing";
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

  std::vector<Node> sequence(const Node& node, const std::string& path, std::size_t max_items) {
    if (!node.IsSequence()) fail(node, path, "expected a list, got " + kind(node));
    if (node.size() > max_items) {
      fail(node, path, "too many entries (" + std::to_string(node.size()) + ", at most " + std::to_string(max_items) + ")");
    }
    std::vector<Node> items;
    items.reserve(node.size());
    for (std::size_t i = 0; i < node.size(); ++i) {
      visit(node[i], path);
      items.push_back(node[i]);
    }
    return items;
  }

  double number(const Node& node, const std::string& path) {
    visit(node, path);
    if (!node.IsScalar()) fail(node, path, "expected a number, got " + kind(node));
    if (node.quoted()) fail(node, path, "expected a number, got the quoted text " + kind(node));
    std::string text = node.Scalar();
    const std::string lower = [&] {
      std::string s = text;
      std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      return s;
    }();
    for (const char* special : {".nan", "nan", ".inf", "+.inf", "-.inf", "inf", "+inf", "-inf", "infinity", "-infinity"}) {
      if (lower == special) fail(node, path, "expected a finite number, got " + printable(text));
    }
    if (!text.empty() && text.front() == '+') text.erase(0, 1);
    double value = 0.0;
    const char* const begin = text.data();
    const char* const end = begin + text.size();
    const auto [stop, error] = std::from_chars(begin, end, value);
    if (text.empty() || error == std::errc::invalid_argument || stop != end) {
      fail(node, path, "expected a number, got " + kind(node));
    }
    if (error == std::errc::result_out_of_range || !std::isfinite(value)) {
      fail(node, path, "expected a finite number, got " + printable(node.Scalar()));
    }
    return value;
  }

  double length(const Node& node, const std::string& path, bool allow_negative) {
    const double value = number(node, path);
    if (!allow_negative && value <= 0.0) fail(node, path, "expected a positive length in metres, got " + printable(node.Scalar()));
    if (std::abs(value) > kMaxLength) {
      fail(node, path, "expected at most " + std::to_string(static_cast<int>(kMaxLength)) + " m, got " + printable(node.Scalar()));
    }
    return value;
  }

  Eigen::VectorXd numbers(const Node& node, const std::string& path, std::size_t min_count, std::size_t max_count) {
    if (!node.IsSequence()) fail(node, path, "expected a list of numbers, got " + kind(node));
    if (node.size() < min_count || node.size() > max_count) {
      const std::string expected = min_count == max_count ? std::to_string(min_count)
                                                          : std::to_string(min_count) + " to " + std::to_string(max_count);
      fail(node, path, "expected " + expected + " numbers, got " + std::to_string(node.size()));
    }
    Eigen::VectorXd values(static_cast<Eigen::Index>(node.size()));
    for (std::size_t i = 0; i < node.size(); ++i) {
      values[static_cast<Eigen::Index>(i)] = number(node[i], path + "[" + std::to_string(i) + "]");
    }
    return values;
  }

  // [x, y, z] in metres.
  Eigen::Vector3d position(const Node& node, const std::string& path) {
    const Eigen::VectorXd v = numbers(node, path, 3, 3);
    if (v.cwiseAbs().maxCoeff() > kMaxLength) {
      fail(node, path, "coordinates beyond " + std::to_string(static_cast<int>(kMaxLength)) + " m");
    }
    return v;
  }

  // Places the arm is asked to reach: the robot stands on the table top z = 0, so a place below
  // it could only be reached through the table (or, with `table: false`, through what the
  // collision model does not know).
  Eigen::Vector3d placeAboveTable(const Node& node, const std::string& path) {
    const Eigen::Vector3d p = position(node, path);
    if (p.z() < 0.0) {
      std::ostringstream z;
      z << p.z();
      fail(node, path, "lies below the table top or mount the robot stands on, z = 0 (z = " + z.str() + " m); places to reach lie at z >= 0");
    }
    return p;
  }

  bool boolean(const Node& node, const std::string& path) {
    visit(node, path);
    if (!node.IsScalar() || node.quoted() || (node.Scalar() != "true" && node.Scalar() != "false")) {
      fail(node, path, "expected true or false (unquoted), got " + kind(node));
    }
    return node.Scalar() == "true";
  }

  Eigen::Vector3d positiveSize(const Node& node, const std::string& path) {
    const Eigen::Vector3d v = position(node, path);
    if ((v.array() <= 0.0).any()) fail(node, path, "expected three positive lengths in metres");
    return v;
  }

  std::string text(const Node& node, const std::string& path, std::size_t max_length) {
    visit(node, path);
    if (!node.IsScalar()) fail(node, path, "expected text, got " + kind(node));
    // Characters, not bytes: "ä" is two bytes of UTF-8 (continuation bytes are 10xxxxxx).
    const std::string& scalar = node.Scalar();
    const auto characters = static_cast<std::size_t>(
        std::count_if(scalar.begin(), scalar.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0U) != 0x80U; }));
    if (characters > max_length) fail(node, path, "text longer than " + std::to_string(max_length) + " characters");
    return node.Scalar();
  }

  std::string name(const Node& node, const std::string& path) {
    std::string value = text(node, path, kMaxNameLength);
    if (value.empty()) fail(node, path, "expected a non-empty name");
    if (std::any_of(value.begin(), value.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; })) {
      fail(node, path, "names may not contain control characters or line breaks");
    }
    return value;
  }

  std::string robot(const Node& node, const std::string& path, std::string& unreadable) {
    const std::string value = name(node, path);
    const auto& builtin = builtinRobotNames();
    if (std::find(builtin.begin(), builtin.end(), value) != builtin.end()) return value;
    fs::path file(value);
    if (file.is_relative()) file = base_dir_ / file;
    std::error_code error;
    if (source_ == SceneText::kFile && !fs::is_regular_file(file, error)) {
      unreadable = located(node, path, "'" + printable(value) + "' is neither a built-in robot (lwr4, arm9) nor an existing URDF file");
    }
    return file.lexically_normal().string();
  }

  double angleUnit(const Node& node, const std::string& path) {
    const std::string unit = text(node, path, 16);
    if (unit == "rad") return 1.0;
    if (unit == "deg") return kPi / 180.0;
    fail(node, path, "expected 'rad' or 'deg', got '" + printable(unit) + "'");
  }

  // A joint posture: a list of radians, or {unit: deg|rad, values: [...]}.
  Eigen::VectorXd posture(const Node& node, const std::string& path) {
    if (node.IsSequence()) return numbers(node, path, 1, kMaxJoints);
    if (!node.IsMap()) fail(node, path, "expected a list of joint angles in radians or {unit: deg, values: [...]}, got " + kind(node));
    checkKeys(node, path, {"unit", "values"});
    if (!node["values"]) fail(node, path, "missing key 'values'");
    const double scale = node["unit"] ? angleUnit(node["unit"], join(path, "unit")) : 1.0;
    return numbers(node["values"], join(path, "values"), 1, kMaxJoints) * scale;
  }

  // Whether a posture that posture() accepted was written in degrees.
  static bool inDegrees(const Node& node) { return node.IsMap() && node["unit"].IsScalar() && node["unit"].Scalar() == "deg"; }

  Eigen::Matrix3d rotation(const Node& node, const std::string& path) {
    checkKeys(node, path, {"rpy", "quaternion", "unit"});
    const bool has_rpy = static_cast<bool>(node["rpy"]);
    const bool has_quaternion = static_cast<bool>(node["quaternion"]);
    if (has_rpy == has_quaternion) fail(node, path, "give exactly one of 'rpy' and 'quaternion'");
    if (has_quaternion) {
      if (node["unit"]) fail(node["unit"], join(path, "unit"), "'unit' applies to 'rpy' only");
      const Eigen::VectorXd q = numbers(node["quaternion"], join(path, "quaternion"), 4, 4);
      const double norm = q.norm();
      // Hand-typed quaternions carry few digits; anything farther from unit length is a mistake.
      if (std::abs(norm - 1.0) > 1e-3) {
        fail(node["quaternion"], join(path, "quaternion"), "expected a unit quaternion [w, x, y, z], got norm " + std::to_string(norm));
      }
      return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    }
    const double scale = node["unit"] ? angleUnit(node["unit"], join(path, "unit")) : 1.0;
    const Eigen::VectorXd rpy = numbers(node["rpy"], join(path, "rpy"), 3, 3) * scale;
    // No rotation needs an angle beyond a turn; in radians that is 6.28, in degrees a slip of
    // the unit (rpy: [0, 0, 45]).
    if (scale == 1.0 && rpy.cwiseAbs().maxCoeff() > 2.0 * std::numbers::pi + 1e-6) {
      fail(node["rpy"], join(path, "rpy"), "angles are read in radians and one exceeds a turn; for degrees add 'unit: deg'");
    }
    return rotationFromRpy(rpy[0], rpy[1], rpy[2]);
  }

  Eigen::Vector4f colour(const Node& node, const std::string& path) {
    const Eigen::VectorXd c = numbers(node, path, 3, 4);
    if ((c.array() < 0.0).any() || (c.array() > 1.0).any()) fail(node, path, "colour components must lie in [0, 1]");
    Eigen::Vector4f rgba(1.0F, 1.0F, 1.0F, 1.0F);
    for (Eigen::Index i = 0; i < c.size(); ++i) rgba[i] = static_cast<float>(c[i]);
    return rgba;
  }

  Obstacle obstacle(const Node& node, const std::string& path, std::size_t index) {
    checkKeys(node, path, {"name", "shape", "size", "radius", "length", "file", "scale", "position", "rotation", "colour", "color"});
    Obstacle obstacle;
    obstacle.name = node["name"] ? name(node["name"], join(path, "name")) : "obstacle_" + std::to_string(index);
    if (!node["shape"]) fail(node, path, "missing key 'shape' (box, cylinder, sphere or mesh)");
    const std::string shape = text(node["shape"], join(path, "shape"), 16);
    // Keys each shape needs and admits besides the common ones.
    std::vector<std::string> needed;
    if (shape == "box") {
      obstacle.shape = Obstacle::Shape::kBox;
      needed = {"size"};
    } else if (shape == "cylinder") {
      obstacle.shape = Obstacle::Shape::kCylinder;
      needed = {"radius", "length"};
    } else if (shape == "sphere") {
      obstacle.shape = Obstacle::Shape::kSphere;
      needed = {"radius"};
    } else if (shape == "mesh") {
      obstacle.shape = Obstacle::Shape::kMesh;
      needed = {"file"};
    } else {
      fail(node["shape"], join(path, "shape"), "expected box, cylinder, sphere or mesh, got '" + printable(shape) + "'");
    }
    for (const char* key : {"size", "radius", "length", "file", "scale"}) {
      const bool admitted = std::find(needed.begin(), needed.end(), key) != needed.end() ||
                            (obstacle.shape == Obstacle::Shape::kMesh && std::string(key) == "scale");
      if (node[key] && !admitted) fail(node[key], join(path, key), "key '" + std::string(key) + "' does not apply to a " + shape);
    }
    for (const auto& key : needed) {
      if (!node[key]) fail(node, path, "a " + shape + " needs key '" + key + "'");
    }
    switch (obstacle.shape) {
      case Obstacle::Shape::kBox:
        obstacle.size = positiveSize(node["size"], join(path, "size"));
        break;
      case Obstacle::Shape::kCylinder:
        obstacle.size = Eigen::Vector3d(length(node["radius"], join(path, "radius"), false),
                                        length(node["length"], join(path, "length"), false), 0.0);
        break;
      case Obstacle::Shape::kSphere:
        obstacle.size = Eigen::Vector3d(length(node["radius"], join(path, "radius"), false), 0.0, 0.0);
        break;
      case Obstacle::Shape::kMesh: {
        const std::string file = name(node["file"], join(path, "file"));
        fs::path resolved(file);
        if (resolved.is_relative()) resolved = base_dir_ / resolved;
        std::error_code error;
        if (fs::is_directory(resolved, error)) {
          fail(node["file"], join(path, "file"), "mesh file '" + printable(file) + "' is a folder, not a mesh file");
        }
        if (!fs::is_regular_file(resolved, error)) {
          fail(node["file"], join(path, "file"), "mesh file '" + printable(file) + "' not found (relative paths start at the scene file's folder)");
        }
        obstacle.mesh_file = resolved.lexically_normal();
        // Loaded here (cached for the collision model and the drawing that load it again), so
        // that a broken mesh is reported at the scene line that names it.
        try {
          loadMeshCached(obstacle.mesh_file);
        } catch (const InputError& e) {
          fail(node["file"], join(path, "file"), e.what());
        }
        if (const auto scale = node["scale"]) {
          obstacle.mesh_scale = scale.IsSequence() ? positiveSize(scale, join(path, "scale"))
                                                   : Eigen::Vector3d::Constant(length(scale, join(path, "scale"), false));
        }
        obstacle.mesh_solid = loadMeshSolidCached(obstacle.mesh_file, obstacle.mesh_scale);
        break;
      }
    }
    if (const auto p = node["position"]) obstacle.X_WO.translation() = position(p, join(path, "position"));
    if (const auto r = node["rotation"]) obstacle.X_WO.linear() = rotation(r, join(path, "rotation"));
    if (node["colour"] && node["color"]) fail(node, path, "give either 'colour' or 'color', not both");
    if (const auto c = node["colour"]) obstacle.rgba = colour(c, join(path, "colour"));
    if (const auto c = node["color"]) obstacle.rgba = colour(c, join(path, "color"));
    return obstacle;
  }

  std::vector<Area> areas(const Node& node, const std::string& path) {
    const auto& items = sequence(node, path, kMaxAreas);
    std::vector<Area> result;
    std::set<std::string> names;
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string item_path = path + "[" + std::to_string(i) + "]";
      const Node& item = items[i];
      checkKeys(item, item_path, {"name", "centre", "center", "radius", "box", "posture"});
      Area area;
      area.name = item["name"] ? name(item["name"], join(item_path, "name")) : "area_" + std::to_string(i + 1);
      if (item["centre"] && item["center"]) fail(item, item_path, "give either 'centre' or 'center', not both");
      const Node centre = item["centre"] ? item["centre"] : item["center"];
      if (!centre) fail(item, item_path, "missing key 'centre'");
      area.p_WA = placeAboveTable(centre, join(item_path, "centre"));
      if (const auto r = item["radius"]) area.radius = length(r, join(item_path, "radius"), false);
      if (const auto b = item["box"]) area.box = positiveSize(b, join(item_path, "box"));
      if (const auto q = item["posture"]) {
        area.posture = posture(q, join(item_path, "posture"));
        area.posture_in_degrees = inDegrees(q);
        area.posture_line = q.line() + 1;
      }
      if (!names.insert(area.name).second) fail(item, item_path, "duplicate area name '" + printable(area.name) + "'");
      result.push_back(std::move(area));
    }
    return result;
  }

  EvaluationGrid grid(const Node& node, const std::string& path) {
    checkKeys(node, path, {"lower", "upper", "spacing", "tolerance", "exclude"});
    EvaluationGrid grid;
    if (const auto n = node["lower"]) grid.lower = placeAboveTable(n, join(path, "lower"));
    if (const auto n = node["upper"]) grid.upper = position(n, join(path, "upper"));
    if (const auto n = node["spacing"]) grid.spacing = length(n, join(path, "spacing"), false);
    if (const auto n = node["tolerance"]) {
      grid.tolerance = length(n, join(path, "tolerance"), false);
      // Beyond a few centimetres "reached" stops meaning reached (Sect. 3.3.2: 0.01 m).
      if (grid.tolerance > kMaxGridTolerance) {
        std::ostringstream problem;
        problem << "'tolerance' (how near the tip must come for a target to count as reached) must be at most " << kMaxGridTolerance
                << " m, got " << grid.tolerance << " m";
        fail(n, join(path, "tolerance"), problem.str());
      }
    }
    if ((grid.upper.array() < grid.lower.array()).any()) fail(node, path, "'upper' must not lie below 'lower' on any axis");
    if (const std::string problem = grid.sizeProblem(); !problem.empty()) fail(node, path, problem + "; increase 'spacing'");
    if (const auto n = node["exclude"]) {
      const std::string exclude_path = join(path, "exclude");
      const auto& items = sequence(n, exclude_path, kMaxExcludedBoxes);
      for (std::size_t i = 0; i < items.size(); ++i) {
        const std::string item_path = exclude_path + "[" + std::to_string(i) + "]";
        const Node& item = items[i];
        checkKeys(item, item_path, {"lower", "upper"});
        if (!item["lower"]) fail(item, item_path, "missing key 'lower'");
        if (!item["upper"]) fail(item, item_path, "missing key 'upper'");
        const Eigen::Vector3d lower = position(item["lower"], join(item_path, "lower"));
        const Eigen::Vector3d upper = position(item["upper"], join(item_path, "upper"));
        if ((upper.array() < lower.array()).any()) fail(item, item_path, "'upper' must not lie below 'lower' on any axis");
        grid.excluded.emplace_back(lower, upper);
      }
    }
    return grid;
  }

  std::vector<Trajectory> trajectories(const Node& node, const std::string& path) {
    const auto& items = sequence(node, path, kMaxTrajectories);
    std::vector<Trajectory> result;
    std::set<std::string> names;
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string item_path = path + "[" + std::to_string(i) + "]";
      const Node& item = items[i];
      checkKeys(item, item_path, {"name", "group", "waypoints"});
      Trajectory trajectory;
      trajectory.name = item["name"] ? name(item["name"], join(item_path, "name")) : "trajectory_" + std::to_string(i + 1);
      if (const auto g = item["group"]) trajectory.group = name(g, join(item_path, "group"));
      if (!item["waypoints"]) fail(item, item_path, "missing key 'waypoints'");
      const auto& points = sequence(item["waypoints"], join(item_path, "waypoints"), kMaxWaypoints);
      if (points.size() < 2) fail(item["waypoints"], join(item_path, "waypoints"), "a trajectory needs at least 2 waypoints");
      waypoint_count_ += points.size();
      if (waypoint_count_ > kMaxWaypoints) {
        fail(item["waypoints"], join(item_path, "waypoints"), "more than " + std::to_string(kMaxWaypoints) + " waypoints in all trajectories");
      }
      for (std::size_t k = 0; k < points.size(); ++k) {
        trajectory.waypoints.push_back(placeAboveTable(points[k], join(item_path, "waypoints") + "[" + std::to_string(k) + "]"));
      }
      if (!names.insert(trajectory.name).second) fail(item, item_path, "duplicate trajectory name '" + printable(trajectory.name) + "'");
      result.push_back(std::move(trajectory));
    }
    return result;
  }

  std::map<std::string, double> parameters(const Node& node, const std::string& path) {
    if (!node.IsMap()) fail(node, path, "expected a mapping of parameter names to numbers, got " + kind(node));
    if (node.size() > kMaxParameters) fail(node, path, "more than " + std::to_string(kMaxParameters) + " parameters");
    std::map<std::string, double> result;
    const std::vector<ParameterDeclaration> tunable = sceneTunableParameters();
    ParameterSet in_range(tunable);
    for (std::size_t i = 0; i < node.size(); ++i) {
      const Node key_node = node.key(i);
      visit(key_node, path);
      if (!key_node.IsScalar()) fail(key_node, path, "expected a parameter name, got " + kind(key_node));
      const std::string& key = key_node.Scalar();
      const bool valid = !key.empty() && key.size() <= kMaxNameLength &&
                         (std::isalpha(static_cast<unsigned char>(key.front())) != 0 || key.front() == '_') &&
                         std::all_of(key.begin(), key.end(), [](char c) {
                           return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.';
                         });
      if (!valid) fail(key_node, path, "'" + printable(key) + "' is not a parameter name (letters, digits, '_' and '.')");
      // A misspelt name would otherwise tune nothing without a word.
      const std::string undeclared = undeclaredParameterReason(key, tunable);
      if (!undeclared.empty() && source_ == SceneText::kSessionCopy) {
        ignored_parameters_.push_back(key);
        continue;
      }
      if (!undeclared.empty()) fail(key_node, path, undeclared);
      if (result.count(key) != 0) fail(key_node, path, "parameter '" + key + "' appears twice");
      const double value = number(node.value(i), join(path, key));
      // Out of its range, every program that applies it refuses it; render would draw the scene
      // without a word, so the reader says it where it is written.
      try {
        in_range.set(key, value);
      } catch (const InputError& error) {
        fail(node.value(i), path, error.what());
      }
      result[key] = value;
    }
    return result;
  }

  std::string origin_;
  fs::path base_dir_;
  SceneText source_ = SceneText::kFile;
  std::vector<std::string> ignored_parameters_;
  std::size_t visited_ = 0;
  std::size_t waypoint_count_ = 0;
};

}  // namespace

bool Area::contains(const Eigen::Vector3d& p_W) const {
  // The boundary belongs to the area; 1 nm of slack absorbs the rounding of p_W - p_WA for
  // points written on it in decimal (e.g. -0.45 - (-0.55) != 0.1 in binary).
  constexpr double kSlack = 1e-9;
  const Eigen::Vector3d d = p_W - p_WA;
  if (box) return ((d.cwiseAbs() - 0.5 * *box).array() <= kSlack).all();
  return d.norm() <= radius + kSlack;
}

Eigen::Vector3i EvaluationGrid::counts() const {
  if (!(spacing > 0.0) || (upper.array() < lower.array()).any()) return Eigen::Vector3i::Zero();
  // The 1e-9 slack keeps an upper bound that is a whole number of spacings (0.8 = 0.05 + 15 * 0.05)
  // from being lost to rounding.
  const Eigen::Array3d n = ((upper - lower).array() / spacing + 1e-9).floor() + 1.0;
  return n.cast<int>().matrix();
}

double EvaluationGrid::pointCount() const {
  if (!(spacing > 0.0) || (upper.array() < lower.array()).any()) return 0.0;
  return (((upper - lower).array() / spacing + 1e-9).floor() + 1.0).prod();
}

std::string EvaluationGrid::sizeProblem() const {
  const double count = pointCount();
  if (count <= kMaxGridPoints) return "";
  std::ostringstream out;
  out << "the grid would have " << std::setprecision(3) << count << " points (at most " << std::setprecision(10) << kMaxGridPoints << ")";
  return out.str();
}

std::vector<Eigen::Vector3d> EvaluationGrid::points() const {
  const Eigen::Vector3i n = counts();
  std::vector<Eigen::Vector3d> result;
  result.reserve(static_cast<std::size_t>(n.prod()));
  for (int k = 0; k < n.z(); ++k) {
    for (int j = 0; j < n.y(); ++j) {
      for (int i = 0; i < n.x(); ++i) result.push_back(lower + spacing * Eigen::Vector3d(i, j, k));
    }
  }
  return result;
}

std::string robotFor(const std::string& robot_option, const Scene& scene) {
  if (!robot_option.empty()) return robot_option;
  if (!scene.robot_unreadable.empty()) throw InputError(scene.robot_unreadable);
  return scene.robot.empty() ? std::string("lwr4") : scene.robot;
}

namespace {

// Where a posture of the scene is written, as the reader names a place: "<file>:<line>: " (the
// scene's name where it was not read from a file).
std::string postureOrigin(const Scene& scene, int line) {
  if (scene.source.empty() || line <= 0) return "scene '" + printable(scene.name, 200) + "': ";
  return scene.source.string() + ":" + std::to_string(line) + ": ";
}

}  // namespace

void checkPosturesFit(const Scene& scene, int dof, const std::string& robot_name) {
  const auto check = [&](const std::optional<Eigen::VectorXd>& posture, const std::string& what, int line) {
    if (posture && posture->size() != dof) {
      throw InputError(postureOrigin(scene, line) + what + " has " + std::to_string(posture->size()) +
                       " joint values, the robot '" + printable(robot_name, 200) + "' has " + std::to_string(dof) +
                       " joints (the scene was made for '" + printable(scene.robot, 200) + "')");
    }
  };
  check(scene.home_posture, "home_posture", scene.home_posture_line);
  for (const Area& area : scene.training_areas) check(area.posture, "training area '" + area.name + "' posture", area.posture_line);
  for (const Area& area : scene.working_areas) check(area.posture, "working area '" + area.name + "' posture", area.posture_line);
}

void checkPosturesFit(const Scene& scene, const RobotModel& model, const std::string& robot_name) {
  try {
    checkPosturesFit(scene, model.dof(), robot_name);
  } catch (const InputError& error) {
    // The joint count is that of the chain to the tip: a tip named (or chosen) past a gripper's
    // finger adds its slide to the arm, which the robot's file name alone does not say.
    throw InputError(std::string(error.what()) + "; the robot's chain runs from '" + printable(model.baseLink(), 100) +
                     "' to the tip '" + printable(model.tipLink(), 100) + "' (--tip chooses another tip)");
  }
  // A slide's value in a posture written in degrees is a length, which the reader cannot tell
  // from an angle: 0.2 m had become 3.5 mm without a word.
  const auto slide = std::find_if(model.joints().begin(), model.joints().end(),
                                  [](const Joint& joint) { return joint.type == JointType::kPrismatic; });
  const auto check = [&](const std::optional<Eigen::VectorXd>& posture, const std::string& what, int line, bool in_degrees) {
    if (!posture) return;
    const std::string prefix = postureOrigin(scene, line);
    if (in_degrees && slide != model.joints().end()) {
      throw InputError(prefix + what + " is written in degrees, but joint '" + printable(slide->name, 100) +
                       "' slides; write the posture as a plain list in radians and metres");
    }
    model.checkWithinLimits(*posture, prefix + what);
  };
  check(scene.home_posture, "home_posture", scene.home_posture_line, scene.home_posture_in_degrees);
  // An area's posture is a suggestion for holding the tip there: one that puts the tip
  // elsewhere is a slip of the scene's author, which the tutor would silently pass over.
  Kinematics kinematics(model);
  const auto checkArea = [&](const Area& area, const std::string& what) {
    check(area.posture, what, area.posture_line, area.posture_in_degrees);
    if (!area.posture) return;
    kinematics.update(*area.posture);
    const double off = (kinematics.p_WT() - area.p_WA).norm();
    const double extent = area.box ? 0.5 * area.box->norm() : area.radius;
    if (off > extent + 0.01) {
      std::ostringstream message;
      message << std::fixed << std::setprecision(3) << postureOrigin(scene, area.posture_line) << what << " puts the tip "
              << off << " m from the area's centre (the area extends " << extent
              << " m); an area's posture holds the tip in the area (reach --target with the centre finds one), or leave it out "
                 "and the tutor finds one";
      throw InputError(message.str());
    }
  };
  for (const Area& area : scene.training_areas) checkArea(area, "training area '" + area.name + "' posture");
  for (const Area& area : scene.working_areas) checkArea(area, "working area '" + area.name + "' posture");
}

bool EvaluationGrid::excludes(const Eigen::Vector3d& p_W) const {
  static constexpr double kSlack = 1e-9;  // [m], as counts() keeps an upper bound
  return std::any_of(excluded.begin(), excluded.end(), [&p_W](const Eigen::AlignedBox3d& box) {
    return (p_W.array() >= box.min().array() - kSlack).all() && (p_W.array() <= box.max().array() + kSlack).all();
  });
}

bool obstacleContains(const Obstacle& obstacle, const Eigen::Vector3d& p_W, double margin) {
  const Eigen::Vector3d p_O = obstacle.X_WO.inverse() * p_W;
  switch (obstacle.shape) {
    case Obstacle::Shape::kBox: {
      // Distance from the box (zero inside) compared with the margin.
      const Eigen::Vector3d outside = (p_O.cwiseAbs() - 0.5 * obstacle.size).cwiseMax(0.0);
      return outside.norm() <= margin;
    }
    case Obstacle::Shape::kCylinder: {
      const double radial = std::max(0.0, p_O.head<2>().norm() - obstacle.size.x());
      const double axial = std::max(0.0, std::abs(p_O.z()) - 0.5 * obstacle.size.y());
      return std::hypot(radial, axial) <= margin;
    }
    case Obstacle::Shape::kSphere:
      return p_O.norm() <= obstacle.size.x() + margin;
    case Obstacle::Shape::kMesh: return meshSolidOf(obstacle)->contains(p_O, margin);
  }
  return false;
}

std::shared_ptr<const MeshSolid> meshSolidOf(const Obstacle& obstacle) {
  return obstacle.mesh_solid && obstacle.mesh_solid->scale() == obstacle.mesh_scale
             ? obstacle.mesh_solid
             : loadMeshSolidCached(obstacle.mesh_file, obstacle.mesh_scale);
}

const Obstacle* obstacleAt(const Scene& scene, const Eigen::Vector3d& p_W, double margin) {
  for (const Obstacle& obstacle : scene.obstacles) {
    if (obstacleContains(obstacle, p_W, margin)) return &obstacle;
  }
  return nullptr;
}

const std::vector<std::string>& builtinSceneNames() {
  static const std::vector<std::string> names{"empty",   "setup_A",  "setup_B", "setup_C",   "setup_D",
                                              "setup_I", "setup_II", "harting", "arm9_areas"};
  return names;
}

Scene parseScene(const std::string& yaml_text, const fs::path& base_dir, const std::string& origin, SceneText source) {
  if (yaml_text.find('\0') != std::string::npos || !isValidUtf8(yaml_text)) {
    throw InputError(origin + ": not a text file (binary data or invalid UTF-8)");
  }
  RawDocument document;
  try {
    std::istringstream stream(yaml_text);
    YAML::Parser parser(stream);
    DocumentBuilder builder(document, kMaxYamlValues);
    while (parser.HandleNextDocument(builder)) {
    }
  } catch (const BuildStop& stop) {
    throw InputError(origin + (stop.line >= 0 ? ":" + std::to_string(stop.line + 1) : std::string()) + ": " + stop.reason);
  } catch (const YAML::Exception& error) {
    std::string where = origin;
    if (!error.mark.is_null()) where += ":" + std::to_string(error.mark.line + 1);
    throw InputError(where + ": malformed YAML: " + printable(error.msg, 200));
  }
  SceneReader reader(origin, base_dir, source);
  return reader.read(Node(&document, document.root));
}

namespace {

void emitNumbers(YAML::Emitter& out, const Eigen::Ref<const Eigen::VectorXd>& values) {
  out << YAML::Flow << YAML::BeginSeq;
  for (Eigen::Index i = 0; i < values.size(); ++i) out << values[i];
  out << YAML::EndSeq;
}

void emitAreas(YAML::Emitter& out, const char* key, const std::vector<Area>& areas) {
  if (areas.empty()) return;
  out << YAML::Key << key << YAML::Value << YAML::BeginSeq;
  for (const auto& area : areas) {
    out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << area.name;
    out << YAML::Key << "centre" << YAML::Value;
    emitNumbers(out, area.p_WA);
    out << YAML::Key << "radius" << YAML::Value << area.radius;
    if (area.box) {
      out << YAML::Key << "box" << YAML::Value;
      emitNumbers(out, *area.box);
    }
    if (area.posture) {
      out << YAML::Key << "posture" << YAML::Value;
      emitNumbers(out, *area.posture);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

const char* shapeName(Obstacle::Shape shape) {
  switch (shape) {
    case Obstacle::Shape::kBox: return "box";
    case Obstacle::Shape::kCylinder: return "cylinder";
    case Obstacle::Shape::kSphere: return "sphere";
    case Obstacle::Shape::kMesh: return "mesh";
  }
  return "box";
}

}  // namespace

std::string sceneToYaml(const Scene& scene) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "version" << YAML::Value << 1;
  if (!scene.name.empty()) out << YAML::Key << "name" << YAML::Value << scene.name;
  if (!scene.description.empty()) out << YAML::Key << "description" << YAML::Value << scene.description;
  out << YAML::Key << "robot" << YAML::Value << scene.robot;
  if (scene.home_posture) {
    out << YAML::Key << "home_posture" << YAML::Value;
    emitNumbers(out, *scene.home_posture);
  }
  if (!scene.table) out << YAML::Key << "table" << YAML::Value << false;
  if (!scene.obstacles.empty()) {
    out << YAML::Key << "obstacles" << YAML::Value << YAML::BeginSeq;
    for (const auto& obstacle : scene.obstacles) {
      out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << obstacle.name;
      out << YAML::Key << "shape" << YAML::Value << shapeName(obstacle.shape);
      switch (obstacle.shape) {
        case Obstacle::Shape::kBox:
          out << YAML::Key << "size" << YAML::Value;
          emitNumbers(out, obstacle.size);
          break;
        case Obstacle::Shape::kCylinder:
          out << YAML::Key << "radius" << YAML::Value << obstacle.size.x();
          out << YAML::Key << "length" << YAML::Value << obstacle.size.y();
          break;
        case Obstacle::Shape::kSphere:
          out << YAML::Key << "radius" << YAML::Value << obstacle.size.x();
          break;
        case Obstacle::Shape::kMesh:
          out << YAML::Key << "file" << YAML::Value << obstacle.mesh_file.string();
          out << YAML::Key << "scale" << YAML::Value;
          emitNumbers(out, obstacle.mesh_scale);
          break;
      }
      out << YAML::Key << "position" << YAML::Value;
      emitNumbers(out, obstacle.X_WO.translation());
      const Eigen::Quaterniond q(obstacle.X_WO.linear());
      out << YAML::Key << "rotation" << YAML::Value << YAML::BeginMap << YAML::Key << "quaternion" << YAML::Value;
      emitNumbers(out, Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()));
      out << YAML::EndMap;
      out << YAML::Key << "colour" << YAML::Value;
      emitNumbers(out, obstacle.rgba.cast<double>());
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  emitAreas(out, "training_areas", scene.training_areas);
  emitAreas(out, "working_areas", scene.working_areas);
  if (scene.grid) {
    out << YAML::Key << "grid" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "lower" << YAML::Value;
    emitNumbers(out, scene.grid->lower);
    out << YAML::Key << "upper" << YAML::Value;
    emitNumbers(out, scene.grid->upper);
    out << YAML::Key << "spacing" << YAML::Value << scene.grid->spacing;
    out << YAML::Key << "tolerance" << YAML::Value << scene.grid->tolerance;
    if (!scene.grid->excluded.empty()) {
      out << YAML::Key << "exclude" << YAML::Value << YAML::BeginSeq;
      for (const Eigen::AlignedBox3d& box : scene.grid->excluded) {
        out << YAML::Flow << YAML::BeginMap << YAML::Key << "lower" << YAML::Value;
        emitNumbers(out, box.min());
        out << YAML::Key << "upper" << YAML::Value;
        emitNumbers(out, box.max());
        out << YAML::EndMap;
      }
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  if (!scene.targets.empty()) {
    out << YAML::Key << "targets" << YAML::Value << YAML::BeginSeq;
    for (const auto& target : scene.targets) emitNumbers(out, target);
    out << YAML::EndSeq;
  }
  if (!scene.trajectories.empty()) {
    out << YAML::Key << "trajectories" << YAML::Value << YAML::BeginSeq;
    for (const auto& trajectory : scene.trajectories) {
      out << YAML::BeginMap << YAML::Key << "name" << YAML::Value << trajectory.name;
      if (!trajectory.group.empty()) out << YAML::Key << "group" << YAML::Value << trajectory.group;
      out << YAML::Key << "waypoints" << YAML::Value << YAML::BeginSeq;
      for (const auto& p : trajectory.waypoints) emitNumbers(out, p);
      out << YAML::EndSeq << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (!scene.parameters.empty()) {
    out << YAML::Key << "parameters" << YAML::Value << YAML::BeginMap;
    for (const auto& [key, value] : scene.parameters) out << YAML::Key << key << YAML::Value << value;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

Scene loadSceneFile(const fs::path& file) {
  std::error_code error;
  if (!fs::is_regular_file(file, error)) throw InputError("scene file '" + file.string() + "' does not exist or is not a file");
  const std::uintmax_t bytes = fs::file_size(file, error);
  if (error) throw InputError("cannot read scene file '" + file.string() + "'");
  if (bytes > kMaxFileBytes) {
    throw InputError(file.string() + ": scene file is larger than 16 MB (" + std::to_string(bytes) + " bytes)");
  }
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw InputError("cannot open scene file '" + file.string() + "'");
  // Read at most one byte more than the size checked above, so a file that grew meanwhile
  // cannot make us read more than the limit.
  std::string text(static_cast<std::size_t>(bytes) + 1, '\0');
  stream.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(stream.gcount()));
  if (text.size() > kMaxFileBytes) throw InputError(file.string() + ": scene file is larger than 16 MB");
  Scene scene = parseScene(text, fs::absolute(file).parent_path(), file.string());
  scene.source = file;
  if (scene.name.empty()) scene.name = file.stem().string();
  return scene;
}

std::string sceneOrigin(const Scene& scene) {
  return scene.source.empty() ? "scene '" + printable(scene.name) + "'" : scene.source.string();
}

Scene loadScene(const std::string& name_or_path) {
  if (name_or_path.empty()) {
    // No scene requested: nothing around the robot; needs no resources folder.
    Scene scene;
    scene.name = "empty";
    scene.description = "Nothing but the table top the robot stands on: no obstacles, no areas.";
    return scene;
  }
  const auto& names = builtinSceneNames();
  if (std::find(names.begin(), names.end(), name_or_path) != names.end()) {
    return loadSceneFile(resourceDir() / "scenes" / (name_or_path + ".yaml"));
  }
  if (const std::string reason = unreadableFileReason(name_or_path); !reason.empty()) {
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    throw InputError("scene '" + printable(name_or_path, 200) + "' is neither a built-in scene (" + known +
                     ") nor a readable scene file (" + reason + ")");
  }
  return loadSceneFile(name_or_path);
}

std::vector<std::string> sceneNotes(const Scene& scene) {
  std::vector<std::string> notes;
  for (const Obstacle& obstacle : scene.obstacles) {
    if (obstacle.shape != Obstacle::Shape::kMesh) continue;
    const std::shared_ptr<const MeshSolid> solid = meshSolidOf(obstacle);
    if (solid->deviation() <= 0.0) continue;
    std::ostringstream note;
    note << "obstacle '" << obstacle.name << "': its " << solid->sourceTriangleCount()
         << " triangles are simplified to " << solid->triangles().size()
         << " for collisions and inside tests; the surface moves by up to " << std::fixed << std::setprecision(1)
         << 1000.0 * solid->deviation() << " mm";
    notes.push_back(note.str());
  }
  // An open mesh is read as the solid it mostly surrounds; one around the robot (a housing open
  // at the floor) holds the whole workspace as inside, while the simulation collides only with
  // its sheets: every area and target would be refused as inside it, with no word of why.
  for (const Obstacle& obstacle : scene.obstacles) {
    if (obstacle.shape != Obstacle::Shape::kMesh || !obstacleContains(obstacle, Eigen::Vector3d(0.0, 0.0, 0.01))) continue;
    notes.push_back("obstacle '" + obstacle.name +
                    "' holds the robot's base inside it: an open mesh counts as the solid it surrounds, so every point "
                    "it surrounds is inside it for areas, targets and evaluations (the simulation touches only its "
                    "surface); model its walls as closed solids");
  }
  // An obstacle wholly under the table top is one no link can touch: most likely a sign slip.
  if (scene.table) {
    for (const Obstacle& obstacle : scene.obstacles) {
      Eigen::Vector3d half = Eigen::Vector3d::Zero();
      switch (obstacle.shape) {
        case Obstacle::Shape::kBox: half = 0.5 * obstacle.size; break;
        case Obstacle::Shape::kCylinder: half = Eigen::Vector3d(obstacle.size.x(), obstacle.size.x(), 0.5 * obstacle.size.y()); break;
        case Obstacle::Shape::kSphere: half = Eigen::Vector3d::Constant(obstacle.size.x()); break;
        case Obstacle::Shape::kMesh: continue;
      }
      // The highest corner of the box around the shape, turned as the obstacle is.
      const double top = obstacle.X_WO.translation().z() + (obstacle.X_WO.linear().row(2).cwiseAbs() * half)(0);
      if (top >= 0.0) continue;
      std::ostringstream note;
      note << std::fixed << std::setprecision(3) << "obstacle '" << obstacle.name << "' lies wholly under the table top (its top at z = "
           << top << " m), where no link reaches: was z meant to be positive?";
      notes.push_back(note.str());
    }
  }
  // A single evaluation target inside an obstacle can never be reached: say so once here
  // rather than let `eval reachable` report it as a failed target of the learned map.
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    const Obstacle* inside = obstacleAt(scene, scene.targets[i]);
    if (inside == nullptr) continue;
    std::ostringstream note;
    const Eigen::Vector3d& p = scene.targets[i];
    note << std::fixed << std::setprecision(3) << "targets[" << i << "] (" << p.x() << ", " << p.y() << ", " << p.z()
         << ") m lies inside obstacle '" << inside->name << "': no posture reaches it";
    notes.push_back(note.str());
  }
  // No arm this tool drives reaches 20 m: places that far are most likely lengths written in
  // millimetres, which the parser cannot tell from metres.
  constexpr double kFar = 20.0;
  double farthest = 0.0;
  std::string where;
  const auto consider = [&](const Eigen::Vector3d& p, const std::string& what) {
    if (p.norm() > farthest) {
      farthest = p.norm();
      where = what;
    }
  };
  for (const Obstacle& obstacle : scene.obstacles) consider(obstacle.X_WO.translation(), "obstacle '" + obstacle.name + "'");
  for (const Area& area : scene.training_areas) consider(area.p_WA, "training area '" + area.name + "'");
  for (const Area& area : scene.working_areas) consider(area.p_WA, "working area '" + area.name + "'");
  for (const Trajectory& trajectory : scene.trajectories) {
    for (const Eigen::Vector3d& p : trajectory.waypoints) consider(p, "trajectory '" + trajectory.name + "'");
  }
  if (scene.grid) {
    consider(scene.grid->lower, "the grid");
    consider(scene.grid->upper, "the grid");
  }
  if (farthest > kFar) {
    std::ostringstream note;
    note << std::fixed << std::setprecision(0) << where << " lies " << farthest
         << " m from the robot's base; lengths are read in metres (was the scene written in millimetres?)";
    notes.push_back(note.str());
  }
  // An area reaching farther than any arm this tool drives, wherever its centre, hides the arm
  // in the view and holds the whole workspace: centimetres or millimetres read as metres.
  constexpr double kWiderThanAnyArm = 3.0;
  const auto noteWide = [&](const Area& area, const char* kind) {
    const double extent = area.box ? 0.5 * area.box->norm() : area.radius;
    if (!(extent > kWiderThanAnyArm)) return;
    std::ostringstream note;
    note << std::fixed << std::setprecision(extent < 10.0 ? 1 : 0) << kind << " '" << area.name << "' reaches " << extent
         << " m from its centre; lengths are read in metres (was the scene written in "
         << (extent > kFar ? "millimetres" : "centimetres or millimetres") << "?)";
    notes.push_back(note.str());
  };
  // A spacing as wide as the grid leaves a handful of targets: `eval reachable` would measure
  // little, or refuse for want of a target, long after the scene was written.
  if (scene.grid && scene.grid->pointCount() < 8.0) {
    std::ostringstream note;
    note << "the grid holds " << scene.grid->pointCount() << (scene.grid->pointCount() == 1.0 ? " point" : " points")
         << " (spacing " << scene.grid->spacing << " m); lengths are read in metres (was 'spacing' written in centimetres?)";
    notes.push_back(note.str());
  }
  if (!scene.ignored_parameters.empty()) {
    std::string names;
    for (const std::string& name : scene.ignored_parameters) names += (names.empty() ? "'" : ", '") + printable(name) + "'";
    notes.push_back((scene.ignored_parameters.size() == 1 ? "parameter " + names + " is not one" : "parameters " + names + " are not ones") +
                    " a scene sets; left out, as programs did when this copy was stored");
  }
  for (const Area& area : scene.training_areas) noteWide(area, "training area");
  for (const Area& area : scene.working_areas) noteWide(area, "working area");
  return notes;
}

}  // namespace flexirob::robot
