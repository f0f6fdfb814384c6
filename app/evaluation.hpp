#pragma once
// Evaluations of a taught session in simulation (kinematic, with the collision world):
// the reachable workspace of Sect. 3.3.2 (Tab. 3.3) and planned paths through the ITM graph of
// Sect. 8.3. The robot is driven by the hierarchical controller (Eq. 2.11) with the learned
// q_c(x) and the command limiter; the collision world only counts contacts (model-free
// control, Sect. A.4). Frames: W = robot base; metres, radians.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "learning/learner.hpp"
#include "planning/itm.hpp"
#include "planning/path_postures.hpp"
#include "robot/collision.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {

using ProgressCallback = std::function<void(double fraction)>;

/// One motion executed kinematically with the hierarchical controller.
struct MotionOutcome {
  double final_error_m = 0.0;
  double mean_error_m = 0.0;  ///< E_task: mean |x_des(t) − x(t)| over the motion, sampled every 10 ms
  double max_error_m = 0.0;
  double max_error_time = 0.0;  ///< [s] into the motion when the error was largest
  bool collided = false;  ///< a contact with an obstacle or the robot itself at a checked sample
  std::string contact;    ///< the first contact, "body/other" (empty without one)
  double contact_time = 0.0;        ///< [s] when it happened
  double contact_task_error = 0.0;  ///< [m] |x_des − x| at the contact
  int colliding_checks = 0;  ///< 10 ms checks in contact (at most 1 unless the motion went on through contacts)
  Eigen::VectorXd q;      ///< final posture
};

/// What executeMotion does at a contact: stop there as the real robot would (the reachability
/// and trajectory evaluations), or go on and count the checks in contact (the check of a
/// transition between areas, Sect. 8.3's planned motions).
enum class AtContact { kStop, kContinue };

/// The learned posture q_c(p_W), clamped to the soft limits: where the reachability evaluation
/// starts the arm for a target (ApproachFrom::kLearnedPosture).
Eigen::VectorXd learnedPosture(const robot::RobotModel& model, const learning::Learner& map, const Eigen::Vector3d& p_W);

/// The demonstration's posture of sample `l`, clamped to the soft limits as the learned posture
/// is (a recorded posture may sit a hair beyond one).
Eigen::VectorXd demonstratedPosture(const robot::RobotModel& model, const learning::TrainingSet& training, Eigen::Index l);

/// The demonstration's samples as places the arm stood: tip position with the posture (clamped as
/// demonstratedPosture does), samples without a finite posture left out; none where the
/// demonstration holds no posture that fits the robot. Where ApproachFrom::kNearestVisited starts.
std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> demonstratedStandingPostures(const robot::RobotModel& model,
                                                                                     const learning::TrainingSet& training);

/// One target of the reachability evaluation (Sect. 3.3.2): from q_start to the fixed target p_W,
/// settle time 3 s.
MotionOutcome approachTarget(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                             const learning::Learner& map, const Eigen::VectorXd& q_start, const Eigen::Vector3d& p_W,
                             robot::CollisionWorld* world);

/// The scene's home posture if it fits the robot, else the middle of the joint limits, or, where
/// that touches an obstacle, the table or the arm itself, the nearest posture with 5 cm clearance
/// (a seeded search; the freest posture found if none has it): where a taught session and its
/// evaluations start [rad].
Eigen::VectorXd homePosture(const robot::RobotModel& model, const robot::Scene& scene);

/// A scene as `model` can run in it: each posture (home, training and working areas) that does
/// not fit the arm (another joint count, beyond a limit, an area posture putting the tip outside
/// its area; robot::checkPosturesFit) left out, and why: one line for all postures of another
/// joint count, one line each for the others. The CLI refuses such a
/// scene; the GUI runs the arm without those postures and says so.
struct FittedScene {
  robot::Scene scene;
  std::vector<std::string> left_out;
  int other_joint_count = 0;  ///< postures left out for another joint count (said in left_out's first line)
};
FittedScene fitSceneToRobot(const robot::Scene& scene, const robot::RobotModel& model);

/// Where the tip can usefully be asked to go: within reach of the shoulder and off the column
/// around the first joint's axis, which the arm cannot put its own tip into. Used wherever a
/// place is chosen for the arm (an area, a drawn trajectory) and to bound the grid targets.
struct ArmReach {
  /// Origin of the first joint whose axis is not parallel to the first joint's (the LWR IV's A2),
  /// of the first joint if there is none, or if a joint before it slides or it lies farther off
  /// the first axis than half the reach (a SCARA: the reach is then measured from the first
  /// joint with every joint free); in the posture nearest zero [m, W]
  Eigen::Vector3d shoulder = Eigen::Vector3d::Zero();
  double reach = 0.0;  ///< the largest distance of a body origin (posture nearest zero) or the tip (any posture within the limits) from the shoulder [m]
  Eigen::Vector3d base_point = Eigen::Vector3d::Zero();  ///< a point of the first joint's axis [m, W]
  Eigen::Vector3d base_axis = Eigen::Vector3d::UnitZ();  ///< its direction (unit) [W]
  /// The column's radius: 0.2 m (the LWR IV's base and first links), a quarter of the reach on
  /// smaller arms; 0 when the shoulder is the first joint (every joint turns about an axis
  /// parallel to the first, or the SCARA case above) [m].
  double base_radius = 0.2;

  double fromShoulder(const Eigen::Vector3d& p_W) const { return (p_W - shoulder).norm(); }
  /// Within reach - margin of the shoulder and outside the base column.
  bool roomFor(const Eigen::Vector3d& p_W, double margin) const;
};

ArmReach armReach(const robot::RobotModel& model);

/// [m] the LWR IV's reach from its shoulder (0.868 m), a little less.
inline constexpr double kLwrShoulderReach = 0.85;

/// How much smaller and lighter an arm is than the LWR IV, for what was sized for the LWR IV:
/// Tab. A.1's gains, the interaction's admittance, and the simulated tutor's hands and
/// distances. An arm of the LWR IV's size or larger, up to four times its joint inertia, scales
/// nothing (every factor 1); a smaller or lighter one gets them in proportion, so that it moves
/// as an LWR IV of its size would; a much heavier one stronger hands, triggers and damping
/// (inertia above 1; the workflow keeps the LWR IV's joint gains then).
struct ArmScale {
  double length = 1.0;   ///< reach from the shoulder / kLwrShoulderReach, at most 1
  double inertia = 1.0;  ///< robot::inertiaScaleToLwr()
  /// Mass: inertia / length² (Cartesian stiffness, damping and virtual mass). Above 1 for an
  /// arm as heavy as the LWR IV but shorter.
  double mass() const;
  /// Force: inertia / length, so that a push at the arm's levers makes torques in proportion to
  /// its joints' (and to the trigger's threshold, scaled by the inertia).
  double force() const { return inertia / length; }
};

ArmScale armScale(const robot::RobotModel& model);

/// The ITM's distances (e_max, d_Cmax: Sect. 7.4's, on the LWR IV) times the arm's length scale.
planning::ItmParameters itmParametersForArm(planning::ItmParameters parameters, const ArmScale& scale);

/// Whether the straight segment a–b [m, W] passes through one of the scene's obstacles between
/// its ends (looked at every 5 mm: a sheet thinner than that may be missed; the table top is none
/// of them).
bool crossesObstacle(const robot::Scene& scene, const Eigen::Vector3d& a, const Eigen::Vector3d& b);

/// Drives the command from q_start towards p_des(t) (t in [0, duration], held after) for up to
/// duration + settle seconds at 1 kHz, feeding the path's velocity forward (Eq. 2.6); ends early
/// once settled on target. Checks contacts every 10 ms; `world` may be null.
MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const learning::Learner& map, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world, AtContact at_contact = AtContact::kStop);
/// The null-space posture for a desired tip position [m, W] -> q [rad].
using PostureAt = std::function<void(const Eigen::Vector3d& p_W, Eigen::VectorXd& q)>;
/// As above, with the null-space posture from `posture_at` instead of the learned map.
MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const PostureAt& posture_at, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world, AtContact at_contact = AtContact::kStop);

struct ReachableResult {
  int grid_points = 0;   ///< points of G
  int out_of_reach = 0;  ///< farther from the shoulder than the arm reaches
  int in_obstacles = 0;  ///< within reach, inside an obstacle
  int targets = 0;       ///< |T|: grid points within reach, outside the obstacles and excluded boxes, and accessible
  int inaccessible = 0;  ///< within reach and outside the obstacles, but the IK search found no collision-free posture putting the tip there within the tolerance
  int excluded = 0;      ///< within reach and outside the obstacles, but in a box the grid excludes
  int reached = 0;       ///< reached within the tolerance without collision
  int collided = 0;      ///< not reached: a contact on the way (the others not reached ended farther than the tolerance)
  double reachable_fraction = 0.0;  ///< reached / targets
  /// Targets where the posture the learned redundancy resolution resolves is within the
  /// tolerance and without a contact: the controller run from q_c(x_target) until it settles,
  /// as in kLearnedPosture, but only its final posture checked (the learned IK mapping's own
  /// solution, as Sect. 4.2.2 stores "for each target the resulting posture"; the way there from
  /// q_c(x_target), a posture the arm never stands in with its tip at the target, is not judged).
  /// The same for every ApproachFrom; with kLearnedPosture it costs a second run only for the
  /// collided targets, with the others one for every target (kNearestReached: 1.5 times the
  /// time of kLearnedPosture).
  int resolved_free = 0;
  double resolved_fraction = 0.0;  ///< resolved_free / targets
  double explored_fraction = 0.0;   ///< targets whose grid cell holds a training sample
  std::map<std::string, int> contacts;         ///< collided targets per first contact "body/other"
  std::vector<Eigen::Vector3d> target_points;  ///< T
  std::vector<bool> target_reached;           ///< per target of T
  std::vector<bool> target_resolved_free;     ///< per target of T: counted in resolved_free
  std::vector<Eigen::VectorXd> final_postures; ///< per target of T: where the arm ended [rad]
  std::vector<std::string> target_contact;     ///< per target of T: its first contact "body/other", "" if none
  /// kNearestVisited, kNearestReached: where the arm stood by the end of the run, tip position
  /// with posture (the demonstration's samples for kNearestVisited, then every target reached),
  /// from which the nearest start of a further target is taken (nearestStandingPosture).
  std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> standing_postures;
};

/// The posture of `standing` whose tip lay nearest p_W; `fallback` when `standing` is empty.
const Eigen::VectorXd& nearestStandingPosture(const std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>>& standing,
                                              const Eigen::Vector3d& p_W, const Eigen::VectorXd& fallback);

/// Whether some collision-free posture puts the tip on p_W (within `tolerance_m`): IK with the
/// hierarchical controller from `seeds` null-space targets (q_start first, then seeded random
/// postures). Sect. 3.3.2 keeps in T only the targets "theoretically accessible without
/// colliding" (for setup I it names those above the board); this is the scene-independent test.
/// `posture_found`, if given, receives the collision-free posture that reaches p_W.
/// `postures_reaching`, if given, receives how many of the searches put the tip on p_W, with a
/// contact or without: where the answer is false, 0 says no posture was found that reaches p_W
/// at all, more says every one found makes a contact.
bool accessibleWithoutCollision(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                robot::CollisionWorld& world, const Eigen::Vector3d& p_W,
                                const Eigen::VectorXd& q_start, int seeds, learning::UniformRandom& random,
                                Eigen::VectorXd* posture_found = nullptr, int* postures_reaching = nullptr,
                                double tolerance_m = 1e-3);

/// Where the arm starts when the reachability evaluation commands it to a target. Sect. 3.3.2
/// evaluates the learned map as "the inverse kinematic mapping from 3-D task-space to 7-D
/// joint-space" and Sect. 4.2.2 stores "for each target the resulting posture"; it does not say
/// from where each target is approached. The default, kNearestVisited, starts every target from
/// the posture the arm has stood in with its tip nearest to it.
enum class ApproachFrom {
  /// From the posture the learned map gives for the target, q_c(x_target) (clamped to the soft
  /// limits): the learned IK mapping evaluated at each target, independent of the order of the
  /// targets. The controller then corrects the task error; contacts on that way count. Between
  /// and beyond the areas q_c(x)'s own tip lies up to 0.6 m from x, so this start is a posture
  /// the arm is never in with its tip near x, and it may lie in an obstacle or the table.
  kLearnedPosture,
  /// Every target from the same posture q_start (e.g. the scene's home posture): also tests
  /// large motions from one place, where the null-space term (κ_q) lags the task term (κ_x).
  kStartPosture,
  /// The targets one after another in nearest-neighbour order from q_start, each from where the
  /// previous one ended (after a contact: from the last posture reached without one).
  kPreviousTarget,
  /// The same tour, each target from the posture the arm stood in at the nearest target it has
  /// reached (within the tolerance, without a contact); from q_start until it has reached one.
  /// A contact costs only its own target: the arm goes on from a place next to it.
  kNearestReached,
  /// The same tour, each target from the posture the arm stood in with its tip nearest to the
  /// target: at a target it has reached, or at a sample of the demonstration (the tutor led the
  /// arm there). A region that only a posture of another redundancy family reaches (setup I
  /// behind the box, where the tutor taught the arm leaning back) is then entered from where the
  /// tutor showed it, not swung into from the neighbouring family across the obstacle.
  kNearestVisited,
};

/// Parses "learned", "start", "previous", "nearest" or "visited"; throws InputError otherwise.
ApproachFrom parseApproach(const std::string& name);
std::string approachName(ApproachFrom approach);

/// Sect. 3.3.2: each target of the grid is approached as `approach` says (settle time 3 s).
/// training: the demonstration, tip positions X (3 x L, for the explored fraction) and postures
/// Y (N x L, the postures kNearestVisited may start from; without them it starts only from
/// targets reached).
ReachableResult evaluateReachable(const robot::RobotModel& model, const robot::Scene& scene,
                                  const robot::ParameterSet& parameters, const learning::Learner& map,
                                  const Eigen::VectorXd& q_start, const robot::EvaluationGrid& grid,
                                  const learning::TrainingSet& training, const ProgressCallback& progress = {},
                                  ApproachFrom approach = ApproachFrom::kNearestVisited);

/// One goal of the planning evaluation, for pictures (Fig. 7.7, 8.4).
struct PlannedMotion {
  Eigen::Vector3d start_W = Eigen::Vector3d::Zero();  ///< tip where the motion started [m]
  Eigen::Vector3d goal_W = Eigen::Vector3d::Zero();   ///< the goal node's position [m]
  bool found = false;
  bool collided = false;
  bool reached_1cm = false;  ///< ended within 1 cm of the goal, with or without a contact on the way
  std::vector<Eigen::Vector3d> planned_W;  ///< the planned spline sampled every 50 ms (empty if not found)
  Eigen::Vector3d final_W = Eigen::Vector3d::Zero();  ///< tip where the executed motion ended [m]
  std::string contact;  ///< the first contact "body/other" (empty without one)
  double contact_time = 0.0;  ///< [s] into the motion when it happened
  double contact_path_error = 0.0;  ///< [m] |x_des − x| of the tip at the contact
  double final_error_m = 0.0;  ///< [m] |goal − final| (found paths)
  double tracking_error_max_m = 0.0;  ///< [m] largest |x_des − x| along the motion, every 10 ms
  /// The motion ended with a link in contact: the next starts where the last motion ended free,
  /// not here (an operator frees the arm).
  bool ended_in_contact = false;
};

struct PlanningResult {
  int goals = 0;
  int found = 0;          ///< paths the planner found
  int collision_free = 0; ///< executed without contact
  int reached_1cm = 0;    ///< ended within 1 cm of the goal node (a contact on the way or not)
  double mean_plan_ms = 0.0;
  /// Nodes no edge path connects to the start's nearest node; goals are drawn from the others.
  int disconnected_nodes = 0;
  std::map<std::string, int> contacts;  ///< collided motions per first contact "body/other"
  std::vector<PlannedMotion> motions;  ///< per goal, in the order visited
  double final_error_max_m = 0.0;     ///< [m] the largest |goal − final| of the found paths
  double tracking_error_max_m = 0.0;  ///< [m] the largest |x_des − x| along them
};

/// Eq. 4.1: the implicit scene model S = {x ∈ T : d(x, M) > 0.1 m}, with T the grid points
/// within reach (obstacles not removed) and M the points of the arm (joint origins and the
/// links between them, every 2 cm) in the postures the reachability evaluation ended in.
struct SceneModelResult {
  int workspace_points = 0;         ///< |T| (obstacle-independent)
  int model_points = 0;             ///< |S|
  int obstacle_points = 0;          ///< points of T inside an obstacle
  int obstacle_points_enclosed = 0; ///< of those, in S
  int free_points_in_model = 0;     ///< points of S outside every obstacle
  double obstacle_enclosed_fraction = 0.0;
  std::vector<Eigen::Vector3d> model;  ///< S
};
SceneModelResult evaluateSceneModel(const robot::RobotModel& model, const robot::Scene& scene,
                                    const robot::EvaluationGrid& grid, const std::vector<Eigen::VectorXd>& postures,
                                    double distance = 0.1);

/// A trajectory of a region that met a contact: which one, where and when.
struct CollidedTrajectory {
  std::string name;          ///< the scene's name, or "<region>_<k>" (k from 1) for a drawn one
  std::string contact;       ///< first contact "body/other"
  double contact_time = 0.0; ///< [s] from the trajectory's start (from the way's start if on_way_to_start)
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< [m, W] the desired tip position then
  bool on_way_to_start = false;  ///< on the straight way that leads the tip to the trajectory's start
};
/// Tab. 3.2: E_task and E_coll along straight trajectories per region. With the scene's
/// evaluation trajectories (grouped left / right / interpolation) those are run; otherwise
/// `per_area` random straight trajectories in the axis-aligned box around each area's samples
/// (a region named after the area) and 2·per_area in the box between each two areas taught one
/// after the other ("between A and B"); with two areas the thesis' 25 / 25 / 50.
struct TrajectoryRegionResult {
  std::string name;
  int trajectories = 0;
  int e_task_trajectories = 0;  ///< trajectories E_task is taken over: those whose start the arm reached without a contact
  double e_task_mean_mm = 0.0;  ///< mean over trajectories of their mean tracking error
  double e_task_std_mm = 0.0;
  double e_task_max_mm = 0.0;   ///< largest error at any sample
  std::string e_task_max_trajectory;  ///< the trajectory it occurred on
  double e_task_max_time = 0.0;       ///< [s] from that trajectory's start
  int collisions = 0;           ///< E_coll: trajectories with a contact
  std::map<std::string, int> contacts;  ///< collided trajectories per first contact "body/other"
  std::vector<CollidedTrajectory> collided;  ///< in the order they ran
  /// Each trajectory's waypoints [m, W] in the order they ran (a drawn one: its start and end).
  std::vector<std::vector<Eigen::Vector3d>> waypoints;
  /// "body/other" where every area's taught posture, moved to the region's first point, touches
  /// something (the region then starts in the nearest area's posture); empty otherwise.
  std::string start_contact;
  /// Trajectories no posture can follow, with why: "name: (x, y, z) m is d m from the shoulder,
  /// reach r m" or "name: (x, y, z) m lies inside obstacle" (the first such point, looked at
  /// every 2 cm). They run and count as the others do; a scene's author should know.
  std::vector<std::string> impossible;
  /// Trajectories whose start the tip's straight way from where the arm stood crossed an
  /// obstacle (after a collision the arm stands at the region's start again): the arm was
  /// brought to the start as the region's start is, kinematically, and the trajectory ran from
  /// there. The straight way through a wall between two scene trajectories had counted as the
  /// map's collision.
  int starts_placed = 0;
  /// Of the e_task_trajectories, those a contact ended on the way (the motion stops there, as on
  /// the real robot): their E_task covers the way up to the contact, not the whole trajectory.
  int e_task_until_contact = 0;
};
struct TrajectoryResult {
  std::vector<TrajectoryRegionResult> regions;
  bool from_scene = false;  ///< the scene's trajectories (true) or drawn around the samples
};
/// Where the trajectories of `evaluateTrajectories` come from.
enum class TrajectorySource {
  kAuto,          ///< the scene's, where it lists any; else drawn around the training data
  kScene,         ///< the scene's (an InputError where it lists none)
  kTrainingData,  ///< drawn in the boxes around the areas' samples and between them, as the thesis
                  ///< defines its regions (Sect. 3.3.1, Fig. 3.7), whatever the scene lists
};
/// "auto", "scene" or "training-data"; InputError otherwise.
TrajectorySource parseTrajectorySource(const std::string& name);
/// A taught area as the trajectory evaluation needs it.
struct EvaluatedArea {
  Eigen::MatrixXd samples;  ///< 3 x L [m, W]
  Eigen::VectorXd q_fixed;  ///< [rad]
  std::string name;         ///< as the session names it ("I1", "auto_3"); empty: "area <k>" (k from 1)
};
TrajectoryResult evaluateTrajectories(const robot::RobotModel& model, const robot::Scene& scene,
                                      const robot::ParameterSet& parameters, const learning::Learner& map,
                                      const std::vector<EvaluatedArea>& areas, int per_area, double speed,
                                      std::uint64_t seed, const ProgressCallback& progress = {},
                                      TrajectorySource source = TrajectorySource::kAuto);

/// Sect. 8.3: `goals` random graph nodes (seeded) visited one after another from q_start; each
/// planned with A* + spline and executed with the hierarchical controller, through contacts
/// (counted, the motion goes on to its goal). The next motion starts where this one ended, or
/// where the last one ended free of contact if this one ended in contact. The null-space
/// posture along each path: the postures shown along it (planning::PathPostures), or with
/// kLearned the learned map as in the thesis.
PlanningResult evaluatePlanning(const robot::RobotModel& model, const robot::Scene& scene,
                                const robot::ParameterSet& parameters, const learning::Learner& map,
                                const planning::Itm& graph, const Eigen::VectorXd& q_start, int goals,
                                std::uint64_t seed, const ProgressCallback& progress = {},
                                planning::PlanPostures postures = planning::PlanPostures::kDemonstrated);

}  // namespace flexirob::app
