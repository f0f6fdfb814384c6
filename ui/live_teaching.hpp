#pragma once
// The live robot behind the GUI: the chosen backend (simulation or the LWR IV over FRI,
// app::RobotConnection), the teaching workflow and the 1 kHz worker that runs it
// (app::WorkflowThread). The GUI talks to it only through the worker's lock-free request queue
// and reads its newest snapshot at display rate, so nothing here ever blocks the control cycle.
//
// On top of the worker's requests this class keeps what belongs to the GUI side:
//  - the mouse spring (issue #7 item 3; MuJoCo's and Gazebo's perturbation): F = k (p_cursor −
//    p_grab) with p_grab fixed to the link, re-evaluated at every display tick from the newest
//    posture and sent as the simulation's hand force; k and the clip (max_hand_force) are the
//    LWR IV's, times the arm's ArmScale::mass() and force();
//  - the workflow's events, read from the snapshot's ring once each (sequence numbers);
//  - the link status of the backend.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "app/backend_factory.hpp"
#include "app/workflow.hpp"
#include "app/workflow_thread.hpp"
#include "robot/kinematics.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {
class Simulation;
}

namespace flexirob::ui {

using LiveSnapshot = app::WorkflowSnapshot;

/// A workflow event as the GUI shows it.
struct LiveEvent {
  std::uint64_t sequence = 0;
  double time = 0.0;
  app::WorkflowEvent::Kind kind = app::WorkflowEvent::Kind::kStage;
  int area = -1;
  std::string name, detail;
};

class LiveTeaching {
 public:
  struct Options {
    bool paced = true;             ///< real time; off: as fast as possible (tests)
    /// [N] the mouse spring's force is clipped to this on the LWR IV (times the arm's
    /// ArmScale::force() on another)
    double max_hand_force = 80.0;
    /// The control thread asks for SCHED_FIFO (granted to root or with an rtprio limit, else it
    /// runs at normal priority): the GUI's rendering must not delay the 1 ms cycle.
    bool realtime_priority = true;
  };

  /// Model and scene must outlive this object. The simulation starts at the scene's home
  /// posture when it fits the robot. Throws InputError for an unusable model, scene or backend
  /// (e.g. an FRI port in use, or FRI with a robot other than the LWR IV).
  LiveTeaching(const robot::RobotModel& model, const robot::Scene& scene, const robot::ParameterSet& parameters,
               app::WorkflowOptions workflow_options, const app::BackendChoice& backend, Options options);
  ~LiveTeaching();
  LiveTeaching(const LiveTeaching&) = delete;
  LiveTeaching& operator=(const LiveTeaching&) = delete;

  void start();
  /// Stops and joins the worker (idempotent).
  void stop();
  bool running() const;

  // --- From the GUI thread only. Each returns false if the request queue is full.
  bool press(app::Button button);
  bool fire(app::Trigger trigger);
  /// Grabs `body` (1..dof) at p_B [m, body frame] and pulls it towards target_W [m] with a
  /// spring of `stiffness` [N/m] on the LWR IV, times the arm's ArmScale::mass() on another
  /// (re-sent at each tick()).
  bool grab(int body, const Eigen::Vector3d& p_B, const Eigen::Vector3d& target_W, double stiffness);
  /// The hand lets go (mouse spring and forces).
  bool release();
  /// Keyboard tele-operation (Sect. 8.1): keyboard mode, task target steps Δx [m, W] and
  /// null-space steps of one joint Δq [rad].
  bool setKeyboardMode(bool keyboard);
  bool nudgeTask(const Eigen::Vector3d& dx);
  bool nudgeJoint(int joint, double dq);
  /// EXECUTION: plan through the ITM to `goal` and execute (Sect. 7.4).
  bool planTo(const Eigen::Vector3d& goal);
  /// EXECUTION: replay teach-in `teach_in` (0-based).
  bool replayTeachIn(int teach_in);
  /// Removes area `area` (0-based), or has the next RECORDING replace it.
  bool removeArea(int area);
  bool reteachArea(int area);
  /// Display tick: re-evaluates the mouse spring at the newest posture.
  void tick();

  /// The newest snapshot (GUI thread).
  const LiveSnapshot& snapshot() { return thread_->snapshot(); }
  /// Workflow events not returned before (at most the snapshot's ring back).
  std::vector<LiveEvent> takeEvents();
  app::CycleStatistics statistics() const { return thread_->statistics(); }
  /// The session recorder the control thread records into (null: none); see
  /// app::WorkflowThread::setRecorder. It must stay alive until detached or stop().
  void setRecorder(app::SessionRecorder* recorder) { thread_->setRecorder(recorder); }

  bool simulated() const { return simulation_ != nullptr; }
  bool grabbing() const { return grab_body_ > 0; }
  /// The backend's link status (never waits for the worker).
  app::LinkStatus linkStatus() const;
  /// The operator confirms resuming after an FRI watchdog fault.
  void requestReconnect() { connection_->requestReconnect(); }

  const robot::RobotModel& model() const { return *model_; }
  const Options& options() const { return options_; }
  /// The arm against the LWR IV (fixed for the live robot's lifetime).
  const app::ArmScale& armScale() const { return workflow_->armScale(); }

 private:
  bool post(const app::WorkflowRequest& request) { return thread_->post(request) != 0; }
  void sendSpring();

  const robot::RobotModel* model_;
  Options options_;
  robot::ParameterSet parameters_;
  std::unique_ptr<app::RobotConnection> connection_;
  robot::Simulation* simulation_ = nullptr;  // the connection's backend when simulated
  std::unique_ptr<app::Workflow> workflow_;
  std::unique_ptr<app::WorkflowThread> thread_;
  robot::Kinematics kinematics_;  // GUI side, for the spring's point
  std::uint64_t shown_event_ = 0;
  int grab_body_ = -1;
  Eigen::Vector3d grab_p_B_ = Eigen::Vector3d::Zero(), grab_target_W_ = Eigen::Vector3d::Zero();
  double grab_stiffness_ = 0.0;
};

/// Whether pressing `button` makes sense in the state of `snapshot` (the workflow's own rules,
/// Workflow::press): the GUI enables its buttons with it.
bool buttonMakesSense(app::Button button, const LiveSnapshot& snapshot);

}  // namespace flexirob::ui
