#pragma once
// A simulated tutor: plays a person teaching the simulated arm through the same interface a
// person uses — hand forces on the links (Simulation::setHandForce) and the workflow's buttons.
// Like a person it sees the scene: for each training area it picks a collision-free posture
// with good clearance (IK solutions of the hierarchical controller from different null-space
// targets, scored by the collision world's clearance), approaches it under π_q by pushing the
// links, lets go and waits for on_converged, draws circular deflections under π_rec, lets go
// again. In PROGRAMMING it guides the tip along a target trajectory. Seeded and deterministic.
//
// Frames: world W = robot base; metres, radians, newtons.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/evaluation.hpp"
#include "app/workflow.hpp"
#include "learning/learner.hpp"
#include "robot/collision.hpp"
#include "robot/parameters.hpp"
#include "robot/scene.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {

/// [m] the helix diameters a tutor may be asked for: below 1 cm the recording is too small for
/// on_converged to tell it from standing still; 0.5 m is past the largest a participant drew.
inline constexpr double kSmallestCircleDiameter = 0.01;
inline constexpr double kLargestCircleDiameter = 0.5;

struct TutorOptions {
  std::uint64_t seed = 1;
  /// [m] largest diameter of the deflection helix (participants drew 0.02-0.32 m, Sect. 3.3);
  /// the tutor draws smaller where the arm would come closer than half min_clearance to an
  /// obstacle under π_rec, down to 0.02 m. These and min_clearance are for the LWR IV's size:
  /// on a smaller arm the tutor takes them times ArmScale::length (the helix at least 1 cm): a
  /// person keeps a 30 cm arm's links millimetres from a box, not 3 cm, and draws a helix it
  /// can follow. Its hands push a lighter arm more gently (ArmScale).
  double circle_diameter = 0.3;
  double helix_height = 0.6;       ///< height range the helix sweeps over its turns, times the diameter
  int circles = 4;                 ///< turns of the helix per area
  double circle_period = 4.0;      ///< [s] per turn
  int posture_candidates = 24;     ///< IK solutions tried per area
  double min_clearance = 0.03;     ///< [m] a posture (and the approach) must keep from obstacles
  double approach_speed = 0.4;     ///< [rad/s] of the tutor's joint-space reference
  double max_phase_time = 30.0;    ///< [s] a phase may take beyond its planned duration before the tutor gives up
  int approach_iterations = 4000;  ///< RRT-Connect iterations for a way around obstacles
  int posture_attempts = 3;        ///< postures with enough clearance tried, best first, until a way to one is found
  /// For an area of the scene's list where none of the posture_candidates keeps min_clearance:
  /// the best of them (at most this many) pushed clear of the nearest obstacle while the tip
  /// holds, as a person asked to teach a place between shelf boards moves the links away by
  /// hand (postureClearOfObstacles); 0 gives the area up at once. A place the tutor chose
  /// itself is given up instead: another place serves as well.
  int clearing_candidates = 8;
  bool realtime = false;           ///< pace at wall-clock speed
  /// Areas chosen automatically (beyond the scene's list) are checked on this many points drawn
  /// over the scene's workspace: the tutor teaches where the learned map fails and takes an area
  /// back when the map fails at more check points with it than without (the report says so, and
  /// the configuration may end with fewer areas than asked). 0: random places, all kept.
  int check_points = 150;
  /// Called with the measured state after every control cycle (a session recorder); may be empty.
  std::function<void(const robot::RobotState&)> on_cycle;
  /// Set when another thread steps the arm (the FRI controller stand-in,
  /// robot::FriSimulatedController::armMutex()): the tutor holds it for every touch of the
  /// arm, as that thread does for each integration step. on_cycle runs under it as well.
  std::mutex* arm_mutex = nullptr;
  /// Progress callback (what, fraction in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
  /// Asked after every control cycle; true ends configure() or program() where it is (a person
  /// stopped the run): the hands let go, configure()'s report says `interrupted`, program()
  /// returns false. May be empty.
  std::function<bool()> stop_requested;
  /// Where the map's checks start (homePosture of the scene); computed when empty. A caller
  /// that has it already passes it in, as the search behind it is not free.
  std::optional<Eigen::VectorXd> home;
  /// Where the scene suggests a posture for an area: false (the default, and the thesis'
  /// experiments in docs/RESULTS.md) starts the search there and shows the posture nearest the
  /// areas already taught, so that neighbouring areas share one redundancy family; true shows the
  /// posture nearest the scene's (teach --scene-postures), as its author wrote it.
  bool follow_scene_postures = false;
};

/// What the tutor did in one area.
struct TutorAreaReport {
  std::string name;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  ///< intended area centre [m, W]
  Eigen::VectorXd q_chosen;                          ///< posture the tutor aimed at [rad]
  double clearance = 0.0;                            ///< its clearance [m]
  bool taught = false;
  std::string failure;                               ///< why not, if not taught
  bool automatic = false;                            ///< chosen by the tutor, not the scene's list
  /// Automatic areas: check points the learned map missed before the area and with it
  /// (TutorOptions::check_points); -1 where not checked.
  int map_failures_before = -1;
  int map_failures_with = -1;
  double helix_diameter = 0.0;  ///< [m] of the helix drawn (smaller near obstacles); 0 if none was drawn
  Eigen::Index samples = 0;     ///< samples the area's recording holds (0 if none)
  /// [m] twice the largest distance of a recorded tip position from their mean: 0.85-1.05 times
  /// the helix diameter when the arm followed the hands.
  double span = 0.0;
  /// [m] from where the tip was grabbed to where it was when the lead under assistance blending
  /// ended and the links were pushed (Sect. 6.1: where the robot is confident it holds the null
  /// space); 0 where no lead was needed.
  double assistance_lead = 0.0;
  Eigen::VectorXd q_suggested;  ///< the scene's suggested posture for the area [rad] (empty: none)
};

struct TutorReport {
  std::vector<TutorAreaReport> areas;
  std::uint64_t collisions = 0;       ///< contact events in the simulation (E_coll)
  std::uint64_t colliding_steps = 0;
  /// [rad] largest lead of the tutor's reference over the arm (largest joint) along an approach
  /// path. The reference stops while the arm lags by more than 0.05 rad; a light arm pushed one
  /// link at a time can still fall further behind while it waits.
  double max_approach_lead = 0.0;
  double simulated_time = 0.0;        ///< [s]
  bool interrupted = false;           ///< TutorOptions::stop_requested ended the run
};

/// A posture choice for one task-space point.
struct PostureChoice {
  bool found = false;
  Eigen::VectorXd q;
  double clearance = 0.0;  ///< [m]
};

/// The reasons areas were not taught, counted by kind (a failure's text up to its first " ("
/// or ": "), the most frequent first: "8 × the posture was not reached, 1 × taken back". Empty
/// when every area was taught.
std::string failureKinds(const std::vector<TutorAreaReport>& areas);

class SimulatedTutor {
 public:
  /// sim, workflow and scene must outlive the tutor; the workflow drives the same simulation.
  SimulatedTutor(robot::Simulation& sim, Workflow& workflow, const robot::Scene& scene,
                 const robot::ParameterSet& parameters, TutorOptions options = {});
  ~SimulatedTutor();

  /// The whole configuration stage: start_configuration, `area_count` areas (the scene's
  /// training areas first, then points drawn in the evaluation grid), finished_configuration,
  /// and the learned map taken over.
  TutorReport configure(int area_count);
  /// PROGRAMMING: start_programming, guide the tip to the first waypoint (APPROACHING), then
  /// along the waypoints (TEACH-IN), let go; finished_programming. Returns false if a phase
  /// did not complete or TutorOptions::stop_requested ended it.
  bool program(const std::vector<Eigen::Vector3d>& waypoints);

  /// Collision-free IK postures for p_W (the suggested posture tried first), best first: the best
  /// candidate (found only if it has the clearance asked for), then the next distinct ones with
  /// that clearance, TutorOptions::posture_attempts in all at most. Where the way to the first
  /// cannot be found, a person tries the next before giving the area up. Empty when no
  /// candidate reached p_W collision-free; `reaching` (if given) counts the candidates that put
  /// the tip on p_W at all, with or without a contact. With `push_links_clear`, where no
  /// candidate keeps the clearance, the best ones are pushed clear (TutorOptions::clearing_candidates).
  /// A posture whose gravity load exceeds kHoldableLoad of a joint's effort is left out (the arm
  /// would sag out of it); lightest_rejected_ keeps the least such load of the last call.
  /// Where the TutorOptions::posture_candidates searches find no posture, as many more start
  /// from `known_to_reach` (the posture that showed an automatic place reachable; may be
  /// empty), the home posture and draws over the joints' whole range.
  std::vector<PostureChoice> choosePostures(const Eigen::Vector3d& p_W, const std::optional<Eigen::VectorXd>& suggested,
                                            int* reaching = nullptr, bool push_links_clear = false,
                                            const Eigen::VectorXd& known_to_reach = Eigen::VectorXd());

  /// IK from q_start that holds the tip on p_W while the null space moves the link point
  /// nearest an obstacle away from it (from 8 cm in), within the soft limits. The result need
  /// not reach p_W or be free: the caller checks.
  Eigen::VectorXd postureClearOfObstacles(const Eigen::Vector3d& p_W, const Eigen::VectorXd& q_start);

  /// The joint-space way a person leads the arm on from `from` to `to`: first out of any
  /// contact `from` rests in (small steps up the gradient of the signed clearance, to half
  /// TutorOptions::min_clearance), then around the obstacles with min_clearance, or half of it
  /// where that fails. Starts at `from`, ends at `to`; empty if no way was found.
  std::vector<Eigen::VectorXd> planWay(const Eigen::VectorXd& from, const Eigen::VectorXd& to);

  const TutorReport& report() const { return report_; }

 private:
  /// Throws StopRequested when TutorOptions::stop_requested says so (the searches that run
  /// between simulation ticks call it too).
  void stopIfAsked() const;
  /// Thrown by tick() when TutorOptions::stop_requested says so; caught by configure() and program().
  struct StopRequested {};
  TutorReport configureAreas(int area_count);
  bool programWaypoints(const std::vector<Eigen::Vector3d>& waypoints);
  bool teachArea(TutorAreaReport& area, const std::optional<Eigen::VectorXd>& suggested);
  /// Pushes the links so that the posture follows a joint-space path with the reference
  /// moving at `speed` [rad/s, largest joint]; false on timeout or when the arm runs off the
  /// way (kRunOffError), with the reason in last_failure_detail_.
  bool pushAlong(const std::vector<Eigen::VectorXd>& path, double speed);
  /// Pushes the tip towards a moving reference p_ref(t) for `duration` seconds, or until
  /// `done` (if given, asked before every cycle) says so.
  void pushTip(const std::function<Eigen::Vector3d(double)>& p_ref, double duration,
               const std::function<bool()>& done = {});
  /// Pushes the tip along the polyline `line` (from its first point) at `speed` [m/s], for
  /// `extra_time` [s] beyond its end, or until `done` says so.
  void pushTipAlong(const std::vector<Eigen::Vector3d>& line, double speed, double extra_time,
                    const std::function<bool()>& done = {});
  /// Under assistance blending (Sect. 6.1) the robot holds the null space where it is
  /// confident, and pushing the links there moves only the tip: a person who feels that leads
  /// the tip along the way the tip takes on the joint-space `path` until the arm yields (C(x)
  /// at the tip below kYieldingConfidence), the tip is at the path's end, or the arm comes near
  /// an obstacle (closer than half min_clearance), or on_converged ends APPROACHING.
  void leadTipOutOfAssistance(const std::vector<Eigen::VectorXd>& path);
  /// C(x) the workflow's assistance blending uses at the tip now; 0 while another controller runs.
  double assistanceAtTip() const;
  /// Steps until the workflow reaches `sub_stage` (hands off); false on timeout.
  bool waitFor(SubStage sub_stage, double max_time);
  /// Steps with a constant tip force until the workflow leaves `sub_stage`.
  bool grab(SubStage sub_stage, const Eigen::Vector3d& direction);
  void tick();
  /// An approach that ended short can leave the arm posed (POSED, held under π_rec) where the
  /// tutor did not mean to record, and the workflow's only way on from POSED is a recording
  /// (Fig. 2.5): the tutor does what a person would, touches the arm, lets go and removes the
  /// area that made, so that the next area starts from WAITING instead of recording there.
  void discardPose();
  double pathClearance(const std::vector<Eigen::VectorXd>& path);
  /// A joint-space path from `from` to `to` keeping `margin` [m] from the obstacles at every
  /// sample (RRT-Connect, then shortcuts), as a person leads the arm around an obstacle rather
  /// than straight through it; empty if none was found.
  std::vector<Eigen::VectorXd> planApproach(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double margin);
  /// Small joint steps from a posture in contact up the gradient of signedClearance until it
  /// keeps `margin` [m], or, where the climb stalls short of it, until it is out of every
  /// contact; empty if it cannot get out (a stationary point in contact, or the joint limits).
  std::vector<Eigen::VectorXd> planRetreat(const Eigen::VectorXd& from, double margin);
  /// Out of contact, the smaller of the obstacle and the link-to-link clearance at q (links at
  /// least 3 apart, as postureFree), at most 0.2 m; in contact, minus the summed penetration
  /// depths of every touching pair [m].
  double signedClearance(const Eigen::VectorXd& q);
  bool postureFree(const Eigen::VectorXd& q, double margin);
  /// Where a posture stands, as a person would say it: the first contact, or the nearest
  /// obstacle and the links' distance to each other.
  std::string describePosture(const Eigen::VectorXd& q);
  bool segmentFree(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double margin);
  /// Whether the postures π_rec gives (IK with q_fixed as null-space target) along `helix`
  /// keep `margin` [m] from the obstacles: a person sees how far the arm can be deflected.
  bool helixFree(const Eigen::VectorXd& q_fixed, const std::vector<Eigen::Vector3d>& helix, double margin);
  void updateReport();
  /// The check points of automatic areas: drawn over the scene's workspace box, within reach,
  /// outside the grid's excluded boxes and 5 cm outside the obstacles (seeded; the same for the
  /// whole configuration).
  void drawCheckPoints();
  /// Fits the workflow's learner to what was taught and marks the check points the arm does not
  /// reach from the learned posture (as `eval reachable` does); returns how many.
  int mapFailures();
  /// Whether an area centred at p_W leaves the arm room: 0.1 m to the obstacles, off the base
  /// and the table, outside the grid's excluded boxes.
  bool roomyForAnArea(const Eigen::Vector3d& p_W) const { return whyNoRoom(p_W) == nullptr; }
  /// Why an area centred at p_W leaves the arm no room (a short phrase), or null.
  const char* whyNoRoom(const Eigen::Vector3d& p_W) const;
  /// Where to teach next automatically: with `where_it_fails`, the failing check point with the
  /// most failing neighbours within 0.2 m that is roomy and 0.1 m from earlier attempts;
  /// otherwise, or before any map, or when none is left, a random roomy point of the workspace box
  /// that some collision-free IK posture reaches; none when 200 random points were not.
  std::optional<Eigen::Vector3d> nextAutomaticTarget(const robot::EvaluationGrid& grid, const std::vector<Eigen::Vector3d>& tried,
                                      bool where_it_fails);
  /// Why the random points of the last nextAutomaticTarget() that found none were passed over:
  /// "180 beyond the arm's reach or at its base, 20 near an obstacle", most frequent first.
  std::string placesPassedOver() const;

  /// The arm held under TutorOptions::arm_mutex (if set) for one full expression,
  /// `arm()->time()`; never two in one expression.
  std::map<std::string, int> places_passed_over_;  // reason -> random points, in nextAutomaticTarget()

  class LockedArm {
   public:
    LockedArm(robot::Simulation* sim, std::mutex* mutex)
        : sim_(sim), lock_(mutex != nullptr ? std::unique_lock(*mutex) : std::unique_lock<std::mutex>()) {}
    robot::Simulation* operator->() const { return sim_; }

   private:
    robot::Simulation* sim_;
    std::unique_lock<std::mutex> lock_;
  };
  LockedArm arm() const { return LockedArm(sim_, options_.arm_mutex); }

  robot::Simulation* sim_;
  Workflow* workflow_;
  const robot::Scene* scene_;
  const robot::RobotModel* model_;
  robot::ParameterSet parameters_;
  TutorOptions options_;
  std::unique_ptr<robot::CollisionWorld> world_;
  robot::Kinematics kinematics_;
  ArmReach arm_reach_;  ///< where areas can lie
  ArmScale arm_scale_;  ///< the workflow's: the gains, the hands and the distances for this arm
  double min_clearance_;    ///< [m] TutorOptions::min_clearance for this arm
  double circle_diameter_;  ///< [m] TutorOptions::circle_diameter for this arm
  /// [m] a distance chosen for the LWR IV, for this arm.
  double scaled(double lwr_length) const { return arm_scale_.length * lwr_length; }
  Eigen::VectorXd home_;  ///< homePosture: where evaluations of the map start
  learning::UniformRandom random_;
  /// The draws of choosePostures()'s second round: its own, so that a round that finds nothing
  /// leaves every later choice as it was without it.
  learning::UniformRandom second_round_random_;
  robot::RobotState state_;
  TutorReport report_;
  std::uint64_t ticks_ = 0;
  double wall_start_ = -1.0;
  std::string last_failure_detail_;
  // Of the last choosePostures(): the candidates that reached p_W free of contacts but that the
  // joints could not hold against gravity, and the least load among them.
  int too_heavy_candidates_ = 0;
  robot::Simulation::GravityLoad lightest_rejected_;
  /// The share of a joint's effort limit gravity may take at a posture the tutor chooses: the
  /// rest moves the arm and holds it against the hand.
  static constexpr double kHoldableLoad = 0.9;
  std::vector<Eigen::Vector3d> check_points_;
  std::vector<Eigen::VectorXd> check_postures_;  ///< a collision-free posture reaching each check point
  std::vector<bool> check_failed_;
  /// The posture that showed the last automatic place reachable without a contact (empty for a
  /// listed area): choosePostures() starts from it where its first searches found none.
  Eigen::VectorXd place_posture_;
};

}  // namespace flexirob::app
