#pragma once
// The teaching workflow (thesis Sect. 2.3, Fig. 2.5 and 2.8, App. A.3): stages, sub-stages,
// the four buttons and the two interaction triggers, the interaction controller of each
// sub-stage, training areas, learning of q_c(x) and the ITM of the configuration stage.
//
// Stages and sub-stages (IDLE between stages):
//   CONFIGURATION: WAITING (robot held) --on_affected--> APPROACHING (gravity compensation π_q)
//                  --on_converged--> POSED (compliant recording π_rec around q_fixed = q)
//                  --on_affected--> RECORDING (samples (x, q) recorded)
//                  --on_converged--> WAITING (area created; on_affected starts the next APPROACHING)
//   PROGRAMMING:   WAITING --on_affected--> APPROACHING (assisted gravity compensation)
//                  --on_converged--> POSED (held at x_start) --on_affected--> TEACH-IN
//                  (trajectory recorded) --on_converged--> WAITING
//   EXECUTION:     hierarchical control (Eq. 2.11) with the learned q_c along queued waypoints.
// Buttons: start_configuration (IDLE, EXECUTION -> CONFIGURATION), finished_configuration
// (CONFIGURATION, not while recording, >= 1 area -> IDLE, learning starts), start_programming
// (IDLE, EXECUTION with a learned map -> PROGRAMMING), finished_programming (PROGRAMMING, not
// during TEACH-IN -> EXECUTION). Anything else is refused with a reason; nothing changes then.
//
// Pure logic over a RobotBackend: no Qt, no OSG. One thread (the control thread) calls
// update()/step() and the requests; batch learning runs on its own thread and its result is
// taken over in update() without blocking. Frames: task space = tip position p_WT in the base
// frame W [m]; joint space [rad].
#include <Eigen/Core>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/evaluation.hpp"
#include "learning/confidence.hpp"
#include "learning/elm.hpp"
#include "learning/learner.hpp"
#include "learning/llm.hpp"
#include "planning/itm.hpp"
#include "planning/path_planner.hpp"
#include "planning/path_postures.hpp"
#include "robot/backend.hpp"
#include "robot/collision.hpp"
#include "robot/controllers.hpp"
#include "robot/interaction.hpp"
#include "robot/parameters.hpp"
#include "robot/scene.hpp"
#include "robot/triggers.hpp"

namespace flexirob::app {

/// The least distance [m] a RECORDING's tip is expected to move from where it began, on the
/// LWR IV (times ArmScale::length on another arm); a smaller area is warned about. Half the
/// smallest helix the simulated tutor draws (1 cm across), so that only a tip hardly moved warns.
inline constexpr double kSmallestAreaExtent = 0.005;

enum class Stage { kIdle, kConfiguration, kProgramming, kExecution };
enum class SubStage { kNone, kWaiting, kApproaching, kPosed, kRecording, kTeachIn };
enum class Button { kStartConfiguration, kFinishedConfiguration, kStartProgramming, kFinishedProgramming };
/// The interaction triggers are the robot core's (robot/triggers.hpp, App. A.3).
using Trigger = robot::TriggerKind;

/// The workflow's interaction controllers are the robot core's (robot/interaction.hpp, Tab. A.1):
/// hierarchical control holds a posture or follows the execution target, π_q, π_rec, assisted
/// gravity compensation and assistance blending (Eq. 6.2) drive the teaching sub-stages.
using InteractionController = robot::InteractionMode;

enum class LearnerKind { kElm, kOsElm, kLlm };

const char* toString(Stage stage);
const char* toString(SubStage sub_stage);
const char* toString(Button button);
/// The robot core's names of the controllers ("hierarchical_control", "gravity_compensation",
/// ...) and triggers ("on_affected", "on_converged"), also as app::toString.
using robot::toString;
const char* toString(LearnerKind kind);
/// "elm", "oselm", "llm" in any case, "OS-ELM" too; throws InputError otherwise.
LearnerKind learnerKindFromString(const std::string& name);

/// One record of what happened, for the session recorder and the GUI.
struct WorkflowEvent {
  enum class Kind { kStage, kButton, kTrigger, kRefused, kAreaCreated, kAreaRemoved, kModelLearned, kWarning, kCheck, kTeachIn, kExecution };
  double time = 0.0;   ///< [s] backend time
  Kind kind = Kind::kStage;
  std::string name;    ///< e.g. "CONFIGURATION/APPROACHING", "start_configuration", "on_affected"
  std::string detail;  ///< a human-readable line
  int area = -1;       ///< area index concerned, or -1
};
const char* toString(WorkflowEvent::Kind kind);
/// The warning lines that still stand at the end of `events`, each distinct line once, in order:
/// every refit checks the transitions again (OS-ELM refits after each area), and only the last
/// map's transition warnings stand, as Workflow::transitionChecks() holds only its checks; a
/// joint-limit warning stands once its recording made an area, until the area is re-taught or
/// removed. `with_the_pose_in_hand`: also the joint-limit warnings of the pose being recorded
/// now, which stand once its area is made (the window shows them meanwhile; a finished run
/// lists only what stands).
std::vector<std::string> standingWarnings(const std::vector<WorkflowEvent>& events, bool with_the_pose_in_hand = false);

/// A training area D^(k) (Sect. 3.1): the samples recorded in one RECORDING.
struct TrainingArea {
  std::string name;
  Eigen::VectorXd q_fixed;     ///< posture chosen in APPROACHING [rad]
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< LLM centre c_k = x_init (first sample) [m, W]
  Eigen::MatrixXd X;           ///< 3 x L tip positions [m, W]
  Eigen::MatrixXd Q;           ///< N x L postures [rad]
};

/// Result of a request (button, area removal): refused requests leave the state untouched.
struct RequestResult {
  bool accepted = false;
  std::string reason;  ///< why it was refused (empty if accepted)
  explicit operator bool() const { return accepted; }
};

/// The tutor feedback after learning with two or more areas (Sect. 4.3.4, Tab. 4.1): the
/// straight motion between two area centres executed (kinematically) with the learned map.
struct TransitionCheck {
  int from = -1, to = -1;
  double mean_error_m = 0.0;   ///< mean |x_des − x| along the line [m]
  double max_error_m = 0.0;
  double final_error_m = 0.0;
  double posture_error_rad = 0.0;  ///< |q_end − q_fixed(to)| at the goal
  int colliding_samples = 0;   ///< samples (every 10 ms) in contact; -1 without a scene
  std::string first_contact;   ///< "link/obstacle" of the first contact (empty without one)
  double first_contact_along_m = 0.0;  ///< how far along the line from `from` it happened [m]
  bool ok = false;
};

struct WorkflowOptions {
  LearnerKind learner = LearnerKind::kElm;
  learning::ElmParams elm;        ///< also the OS-ELM's
  learning::LlmParams llm;
  double confidence_d = 15.0;     ///< Eq. 6.8
  planning::ItmParameters itm;
  double affected_torque = 1.5;   ///< [Nm] on_affected threshold on max |τ_ext|
  double still_velocity = 0.02;   ///< [rad/s] max |q̇| below which the robot counts as not moving
  double converged_time = 2.0;    ///< [s] still time for on_converged
  double sample_period = 0.02;    ///< [s] between recorded samples and ITM inputs
  /// [s] of samples preallocated for one RECORDING or TEACH-IN, so that recording never
  /// allocates in the control cycle; longer recordings keep their first samples and warn.
  double max_recording_time = 600.0;
  double limit_warning_margin = 0.17;  ///< [rad] q_fixed closer than this to a soft limit warns
  double limit_warning_margin_m = 0.02;  ///< [m] the same for a prismatic joint (at most 1/10 of its travel)
  bool background_learning = true;     ///< false: fit synchronously in finished_configuration (tests)
  /// Box for the OS-ELM's fixed input normalization [m, W] (its workspace).
  Eigen::Vector3d workspace_lower = Eigen::Vector3d(-1.0, -1.0, -0.2);
  Eigen::Vector3d workspace_upper = Eigen::Vector3d(1.0, 1.0, 1.2);
  /// Scene for the transition check's collision test (simulation only; the workflow's own
  /// collision world, never the learner's input). Null: accuracy only.
  const robot::Scene* check_scene = nullptr;
  double check_speed = 0.1;        ///< [m/s] along the straight transition
  double check_tolerance = 0.01;   ///< [m] error that still counts as accurate
  double execution_speed = 0.1;    ///< [m/s] in EXECUTION
  /// Null-space posture along a planned path: the postures the configuration stage showed along
  /// it (planning::PathPostures), or the learned map alone as in the thesis.
  planning::PlanPostures plan_postures = planning::PlanPostures::kDemonstrated;
  /// [m] planTo() refuses goals farther than this from every ITM node: unexplored space. The
  /// ITM's quantization error e_max (0.1 m) is the distance within which a node stands for
  /// the explored positions around it.
  double max_goal_gap = 0.10;
};

class Workflow {
 public:
  /// The backend and the robot model must outlive the workflow. `parameters` holds at least
  /// the hierarchical.* and limits.* parameters (robot::reachParameters() does).
  Workflow(robot::RobotBackend& backend, const robot::ParameterSet& parameters, WorkflowOptions options = {});
  ~Workflow();
  Workflow(const Workflow&) = delete;
  Workflow& operator=(const Workflow&) = delete;

  /// One control cycle: read the state, evaluate the triggers, record, command the robot.
  void update();
  /// update() followed by backend.step().
  void step();

  RequestResult press(Button button);
  /// A trigger from another input (keyboard bindings, Sect. 8.1), as if detected.
  RequestResult fire(Trigger trigger);
  /// Removes area k (IDLE or CONFIGURATION outside RECORDING). The learned map is dropped and,
  /// in IDLE, learned again from the remaining areas.
  RequestResult removeArea(int k);
  /// The next RECORDING replaces area k instead of adding one (CONFIGURATION, not recording).
  RequestResult reteachArea(int k);
  /// The name the area of the next RECORDING gets (e.g. the scene's name of the place taught),
  /// in its events, the transition checks and the session; without one it is area_<k>. A
  /// re-taught area keeps its name.
  void nameNextArea(std::string name) { next_area_name_ = std::move(name); }
  /// EXECUTION: follow these waypoints [m, W] with the hierarchical controller and q_c.
  RequestResult execute(const std::vector<Eigen::Vector3d>& waypoints);
  /// EXECUTION: replay teach-in k (straight to its first point, then along it).
  RequestResult replayTeachIn(int k);
  /// EXECUTION: plan from the tip to `goal` [m, W] through the ITM graph of the configuration
  /// stage (Sect. 7.4) and execute the path. Refused when the graph holds no path or the goal
  /// lies farther than max_goal_gap from every explored position.
  RequestResult planTo(const Eigen::Vector3d& goal);
  /// Keyboard tele-operation (Sect. 8.1): moves the task target by dx [m, W]; moves the
  /// null-space target of joint `joint` by dq [rad]. Refused while a motion is executed.
  RequestResult nudgeTask(const Eigen::Vector3d& dx);
  RequestResult nudgeJoint(int joint, double dq);
  /// Keyboard mode: the interaction controllers follow the nudges instead of the hand.
  void setKeyboardMode(bool keyboard);
  bool keyboardMode() const { return keyboard_; }

  Stage stage() const { return stage_; }
  SubStage subStage() const { return sub_stage_; }
  InteractionController controller() const { return controller_; }
  std::string stateName() const;
  const std::vector<TrainingArea>& areas() const { return areas_; }
  /// Teach-in trajectories of PROGRAMMING, each 3 x T [m, W].
  const std::vector<Eigen::MatrixXd>& teachIns() const { return teach_ins_; }
  /// The learned q_c(x), or null (nothing learned yet / learning in progress).
  std::shared_ptr<const learning::Learner> model() const { return model_; }
  /// The samples model() was learned from (0 without a model).
  Eigen::Index modelSamples() const { return model_ != nullptr ? model_samples_ : 0; }
  bool learning() const { return learning_thread_.joinable(); }
  /// [s] wall time since the running fit started (or the last fit took); 0 before any.
  double learningSeconds() const;
  /// Blocks until a background fit has finished and takes its result over (tests, CLI).
  void waitForLearning();
  const learning::ConfidenceModel& confidence() const { return confidence_; }
  const planning::Itm& itm() const { return itm_; }
  const std::vector<TransitionCheck>& transitionChecks() const { return checks_; }
  bool executionDone() const { return execution_waypoints_.empty(); }
  /// The last planned path (null before the first accepted planTo()).
  std::shared_ptr<const planning::PlannedPath> plannedPath() const { return planned_path_; }
  /// The interaction controller's task target x_des [m, W] and α of assistance blending.
  const Eigen::Vector3d& taskTarget() const { return interaction_.taskTarget(); }
  /// Whether the controller in force steers the tip to taskTarget() (not π_q or π_rec by hand).
  bool tracksTaskTarget() const { return interaction_.tracksTaskTarget(); }
  /// The null-space posture the map gave in the last cycle of hierarchical control: q_c(x_des),
  /// or along a planned path the postures shown along it [rad].
  const Eigen::VectorXd& mapPosture() const { return interaction_.mapPosture(); }
  double alpha() const { return interaction_.alpha(); }
  /// The command written in the last cycle.
  const robot::JointImpedanceCommand& lastCommand() const { return command_; }
  /// Change counters: each increases when its data changes (areas incl. removal, teach-ins,
  /// the learned map, the ITM graph, the planned path). Cheap to poll every cycle.
  std::uint64_t areasVersion() const { return areas_version_; }
  std::uint64_t teachInsVersion() const { return teach_ins_version_; }
  std::uint64_t modelVersion() const { return model_version_; }
  std::uint64_t itmVersion() const { return itm_version_; }
  std::uint64_t pathVersion() const { return path_version_; }
  const robot::RobotState& state() const { return state_; }
  /// The options given, with the ITM's, the goal gap's and the OS-ELM box's distances times
  /// armScale().length.
  const WorkflowOptions& options() const { return options_; }
  /// The arm against the LWR IV (app/evaluation.hpp), which the gains are scaled by.
  const ArmScale& armScale() const { return arm_scale_; }
  /// [Nm] on_affected's threshold for this arm: options().affected_torque times its inertia scale.
  double affectedTorque() const { return options_.affected_torque * arm_scale_.inertia; }
  const robot::RobotModel& robotModel() const { return *model_robot_; }
  robot::RobotBackend& backend() { return *backend_; }

  /// Every event so far, in time order.
  const std::vector<WorkflowEvent>& events() const { return events_; }
  /// Events since the last call (for a recorder draining them).
  std::vector<WorkflowEvent> takeNewEvents();

  /// The RECORDING in progress (CONFIGURATION), for a recorder that streams its samples as they
  /// come: columns [0, recordingSamples()) of recordingX() / recordingQ(), the newest taken at
  /// lastSampleTime(); the index of the area it will create; a serial number that increases
  /// with every RECORDING started. recordingSamples() is 0 outside RECORDING.
  Eigen::Index recordingSamples() const { return sub_stage_ == SubStage::kRecording ? recording_samples_ : 0; }
  const Eigen::MatrixXd& recordingX() const { return recording_X_; }
  const Eigen::MatrixXd& recordingQ() const { return recording_Q_; }
  double lastSampleTime() const { return last_sample_time_; }
  int recordingArea() const {
    const int next = static_cast<int>(areas_.size());
    return reteach_index_ >= 0 && reteach_index_ < next ? reteach_index_ : next;
  }
  std::uint64_t recordingSerial() const { return recording_serial_; }

  /// The training set of all areas (3 x L, N x L, area labels).
  learning::TrainingSet trainingSet() const;

 private:
  struct LearningResult;
  /// q_c(x) of the control side: the online learner while it learns, else the learned map,
  /// else the posture held when the sub-stage began.
  class PostureMap final : public robot::RedundancyMap {
   public:
    explicit PostureMap(const Workflow& workflow) : workflow_(&workflow) {}
    int dof() const override;
    void predict(const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) const override;

   private:
    const Workflow* workflow_;
  };
  /// C(x) of assistance blending (Eq. 6.1) from the areas' confidence Gaussians.
  class AreaConfidence final : public robot::ConfidenceMap {
   public:
    explicit AreaConfidence(const learning::ConfidenceModel& model) : model_(&model) {}
    double confidence(const Eigen::Vector3d& p_W) const override;

   private:
    const learning::ConfidenceModel* model_;
  };

  void setState(Stage stage, SubStage sub_stage);
  /// Starts the current controller from the state of now, aimed at q_fixed (recording) or the held posture.
  void restartController();
  void emit(WorkflowEvent::Kind kind, std::string name, std::string detail, int area = -1);
  RequestResult refuse(const std::string& request, std::string reason);
  void onTrigger(Trigger trigger);
  /// Stores the RECORDING as an area; its index, or -1 when it held no sample.
  int finishArea();
  std::string freshAreaName() const;  ///< area_N with the lowest N from the area count on that no area bears
  void warnIfTheAreaIsSmall(int index);
  void warnIfTheAreaWasTaughtInContact(int index, Eigen::Index contacts);
  int finishTeachIn();  ///< the teach-in stored, or -1 for one without a sample
  void warnAboutTheTeachIn(int index);
  void checkJointLimits(const Eigen::VectorXd& q_fixed, int area);
  void startLearning();
  void collectLearning();
  void rebuildConfidence();
  void recordSample();
  void command();
  std::unique_ptr<learning::OsElm> makeOnlineLearner() const;

  robot::RobotBackend* backend_;
  const robot::RobotModel* model_robot_;
  ArmScale arm_scale_;
  WorkflowOptions options_;  ///< as given, its distances scaled to the arm (arm_scale_)
  robot::ParameterSet parameters_;
  robot::InteractionController interaction_;
  robot::InteractionTriggers triggers_;
  robot::RobotState state_;
  robot::JointImpedanceCommand command_;

  Stage stage_ = Stage::kIdle;
  SubStage sub_stage_ = SubStage::kNone;
  InteractionController controller_ = InteractionController::kHierarchicalControl;
  Eigen::VectorXd hold_q_;      // posture held in WAITING / IDLE (null-space target without a map)
  bool measured_ = false;  // a state with time > 0 came in: hold_q_ is where the robot is
  Eigen::VectorXd q_fixed_;     // π_rec target
  double last_sample_time_ = -1e9;

  std::vector<TrainingArea> areas_;
  // The running RECORDING / TEACH-IN, preallocated for max_recording_time (no allocation per sample).
  Eigen::VectorXd recording_q_fixed_;
  Eigen::MatrixXd recording_X_, recording_Q_;
  Eigen::Index recording_samples_ = 0;
  std::uint64_t recording_serial_ = 0;
  bool recording_full_ = false;
  Eigen::Index recording_contacts_ = 0;  ///< samples of this recording taken in contact
  std::size_t itm_positions_in_contact_ = 0;  ///< CONFIGURATION positions kept out of the ITM
  std::size_t itm_positions_inserted_ = 0;    ///< CONFIGURATION positions fed to the ITM
  int reteach_index_ = -1;
  std::string next_area_name_;
  std::vector<Eigen::MatrixXd> teach_ins_;

  std::shared_ptr<learning::Learner> model_;  // used by the control side only
  std::unique_ptr<learning::OsElm> online_;   // OS-ELM learning during RECORDING
  learning::ConfidenceModel confidence_;
  planning::Itm itm_;
  std::vector<TransitionCheck> checks_;
  PostureMap posture_map_;
  AreaConfidence area_confidence_;

  std::thread learning_thread_;
  std::chrono::steady_clock::time_point learning_started_{};
  double learning_seconds_ = 0.0;  // of the last finished fit
  std::atomic<bool> learning_done_{false};
  std::unique_ptr<LearningResult> learning_result_;  // written by the learning thread before learning_done_
  learning::CancellationToken cancel_;

  std::vector<Eigen::Vector3d> execution_waypoints_;
  Eigen::Vector3d execution_target_ = Eigen::Vector3d::Zero();
  std::shared_ptr<const planning::PlannedPath> planned_path_;
  /// The postures along the path being executed (plan_postures kDemonstrated); held at its goal
  /// until the next motion.
  std::unique_ptr<const planning::PathPostures> path_postures_;
  bool keyboard_ = false;
  std::uint64_t areas_version_ = 0, teach_ins_version_ = 0, model_version_ = 0, itm_version_ = 0, path_version_ = 0;
  Eigen::Index model_samples_ = 0;

  std::vector<WorkflowEvent> events_;
  std::size_t events_taken_ = 0;
};

/// Executes the straight line between two area centres kinematically with the hierarchical
/// controller and the map, from area `from`'s q_fixed (Tab. 4.1 "inconsistent combinations").
/// `world` may be null (no collision test).
TransitionCheck checkTransition(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                const learning::Learner& map, const TrainingArea& from, const TrainingArea& to,
                                int from_index, int to_index, robot::CollisionWorld* world, double speed,
                                double tolerance);

/// How near a soft limit a joint value is "near the limit" (Sect. 4.3.4): the options' margin
/// in radians, or in metres for a prismatic joint, at most a tenth of the joint's range (a
/// slide of a few centimetres, a wrist of ±0.1 rad).
double nearLimitMargin(const robot::Joint& joint, const WorkflowOptions& options);

/// A fresh learner of the given kind for 3-D inputs and `dof` outputs.
std::unique_ptr<learning::Learner> makeLearner(const WorkflowOptions& options, int dof);

}  // namespace flexirob::app
