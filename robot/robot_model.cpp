#include "robot/robot_model.hpp"

#include <Eigen/Eigenvalues>
#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <optional>
#include <sstream>
#include <vector>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace fs = std::filesystem;

const char* toString(JointType type) {
  switch (type) {
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
  }
  return "unknown";
}

namespace {

// Files larger than this are refused before parsing: a URDF of a real arm is a few hundred kB.
constexpr std::uintmax_t kMaxUrdfBytes = 64ULL * 1024 * 1024;
// Far beyond any real arm; keeps absurd descriptions from exhausting memory in later stages.
constexpr std::size_t kMaxLinks = 10000;
// Beyond these a description is not of a robot arm (or is in millimetres): its numbers would
// fill the joint panel and put the arm out of every view.
constexpr double kLongestJointOffset = 100.0;  // [m] joint origin from its parent, prismatic travel
constexpr double kWidestJointTurn = 1000.0;    // [rad] revolute limits (159 turns)

// urdfdom reports parse errors through console_bridge; keep the first error as our reason and
// keep the library from printing anything itself.
class ErrorCollector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error.empty()) first_error = text;
  }
  std::string first_error;
};

// XML nesting deeper than this is refused before urdfdom sees it: its XML parser descends
// recursively and overflows the stack on a few hundred thousand nested elements (a real URDF
// nests 5 deep: robot/link/visual/geometry/mesh).
constexpr int kMaxXmlDepth = 100;
// Elements in the whole document (a 10000-link arm with visuals, collisions and inertials has
// well under this); bounds urdfdom's work and memory on absurd files.
constexpr std::size_t kMaxXmlElements = 1'000'000;

// Whether the start tag xml[begin, end) (from '<' to before '>') reads as a name followed by
// name="value" pairs: urdfdom's XML errors name no place, so a failed parse is located with this.
bool startTagWellFormed(const std::string& xml, std::size_t begin, std::size_t end) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  std::size_t k = begin + 1;
  while (k < end && !space(xml[k]) && xml[k] != '/') ++k;
  if (k == begin + 1) return false;  // no element name
  while (true) {
    while (k < end && space(xml[k])) ++k;
    if (k >= end || (xml[k] == '/' && k + 1 == end)) return true;
    const std::size_t name_begin = k;
    while (k < end && !space(xml[k]) && xml[k] != '=' && xml[k] != '/' && xml[k] != '"' && xml[k] != '\'') ++k;
    if (k == name_begin) return false;
    while (k < end && space(xml[k])) ++k;
    if (k >= end || xml[k] != '=') return false;
    ++k;
    while (k < end && space(xml[k])) ++k;
    if (k >= end || (xml[k] != '"' && xml[k] != '\'')) return false;
    const std::size_t close = xml.find(xml[k], k + 1);
    if (close == std::string::npos || close >= end) return false;
    k = close + 1;
    if (k < end && !space(xml[k]) && xml[k] != '/') return false;  // a quote inside the value
  }
}

// A linear pre-scan of the XML structure: element depth and count (comments, CDATA,
// processing instructions, declarations and quoted attribute values are skipped). Whether the
// document is well formed is left to urdfdom; returns the line of the first start tag whose
// attributes do not read (0: none), for urdfdom's error to name a place.
std::size_t checkXmlShape(const std::string& xml) {
  std::size_t first_bad_tag = std::string::npos;
  int depth = 0;
  std::size_t elements = 0;
  const auto skipPast = [&xml](std::size_t from, const char* terminator) {
    const std::size_t at = xml.find(terminator, from);
    return at == std::string::npos ? xml.size() : at + std::char_traits<char>::length(terminator);
  };
  std::size_t i = xml.find('<');
  while (i < xml.size()) {
    if (xml.compare(i, 4, "<!--") == 0) {
      i = skipPast(i + 4, "-->");
    } else if (xml.compare(i, 9, "<![CDATA[") == 0) {
      i = skipPast(i + 9, "]]>");
    } else if (xml.compare(i, 2, "<?") == 0) {
      i = skipPast(i + 2, "?>");
    } else if (xml.compare(i, 2, "<!") == 0) {
      i = skipPast(i + 2, ">");
    } else if (xml.compare(i, 2, "</") == 0) {
      --depth;
      i = skipPast(i + 2, ">");
    } else {
      // A start tag: find its end outside quoted attribute values.
      char quote = 0;
      std::size_t j = i + 1;
      for (; j < xml.size(); ++j) {
        const char c = xml[j];
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          break;
        }
      }
      if (first_bad_tag == std::string::npos && !startTagWellFormed(xml, i, std::min(j, xml.size()))) first_bad_tag = i;
      if (j >= xml.size()) break;
      if (xml[j - 1] != '/') ++depth;
      if (++elements > kMaxXmlElements) {
        throw InputError("invalid URDF: more than " + std::to_string(kMaxXmlElements) + " XML elements");
      }
      if (depth > kMaxXmlDepth) {
        throw InputError("invalid URDF: XML nested deeper than " + std::to_string(kMaxXmlDepth) + " elements");
      }
      i = j + 1;
    }
    i = xml.find('<', i);
  }
  if (first_bad_tag == std::string::npos) return 0;
  return 1 + static_cast<std::size_t>(std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(first_bad_tag), '\n'));
}

std::string oneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  return text;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond rotation(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  X.linear() = rotation.normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return X;
}

bool isFinite(const Eigen::Isometry3d& X) { return X.matrix().allFinite(); }

// A package:// URI names a ROS package; without ROS we look for a folder of that name among
// the URDF's ancestors (the usual layout pkg/urdf/robot.urdf) and in $ROS_PACKAGE_PATH.
fs::path resolveMeshUri(const std::string& uri, const fs::path& base_dir, const std::string& link) {
  const std::string package_prefix = "package://";
  const std::string file_prefix = "file://";
  std::vector<fs::path> candidates;
  std::string looked;  // where the candidates came from, for the message when none exists
  if (uri.rfind(package_prefix, 0) == 0) {
    const std::string rest = uri.substr(package_prefix.size());
    const auto slash = rest.find('/');
    if (slash == std::string::npos || slash == 0) {
      throw InputError("link '" + link + "': malformed mesh URI '" + uri + "'");
    }
    const std::string package = rest.substr(0, slash);
    const fs::path relative = rest.substr(slash + 1);
    std::error_code error;
    for (fs::path dir = fs::absolute(base_dir, error); !error && !dir.empty(); dir = dir.parent_path()) {
      if (dir.filename() == package) candidates.push_back(dir / relative);
      candidates.push_back(dir / package / relative);
      if (dir == dir.parent_path()) break;
    }
    const char* ros_path = std::getenv("ROS_PACKAGE_PATH");
    if (ros_path != nullptr) {
      std::stringstream entries(ros_path);
      for (std::string entry; std::getline(entries, entry, ':');) {
        if (!entry.empty()) candidates.push_back(fs::path(entry) / package / relative);
      }
    }
    looked = std::string(" (looked for its package folder among the URDF's parent folders and in $ROS_PACKAGE_PATH") +
             (ros_path == nullptr ? ", which is not set)" : ")");
  } else if (uri.rfind(file_prefix, 0) == 0) {
    // RFC 8089 as exporters write it: file:///abs, file://localhost/abs, %20 for a space; a
    // relative path (file://meshes/x.stl, not in the RFC) from the URDF's folder as a plain one.
    std::string path = uri.substr(file_prefix.size());
    if (path.rfind("localhost/", 0) == 0) path = path.substr(std::string("localhost").size());
    std::string decoded;
    for (std::size_t i = 0; i < path.size(); ++i) {
      if (path[i] == '%' && i + 2 < path.size() && std::isxdigit(static_cast<unsigned char>(path[i + 1])) &&
          std::isxdigit(static_cast<unsigned char>(path[i + 2]))) {
        const int byte = std::stoi(path.substr(i + 1, 2), nullptr, 16);
        // A NUL would end the path where the system reads it (x.stl%00.dae opening x.stl).
        if (byte < 0x20 || byte == 0x7f) throw InputError("link '" + link + "': mesh URI '" + printable(uri) + "' escapes a control byte");
        decoded += static_cast<char>(byte);
        i += 2;
      } else {
        decoded += path[i];
      }
    }
    const fs::path file(decoded);
    candidates.push_back(file.is_absolute() ? file : base_dir / file);
    if (decoded != path) {  // a file whose name holds a literal %
      const fs::path literal(path);
      candidates.push_back(literal.is_absolute() ? literal : base_dir / literal);
    }
    // file://host/x.stl names a file on another machine, which cannot be read here; it and a
    // relative path look alike, so where the relative one is missing the message says both.
    if (!file.is_absolute()) {
      const std::string first = decoded.substr(0, decoded.find('/'));
      looked = " (relative to the URDF's folder " + base_dir.lexically_normal().string() +
               "; if '" + printable(first) + "' is a host name: only files on this machine are read, write file:///path or file://localhost/path)";
    }
  } else if (uri.find("://") != std::string::npos) {
    throw InputError("link '" + link + "': unsupported mesh URI scheme in '" + uri + "'");
  } else {
    const fs::path path(uri);
    candidates.push_back(path.is_absolute() ? path : base_dir / path);
    if (!path.is_absolute()) looked = " (relative to the URDF's folder " + base_dir.lexically_normal().string() + ")";
  }
  for (const auto& candidate : candidates) {
    std::error_code error;
    if (fs::is_regular_file(candidate, error)) return fs::weakly_canonical(candidate);
  }
  throw InputError("link '" + link + "': mesh file '" + uri + "' not found" + looked);
}

// Where a URDF's meshes are looked for, and whether one that is not there refuses the URDF
// (left_out null) or is left out and named in left_out (a recording reviewed on a machine
// without the robot's mesh folder).
struct MeshSource {
  fs::path base_dir;
  std::vector<std::string>* left_out = nullptr;
};

Geometry toGeometry(const urdf::GeometrySharedPtr& geometry, const urdf::Pose& origin,
                    const fs::path& base_dir, const std::string& link) {
  if (!geometry) throw InputError("link '" + link + "': a visual or collision element has no geometry");
  Geometry result;
  result.X_BG = toIsometry(origin);
  result.source_link = link;
  switch (geometry->type) {
    case urdf::Geometry::SPHERE: {
      const auto& sphere = dynamic_cast<const urdf::Sphere&>(*geometry);
      result.kind = Geometry::Kind::kSphere;
      result.size = Eigen::Vector3d(sphere.radius, 0, 0);
      break;
    }
    case urdf::Geometry::BOX: {
      const auto& box = dynamic_cast<const urdf::Box&>(*geometry);
      result.kind = Geometry::Kind::kBox;
      result.size = Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z);
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cylinder = dynamic_cast<const urdf::Cylinder&>(*geometry);
      result.kind = Geometry::Kind::kCylinder;
      result.size = Eigen::Vector3d(cylinder.radius, cylinder.length, 0);
      break;
    }
    case urdf::Geometry::MESH: {
      const auto& mesh = dynamic_cast<const urdf::Mesh&>(*geometry);
      result.kind = Geometry::Kind::kMesh;
      // A zero flattens the mesh into a sheet (a negative one mirrors it, which is a shape).
      if (mesh.scale.x == 0.0 || mesh.scale.y == 0.0 || mesh.scale.z == 0.0) {
        throw InputError("link '" + link + "': mesh '" + mesh.filename + "' has a scale with a zero component");
      }
      result.mesh_file = resolveMeshUri(mesh.filename, base_dir, link);
      result.mesh_scale = Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z);
      break;
    }
  }
  if (!result.size.allFinite() || (result.size.array() < 0).any() || !result.mesh_scale.allFinite() ||
      !isFinite(result.X_BG)) {
    throw InputError("link '" + link + "': geometry with a negative or non-finite size or pose");
  }
  return result;
}

// Adds a link's own geometry and inertia to a body; X_BL is the link's pose in the body frame.
std::optional<Geometry> geometryOf(const urdf::GeometrySharedPtr& geometry, const urdf::Pose& origin,
                                   const MeshSource& meshes, const std::string& link) {
  try {
    return toGeometry(geometry, origin, meshes.base_dir, link);
  } catch (const InputError& error) {
    const bool mesh = geometry && geometry->type == urdf::Geometry::MESH;
    if (!mesh || meshes.left_out == nullptr) throw;
    meshes.left_out->push_back(error.what());
    return std::nullopt;
  }
}

void foldLinkInto(Body& body, const urdf::Link& link, const Eigen::Isometry3d& X_BL,
                  const MeshSource& meshes) {
  for (const auto& visual : link.visual_array) {
    if (!visual) continue;
    std::optional<Geometry> found = geometryOf(visual->geometry, visual->origin, meshes, link.name);
    if (!found) continue;
    Geometry& geometry = *found;
    geometry.X_BG = X_BL * geometry.X_BG;
    if (visual->material) {
      const auto& c = visual->material->color;
      geometry.rgba = Eigen::Vector4f(c.r, c.g, c.b, c.a);
    }
    body.visuals.push_back(std::move(geometry));
  }
  for (const auto& collision : link.collision_array) {
    if (!collision) continue;
    std::optional<Geometry> found = geometryOf(collision->geometry, collision->origin, meshes, link.name);
    if (!found) continue;
    Geometry& geometry = *found;
    geometry.X_BG = X_BL * geometry.X_BG;
    body.collisions.push_back(std::move(geometry));
  }
  if (link.inertial && !(link.inertial->mass >= 0.0 && std::isfinite(link.inertial->mass))) {
    throw InputError("link '" + link.name + "': mass must be a finite, non-negative number of kg");
  }
  if (link.inertial && link.inertial->mass > 0.0) {
    const auto& inertial = *link.inertial;
    const Eigen::Isometry3d X_BC = X_BL * toIsometry(inertial.origin);
    Eigen::Matrix3d I_C;
    I_C << inertial.ixx, inertial.ixy, inertial.ixz, inertial.ixy, inertial.iyy, inertial.iyz,
        inertial.ixz, inertial.iyz, inertial.izz;
    if (!I_C.allFinite()) throw InputError("link '" + link.name + "': non-finite inertia");
    // Combine with what the body already has: common COM, then parallel-axis theorem.
    const double total_mass = body.mass + inertial.mass;
    const Eigen::Vector3d p_new = X_BC.translation();
    const Eigen::Vector3d com = (body.mass * body.p_BCom + inertial.mass * p_new) / total_mass;
    auto shifted = [](const Eigen::Matrix3d& I, double m, const Eigen::Vector3d& d) {
      return Eigen::Matrix3d(I + m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
    };
    const Eigen::Matrix3d I_new_B = X_BC.linear() * I_C * X_BC.linear().transpose();
    body.I_BCom = shifted(body.I_BCom, body.mass, body.p_BCom - com) + shifted(I_new_B, inertial.mass, p_new - com);
    body.p_BCom = com;
    body.mass = total_mass;
  }
}

// Kinematics-only URDFs leave out <inertial>. A moving body without mass would make the
// simulated joints (stiffness and damping tuned for the LWR IV's kilograms) numerically stiff
// beyond any time step, and the gravity model would see nothing to hold. Such a body is given
// kAssumedMass at the middle of its link (from its joint to the next joint, or to the tip),
// with the inertia of a solid sphere spanning that link.
void assumeInertiaOfMasslessBodies(std::vector<Body>& bodies, const std::vector<Joint>& joints,
                                   const Eigen::Isometry3d& X_last_body_tip) {
  for (std::size_t b = 1; b < bodies.size(); ++b) {
    Body& body = bodies[b];
    if (body.mass > 0.0) continue;
    const Eigen::Vector3d link_end = b < joints.size() ? joints[b].X_PJ.translation() : X_last_body_tip.translation();
    const double radius = std::max(kAssumedMinRadius, 0.5 * link_end.norm());
    body.mass = kAssumedMass;
    body.p_BCom = 0.5 * link_end;
    body.I_BCom = 0.4 * kAssumedMass * radius * radius * Eigen::Matrix3d::Identity();
    body.inertia_assumed = true;
  }
}

// urdfdom links a joint's child to its parent without checking that the joints form a tree: a
// link can be the child of two joints, and joints can form a cycle away from the root. Every
// walk below (up to the root, down through fixed joints) assumes a tree, so check it first:
// every link's children name it as their parent, and every chain of parents ends.
void checkTree(const urdf::ModelInterface& model) {
  std::set<const urdf::Link*> ends_at_a_root;
  for (const auto& [name, link] : model.links_) {
    for (const auto& child : link->child_links) {
      if (child->getParent().get() != link.get()) {
        throw InputError("invalid URDF: link '" + child->name + "' is the child of more than one joint");
      }
    }
    std::vector<const urdf::Link*> chain;
    for (const urdf::Link* l = link.get(); l != nullptr && ends_at_a_root.count(l) == 0; l = l->getParent().get()) {
      if (chain.size() > model.links_.size()) {
        throw InputError("invalid URDF: the joints above link '" + name + "' form a cycle");
      }
      chain.push_back(l);
      if (!l->parent_joint) break;
    }
    ends_at_a_root.insert(chain.begin(), chain.end());
  }
}

int countMovable(const urdf::Link* link) {
  int count = 0;
  for (; link != nullptr && link->parent_joint; link = link->getParent().get()) {
    if (link->parent_joint->type != urdf::Joint::FIXED) ++count;
  }
  return count;
}

int countDepth(const urdf::Link* link) {
  int depth = 0;
  for (; link != nullptr && link->parent_joint; link = link->getParent().get()) ++depth;
  return depth;
}

// The default tip: the leaf with the most movable joints above it; among equals the deepest
// (so a flange or tool frame after the last joint wins). Equally long chains that part only
// for up to three joints at their ends (a knuckle, a finger, a pad), below an arm of more joints,
// are a hand's fingers: the tip is the link they branch from, said in `note`. Other chains of equal length are ambiguous (two
// arms on a torso): the description is not a serial arm unless a tip is named.
std::string defaultTip(const urdf::ModelInterface& model, std::string& note) {
  const urdf::Link* best = nullptr;
  int best_movable = -1;
  int best_depth = -1;
  std::vector<const urdf::Link*> tied;
  for (const auto& [name, link] : model.links_) {
    if (!link->child_links.empty()) continue;
    const int movable = countMovable(link.get());
    const int depth = countDepth(link.get());
    if (movable > best_movable || (movable == best_movable && depth > best_depth)) {
      best = link.get();
      best_movable = movable;
      best_depth = depth;
      tied = {best};
    } else if (movable == best_movable && depth == best_depth && movable > 0) {
      tied.push_back(link.get());
    }
  }
  if (best == nullptr) throw InputError("the URDF has no links");
  if (best_movable <= 0) throw InputError("the URDF has no movable joint between its root and any leaf");
  if (tied.size() == 1) return best->name;
  const auto below = [](const urdf::Link* ancestor, const urdf::Link* link) {
    for (; link != nullptr; link = link->getParent().get()) {
      if (link == ancestor) return true;
    }
    return false;
  };
  const urdf::Link* branch = best->getParent().get();
  while (branch != nullptr && !std::all_of(tied.begin(), tied.end(), [&](const urdf::Link* leaf) { return below(branch, leaf); })) {
    branch = branch->getParent().get();
  }
  constexpr int kMaxFingerJoints = 3;
  const int arm_joints = countMovable(branch);
  const int finger_joints = best_movable - arm_joints;
  if (branch != nullptr && finger_joints <= kMaxFingerJoints && arm_joints > finger_joints) {
    std::string fingers;
    for (const urdf::Link* leaf : tied) fingers += (fingers.empty() ? "'" : ", '") + leaf->name + "'";
    note = "the longest chains end in " + fingers + ", which branch at '" + branch->name +
           "' (a gripper's fingers?): the tip is '" + branch->name + "', the fingers move with it (--tip names another tip)";
    return branch->name;
  }
  // A hand of longer fingers still ends the arm where they part, which the user may name.
  const std::string hand = branch != nullptr && arm_joints > 0 ? " (--tip " + branch->name + " ends the chain where they part)" : "";
  throw InputError("not a serial chain: the chains to '" + tied[0]->name + "' and '" + tied[1]->name +
                   "' are equally long; choose the tip with --tip" + hand);
}

// The motion of an off-chain joint held still: at 0, or at the limit nearest to 0 when 0 lies
// outside its range. Floating and planar joints are held at their origin.
Eigen::Isometry3d heldJointMotion(const urdf::Joint& joint) {
  const bool revolute = joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS;
  if (!revolute && joint.type != urdf::Joint::PRISMATIC) return Eigen::Isometry3d::Identity();
  double value = 0.0;
  if (joint.type != urdf::Joint::CONTINUOUS && joint.limits && std::isfinite(joint.limits->lower) &&
      std::isfinite(joint.limits->upper) && joint.limits->lower <= joint.limits->upper) {
    value = std::clamp(0.0, joint.limits->lower, joint.limits->upper);
  }
  const Eigen::Vector3d axis(joint.axis.x, joint.axis.y, joint.axis.z);
  if (value == 0.0 || !axis.allFinite() || axis.norm() < 1e-9) return Eigen::Isometry3d::Identity();
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  if (revolute) {
    motion.linear() = Eigen::AngleAxisd(value, axis.normalized()).toRotationMatrix();
  } else {
    motion.translation() = value * axis.normalized();
  }
  return motion;
}

// Links hanging off `link`, except `skip` (the next chain link), join the body: through fixed
// joints as the URDF means them, through movable joints off the chain (a gripper's fingers, the
// links past a --tip inside the chain) held still, so that they are still drawn, weighed and
// collided with instead of vanishing from the model.
void foldSubtree(Body& body, const urdf::Link& link, const Eigen::Isometry3d& X_BL, const urdf::Link* skip,
                 const MeshSource& meshes) {
  for (const auto& child : link.child_links) {
    if (child.get() == skip || !child->parent_joint) continue;
    const urdf::Joint& joint = *child->parent_joint;
    const Eigen::Isometry3d X_BC = X_BL * toIsometry(joint.parent_to_joint_origin_transform) * heldJointMotion(joint);
    if (!isFinite(X_BC)) throw InputError("joint '" + joint.name + "': non-finite origin");
    foldLinkInto(body, *child, X_BC, meshes);
    body.folded_links.push_back(child->name);
    if (joint.type != urdf::Joint::FIXED) body.held_links.push_back(child->name);
    foldSubtree(body, *child, X_BC, nullptr, meshes);
  }
}

}  // namespace

RobotModel RobotModel::fromUrdfFile(const fs::path& urdf_file, const std::string& tip_link) {
  std::error_code error;
  if (!fs::is_regular_file(urdf_file, error)) throw InputError("cannot read URDF '" + urdf_file.string() + "'");
  if (fs::file_size(urdf_file, error) > kMaxUrdfBytes) {
    throw InputError("URDF '" + urdf_file.string() + "' is larger than 64 MB");
  }
  std::ifstream stream(urdf_file, std::ios::binary);
  if (!stream) throw InputError("cannot open URDF '" + urdf_file.string() + "'");
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  try {
    RobotModel model = fromUrdfString(buffer.str(), fs::absolute(urdf_file).parent_path(), tip_link);
    model.urdf_path_ = fs::weakly_canonical(fs::absolute(urdf_file));
    return model;
  } catch (const InputError& refused) {
    // A scene's `robot:` may name any file: the message says which one did not read.
    const std::string what = refused.what();
    if (what.find(urdf_file.string()) != std::string::npos) throw;
    throw InputError(printable(urdf_file.string(), 200) + ": " + what);
  }
}

RobotModel RobotModel::fromUrdfString(const std::string& xml, const fs::path& base_dir,
                                      const std::string& tip_link, std::vector<std::string>* left_out_meshes) {
  const MeshSource meshes{base_dir, left_out_meshes};
  if (xml.size() > kMaxUrdfBytes) throw InputError("URDF is larger than 64 MB");
  const std::size_t bad_tag_line = checkXmlShape(xml);
  ErrorCollector collector;
  console_bridge::OutputHandler* previous = console_bridge::getOutputHandler();
  console_bridge::useOutputHandler(&collector);
  urdf::ModelInterfaceSharedPtr urdf_model;
  try {
    urdf_model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    collector.first_error = collector.first_error.empty() ? e.what() : collector.first_error;
  }
  console_bridge::useOutputHandler(previous);
  if (!urdf_model) {
    // TinyXML calls a document without any element "empty", also when it holds text.
    if (collector.first_error.find("Error document empty") != std::string::npos &&
        xml.find_first_not_of(" \t\r\n") != std::string::npos) {
      throw InputError("invalid URDF: no XML element in the file (a URDF is XML with a <robot> element)");
    }
    const std::string reason = collector.first_error.empty() ? "malformed XML" : oneLine(collector.first_error);
    // TinyXML's own errors ("Error reading Attributes", "Error parsing Element") name no place;
    // urdfdom's about what the document means do, by the joint or link.
    const bool xml_error = collector.first_error.rfind("Error", 0) == 0;
    throw InputError("invalid URDF: " + reason +
                     (xml_error && bad_tag_line > 0 ? " (the first malformed tag is on line " + std::to_string(bad_tag_line) + ")" : ""));
  }
  if (urdf_model->links_.size() > kMaxLinks) throw InputError("URDF has more than 10000 links");
  try {
    checkTree(*urdf_model);
  } catch (const InputError&) {
    // Links own their children through shared pointers, so a cycle would keep itself alive
    // (a leak per refused file): drop the child lists before the model goes.
    for (auto& [name, link] : urdf_model->links_) {
      link->child_links.clear();
      link->child_joints.clear();
    }
    throw;
  }
  const urdf::LinkConstSharedPtr root = urdf_model->getRoot();
  if (!root) throw InputError("invalid URDF: no root link");

  // The chain, from the tip up to the root.
  std::string tip_note;
  const std::string tip = tip_link.empty() ? defaultTip(*urdf_model, tip_note) : tip_link;
  const urdf::LinkConstSharedPtr tip_ptr = urdf_model->getLink(tip);
  if (!tip_ptr) throw InputError("tip link '" + tip + "' is not in the URDF");
  std::vector<const urdf::Link*> path;  // root ... tip
  for (const urdf::Link* link = tip_ptr.get(); link != nullptr; link = link->getParent().get()) {
    path.push_back(link);
    if (path.size() > kMaxLinks) throw InputError("invalid URDF: the chain to the tip does not end at a root");
  }
  std::reverse(path.begin(), path.end());
  if (path.front() != root.get()) throw InputError("invalid URDF: the tip is not connected to the root link");

  RobotModel model;
  model.name_ = urdf_model->getName();
  model.tip_link_ = tip;
  if (!tip_note.empty()) model.notes_.push_back(tip_note);
  model.bodies_.emplace_back();
  model.bodies_.back().name = root->name;
  foldLinkInto(model.bodies_.back(), *root, Eigen::Isometry3d::Identity(), meshes);

  // Walk down the chain. X_BL: pose of the current link in the current body frame.
  Eigen::Isometry3d X_BL = Eigen::Isometry3d::Identity();
  for (std::size_t i = 1; i < path.size(); ++i) {
    const urdf::Link& link = *path[i];
    const urdf::Joint& joint = *link.parent_joint;
    const Eigen::Isometry3d X_PJ = X_BL * toIsometry(joint.parent_to_joint_origin_transform);
    if (!isFinite(X_PJ)) throw InputError("joint '" + joint.name + "': non-finite origin");
    const urdf::Vector3& offset = joint.parent_to_joint_origin_transform.position;
    if (const double reach = std::sqrt(offset.x * offset.x + offset.y * offset.y + offset.z * offset.z); reach > kLongestJointOffset) {
      std::ostringstream message;
      message << "joint '" << joint.name << "': origin " << reach << " m from its parent link, beyond "
              << kLongestJointOffset << " m (a URDF is in metres)";
      throw InputError(message.str());
    }
    // Side-branches of the previous chain link belong to the current body.
    foldSubtree(model.bodies_.back(), *path[i - 1], X_BL, &link, meshes);
    if (joint.type == urdf::Joint::FIXED) {
      X_BL = X_PJ;
      foldLinkInto(model.bodies_.back(), link, X_BL, meshes);
      model.bodies_.back().folded_links.push_back(link.name);
      continue;
    }
    Joint model_joint;
    model_joint.name = joint.name;
    model_joint.X_PJ = X_PJ;
    switch (joint.type) {
      case urdf::Joint::REVOLUTE: model_joint.type = JointType::kRevolute; break;
      case urdf::Joint::CONTINUOUS: model_joint.type = JointType::kContinuous; break;
      case urdf::Joint::PRISMATIC: model_joint.type = JointType::kPrismatic; break;
      case urdf::Joint::FLOATING:
        throw InputError("joint '" + joint.name + "': floating joints are not supported on the chain");
      case urdf::Joint::PLANAR:
        throw InputError("joint '" + joint.name + "': planar joints are not supported on the chain");
      default: throw InputError("joint '" + joint.name + "': unknown joint type");
    }
    if (joint.mimic) {
      throw InputError("joint '" + joint.name + "': mimic joints are not supported on the chain to the tip '" + tip +
                       "' (a gripper's finger?); name the arm's last link with --tip, e.g. --tip " + joint.parent_link_name);
    }
    const Eigen::Vector3d axis(joint.axis.x, joint.axis.y, joint.axis.z);
    if (!axis.allFinite() || axis.norm() < 1e-9) throw InputError("joint '" + joint.name + "': zero or non-finite axis");
    model_joint.axis_J = axis.normalized();
    JointLimits& limits = model_joint.limits;
    if (model_joint.type == JointType::kContinuous) {
      limits.lower = -std::numeric_limits<double>::infinity();
      limits.upper = std::numeric_limits<double>::infinity();
    } else {
      if (!joint.limits) throw InputError("joint '" + joint.name + "': no <limit> element");
      limits.lower = joint.limits->lower;
      limits.upper = joint.limits->upper;
      if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper) || limits.lower > limits.upper) {
        throw InputError("joint '" + joint.name + "': expected finite limits with lower <= upper");
      }
      const bool sliding = model_joint.type == JointType::kPrismatic;
      const double widest = sliding ? kLongestJointOffset : kWidestJointTurn;
      if (std::max(std::abs(limits.lower), std::abs(limits.upper)) > widest) {
        std::ostringstream message;
        message << "joint '" << joint.name << "': limits [" << limits.lower << ", " << limits.upper << "] beyond ±" << widest
                << (sliding ? " m" : " rad; a joint that turns without end is of type 'continuous'");
        throw InputError(message.str());
      }
    }
    limits.soft_lower = limits.lower;
    limits.soft_upper = limits.upper;
    if (joint.safety && model_joint.type != JointType::kContinuous) {
      const double soft_lower = joint.safety->soft_lower_limit;
      const double soft_upper = joint.safety->soft_upper_limit;
      // urdfdom defaults both to 0 when absent; only a proper interval narrows the limits, and
      // an inverted one is a mistake in the file, not a wish to ignore it.
      if (soft_lower > soft_upper) {
        throw InputError("joint '" + joint.name + "': <safety_controller> soft_lower_limit lies above soft_upper_limit");
      }
      if (std::isfinite(soft_lower) && std::isfinite(soft_upper) && soft_lower < soft_upper) {
        // A software range that misses the hardware range leaves no posture the joint may take.
        if (soft_lower > limits.upper || soft_upper < limits.lower) {
          throw InputError("joint '" + joint.name + "': <safety_controller> soft limits lie outside its <limit>");
        }
        limits.soft_lower = std::max(limits.lower, soft_lower);
        limits.soft_upper = std::min(limits.upper, soft_upper);
      }
    }
    if (joint.limits) {
      limits.velocity = joint.limits->velocity;
      limits.effort = joint.limits->effort;
    }
    if (!std::isfinite(limits.velocity) || limits.velocity < 0 || !std::isfinite(limits.effort) || limits.effort < 0) {
      throw InputError("joint '" + joint.name + "': expected finite, non-negative velocity and effort limits");
    }
    limits.velocity_from_urdf = limits.velocity > 0.0;
    if (!limits.velocity_from_urdf) limits.velocity = kUnspecifiedVelocityLimit;
    if (joint.dynamics) {
      model_joint.damping = joint.dynamics->damping;
      model_joint.friction = joint.dynamics->friction;
    }
    model.joints_.push_back(model_joint);
    model.bodies_.emplace_back();
    model.bodies_.back().name = link.name;
    X_BL = Eigen::Isometry3d::Identity();
    foldLinkInto(model.bodies_.back(), link, X_BL, meshes);
  }
  // What hangs off the tip (tools, sensors, links past a tip inside the chain) moves with the last body.
  foldSubtree(model.bodies_.back(), *path.back(), X_BL, nullptr, meshes);
  model.X_last_body_tip_ = X_BL;
  if (model.joints_.empty()) throw InputError("no movable joint between root '" + root->name + "' and tip '" + tip + "'");
  // The longest chain of an arm with a gripper can end in a finger: its slide would become a
  // joint of the arm, redundant to the tip task, without a word.
  if (tip_link.empty() && model.joints_.back().type == JointType::kPrismatic) {
    const urdf::Joint* last_movable = nullptr;
    for (std::size_t i = path.size() - 1; i > 0 && last_movable == nullptr; --i) {
      if (path[i]->parent_joint->type != urdf::Joint::FIXED) last_movable = path[i]->parent_joint.get();
    }
    const urdf::Link* hand = last_movable != nullptr ? urdf_model->getLink(last_movable->parent_link_name).get() : nullptr;
    if (hand != nullptr && hand->child_links.size() > 1) {
      model.notes_.push_back("the tip is '" + tip + "', the end of the longest chain, past the slide '" + last_movable->name +
                                "' where '" + hand->name + "' branches (a gripper's finger?): the slide is a joint of the arm; " +
                                "--tip " + hand->name + " ends the arm before it");
    }
  }
  // A link drawn but given no collision element is often meant to touch nothing; the collision
  // world stands a capsule between its joints in for it, and contacts then name it.
  for (std::size_t b = 1; b < model.bodies_.size(); ++b) {
    const Body& body = model.bodies_[b];
    if (!body.collisions.empty() || body.visuals.empty()) continue;
    std::string drawn;  // the links whose visuals the body carries
    for (const Geometry& visual : body.visuals) {
      if (drawn.find("'" + visual.source_link + "'") == std::string::npos) drawn += (drawn.empty() ? "'" : ", '") + visual.source_link + "'";
    }
    model.notes_.push_back("link " + drawn + " has a visual but no collision element: a capsule along '" + body.name +
                           "' stands in for it in contacts and clearances");
  }
  // Scenes put the URDF's root at their origin and the table top at its z = 0. A cell's URDF
  // often mounts the arm on a stand from a bare `world` root: the arm then stands that high
  // over the table, which is right for a pedestal and a surprise otherwise.
  {
    Eigen::Isometry3d X_RL = Eigen::Isometry3d::Identity();
    for (std::size_t i = 0; i < path.size(); ++i) {
      const urdf::Link* link = path[i];
      if (i > 0) {
        if (link->parent_joint->type != urdf::Joint::FIXED) break;
        X_RL = X_RL * toIsometry(link->parent_joint->parent_to_joint_origin_transform);
      }
      if (link->visual_array.empty() && link->collision_array.empty() && !link->visual && !link->collision) continue;
      if (i > 0 && std::abs(X_RL.translation().z()) > 0.05) {
        std::ostringstream line;
        line << std::fixed << std::setprecision(2) << "the URDF's root '" << root->name << "' holds '" << link->name << "' "
             << std::abs(X_RL.translation().z()) << " m " << (X_RL.translation().z() > 0.0 ? "above" : "below")
             << " its origin, where a scene's table top (z = 0) lies: the arm is mounted there in every scene "
                "(a scene's `table: false` where nothing stands at z = 0)";
        model.notes_.push_back(line.str());
      }
      break;
    }
  }
  // URDFs written for kinematics give 0 where they mean "not given"; a robot would not move at
  // all with those limits, so 0 is read as none, and the author should know that.
  std::string no_effort;
  std::string no_velocity;
  for (const Joint& joint : model.joints_) {
    const urdf::JointConstSharedPtr urdf_joint = urdf_model->getJoint(joint.name);
    if (!urdf_joint || !urdf_joint->limits) continue;
    if (urdf_joint->limits->effort == 0.0) no_effort += (no_effort.empty() ? "'" : ", '") + joint.name + "'";
    if (urdf_joint->limits->velocity == 0.0) no_velocity += (no_velocity.empty() ? "'" : ", '") + joint.name + "'";
  }
  const auto joints = [](const std::string& names) {
    return names.find(',') == std::string::npos ? "joint " + names + " gives" : "joints " + names + " give";
  };
  // A revolute joint turning more than two turns each way is rare (multi-turn wrists allow ±2π);
  // ±110 is a range in degrees read as radians, which lets the arm through itself.
  std::string beyond_turns;
  for (const Joint& joint : model.joints_) {
    if (joint.type != JointType::kRevolute) continue;
    if (std::max(std::abs(joint.limits.lower), std::abs(joint.limits.upper)) > 4.0 * std::numbers::pi + 1e-6) {
      std::ostringstream range;
      range << "'" << joint.name << "' [" << joint.limits.lower << ", " << joint.limits.upper << "]";
      beyond_turns += (beyond_turns.empty() ? "" : ", ") + range.str();
    }
  }
  // Equal limits are how some exports write a joint locked in place: it is kept as a joint (the
  // posture vector keeps its length) that no controller can move, which is worth saying once.
  std::string locked;
  for (const Joint& joint : model.joints_) {
    if (joint.type == JointType::kContinuous || joint.limits.lower != joint.limits.upper) continue;
    std::ostringstream at;
    at << "'" << joint.name << "' at " << joint.limits.lower;
    locked += (locked.empty() ? "" : ", ") + at.str();
  }
  if (!locked.empty()) {
    model.notes_.push_back("equal lower and upper limits lock " + std::string(locked.find(',') == std::string::npos ? "joint " : "joints ") +
                           locked + " in place (rad, m for a slide): such a joint keeps its place in the posture but never moves; type=\"fixed\" removes it");
  }
  if (!beyond_turns.empty()) {
    model.notes_.push_back("revolute joint limits beyond two turns either way, " + beyond_turns +
                           " rad: URDF limits are radians (written in degrees?)");
  }
  if (!no_effort.empty()) {
    model.notes_.push_back(joints(no_effort) + " <limit effort=\"0\">: read as no effort limit (the simulated joint "
                           "is not saturated, and no posture counts as too heavy for it)");
  }
  if (!no_velocity.empty()) {
    std::ostringstream assumed;
    assumed << kUnspecifiedVelocityLimit;
    model.notes_.push_back(joints(no_velocity) + " <limit velocity=\"0\">: read as not given, " + assumed.str() +
                           " rad/s (m/s for a slide)");
  }
  // Bullet takes a link's principal moments as they are; a set no solid body has (one larger than
  // the other two together, or one below zero, which the simulation clamps) moves unlike any link.
  for (const auto& [name, link] : urdf_model->links_) {
    if (!link || !link->inertial || !(link->inertial->mass > 0.0)) continue;
    const urdf::Inertial& inertial = *link->inertial;
    Eigen::Matrix3d I_C;
    I_C << inertial.ixx, inertial.ixy, inertial.ixz, inertial.ixy, inertial.iyy, inertial.iyz, inertial.ixz, inertial.iyz,
        inertial.izz;
    if (!I_C.allFinite()) continue;
    const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I_C, Eigen::EigenvaluesOnly).eigenvalues();
    // 1 % of the largest moment: CAD exports round to a few digits, and a flat plate's moments
    // meet the inequality exactly.
    const double slack = 1e-2 * moments.cwiseAbs().maxCoeff();
    if (moments.minCoeff() >= -slack && moments(0) + moments(1) >= moments(2) - slack) continue;
    std::ostringstream line;
    line << "link '" << name << "' has an inertia no solid body has (principal moments " << std::setprecision(3)
         << moments(0) << ", " << moments(1) << ", " << moments(2) << " kg m^2: "
         << (moments.minCoeff() < -slack ? "one below zero" : "the largest above the sum of the other two")
         << "); the simulated link may move unlike a real one, its <inertia> is worth a check";
    model.notes_.push_back(line.str());
  }
  // A kinematics-only URDF (no masses at all) is simulated with the assumed masses as documented;
  // one that gives the other links' masses (0.4 kg each, say) meant something else by mass 0.
  const bool some_given = model.bodies_.size() > 1 && std::any_of(model.bodies_.begin() + 1, model.bodies_.end(), [](const Body& body) { return body.mass > 0.0; });
  assumeInertiaOfMasslessBodies(model.bodies_, model.joints_, model.X_last_body_tip_);
  std::string massless;
  for (const Body& body : model.bodies_) {
    if (body.inertia_assumed) massless += (massless.empty() ? "'" : ", '") + body.name + "'";
  }
  if (some_given && !massless.empty()) {
    std::ostringstream line;
    const bool one = massless.find(',') == std::string::npos;
    line << (one ? "moving body " : "moving bodies ") << massless << (one ? " gives" : " give")
         << " no mass (no <inertial>, or mass 0): each is simulated as " << kAssumedMass
         << " kg at the middle of its link; give the links' masses for a simulation that moves like the arm";
    model.notes_.push_back(line.str());
  }
  return model;
}

namespace {
template <typename Getter>
Eigen::VectorXd collect(const std::vector<Joint>& joints, Getter getter) {
  Eigen::VectorXd values(static_cast<Eigen::Index>(joints.size()));
  for (std::size_t i = 0; i < joints.size(); ++i) values[static_cast<Eigen::Index>(i)] = getter(joints[i].limits);
  return values;
}
}  // namespace

Eigen::VectorXd RobotModel::lowerLimits() const { return collect(joints_, [](const JointLimits& l) { return l.lower; }); }
Eigen::VectorXd RobotModel::upperLimits() const { return collect(joints_, [](const JointLimits& l) { return l.upper; }); }
Eigen::VectorXd RobotModel::softLowerLimits() const { return collect(joints_, [](const JointLimits& l) { return l.soft_lower; }); }
Eigen::VectorXd RobotModel::softUpperLimits() const { return collect(joints_, [](const JointLimits& l) { return l.soft_upper; }); }
Eigen::VectorXd RobotModel::velocityLimits() const { return collect(joints_, [](const JointLimits& l) { return l.velocity; }); }

Eigen::VectorXd RobotModel::sampleLowerLimits() const {
  return collect(joints_, [](const JointLimits& l) { return std::isfinite(l.soft_lower) ? l.soft_lower : -std::numbers::pi; });
}
Eigen::VectorXd RobotModel::sampleUpperLimits() const {
  return collect(joints_, [](const JointLimits& l) { return std::isfinite(l.soft_upper) ? l.soft_upper : std::numbers::pi; });
}

Eigen::VectorXd RobotModel::midPosture() const { return 0.5 * (sampleLowerLimits() + sampleUpperLimits()); }

void RobotModel::postureDifference(const Eigen::VectorXd& to, const Eigen::VectorXd& from, Eigen::VectorXd& difference) const {
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    const double delta = to[i] - from[i];
    difference[i] = joints_[j].type == JointType::kContinuous ? std::remainder(delta, 2.0 * std::numbers::pi) : delta;
  }
}

Eigen::VectorXd RobotModel::postureDifference(const Eigen::VectorXd& to, const Eigen::VectorXd& from) const {
  Eigen::VectorXd difference(dof());
  postureDifference(to, from, difference);
  return difference;
}

Eigen::VectorXd RobotModel::withinOneTurn(Eigen::VectorXd q) const {
  for (std::size_t j = 0; j < joints_.size() && static_cast<Eigen::Index>(j) < q.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    if (joints_[j].type == JointType::kContinuous && std::isfinite(q[i])) q[i] = std::remainder(q[i], 2.0 * std::numbers::pi);
  }
  return q;
}

void RobotModel::checkWithinLimits(const Eigen::VectorXd& q, const std::string& what, double overshoot_rad,
                                   double overshoot_m) const {
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    const JointLimits& limits = joints_[j].limits;
    const double overshoot = joints_[j].type == JointType::kPrismatic ? overshoot_m : overshoot_rad;
    const double value = q[static_cast<Eigen::Index>(j)];
    if (value >= limits.lower - overshoot && value <= limits.upper + overshoot) continue;
    std::ostringstream message;
    message << std::setprecision(4) << what << ": joint " << j + 1 << " (" << joints_[j].name << ") at " << value
            << " lies outside its limits [" << limits.lower << ", " << limits.upper << "]";
    throw InputError(message.str());
  }
}

void RobotModel::checkPosture(const Eigen::VectorXd& q) const {
  if (q.size() != dof()) {
    throw InputError("expected " + std::to_string(dof()) + " joint values, got " + std::to_string(q.size()));
  }
  if (!q.allFinite()) throw InputError("joint values must be finite numbers");
}

}  // namespace flexirob::robot
