#include "app/workflow.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <numbers>
#include <cmath>
#include <sstream>

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

const char* toString(Trigger trigger) { return trigger == Trigger::kOnAffected ? "on_affected" : "on_converged"; }

const char* toString(InteractionController controller) {
  switch (controller) {
    case InteractionController::kHold: return "hierarchical";
    case InteractionController::kGravityCompensation: return "gravity_compensation";
    case InteractionController::kCompliantRecording: return "compliant_recording";
    case InteractionController::kAssistedGravityCompensation: return "assisted_gravity_compensation";
    case InteractionController::kAssistanceBlending: return "assistance_blending";
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
  }
  return "?";
}

LearnerKind learnerKindFromString(const std::string& name) {
  if (name == "elm") return LearnerKind::kElm;
  if (name == "oselm") return LearnerKind::kOsElm;
  if (name == "llm") return LearnerKind::kLlm;
  throw InputError("learner: expected elm, oselm or llm, got '" + name + "'");
}

ImpedanceGains gainsOf(InteractionController controller) {
  switch (controller) {
    case InteractionController::kHold: return {300.0, 0.95};
    case InteractionController::kGravityCompensation: return {20.0, 0.7};
    case InteractionController::kCompliantRecording: return {80.0, 0.7};
    case InteractionController::kAssistedGravityCompensation: return {50.0, 0.7};
    case InteractionController::kAssistanceBlending: return {50.0, 0.7};
  }
  return {300.0, 0.95};
}

// ---------------------------------------------------------------------------------------------
// Triggers (App. A.3): on_affected when max |τ_ext| exceeds the threshold while the robot is
// not moving; on_converged when, after on_affected, the robot has not moved for converged_time.

std::optional<Trigger> InteractionTriggers::update(const robot::RobotState& state) {
  const double speed = state.qd.size() > 0 ? state.qd.cwiseAbs().maxCoeff() : 0.0;
  const double torque = state.tau_ext.size() > 0 ? state.tau_ext.cwiseAbs().maxCoeff() : 0.0;
  const bool still = speed < still_velocity_;
  if (still && !was_still_) still_since_ = state.time;
  was_still_ = still;
  if (!affected_) {
    if (still && torque > affected_torque_) {
      affected_ = true;
      still_since_ = state.time;
      return Trigger::kOnAffected;
    }
    return std::nullopt;
  }
  if (still && state.time - still_since_ >= converged_time_) {
    affected_ = false;
    return Trigger::kOnConverged;
  }
  return std::nullopt;
}

void InteractionTriggers::reset(bool affected, double time) {
  affected_ = affected;
  still_since_ = time;
}

// ---------------------------------------------------------------------------------------------

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

Workflow::Workflow(robot::RobotBackend& backend, const robot::ParameterSet& parameters, WorkflowOptions options)
    : backend_(&backend),
      model_robot_(&backend.model()),
      options_(std::move(options)),
      hierarchical_(backend.model(), parameters),
      limiter_(backend.model(), parameters, backend.cycleTime()),
      parameters_(parameters),
      triggers_(options_.affected_torque, options_.still_velocity, options_.converged_time),
      confidence_(options_.confidence_d),
      itm_(options_.itm, backend.model().dof()) {
  const int dof = model_robot_->dof();
  if (options_.sample_period <= 0.0 || options_.converged_time <= 0.0 || options_.affected_torque <= 0.0) {
    throw InputError("workflow: sample period, converged time and affected torque must be positive");
  }
  state_.resize(dof);
  command_.resize(dof);
  q_c_.setZero(dof);
  qd_.setZero(dof);
  backend_->readState(state_);
  hold_q_ = state_.q;
  limiter_.reset(state_.q);
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
    case SubStage::kWaiting: controller_ = InteractionController::kHold; break;
  }
  if (controller_ == InteractionController::kHold) {
    hold_q_ = state_.q;
    limiter_.reset(state_.q);
  }
  emit(WorkflowEvent::Kind::kStage, stateName(), std::string("controller ") + toString(controller_));
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
      triggers_.reset(false, state_.time);
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
      triggers_.reset(false, state_.time);
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
      execution_target_ = state_.p_WT();
      return {true, ""};
  }
  return refuse(name, "unknown button");
}

RequestResult Workflow::fire(Trigger trigger) {
  if (stage_ != Stage::kConfiguration && stage_ != Stage::kProgramming) {
    return refuse(toString(trigger), std::string(toString(trigger)) + ": no interaction in " + stateName());
  }
  triggers_.reset(trigger == Trigger::kOnAffected, state_.time);
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
  return {true, ""};
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
      if (stage_ == Stage::kConfiguration) checkJointLimits(q_fixed_, static_cast<int>(areas_.size()));
      break;
    case SubStage::kPosed:
      if (!affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      if (stage_ == Stage::kConfiguration) {
        current_ = TrainingArea{};
        current_.q_fixed = q_fixed_;
        current_.X.resize(3, 0);
        current_.Q.resize(model_robot_->dof(), 0);
        last_sample_time_ = -1e9;
        setState(stage_, SubStage::kRecording);
      } else {
        teach_in_points_.clear();
        last_sample_time_ = -1e9;
        setState(stage_, SubStage::kTeachIn);
      }
      break;
    case SubStage::kRecording:
      if (affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      finishArea();
      setState(stage_, SubStage::kWaiting);
      break;
    case SubStage::kTeachIn: {
      if (affected) return;
      emit(WorkflowEvent::Kind::kTrigger, toString(trigger), from);
      Eigen::MatrixXd trajectory(3, static_cast<Eigen::Index>(teach_in_points_.size()));
      for (std::size_t i = 0; i < teach_in_points_.size(); ++i) trajectory.col(static_cast<Eigen::Index>(i)) = teach_in_points_[i];
      teach_ins_.push_back(std::move(trajectory));
      setState(stage_, SubStage::kWaiting);
      break;
    }
    case SubStage::kNone: break;
  }
}

void Workflow::checkJointLimits(const Eigen::VectorXd& q_fixed, int area) {
  const Eigen::VectorXd lower = model_robot_->softLowerLimits();
  const Eigen::VectorXd upper = model_robot_->softUpperLimits();
  for (Eigen::Index j = 0; j < q_fixed.size(); ++j) {
    const double margin = std::min(q_fixed[j] - lower[j], upper[j] - q_fixed[j]);
    if (margin < options_.limit_warning_margin) {
      std::ostringstream detail;
      detail << "posture near the joint limit: joint " << (j + 1) << " (" << model_robot_->joints()[static_cast<std::size_t>(j)].name
             << ") is " << margin * 180.0 / std::numbers::pi << " deg from its limit";
      emit(WorkflowEvent::Kind::kWarning, "joint_limit", detail.str(), area);
    }
  }
}

void Workflow::finishArea() {
  if (current_.X.cols() == 0) {
    emit(WorkflowEvent::Kind::kWarning, "empty_recording", "the recording held no sample; no area created");
    return;
  }
  int index = static_cast<int>(areas_.size());
  if (reteach_index_ >= 0 && reteach_index_ < index) {
    index = reteach_index_;
    current_.name = areas_[static_cast<std::size_t>(index)].name;
    areas_[static_cast<std::size_t>(index)] = std::move(current_);
    reteach_index_ = -1;
    model_.reset();
    online_.reset();
    checks_.clear();
    if (options_.learner == LearnerKind::kOsElm) startLearning();  // refit what the online learner cannot forget
  } else {
    current_.name = "area_" + std::to_string(index + 1);
    areas_.push_back(std::move(current_));
  }
  current_ = TrainingArea{};
  rebuildConfidence();
  const TrainingArea& area = areas_[static_cast<std::size_t>(index)];
  std::ostringstream detail;
  detail << area.name << ": " << area.X.cols() << " samples, centre (" << area.centre.transpose() << ") m";
  emit(WorkflowEvent::Kind::kAreaCreated, area.name, detail.str(), index);
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
    learning_thread_ = std::thread(std::move(job));
  } else {
    job();
    collectLearning();
  }
}

void Workflow::collectLearning() {
  if (!learning_result_ || !learning_done_.load(std::memory_order_acquire)) return;
  if (learning_thread_.joinable()) learning_thread_.join();  // it has finished: no wait
  std::unique_ptr<LearningResult> result = std::move(learning_result_);
  if (!result->error.empty()) {
    emit(WorkflowEvent::Kind::kWarning, "learning_failed", result->error);
    return;
  }
  model_ = std::move(result->model);
  // OS-ELM: keep learning online from the refit on.
  if (result->online) online_ = std::move(result->online);
  std::ostringstream detail;
  detail << toString(options_.learner) << " from " << areas_.size() << " areas, " << result->samples
         << " samples in " << result->seconds << " s";
  emit(WorkflowEvent::Kind::kModelLearned, toString(options_.learner), detail.str());
  checks_ = std::move(result->checks);
  for (const auto& check : checks_) {
    std::ostringstream line;
    line << areas_[static_cast<std::size_t>(check.from)].name << " -> " << areas_[static_cast<std::size_t>(check.to)].name
         << ": mean error " << check.mean_error_m * 1e3 << " mm, max " << check.max_error_m * 1e3 << " mm, posture error "
         << check.posture_error_rad << " rad, colliding samples " << check.colliding_samples;
    emit(check.ok ? WorkflowEvent::Kind::kCheck : WorkflowEvent::Kind::kWarning,
         check.ok ? "transition_ok" : "transition_inconsistent", line.str(), check.to);
  }
}

void Workflow::waitForLearning() {
  if (learning_thread_.joinable()) learning_thread_.join();
  collectLearning();
}

TransitionCheck checkTransition(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                const learning::Learner& map, const TrainingArea& from, const TrainingArea& to,
                                int from_index, int to_index, robot::CollisionWorld* world, double speed,
                                double tolerance) {
  constexpr double kDt = 1e-3;
  TransitionCheck check;
  check.from = from_index;
  check.to = to_index;
  robot::HierarchicalController controller(model, parameters);
  robot::CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(from.q_fixed);
  robot::Kinematics kinematics(model);
  Eigen::VectorXd qd(model.dof()), q_c(model.dof());
  const Eigen::Vector3d start = tipPose(model, from.q_fixed).translation();
  const Eigen::Vector3d goal = to.centre;
  const double length = (goal - start).norm();
  const double duration = length / speed;
  const double settle = 2.0;
  const auto steps = static_cast<int>(std::ceil((duration + settle) / kDt));
  double error_sum = 0.0;
  int error_count = 0;
  check.colliding_samples = world != nullptr ? 0 : -1;
  for (int k = 1; k <= steps; ++k) {
    const double s = duration > 0.0 ? std::min(1.0, k * kDt / duration) : 1.0;
    const Eigen::Vector3d p_des = start + s * (goal - start);
    map.predict(p_des, q_c);
    controller.velocity(limiter.command(), p_des, q_c, qd, &limiter);
    const Eigen::VectorXd& q = limiter.updateVelocity(qd);
    if (k % 10 == 0) {
      kinematics.update(q);
      const double error = (kinematics.p_WT() - p_des).norm();
      error_sum += error;
      ++error_count;
      check.max_error_m = std::max(check.max_error_m, error);
      if (world != nullptr) {
        world->update(q);
        if (!world->contacts().empty()) ++check.colliding_samples;
      }
    }
  }
  kinematics.update(limiter.command());
  check.final_error_m = (kinematics.p_WT() - goal).norm();
  check.mean_error_m = error_count > 0 ? error_sum / error_count : 0.0;
  check.posture_error_rad = (limiter.command() - to.q_fixed).norm();
  check.ok = check.colliding_samples <= 0 && check.final_error_m <= tolerance && check.max_error_m <= 5.0 * tolerance;
  return check;
}

// ---------------------------------------------------------------------------------------------
// The control cycle.

void Workflow::predictPosture(const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) const {
  const learning::Learner* learner = online_ ? online_.get() : model_.get();
  if (learner != nullptr && learner->trained()) {
    learner->predict(p_W, q_c);
  } else {
    q_c = state_.q;
  }
}

void Workflow::recordSample() {
  if (state_.time - last_sample_time_ < options_.sample_period - 1e-9) return;
  last_sample_time_ = state_.time;
  const Eigen::Vector3d p = state_.p_WT();
  // Every position of the configuration stage feeds the ITM (DESIGN §3, Chap. 7).
  if (stage_ == Stage::kConfiguration) itm_.insert(p, state_.q);
  if (sub_stage_ == SubStage::kRecording) {
    const Eigen::Index l = current_.X.cols();
    if (l == 0) current_.centre = p;  // c_k = x_init (Eq. 3.14)
    current_.X.conservativeResize(3, l + 1);
    current_.Q.conservativeResize(current_.Q.rows(), l + 1);
    current_.X.col(l) = p;
    current_.Q.col(l) = state_.q;
    if (options_.learner == LearnerKind::kOsElm) {
      // Online learning during RECORDING (Chap. 6, Eq. 6.4-6.5).
      if (!online_) {
        online_ = makeOnlineLearner();
      }
      online_->update(p, state_.q);
    }
  } else if (sub_stage_ == SubStage::kTeachIn) {
    teach_in_points_.push_back(p);
  }
}

void Workflow::command() {
  const ImpedanceGains gains = gainsOf(controller_);
  command_.stiffness.setConstant(gains.stiffness);
  command_.damping.setConstant(gains.damping);
  switch (controller_) {
    case InteractionController::kHold:
      if (stage_ == Stage::kExecution && model_) {
        // Eq. 2.11 with the learned q_c, the target moving along the waypoints.
        if (!execution_waypoints_.empty()) {
          const Eigen::Vector3d to = execution_waypoints_.back() - execution_target_;
          const double step = options_.execution_speed * backend_->cycleTime();
          if (to.norm() <= step) {
            execution_target_ = execution_waypoints_.back();
            execution_waypoints_.pop_back();
          } else {
            execution_target_ += to.normalized() * step;
          }
        }
        predictPosture(execution_target_, q_c_);
        hierarchical_.velocity(limiter_.command(), execution_target_, q_c_, qd_, &limiter_);
        command_.q_cmd = limiter_.updateVelocity(qd_);
      } else {
        command_.q_cmd = limiter_.update(hold_q_);
      }
      break;
    case InteractionController::kGravityCompensation:
      // π_q: the inner loop compensates gravity; the spring is centred on the measured posture.
      command_.q_cmd = state_.q;
      break;
    case InteractionController::kCompliantRecording: command_.q_cmd = q_fixed_; break;
    case InteractionController::kAssistedGravityCompensation:
    case InteractionController::kAssistanceBlending: {
      // The tip is free (the command agrees with the measured tip position); the null space is
      // pulled towards q_c(x): q_cmd = q + α (I − J⁺J)(q_c(x) − q), with α = 1 for assisted
      // gravity compensation and α = C(x) for assistance blending (Eq. 6.2 in the null space).
      const Eigen::Vector3d p = state_.p_WT();
      predictPosture(p, q_c_);
      hierarchical_.velocity(state_.q, p, q_c_, qd_);
      double alpha = 1.0;
      if (controller_ == InteractionController::kAssistanceBlending) alpha = confidence_.areas() > 0 ? confidence_.evaluate(p) : 0.0;
      const double kappa_q = hierarchical_.kappaQ() > 0.0 ? hierarchical_.kappaQ() : 1.0;
      command_.q_cmd = state_.q + (alpha / kappa_q) * qd_;
      break;
    }
  }
  // Keep inside the software limits (the robot rejects commands beyond its limits).
  command_.q_cmd = command_.q_cmd.cwiseMax(limiter_.lower()).cwiseMin(limiter_.upper());
  if (controller_ != InteractionController::kHold) limiter_.reset(state_.q);
  backend_->writeCommand(command_);
}

std::unique_ptr<learning::OsElm> Workflow::makeOnlineLearner() const {
  return std::make_unique<learning::OsElm>(
      3, model_robot_->dof(), learning::InputNormalization::fromBox(options_.workspace_lower, options_.workspace_upper),
      options_.elm);
}

void Workflow::update() {
  backend_->readState(state_);
  collectLearning();
  if (stage_ == Stage::kConfiguration || stage_ == Stage::kProgramming) {
    if (const auto trigger = triggers_.update(state_)) onTrigger(*trigger);
    recordSample();
  }
  command();
}

void Workflow::step() {
  update();
  backend_->step();
}

}  // namespace flexirob::app
