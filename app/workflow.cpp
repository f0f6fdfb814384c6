#include "app/workflow.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <numbers>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "app/evaluation.hpp"
#include "app/realtime.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::app {

const char* toString(Stage stage) {
  switch (stage) {
    case Stage::kIdle: return "IDLE";
    case Stage::kConfiguration: return "CONFIGURATION";
    case Stage::kProgramming: return "PROGRAMMING";
    case Stage::kExecution: return "EXECUTION";
  }
  return "?";
}

const char* toString(SubStage sub_stage) {
  switch (sub_stage) {
    case SubStage::kNone: return "";
    case SubStage::kWaiting: return "WAITING";
    case SubStage::kApproaching: return "APPROACHING";
    case SubStage::kPosed: return "POSED";
    case SubStage::kRecording: return "RECORDING";
    case SubStage::kTeachIn: return "TEACH-IN";
  }
  return "?";
}

const char* toString(Button button) {
  switch (button) {
    case Button::kStartConfiguration: return "start_configuration";
    case Button::kFinishedConfiguration: return "finished_configuration";
    case Button::kStartProgramming: return "start_programming";
    case Button::kFinishedProgramming: return "finished_programming";
  }
  return "?";
}


const char* toString(LearnerKind kind) {
  switch (kind) {
    case LearnerKind::kElm: return "elm";
    case LearnerKind::kOsElm: return "oselm";
    case LearnerKind::kLlm: return "llm";
  }
  return "?";
}

const char* toString(WorkflowEvent::Kind kind) {
  using K = WorkflowEvent::Kind;
  switch (kind) {
    case K::kStage: return "stage";
    case K::kButton: return "button";
    case K::kTrigger: return "trigger";
    case K::kRefused: return "refused";
    case K::kAreaCreated: return "area_created";
    case K::kAreaRemoved: return "area_removed";
    case K::kModelLearned: return "model_learned";
    case K::kWarning: return "warning";
    case K::kCheck: return "check";
    case K::kTeachIn: return "teach_in";
    case K::kExecution: return "execution";
  }
  return "?";
}

LearnerKind learnerKindFromString(const std::string& name) {
  // The thesis writes ELM, OS-ELM and LLM; any case and a hyphen name the same learner.
  std::string key;
  for (const char c : name) {
    if (c != '-') key += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (key == "elm") return LearnerKind::kElm;
  if (key == "oselm") return LearnerKind::kOsElm;
  if (key == "llm") return LearnerKind::kLlm;
  throw InputError("learner: expected elm, oselm or llm, got '" + name + "'");
}

// ---------------------------------------------------------------------------------------------

double nearLimitMargin(const robot::Joint& joint, const WorkflowOptions& options) {
  const bool sliding = joint.type == robot::JointType::kPrismatic;
  return std::min(sliding ? options.limit_warning_margin_m : options.limit_warning_margin,
                  0.1 * (joint.limits.soft_upper - joint.limits.soft_lower));
}

std::unique_ptr<learning::Learner> makeLearner(const WorkflowOptions& options, int dof) {
  switch (options.learner) {
    case LearnerKind::kElm: return std::make_unique<learning::Elm>(3, dof, options.elm);
    case LearnerKind::kLlm: return std::make_unique<learning::Llm>(3, dof, options.llm);
    case LearnerKind::kOsElm:
      return std::make_unique<learning::OsElm>(
          3, dof, learning::InputNormalization::fromBox(options.workspace_lower, options.workspace_upper), options.elm);
  }
  return nullptr;
}

struct Workflow::LearningResult {
  std::shared_ptr<learning::Learner> model;
  std::unique_ptr<learning::OsElm> online;  // OS-ELM only: the refit that keeps learning online
  Eigen::Index samples = 0;
  std::vector<TransitionCheck> checks;
  double seconds = 0.0;
  std::string error;
};

namespace {

/// The options' distances are a person's with the LWR IV (the ITM's e_max of Sect. 7.4, the
/// bootstrapping radius, the goal gap, the OS-ELM's workspace box); an arm of less reach takes
/// them times ArmScale::length, as its gains and the tutor's distances are scaled. A 17 cm arm's
/// configuration stage had left an ITM of 3 nodes, and `plan` drew its goals among them. The
/// LWR IV and arm9 (length 1) keep every value.
WorkflowOptions optionsForArm(WorkflowOptions options, const robot::RobotModel& model, const ArmScale& scale) {
  if (scale.length >= 1.0) return options;
  options.itm = itmParametersForArm(options.itm, scale);
  options.max_goal_gap *= scale.length;
  // The box about the shoulder as far as the arm reaches (on a pedestal too): scaled about the
  // world's origin it had ended under a pedestal arm's shoulder.
  const ArmReach reach = armReach(model);
  options.workspace_lower = reach.shoulder - Eigen::Vector3d::Constant(reach.reach);
  options.workspace_upper = reach.shoulder + Eigen::Vector3d::Constant(reach.reach);
  return options;
}

/// The interaction controllers' and the triggers' parameters: values from `given` where it
/// declares them (a scene's overrides), the triggers' from the workflow options.
robot::ParameterSet workflowParameters(const robot::ParameterSet& given, const WorkflowOptions& options, const ArmScale& scale) {
  std::vector<robot::ParameterDeclaration> declarations = robot::interactionControllerParameters();
  for (const auto& declaration : robot::triggerParameters()) declarations.push_back(declaration);
  for (const auto& declaration : given.declarations()) {
    const bool known = std::any_of(declarations.begin(), declarations.end(),
                                   [&](const robot::ParameterDeclaration& d) { return d.name == declaration.name; });
    if (!known) declarations.push_back(declaration);
  }
  robot::ParameterSet parameters(declarations);
  for (const auto& declaration : given.declarations()) parameters.set(declaration.name, given.get(declaration.name));
  if (options.sample_period <= 0.0 || options.converged_time <= 0.0 || options.affected_torque <= 0.0 ||
      options.still_velocity <= 0.0 || options.max_recording_time <= 0.0) {
    throw InputError("workflow: sample period, trigger thresholds, converged time and recording time must be positive");
  }
  // The LWR IV's threshold; a lighter arm's torques are smaller in proportion (ArmScale).
  parameters.set("triggers.torque_threshold", options.affected_torque * scale.inertia);
  parameters.set("triggers.still_velocity", options.still_velocity);
  parameters.set("triggers.converged_time", options.converged_time);
  return parameters;
}

}  // namespace

int Workflow::PostureMap::dof() const { return workflow_->model_robot_->dof(); }

void Workflow::PostureMap::predict(const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) const {
  if (workflow_->stage_ == Stage::kExecution && workflow_->path_postures_) {
    workflow_->path_postures_->at(p_W, q_c);
    return;
  }
  const learning::Learner* learner = workflow_->online_ ? workflow_->online_.get() : workflow_->model_.get();
  if (learner != nullptr && learner->trained()) {
    learner->predict(p_W, q_c);
  } else {
    q_c = workflow_->hold_q_;
  }
}

double Workflow::AreaConfidence::confidence(const Eigen::Vector3d& p_W) const {
  return model_->areas() > 0 ? model_->evaluate(p_W) : 0.0;
}

Workflow::Workflow(robot::RobotBackend& backend, const robot::ParameterSet& parameters, WorkflowOptions options)
    : backend_(&backend),
      model_robot_(&backend.model()),
      arm_scale_(app::armScale(backend.model())),
      options_(optionsForArm(std::move(options), backend.model(), arm_scale_)),
      parameters_(workflowParameters(parameters, options_, arm_scale_)),
      interaction_(backend.model(), parameters_, backend.cycleTime()),
      triggers_(parameters_),
      confidence_(options_.confidence_d),
      itm_(options_.itm, backend.model().dof()),
      posture_map_(*this),
      area_confidence_(confidence_) {
  const int dof = model_robot_->dof();
  state_.resize(dof);
  command_.resize(dof);
  // Room for one whole RECORDING / TEACH-IN: the control cycle never allocates per sample.
  const auto capacity = static_cast<Eigen::Index>(std::ceil(options_.max_recording_time / options_.sample_period)) + 1;
  recording_X_.setZero(3, capacity);
  recording_Q_.setZero(dof, capacity);
  recording_q_fixed_.setZero(dof);
  backend_->readState(state_);
  hold_q_ = state_.q;
  q_fixed_ = state_.q;
  interaction_.setConfidence(&area_confidence_);
  // The joint gains of an arm much heavier than the LWR IV stay the LWR IV's: scaled with it
  // (21.5 times on a 260 kg arm), its joints held against the tutor's hands, which grow as much,
  // and 3 of 9 areas were taught with 5 contacts; with the LWR IV's, 3 of 3 without one.
  interaction_.setArmScale(std::min(1.0, arm_scale_.inertia), arm_scale_.mass());
  setState(Stage::kIdle, SubStage::kNone);
  events_.clear();  // the initial state is no event
  command();
}

Workflow::~Workflow() {
  cancel_.cancel();
  if (learning_thread_.joinable()) learning_thread_.join();
}

std::string Workflow::stateName() const {
  std::string name = toString(stage_);
  if (sub_stage_ != SubStage::kNone) name += std::string("/") + toString(sub_stage_);
  return name;
}

void Workflow::emit(WorkflowEvent::Kind kind, std::string name, std::string detail, int area) {
  events_.push_back({state_.time, kind, std::move(name), std::move(detail), area});
}

std::vector<WorkflowEvent> Workflow::takeNewEvents() {
  std::vector<WorkflowEvent> fresh(events_.begin() + static_cast<std::ptrdiff_t>(events_taken_), events_.end());
  events_taken_ = events_.size();
  return fresh;
}

RequestResult Workflow::refuse(const std::string& request, std::string reason) {
  emit(WorkflowEvent::Kind::kRefused, request, reason);
  return {false, std::move(reason)};
}

void Workflow::setState(Stage stage, SubStage sub_stage) {
  stage_ = stage;
  sub_stage_ = sub_stage;
  // The controller of each sub-stage (Fig. 2.5, 2.8, 6.1).
  const bool online = options_.learner == LearnerKind::kOsElm && (online_ || model_) && !areas_.empty();
  switch (sub_stage) {
    case SubStage::kApproaching:
      if (stage == Stage::kConfiguration) {
        controller_ = online ? InteractionController::kAssistanceBlending : InteractionController::kGravityCompensation;
      } else {
        controller_ = InteractionController::kAssistedGravityCompensation;
      }
      break;
    case SubStage::kPosed:
    case SubStage::kRecording:
      controller_ = stage == Stage::kConfiguration ? InteractionController::kCompliantRecording
                                                   : InteractionController::kAssistedGravityCompensation;
      break;
    case SubStage::kTeachIn: controller_ = InteractionController::kAssistedGravityCompensation; break;
    case SubStage::kNone:
    case SubStage::kWaiting: controller_ = InteractionController::kHierarchicalControl; break;
  }
  // Holding (IDLE, WAITING) keeps the posture of now; EXECUTION follows q_c(x) of the map.
  hold_q_ = state_.q;
  const bool mapped = controller_ != InteractionController::kHierarchicalControl || stage == Stage::kExecution;
  interaction_.setRedundancyMap(mapped ? &posture_map_ : nullptr);
  // PROGRAMMING's POSED holds the start position: the compliant following of APPROACHING would
  // give way to a slow pull before its torque crossed on_affected's threshold, and the arm
  // would leave the start without the TEACH-IN starting.
  interaction_.setTaskHeld(stage == Stage::kProgramming && sub_stage == SubStage::kPosed);
  restartController();
  emit(WorkflowEvent::Kind::kStage, stateName(), std::string("controller ") + toString(controller_));
}

void Workflow::restartController() {
  interaction_.setFixedPosture(controller_ == InteractionController::kCompliantRecording ? q_fixed_ : hold_q_);
  interaction_.start(controller_, state_);
}

// ---------------------------------------------------------------------------------------------
// Buttons

RequestResult Workflow::press(Button button) {
  const std::string name = toString(button);
  collectLearning();
  switch (button) {
    case Button::kStartConfiguration:
      if (stage_ != Stage::kIdle && stage_ != Stage::kExecution) {
        return refuse(name, std::string("start_configuration: only from IDLE or EXECUTION, not in ") + stateName());
      }
      if (learning()) return refuse(name, "start_configuration: learning is still running");
      emit(WorkflowEvent::Kind::kButton, name, "");
      execution_waypoints_.clear();
      next_area_name_.clear();  // a name given for a place never recorded is not the next area's
      triggers_.reset();
      setState(Stage::kConfiguration, SubStage::kWaiting);
      return {true, ""};
    case Button::kFinishedConfiguration:
      if (stage_ != Stage::kConfiguration) {
        return refuse(name, std::string("finished_configuration: not in CONFIGURATION but ") + stateName());
      }
      if (sub_stage_ == SubStage::kRecording) {
        return refuse(name, "finished_configuration: a RECORDING is running; let go of the robot first");
      }
      if (areas_.empty()) return refuse(name, "finished_configuration: no training area recorded yet");
      emit(WorkflowEvent::Kind::kButton, name, "");
      setState(Stage::kIdle, SubStage::kNone);
      startLearning();
      return {true, ""};
    case Button::kStartProgramming:
      if (stage_ != Stage::kIdle && stage_ != Stage::kExecution) {
        return refuse(name, std::string("start_programming: only from IDLE or EXECUTION, not in ") + stateName());
      }
      if (areas_.empty()) return refuse(name, "start_programming: configure the robot first (no training area)");
      if (learning()) return refuse(name, "start_programming: the redundancy resolution is still being learned");
      if (!model_) return refuse(name, "start_programming: no learned redundancy resolution");
      emit(WorkflowEvent::Kind::kButton, name, "");
      execution_waypoints_.clear();
      triggers_.reset();
      setState(Stage::kProgramming, SubStage::kWaiting);
      return {true, ""};
    case Button::kFinishedProgramming:
      if (stage_ != Stage::kProgramming) {
        return refuse(name, std::string("finished_programming: not in PROGRAMMING but ") + stateName());
      }
      if (sub_stage_ == SubStage::kTeachIn) {
        return refuse(name, "finished_programming: a TEACH-IN is running; let go of the robot first");
      }
      emit(WorkflowEvent::Kind::kButton, name, "");
      setState(Stage::kExecution, SubStage::kNone);
      execution_target_ = interaction_.taskTarget();
      path_postures_.reset();
      return {true, ""};
  }
  return refuse(name, "unknown button");
}

RequestResult Workflow::fire(Trigger trigger) {
  if (stage_ != Stage::kConfiguration && stage_ != Stage::kProgramming) {
    return refuse(toString(trigger), std::string(toString(trigger)) + ": no interaction in " + stateName());
  }
  if (trigger == Trigger::kOnAffected) {
    triggers_.markAffected(state_.time);
  } else {
    triggers_.reset();
  }
  onTrigger(trigger);
  return {true, ""};
}

RequestResult Workflow::removeArea(int k) {
  collectLearning();
  if (k < 0 || k >= static_cast<int>(areas_.size())) {
    return refuse("remove_area", "remove_area: expected an area index in [0, " + std::to_string(areas_.size()) +
                                     "), got " + std::to_string(k));
  }
  const bool allowed = stage_ == Stage::kIdle ||
                       (stage_ == Stage::kConfiguration && sub_stage_ != SubStage::kRecording);
  if (!allowed) return refuse("remove_area", std::string("remove_area: not possible in ") + stateName());
  if (learning()) return refuse("remove_area", "remove_area: learning is still running");
  const std::string area_name = areas_[static_cast<std::size_t>(k)].name;
  areas_.erase(areas_.begin() + k);
  if (reteach_index_ == k) reteach_index_ = -1;
  if (reteach_index_ > k) --reteach_index_;
  model_.reset();
  online_.reset();
  checks_.clear();
  rebuildConfidence();
  ++areas_version_;
  ++model_version_;
  emit(WorkflowEvent::Kind::kAreaRemoved, "area_removed", area_name, k);
  if (options_.learner == LearnerKind::kOsElm && !areas_.empty()) {
    // The online learner cannot forget: refit it on what remains.
    startLearning();
  } else if (stage_ == Stage::kIdle && !areas_.empty()) {
    startLearning();
  }
  return {true, ""};
}

RequestResult Workflow::reteachArea(int k) {
  if (k < 0 || k >= static_cast<int>(areas_.size())) {
    return refuse("reteach_area", "reteach_area: expected an area index in [0, " + std::to_string(areas_.size()) +
                                      "), got " + std::to_string(k));
  }
  if (stage_ != Stage::kConfiguration || sub_stage_ == SubStage::kRecording) {
    return refuse("reteach_area", std::string("reteach_area: only in CONFIGURATION outside RECORDING, not in ") + stateName());
  }
  reteach_index_ = k;
  emit(WorkflowEvent::Kind::kButton, "reteach_area", areas_[static_cast<std::size_t>(k)].name, k);
  return {true, ""};
}

RequestResult Workflow::execute(const std::vector<Eigen::Vector3d>& waypoints) {
  if (stage_ != Stage::kExecution) return refuse("execute", std::string("execute: not in EXECUTION but ") + stateName());
  if (waypoints.empty()) return refuse("execute", "execute: expected at least one waypoint");
  for (const auto& p : waypoints) {
    if (!p.allFinite()) return refuse("execute", "execute: waypoints must be finite");
  }
  execution_waypoints_ = waypoints;
  std::reverse(execution_waypoints_.begin(), execution_waypoints_.end());  // back() = next
  execution_target_ = interaction_.taskTarget();
  path_postures_.reset();  // a motion that is not a planned path follows q_c
  return {true, ""};
}

RequestResult Workflow::replayTeachIn(int k) {
  if (stage_ != Stage::kExecution) return refuse("replay", std::string("replay: not in EXECUTION but ") + stateName());
  if (k < 0 || k >= static_cast<int>(teach_ins_.size())) {
    return refuse("replay", "replay: no teach-in " + std::to_string(k + 1) + "; " + std::to_string(teach_ins_.size()) +
                                (teach_ins_.size() == 1 ? " was" : " were") + " recorded");
  }
  const Eigen::MatrixXd& trajectory = teach_ins_[static_cast<std::size_t>(k)];
  std::vector<Eigen::Vector3d> waypoints;
  waypoints.reserve(static_cast<std::size_t>(trajectory.cols()));
  for (Eigen::Index i = 0; i < trajectory.cols(); ++i) waypoints.emplace_back(trajectory.col(i));
  const RequestResult result = execute(waypoints);
  // Named for a person as the window's chooser names it, 1 the first (the event's index and
  // the session's trajectory names, teach_in_<k>, count from 0).
  if (result) emit(WorkflowEvent::Kind::kExecution, "replay", "teach-in " + std::to_string(k + 1), k);
  return result;
}

RequestResult Workflow::planTo(const Eigen::Vector3d& goal) {
  if (stage_ != Stage::kExecution) return refuse("plan", std::string("plan: not in EXECUTION but ") + stateName());
  if (!goal.allFinite()) return refuse("plan", "plan: the goal must be three finite numbers");
  // A map that never grew was mostly taught in contact: then the goal is not what is wrong. A
  // brush of a few seconds in a long configuration is not that (the positions, not the nodes,
  // compare: the ITM keeps far fewer nodes than the positions it is fed).
  const bool mostly_in_contact = itm_positions_in_contact_ > 0 && itm_positions_in_contact_ >= itm_positions_inserted_;
  const std::string left_out = mostly_in_contact ? "; " + std::to_string(itm_positions_in_contact_) +
                                                       " positions of CONFIGURATION were left out of it because the arm touched something"
                                                 : std::string();
  if (itm_.nodeCount() == 0) return refuse("plan", "plan: the ITM graph is empty (nothing explored in CONFIGURATION)" + left_out);
  const Eigen::Vector3d start = interaction_.taskTarget();
  auto path = std::make_shared<planning::PlannedPath>(
      planning::planPath(itm_, Eigen::VectorXd(start), Eigen::VectorXd(goal)));
  if (!path->found) return refuse("plan", "plan: no path through the ITM graph (start and goal in different components)");
  if (path->goal_gap > options_.max_goal_gap) {
    std::ostringstream reason;
    // Rounded up: a gap just over the limit must not read as the limit itself.
    reason << std::fixed << std::setprecision(1) << "plan: the goal is " << std::ceil(path->goal_gap * 1e4) / 10.0
           << " mm from the nearest explored position (at most " << options_.max_goal_gap * 1e3 << " mm)";
    if (mostly_in_contact) reason << "; the map holds " << itm_.nodeCount() << (itm_.nodeCount() == 1 ? " node" : " nodes") << left_out;
    return refuse("plan", reason.str());
  }
  std::vector<Eigen::Vector3d> waypoints;
  for (Eigen::Index i = 0; i < path->waypoints.cols(); ++i) waypoints.emplace_back(path->waypoints.col(i));
  if (waypoints.empty()) waypoints.push_back(goal);
  const RequestResult result = execute(waypoints);
  if (!result) return result;
  if (options_.plan_postures == planning::PlanPostures::kDemonstrated) {
    path_postures_ = std::make_unique<const planning::PathPostures>(itm_, *path, start, state_.q);
  }
  std::ostringstream detail;
  detail << "to (" << goal.transpose() << ") m through " << path->nodes.size() << " nodes, " << path->length << " m";
  planned_path_ = std::move(path);
  ++path_version_;
  emit(WorkflowEvent::Kind::kExecution, "plan", detail.str());
  return result;
}

RequestResult Workflow::nudgeTask(const Eigen::Vector3d& dx) {
  if (!dx.allFinite()) return refuse("nudge_task", "nudge_task: the step must be three finite numbers");
  if (!execution_waypoints_.empty()) return refuse("nudge_task", "nudge_task: a motion is being executed");
  interaction_.nudgeTask(dx);
  execution_target_ = interaction_.taskTarget();
  path_postures_.reset();  // off the path: q_c again
  return {true, ""};
}

RequestResult Workflow::nudgeJoint(int joint, double dq) {
  if (joint < 0 || joint >= model_robot_->dof() || !std::isfinite(dq)) {
    return refuse("nudge_joint", "nudge_joint: expected a joint in [0, " + std::to_string(model_robot_->dof()) +
                                     ") and a finite step");
  }
  if (!execution_waypoints_.empty()) return refuse("nudge_joint", "nudge_joint: a motion is being executed");
  Eigen::VectorXd step = Eigen::VectorXd::Zero(model_robot_->dof());
  step[joint] = dq;
  interaction_.nudgeJoints(step);
  if (controller_ == InteractionController::kHierarchicalControl && stage_ != Stage::kExecution) {
    // Holding without a map: the held posture is the null-space target (Sect. 8.1).
    hold_q_ = (hold_q_ + step).cwiseMax(interaction_.limiter().lower()).cwiseMin(interaction_.limiter().upper());
    interaction_.setFixedPosture(hold_q_);
  }
  return {true, ""};
}

void Workflow::setKeyboardMode(bool keyboard) {
  keyboard_ = keyboard;
  interaction_.setKeyboardMode(keyboard);
}

// ---------------------------------------------------------------------------------------------
// Triggers drive the sub-stages (Fig. 2.5, 2.8).

void Workflow::onTrigger(Trigger trigger) {
  const bool affected = trigger == Trigger::kOnAffected;
  const std::string from = stateName();
  switch (sub_stage_) {
    case SubStage::kWaiting:
      if (!affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      setState(stage_, SubStage::kApproaching);
      break;
    case SubStage::kApproaching:
      if (affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      q_fixed_ = state_.q;
      setState(stage_, SubStage::kPosed);
      if (stage_ == Stage::kConfiguration) checkJointLimits(q_fixed_, recordingArea());
      break;
    case SubStage::kPosed:
      if (!affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      if (stage_ == Stage::kConfiguration) {
        recording_q_fixed_ = q_fixed_;
        ++recording_serial_;
        setState(stage_, SubStage::kRecording);
      } else {
        setState(stage_, SubStage::kTeachIn);
      }
      recording_samples_ = 0;
      recording_contacts_ = 0;
      recording_full_ = false;
      last_sample_time_ = -1e9;
      break;
    case SubStage::kRecording:
      if (affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      {
        const Eigen::Index contacts = recording_contacts_;
        const int created = finishArea();
        setState(stage_, SubStage::kWaiting);
        // After the stage's event: the GUI clears warnings at a new stage.
        if (created >= 0) {
          warnIfTheAreaIsSmall(created);
          warnIfTheAreaWasTaughtInContact(created, contacts);
        }
      }
      break;
    case SubStage::kTeachIn: {
      if (affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      const int stored = finishTeachIn();
      setState(stage_, SubStage::kWaiting);
      warnAboutTheTeachIn(stored);  // after the stage's event, as the areas' warnings
      break;
    }
    case SubStage::kNone: break;
  }
}

void Workflow::checkJointLimits(const Eigen::VectorXd& q_fixed, int area) {
  const Eigen::VectorXd lower = model_robot_->softLowerLimits();
  const Eigen::VectorXd upper = model_robot_->softUpperLimits();
  for (Eigen::Index j = 0; j < q_fixed.size(); ++j) {
    const robot::Joint& joint = model_robot_->joints()[static_cast<std::size_t>(j)];
    const bool sliding = joint.type == robot::JointType::kPrismatic;
    const double margin = std::min(q_fixed[j] - lower[j], upper[j] - q_fixed[j]);
    const double near = nearLimitMargin(joint, options_);
    if (margin < near) {
      // To a tenth of a degree or millimetre: what a person reads; closer than that is at it.
      const double shown = std::round(std::abs(margin) * (sliding ? 1000.0 : 180.0 / std::numbers::pi) * 10.0) / 10.0;
      std::ostringstream detail;
      // Named as the area will be: the one re-taught keeps its name; a new one gets the tutor's
      // name for it, else the one it gets when created.
      const bool reteaching = area < static_cast<int>(areas_.size());
      const std::string name = reteaching                 ? areas_[static_cast<std::size_t>(area)].name
                               : next_area_name_.empty() ? freshAreaName()
                                                         : next_area_name_;
      detail << "posture near the joint limit at area '" << name << "': joint " << (j + 1) << " (" << joint.name << ") is ";
      if (shown == 0.0) {
        detail << "at its limit";
      } else {
        detail << std::fixed << std::setprecision(1) << shown << (sliding ? " mm" : " deg")
               << (margin < 0.0 ? " beyond" : " from");
      }
      // Named with its value: the software limit lies inside the range the Joints panel shows.
      const double limit = q_fixed[j] - lower[j] < upper[j] - q_fixed[j] ? lower[j] : upper[j];
      detail << (shown == 0.0 ? " (" : " its software limit (") << std::fixed << std::setprecision(1)
             << limit * (sliding ? 1000.0 : 180.0 / std::numbers::pi) << (sliding ? " mm" : " deg")
             << "): the controller has " << (shown == 0.0 || margin < 0.0 ? "no" : "little") << " room left to move that joint there; re-teach the area with the joint farther from it";
      emit(WorkflowEvent::Kind::kWarning, "joint_limit", detail.str(), area);
    }
  }
}

int Workflow::finishTeachIn() {
  if (recording_samples_ == 0) return -1;
  teach_ins_.emplace_back(recording_X_.leftCols(recording_samples_));
  ++teach_ins_version_;
  std::ostringstream detail;
  detail << "teach-in " << teach_ins_.size() << ": " << recording_samples_ << " samples";
  const int index = static_cast<int>(teach_ins_.size()) - 1;
  emit(WorkflowEvent::Kind::kTeachIn, "teach_in", detail.str(), index);
  return index;
}

void Workflow::warnAboutTheTeachIn(int index) {
  if (index < 0) {
    emit(WorkflowEvent::Kind::kWarning, "empty_teach_in", "the teach-in held no sample; nothing kept");
    return;
  }
  // A teach-in recorded without moving the tip (keys that only turned the wrist, a hand that
  // let go at once) replays as standing still: kept, as a person may mean it, but said.
  const auto path = teach_ins_[static_cast<std::size_t>(index)].topRows<3>();
  const double extent = (path.colwise() - path.col(0)).colwise().norm().maxCoeff();
  if (extent >= kSmallestAreaExtent * arm_scale_.length) return;
  std::ostringstream warning;
  warning << std::fixed << std::setprecision(1) << "teach-in " << index + 1 << ": the tip moved at most " << extent * 1e3
          << " mm, so replaying it moves nothing; guide the tip along the path while TEACH-IN records, or teach it again";
  emit(WorkflowEvent::Kind::kWarning, "small_teach_in", warning.str(), index);
}

int Workflow::finishArea() {
  if (recording_samples_ == 0) {
    emit(WorkflowEvent::Kind::kWarning, "empty_recording", "the recording held no sample; no area created");
    return -1;
  }
  // The one allocation of a RECORDING: its samples leave the preallocated buffer.
  TrainingArea area;
  area.q_fixed = recording_q_fixed_;
  area.X = recording_X_.leftCols(recording_samples_);
  area.Q = recording_Q_.leftCols(recording_samples_);
  area.centre = area.X.col(0);  // c_k = x_init (Eq. 3.14)
  int index = static_cast<int>(areas_.size());
  if (reteach_index_ >= 0 && reteach_index_ < index) {
    index = reteach_index_;
    area.name = areas_[static_cast<std::size_t>(index)].name;
    areas_[static_cast<std::size_t>(index)] = std::move(area);
    reteach_index_ = -1;
    model_.reset();
    online_.reset();
    checks_.clear();
    if (options_.learner == LearnerKind::kOsElm) startLearning();  // refit what the online learner cannot forget
  } else {
    area.name = next_area_name_.empty() ? freshAreaName() : next_area_name_;
    areas_.push_back(std::move(area));
  }
  next_area_name_.clear();
  recording_samples_ = 0;
  rebuildConfidence();
  ++areas_version_;
  ++model_version_;  // the confidence model changed (and, re-teaching, the map was dropped)
  const TrainingArea& created = areas_[static_cast<std::size_t>(index)];
  std::ostringstream detail;
  detail << std::fixed << std::setprecision(3) << created.name << ": " << created.X.cols()
         << (created.X.cols() == 1 ? " sample" : " samples") << ", centre (" << created.centre.x() << ", "
         << created.centre.y() << ", " << created.centre.z() << ") m";
  emit(WorkflowEvent::Kind::kAreaCreated, created.name, detail.str(), index);
  return index;
}

std::string Workflow::freshAreaName() const {
  // After a removal the count no longer names a free number (area_1 removed, area_2 kept: a
  // third area counted as area_2 would share its name).
  for (std::size_t number = areas_.size() + 1;; ++number) {
    const std::string name = "area_" + std::to_string(number);
    if (std::none_of(areas_.begin(), areas_.end(), [&](const TrainingArea& area) { return area.name == name; })) return name;
  }
}

void Workflow::warnIfTheAreaIsSmall(int index) {
  const TrainingArea& area = areas_[static_cast<std::size_t>(index)];
  // An area recorded without moving the tip (a tutor who let go at once, a keyboard user whose
  // 2 s of stillness ran out) teaches one point: its confidence is nil a few millimetres away.
  // The thesis' participants recorded from almost no spread to circles of 32 cm (Fig. 4.10).
  const double extent = (area.X.colwise() - area.centre).colwise().norm().maxCoeff();
  if (extent >= kSmallestAreaExtent * arm_scale_.length) return;
  std::ostringstream warning;
  warning << std::fixed << std::setprecision(1) << area.name << ": the tip moved at most " << extent * 1e3
          << " mm from where the recording began; move it around inside the area while RECORDING (a few "
             "centimetres), or re-teach the area";
  emit(WorkflowEvent::Kind::kWarning, "small_area", warning.str(), index);
}

void Workflow::warnIfTheAreaWasTaughtInContact(int index, Eigen::Index contacts) {
  // A simulated link passes through the table or an obstacle; a tutor who posed the arm there
  // teaches the map a posture inside it, and the map of free space (Chap. 7) keeps none of
  // those positions, so a session taught that way cannot plan. Said now, not at the first plan.
  // A circle that brushes an obstacle for a moment (under 5 % of the samples) is not worth it.
  const TrainingArea& area = areas_[static_cast<std::size_t>(index)];
  if (contacts == 0 || 20 * contacts < area.X.cols()) return;
  std::ostringstream warning;
  warning << area.name << ": " << contacts << " of " << area.X.cols()
          << " samples were recorded with the arm touching something (drawn red); the map of free space "
             "keeps none of them and the learned postures lead into the contact: re-teach the area with the arm clear";
  emit(WorkflowEvent::Kind::kWarning, "area_in_contact", warning.str(), index);
}

void Workflow::rebuildConfidence() {
  confidence_ = learning::ConfidenceModel(options_.confidence_d);
  for (const auto& area : areas_) confidence_.addArea(area.X);
}

learning::TrainingSet Workflow::trainingSet() const {
  learning::TrainingSet data;
  Eigen::Index total = 0;
  for (const auto& area : areas_) total += area.X.cols();
  data.X.resize(3, total);
  data.Y.resize(model_robot_->dof(), total);
  Eigen::Index l = 0;
  for (std::size_t k = 0; k < areas_.size(); ++k) {
    const auto& area = areas_[k];
    data.X.middleCols(l, area.X.cols()) = area.X;
    data.Y.middleCols(l, area.Q.cols()) = area.Q;
    for (Eigen::Index i = 0; i < area.X.cols(); ++i) data.area.push_back(static_cast<int>(k));
    l += area.X.cols();
  }
  return data;
}

// ---------------------------------------------------------------------------------------------
// Learning: after finished_configuration on a background thread; the result is taken over in
// update() without waiting (the control side never blocks on learning).

void Workflow::startLearning() {
  if (learning_thread_.joinable()) return;
  learning::TrainingSet data = trainingSet();
  std::vector<TrainingArea> areas = areas_;
  learning_done_.store(false, std::memory_order_relaxed);
  learning_started_ = std::chrono::steady_clock::now();
  learning_result_ = std::make_unique<LearningResult>();
  auto job = [this, data = std::move(data), areas = std::move(areas)]() {
    LearningResult& result = *learning_result_;
    result.samples = data.size();
    const auto start = std::chrono::steady_clock::now();
    try {
      std::shared_ptr<learning::Learner> learner;
      if (options_.learner == LearnerKind::kOsElm) {
        // Refit the online learner on all samples here, not on the control thread.
        std::unique_ptr<learning::OsElm> online = makeOnlineLearner();
        for (Eigen::Index l = 0; l < data.size(); ++l) {
          if (l % 256 == 0) cancel_.throwIfCancelled();
          online->update(data.X.col(l), data.Y.col(l));
        }
        learner = std::make_shared<learning::OsElm>(*online);
        result.online = std::move(online);
      } else {
        learner = makeLearner(options_, model_robot_->dof());
        learner->fit(data, cancel_);
      }
      result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      // Tutor feedback with two or more areas: straight motions between the areas.
      if (areas.size() >= 2) {
        std::unique_ptr<robot::CollisionWorld> world;
        if (options_.check_scene != nullptr) world = std::make_unique<robot::CollisionWorld>(*model_robot_, *options_.check_scene);
        for (std::size_t i = 0; i < areas.size(); ++i) {
          for (std::size_t j = i + 1; j < areas.size(); ++j) {
            if (areas.size() > 8 && j != i + 1) continue;  // many areas: neighbours in teaching order
            cancel_.throwIfCancelled();
            result.checks.push_back(checkTransition(*model_robot_, parameters_, *learner, areas[i], areas[j],
                                                    static_cast<int>(i), static_cast<int>(j), world.get(),
                                                    options_.check_speed, options_.check_tolerance));
          }
        }
      }
      result.model = std::move(learner);
    } catch (const learning::TrainingCancelled&) {
      result.error = "cancelled";
    } catch (const std::exception& e) {
      result.error = e.what();
    }
    learning_done_.store(true, std::memory_order_release);
  };
  if (options_.background_learning) {
    learning_thread_ = std::thread([job = std::move(job)]() mutable {
      // Started from the control loop, which may run at SCHED_FIFO (WorkflowThread).
      realtime::runAtNormalPriority();
      job();
    });
    realtime::nameThread(learning_thread_, "fr-learning");
  } else {
    job();
    collectLearning();
  }
}

void Workflow::collectLearning() {
  if (!learning_result_ || !learning_done_.load(std::memory_order_acquire)) return;
  if (learning_thread_.joinable()) learning_thread_.join();  // it has finished: no wait
  std::unique_ptr<LearningResult> result = std::move(learning_result_);
  learning_seconds_ = result->seconds;
  if (!result->error.empty()) {
    emit(WorkflowEvent::Kind::kWarning, "learning_failed", result->error);
    return;
  }
  model_ = std::move(result->model);
  model_samples_ = result->samples;
  ++model_version_;
  // OS-ELM: keep learning online from the refit on.
  if (result->online) online_ = std::move(result->online);
  std::ostringstream detail;
  // What a person reads: milliseconds to a tenth, seconds to a hundredth.
  detail << toString(options_.learner) << " from " << areas_.size() << (areas_.size() == 1 ? " area, " : " areas, ")
         << result->samples << (result->samples == 1 ? " sample" : " samples") << " in " << std::fixed
         << (result->seconds < 1.0 ? std::setprecision(1) : std::setprecision(2))
         << (result->seconds < 1.0 ? 1000.0 * result->seconds : result->seconds) << (result->seconds < 1.0 ? " ms" : " s");
  emit(WorkflowEvent::Kind::kModelLearned, toString(options_.learner), detail.str());
  checks_ = std::move(result->checks);
  for (const auto& check : checks_) {
    std::ostringstream line;
    const std::string& from_name = areas_[static_cast<std::size_t>(check.from)].name;
    line << std::fixed << std::setprecision(1) << from_name << " -> " << areas_[static_cast<std::size_t>(check.to)].name
         << ": mean error " << check.mean_error_m * 1e3 << " mm, max " << check.max_error_m * 1e3 << " mm, posture error "
         << std::setprecision(2) << check.posture_error_rad << " rad, colliding samples " << check.colliding_samples;
    if (!check.first_contact.empty()) {
      line << " (first " << check.first_contact << ", " << check.first_contact_along_m << " m from " << from_name << ")";
    }
    emit(check.ok ? WorkflowEvent::Kind::kCheck : WorkflowEvent::Kind::kWarning,
         check.ok ? "transition_ok" : "transition_inconsistent", line.str(), check.to);
  }
}

std::vector<std::string> standingWarnings(const std::vector<WorkflowEvent>& events, bool with_the_pose_in_hand) {
  // Each warning with the index its area has now. A joint-limit warning is said when a recording
  // starts and stands once the recording has made its area: a recording that makes none takes it
  // back, a re-taught area's replaces the old posture's, and a removal takes the removed area's
  // with it (the posture is no longer taught) and moves the later areas down by one.
  std::vector<std::pair<const WorkflowEvent*, int>> standing;
  std::vector<const WorkflowEvent*> this_recordings_limits;
  // A small area's warning follows its area the same way, said once the area is made.
  const auto ofTheArea = [](const auto& e) {
    return e.first->name == "joint_limit" || e.first->name == "small_area" || e.first->name == "area_in_contact";
  };
  const std::string posed = std::string(toString(Stage::kConfiguration)) + "/" + toString(SubStage::kPosed);
  for (const WorkflowEvent& event : events) {
    if (event.kind == WorkflowEvent::Kind::kModelLearned) {
      std::erase_if(standing, [](const auto& e) { return e.first->name == "transition_inconsistent"; });
    }
    if (event.kind == WorkflowEvent::Kind::kAreaRemoved && event.area >= 0) {
      std::erase_if(standing, [&](const auto& e) { return ofTheArea(e) && e.second == event.area; });
      for (auto& e : standing) {
        if (e.second > event.area) --e.second;
      }
    }
    // A pose given up (a button pressed in POSED: configuration finished, an area to re-teach)
    // or taken anew (POSED entered; its joint-limit check follows) makes no area of the pose
    // warned about.
    const bool new_pose = event.kind == WorkflowEvent::Kind::kStage && event.name == posed;
    if (event.kind == WorkflowEvent::Kind::kButton || new_pose) this_recordings_limits.clear();
    if (event.kind == WorkflowEvent::Kind::kAreaCreated && event.area >= 0) {
      std::erase_if(standing, [&](const auto& e) { return ofTheArea(e) && e.second == event.area; });
      for (const WorkflowEvent* limit : this_recordings_limits) standing.emplace_back(limit, event.area);
      this_recordings_limits.clear();
    }
    if (event.kind != WorkflowEvent::Kind::kWarning) continue;
    if (event.name == "joint_limit") {
      this_recordings_limits.push_back(&event);
    } else {
      if (event.name == "empty_recording") this_recordings_limits.clear();
      standing.emplace_back(&event, event.area);
    }
  }
  if (with_the_pose_in_hand) {
    for (const WorkflowEvent* limit : this_recordings_limits) standing.emplace_back(limit, limit->area);
  }
  std::vector<std::string> lines;
  for (const auto& [event, area] : standing) {
    if (std::find(lines.begin(), lines.end(), event->detail) == lines.end()) lines.push_back(event->detail);
  }
  return lines;
}

double Workflow::learningSeconds() const {
  if (learning_result_) return std::chrono::duration<double>(std::chrono::steady_clock::now() - learning_started_).count();
  return learning_seconds_;
}

void Workflow::waitForLearning() {
  if (learning_thread_.joinable()) learning_thread_.join();
  collectLearning();
}

TransitionCheck checkTransition(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                const learning::Learner& map, const TrainingArea& from, const TrainingArea& to,
                                int from_index, int to_index, robot::CollisionWorld* world, double speed,
                                double tolerance) {
  TransitionCheck check;
  check.from = from_index;
  check.to = to_index;
  const Eigen::Vector3d start = tipPose(model, from.q_fixed).translation();
  const Eigen::Vector3d goal = to.centre;
  const double duration = (goal - start).norm() / speed;
  const auto line = [&](double t) -> Eigen::Vector3d {
    return duration > 0.0 ? Eigen::Vector3d(start + (t / duration) * (goal - start)) : goal;
  };
  // The whole line is run through contacts: the tutor hears how much of it collides.
  const MotionOutcome motion =
      executeMotion(model, parameters, map, from.q_fixed, line, duration, 2.0, world, AtContact::kContinue);
  check.mean_error_m = motion.mean_error_m;
  check.max_error_m = motion.max_error_m;
  check.final_error_m = motion.final_error_m;
  check.posture_error_rad = model.postureDifference(motion.q, to.q_fixed).norm();
  check.colliding_samples = world != nullptr ? motion.colliding_checks : -1;
  check.first_contact = motion.contact;
  if (motion.collided) check.first_contact_along_m = std::min(motion.contact_time, duration) * speed;
  check.ok = check.colliding_samples <= 0 && check.final_error_m <= tolerance && check.max_error_m <= 5.0 * tolerance;
  return check;
}

// ---------------------------------------------------------------------------------------------
// The control cycle.

void Workflow::recordSample() {
  if (state_.time - last_sample_time_ < options_.sample_period - 1e-9) return;
  last_sample_time_ = state_.time;
  const Eigen::Vector3d p = state_.p_WT();
  // Every position of the configuration stage feeds the ITM (DESIGN §3, Chap. 7), a map of the
  // visited free space: a simulated arm that sank into an obstacle (the simulation lets links
  // pass through) visited no free space there.
  if (stage_ == Stage::kConfiguration) {
    if (state_.in_contact) {
      ++itm_positions_in_contact_;
    } else {
      itm_.insert(p, state_.q);
      ++itm_positions_inserted_;
      ++itm_version_;
    }
  }
  if (sub_stage_ != SubStage::kRecording && sub_stage_ != SubStage::kTeachIn) return;
  if (recording_samples_ >= recording_X_.cols()) {
    if (!recording_full_) {
      recording_full_ = true;
      emit(WorkflowEvent::Kind::kWarning, "recording_full",
           "the recording is longer than max_recording_time; later samples are not kept");
    }
    return;
  }
  recording_X_.col(recording_samples_) = p;
  recording_Q_.col(recording_samples_) = state_.q;
  ++recording_samples_;
  if (state_.in_contact && sub_stage_ == SubStage::kRecording) ++recording_contacts_;
  if (sub_stage_ == SubStage::kRecording && options_.learner == LearnerKind::kOsElm) {
    // Online learning during RECORDING (Chap. 6, Eq. 6.4-6.5).
    if (!online_) online_ = makeOnlineLearner();
    online_->update(p, state_.q);
  }
}

void Workflow::command() {
  if (stage_ == Stage::kExecution && !execution_waypoints_.empty()) {
    // Eq. 2.11 with the learned q_c, the target moving along the waypoints at execution_speed.
    const Eigen::Vector3d to = execution_waypoints_.back() - execution_target_;
    const double step = options_.execution_speed * backend_->cycleTime();
    const Eigen::Vector3d previous_target = execution_target_;
    if (to.norm() <= step) {
      execution_target_ = execution_waypoints_.back();
      execution_waypoints_.pop_back();
    } else {
      execution_target_ += to.normalized() * step;
    }
    interaction_.setTaskTarget(execution_target_, (execution_target_ - previous_target) / backend_->cycleTime());
  }
  interaction_.update(state_, command_);
  backend_->writeCommand(command_);
}

std::unique_ptr<learning::OsElm> Workflow::makeOnlineLearner() const {
  return std::make_unique<learning::OsElm>(
      3, model_robot_->dof(), learning::InputNormalization::fromBox(options_.workspace_lower, options_.workspace_upper),
      options_.elm);
}

void Workflow::update() {
  backend_->readState(state_);
  if (!measured_ && state_.time > 0.0) {
    // The first measurement: hold where the robot is. A real robot's backend reports a zero
    // posture until its controller has sent one, and holding that would pull the arm towards
    // the stretched posture.
    measured_ = true;
    hold_q_ = state_.q;
    if (stage_ == Stage::kIdle) q_fixed_ = state_.q;
    restartController();
  }
  collectLearning();
  if (stage_ == Stage::kConfiguration || stage_ == Stage::kProgramming) {
    if (const auto event = triggers_.update(state_)) onTrigger(event->kind);
    recordSample();
  }
  command();
}

void Workflow::step() {
  update();
  backend_->step();
}

}  // namespace flexirob::app
