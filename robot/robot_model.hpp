#pragma once
// The immutable kinematic and inertial description of a serial arm, built once from a URDF.
//
// Frames: the base frame W is the URDF's root link; body 0 is the base, body i (1..N) is the
// child link of the i-th movable joint on the chain from the root to the tip, with every link
// attached to it through fixed joints folded in (their geometry and inertia move with it).
// Units: metres, radians, kilograms, seconds.
#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

namespace flexirob::robot {

enum class JointType { kRevolute, kContinuous, kPrismatic };

const char* toString(JointType type);

/// The velocity limit of a joint whose URDF gives none or 0 (a common placeholder): the
/// joint would otherwise never move, and the controllers and the FRI checks need one figure.
inline constexpr double kUnspecifiedVelocityLimit = 1.0;  // [rad/s or m/s]

struct JointLimits {
  double lower = 0.0;       ///< hardware position limit [rad or m]; -inf for continuous joints
  double upper = 0.0;       ///< hardware position limit [rad or m]; +inf for continuous joints
  double soft_lower = 0.0;  ///< software limit (URDF <safety_controller>), else = lower
  double soft_upper = 0.0;  ///< software limit (URDF <safety_controller>), else = upper
  double velocity = 0.0;    ///< [rad/s or m/s]; kUnspecifiedVelocityLimit where the URDF gives 0 or none
  bool velocity_from_urdf = false;  ///< false: the URDF gave no positive velocity limit
  double effort = 0.0;      ///< [Nm or N]
};

/// A visual or collision shape fixed to a body.
struct Geometry {
  enum class Kind { kMesh, kBox, kCylinder, kSphere };
  Kind kind = Kind::kBox;
  Eigen::Isometry3d X_BG = Eigen::Isometry3d::Identity();  ///< pose of the shape in its body
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: edge lengths; cylinder: (radius, length, 0), axis z; sphere: (radius, 0, 0)
  std::filesystem::path mesh_file;                 ///< resolved absolute path (meshes only)
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  Eigen::Vector4f rgba{0.8F, 0.8F, 0.8F, 1.0F};   ///< material colour if the URDF gives one
  std::string source_link;                         ///< URDF link the shape was declared on
};

struct Body {
  std::string name;                    ///< the URDF link on the chain
  std::vector<std::string> folded_links;  ///< links merged into this body (fixed joints, held joints)
  /// Of folded_links, those joined through a movable joint off the chain, held at 0 (or the
  /// limit nearest 0): not controlled, but drawn, weighed and collided with.
  std::vector<std::string> held_links;
  std::vector<Geometry> visuals;
  std::vector<Geometry> collisions;
  double mass = 0.0;                             ///< [kg], folded links included
  Eigen::Vector3d p_BCom = Eigen::Vector3d::Zero();  ///< centre of mass in the body frame
  Eigen::Matrix3d I_BCom = Eigen::Matrix3d::Zero();  ///< inertia about the COM, body axes
  /// The URDF gives this moving body no mass: it carries kAssumedMass instead.
  bool inertia_assumed = false;
};

/// What a moving body without <inertial> in its URDF weighs in the simulation [kg], centred on
/// its link, with the inertia of a solid sphere of at least kAssumedMinRadius [m].
inline constexpr double kAssumedMass = 1.0;
inline constexpr double kAssumedMinRadius = 0.05;

struct Joint {
  std::string name;
  JointType type = JointType::kRevolute;
  /// Pose of the joint frame in the parent body's frame at q = 0 (fixed joints folded in).
  Eigen::Isometry3d X_PJ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis_J = Eigen::Vector3d::UnitZ();  ///< unit axis in the joint (= child body) frame
  JointLimits limits;
  double damping = 0.0;   ///< URDF <dynamics damping>
  double friction = 0.0;  ///< URDF <dynamics friction>
};

class RobotModel {
 public:
  /// Reads a URDF file. tip_link empty: the last link of the longest serial chain. Throws
  /// InputError with a one-line reason for malformed files, missing links or meshes,
  /// ambiguous (non-serial) chains and unsupported joint types on the chain. A moving body
  /// whose links give no mass gets kAssumedMass (Body::inertia_assumed).
  static RobotModel fromUrdfFile(const std::filesystem::path& urdf_file,
                                 const std::string& tip_link = "");
  /// As fromUrdfFile; relative mesh URIs are resolved against base_dir. With left_out_meshes,
  /// a mesh file that is not found is left out (the visual or collision element with it) and
  /// its reason appended there, instead of refusing the URDF: for reviewing a recording whose
  /// robot's mesh folder is not on this machine.
  static RobotModel fromUrdfString(const std::string& xml, const std::filesystem::path& base_dir,
                                   const std::string& tip_link = "",
                                   std::vector<std::string>* left_out_meshes = nullptr);

  const std::string& name() const { return name_; }
  const std::filesystem::path& urdfPath() const { return urdf_path_; }
  const std::string& baseLink() const { return bodies_.front().name; }
  const std::string& tipLink() const { return tip_link_; }
  /// What a user should know of how the description was read, one line each (e.g. a default tip
  /// past a gripper's finger); the tools print them as notes.
  const std::vector<std::string>& notes() const { return notes_; }
  int dof() const { return static_cast<int>(joints_.size()); }
  const std::vector<Joint>& joints() const { return joints_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  /// Pose of the tip link in the frame of the last body (fixed joints after the last movable one).
  const Eigen::Isometry3d& X_LastBodyTip() const { return X_last_body_tip_; }

  Eigen::VectorXd lowerLimits() const;      ///< hardware
  Eigen::VectorXd upperLimits() const;      ///< hardware
  Eigen::VectorXd softLowerLimits() const;  ///< what the controllers keep to
  Eigen::VectorXd softUpperLimits() const;
  Eigen::VectorXd velocityLimits() const;
  /// Centre of the sample limits below (0 for an unbounded joint): a safe default posture.
  Eigen::VectorXd midPosture() const;
  /// to − from per joint, the shorter way round for a continuous joint (a turn is no difference).
  /// `difference` must have dof() entries; does not allocate.
  void postureDifference(const Eigen::VectorXd& to, const Eigen::VectorXd& from, Eigen::VectorXd& difference) const;
  Eigen::VectorXd postureDifference(const Eigen::VectorXd& to, const Eigen::VectorXd& from) const;
  /// `q` with each continuous joint taken into [−π, π] (the same posture): a start many turns
  /// round would cost the single-precision simulation its resolution.
  Eigen::VectorXd withinOneTurn(Eigen::VectorXd q) const;
  /// The software limits with an unbounded (continuous) joint given one turn, [−π, π]: the
  /// range to draw random postures from, which ±inf cannot be.
  Eigen::VectorXd sampleLowerLimits() const;
  Eigen::VectorXd sampleUpperLimits() const;

  /// Throws InputError("expected N joint values, got M") or for NaN/inf entries.
  void checkPosture(const Eigen::VectorXd& q) const;
  /// Throws InputError("<what>: joint j (name) at v lies outside its limits [lower, upper]") for
  /// the first joint beyond its hardware limits by more than `overshoot_rad` (revolute) or
  /// `overshoot_m` (prismatic); q must have dof() entries.
  void checkWithinLimits(const Eigen::VectorXd& q, const std::string& what, double overshoot_rad = 0.0,
                         double overshoot_m = 0.0) const;

 private:
  std::string name_;
  std::filesystem::path urdf_path_;
  std::string tip_link_;
  std::vector<std::string> notes_;
  std::vector<Joint> joints_;
  std::vector<Body> bodies_;
  Eigen::Isometry3d X_last_body_tip_ = Eigen::Isometry3d::Identity();
};

}  // namespace flexirob::robot
