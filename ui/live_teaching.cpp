#include "ui/live_teaching.hpp"

#include <algorithm>

#include "app/evaluation.hpp"
#include "robot/errors.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::ui {
namespace {

template <std::size_t N>
std::string text(const std::array<char, N>& characters) {
  const auto end = std::find(characters.begin(), characters.end(), '\0');
  return std::string(characters.begin(), end);
}

}  // namespace

bool buttonMakesSense(app::Button button, const LiveSnapshot& s) {
  using app::Stage;
  using app::SubStage;
  switch (button) {
    case app::Button::kStartConfiguration:
      return (s.stage == Stage::kIdle || s.stage == Stage::kExecution) && !s.learning;
    case app::Button::kFinishedConfiguration:
      return s.stage == Stage::kConfiguration && s.sub_stage != SubStage::kRecording && s.areas > 0;
    case app::Button::kStartProgramming:
      return (s.stage == Stage::kIdle || s.stage == Stage::kExecution) && s.areas > 0 && !s.learning &&
             s.model_ready;
    case app::Button::kFinishedProgramming:
      return s.stage == Stage::kProgramming && s.sub_stage != SubStage::kTeachIn;
  }
  return false;
}

LiveTeaching::LiveTeaching(const robot::RobotModel& model, const robot::Scene& scene,
                           const robot::ParameterSet& parameters, app::WorkflowOptions workflow_options,
                           const app::BackendChoice& backend, Options options)
    : model_(&model), options_(options), parameters_(parameters), kinematics_(model) {
  if (model.dof() > app::kMaxDof) {
    throw InputError("live robot: at most " + std::to_string(app::kMaxDof) + " joints, got " +
                     std::to_string(model.dof()));
  }
  connection_ = std::make_unique<app::RobotConnection>(backend, model, &scene, parameters_);
  simulation_ = dynamic_cast<robot::Simulation*>(&connection_->backend());
  if (simulation_ != nullptr) {
    // The simulation stands in the middle of the limits; a scene without a home posture whose
    // obstacles that posture touches starts in the free posture nearest it (app::homePosture).
    const Eigen::VectorXd home = app::homePosture(model, scene);
    if (!home.isApprox(model.midPosture())) simulation_->reset(home);
  }
  workflow_options.check_scene = &scene;
  // The worker needs the simulation itself as the workflow's backend (hand forces, contacts);
  // the connection then only names the backend. A real robot is driven through the connection,
  // which watches the link.
  robot::RobotBackend& driven = simulation_ != nullptr ? static_cast<robot::RobotBackend&>(*simulation_)
                                                       : static_cast<robot::RobotBackend&>(*connection_);
  workflow_ = std::make_unique<app::Workflow>(driven, parameters_, std::move(workflow_options));
  app::WorkflowThread::Options thread_options;
  thread_options.paced = options.paced;
  // A real robot's measurements pace the loop (the FRI backend waits for each).
  thread_options.backend_paces = simulation_ == nullptr;
  // Only a loop that waits, on its clock or for the robot: an unpaced loop on the simulation
  // (tests) never sleeps and would starve its core at FIFO priority.
  thread_options.realtime_priority = options.realtime_priority && (options.paced || thread_options.backend_paces);
  thread_ = std::make_unique<app::WorkflowThread>(*workflow_, simulation_, thread_options);
}

LiveTeaching::~LiveTeaching() { stop(); }

void LiveTeaching::start() { thread_->start(); }

void LiveTeaching::stop() {
  if (thread_) thread_->stop();
}

bool LiveTeaching::running() const { return thread_->running(); }

app::LinkStatus LiveTeaching::linkStatus() const {
  app::LinkStatus status = connection_->status();
  if (simulation_ != nullptr) {
    // The simulation is stepped directly (not through the connection): its figures come from
    // the worker's snapshot.
    const app::CycleStatistics stats = thread_->statistics();
    status.measurements = stats.cycles;
    status.cycle = simulation_->cycleTime();
  }
  return status;
}

bool LiveTeaching::press(app::Button button) { return post(app::WorkflowRequest::press(button)); }

bool LiveTeaching::fire(app::Trigger trigger) { return post(app::WorkflowRequest::fire(trigger)); }

bool LiveTeaching::grab(int body, const Eigen::Vector3d& p_B, const Eigen::Vector3d& target_W, double stiffness) {
  if (body < 1 || body > model_->dof() || simulation_ == nullptr) return false;
  grab_body_ = body;
  grab_p_B_ = p_B;
  grab_target_W_ = target_W;
  grab_stiffness_ = stiffness;
  sendSpring();
  return true;
}

bool LiveTeaching::release() {
  grab_body_ = -1;
  return post(app::WorkflowRequest::releaseHand());
}

bool LiveTeaching::setKeyboardMode(bool keyboard) { return post(app::WorkflowRequest::keyboardMode(keyboard)); }

bool LiveTeaching::nudgeTask(const Eigen::Vector3d& dx) { return post(app::WorkflowRequest::nudgeTask(dx)); }

bool LiveTeaching::nudgeJoint(int joint, double dq) { return post(app::WorkflowRequest::nudgeJoint(joint, dq)); }

bool LiveTeaching::planTo(const Eigen::Vector3d& goal) { return post(app::WorkflowRequest::planTo(goal)); }

bool LiveTeaching::replayTeachIn(int teach_in) { return post(app::WorkflowRequest::replayTeachIn(teach_in)); }

bool LiveTeaching::removeArea(int area) { return post(app::WorkflowRequest::removeArea(area)); }

bool LiveTeaching::reteachArea(int area) { return post(app::WorkflowRequest::reteachArea(area)); }

void LiveTeaching::tick() {
  if (grab_body_ > 0) sendSpring();
}

void LiveTeaching::sendSpring() {
  // F = k (p_cursor − p_grab(q)), the grab point taken at the newest measured posture.
  const LiveSnapshot& s = thread_->snapshot();
  if (s.dof == model_->dof()) {
    Eigen::VectorXd q(s.dof);
    for (int j = 0; j < s.dof; ++j) q[j] = s.q[static_cast<std::size_t>(j)];
    kinematics_.update(q);
  }
  const Eigen::Vector3d p_W = kinematics_.X_WB(grab_body_) * grab_p_B_;
  // The spring and its limit are a person's hand on the LWR IV; on a lighter or shorter arm they
  // are scaled as the tutor's hands are (the stiffness by the mass ratio, the limit by the force
  // ratio), or a pull would fling a 1 kg arm about. Both ratios are 1 for the LWR IV and arm9.
  const app::ArmScale& scale = workflow_->armScale();
  Eigen::Vector3d force = grab_stiffness_ * scale.mass() * (grab_target_W_ - p_W);
  const double max_force = options_.max_hand_force * scale.force();
  const double newtons = force.norm();
  if (newtons > max_force) force *= max_force / newtons;
  post(app::WorkflowRequest::handForce(grab_body_, grab_p_B_, force));
}

std::vector<LiveEvent> LiveTeaching::takeEvents() {
  const LiveSnapshot& s = thread_->snapshot();
  std::vector<LiveEvent> events;
  if (s.event_sequence <= shown_event_) return events;
  const std::uint64_t first = std::max<std::uint64_t>(shown_event_ + 1, s.event_sequence > app::kEventRingSize
                                                                            ? s.event_sequence - app::kEventRingSize + 1
                                                                            : 1);
  for (std::uint64_t sequence = first; sequence <= s.event_sequence; ++sequence) {
    const app::EventRecord& record = s.events[static_cast<std::size_t>((sequence - 1) % app::kEventRingSize)];
    if (record.sequence != sequence) continue;  // overwritten meanwhile
    events.push_back({record.sequence, record.time, record.kind, record.area, text(record.name), text(record.detail)});
  }
  shown_event_ = s.event_sequence;
  return events;
}

}  // namespace flexirob::ui
