#pragma once
// The collision world of the simulation (thesis Sect. 3.3 E_coll, App. A.4): the robot's links
// against the scene's obstacles and against each other, contacts with names, collision events
// counted, and distance queries for tools that need clearance.
//
// Only the simulator and the simulated tutor may use this class: it reads the scene's obstacle
// geometry, which controllers and learners never see (the method is model-free).
//
// Link shapes: the URDF's collision geometry (boxes, cylinders, spheres; meshes as their convex
// hulls) where a link has some, else a capsule around the link derived from its joint frames
// (from its joint to the next one) with the radius of a solid cylinder of the link's mass and
// smallest principal inertia, r = sqrt(2·I_min/m). Link pairs joined by a joint, and pairs
// already touching at the robot's reference posture (all joints at the centre of their limits,
// MoveIt's "default" rule), are not checked against each other. The base does not collide with
// obstacles (it stands on them), only with the robot's own links. Obstacle meshes are used as
// they are (concave allowed). Unless the scene says `table: false`, the table top z = 0 is one
// more obstacle, named "table", after the scene's own; the base and links within 1 cm of it at
// the reference posture (they stand on it) are not checked against it.
// Frames: world W = the robot's base frame; metres.
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {

/// The stand-in shape of a body without collision geometry: a capsule (a sphere when
/// `a_B == b_B`) around the segment from a_B to b_B in the body's frame [m], with `radius` [m].
/// The renderer draws the same capsule for a link that has no geometry at all.
struct LinkCapsule {
  Eigen::Vector3d a_B = Eigen::Vector3d::Zero();
  Eigen::Vector3d b_B = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

/// The capsule of body `body` (0 = base): from its joint to the next joint (or the tip); a
/// body whose joints coincide reaches to twice its centre of mass instead.
LinkCapsule linkCapsule(const RobotModel& model, int body);

/// One touching pair. `body` indexes RobotModel::bodies(); the other side is an obstacle
/// (obstacle >= 0, other_body == -1) or another body (self-collision, obstacle == -1).
struct Contact {
  int body = -1;
  int other_body = -1;
  int obstacle = -1;
  double depth = 0.0;                                ///< penetration depth [m], > 0
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();     ///< contact point on `body`
  bool isSelfCollision() const { return other_body >= 0; }
};

/// Closest approach between the robot and the obstacles.
struct Clearance {
  double distance = 0.0;  ///< [m]; negative: penetration depth; +inf without obstacles in range
  int body = -1;
  int obstacle = -1;
  Eigen::Vector3d p_body_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_obstacle_W = Eigen::Vector3d::Zero();
};

class CollisionWorld {
 public:
  /// Builds shapes for every link and obstacle. Throws InputError for obstacles with an
  /// unusable shape (non-positive size, unreadable mesh).
  CollisionWorld(const RobotModel& model, const Scene& scene);
  ~CollisionWorld();
  CollisionWorld(const CollisionWorld&) = delete;
  CollisionWorld& operator=(const CollisionWorld&) = delete;

  /// Places the links at posture q (radians). Does not allocate after the first call.
  void update(const Eigen::VectorXd& q);
  /// Every touching pair at the current posture, the deepest first (reuses its storage; a pair
  /// appears once). Depends on the posture alone, not on the postures queried before.
  const std::vector<Contact>& contacts();
  /// Closest robot–obstacle distance, searched up to max_distance [m].
  Clearance clearance(double max_distance = 1.0);
  /// Closest distance between two links of the arm at least `min_separation` bodies apart along
  /// the chain among the self-collision pairs checked [m]; negative: penetration depth; +inf
  /// beyond max_distance. Links next to each other along the chain are close by construction.
  double selfClearance(int min_separation = 3, double max_distance = 1.0);
  /// Distance between one body and one obstacle (+inf beyond max_distance).
  double distance(int body, int obstacle, double max_distance = 1.0);

  const RobotModel& model() const { return *model_; }
  /// The scene's obstacles in their order, then the table top (Scene::table).
  int obstacleCount() const { return static_cast<int>(obstacle_names_.size()); }
  const std::string& obstacleName(int obstacle) const { return obstacle_names_[static_cast<std::size_t>(obstacle)]; }
  const std::string& bodyName(int body) const;
  /// Whether the pair of bodies is checked for self-collision.
  bool selfPairChecked(int body_a, int body_b) const;
  /// How a body is represented: "urdf" (its collision geometry) or "capsule".
  const std::string& bodyShapeSource(int body) const;
  /// Name of whatever the contact's other side is.
  const std::string& otherName(const Contact& contact) const;

 private:
  struct Impl;
  const RobotModel* model_;
  std::vector<std::string> obstacle_names_;
  std::unique_ptr<Impl> impl_;
};

/// Counts collisions over time as E_coll (Sect. 3.3): an event is a pair that starts touching;
/// colliding steps are the steps with at least one contact.
class CollisionMonitor {
 public:
  struct Event {
    double time = 0.0;  ///< [s]
    Contact contact;
  };
  /// Feeds the contacts of one step at `time`.
  void observe(const std::vector<Contact>& contacts, double time);
  std::uint64_t events() const { return event_count_; }
  std::uint64_t collidingSteps() const { return colliding_steps_; }
  /// The first events (at most 1000 are kept, all are counted).
  const std::vector<Event>& eventLog() const { return log_; }
  void reset();

 private:
  std::vector<std::pair<int, int>> touching_, next_;
  std::vector<Event> log_;
  std::uint64_t event_count_ = 0;
  std::uint64_t colliding_steps_ = 0;
};

}  // namespace flexirob::robot
