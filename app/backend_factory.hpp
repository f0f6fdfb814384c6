#pragma once
// The backend choice of the GUI and the CLI (`--backend sim` or `--backend fri://HOST:PORT`,
// DESIGN §9, issue #9) and the robot connection the application drives.
//
// A RobotConnection is itself a RobotBackend: the control thread (or the workflow) steps it like
// any backend. After every step it publishes a link status that other threads (the GUI's timer)
// copy without waiting on the control cycle, and it carries out the operator's reconnect
// confirmation on the control thread, where the FRI backend may be touched. The control thread
// never blocks on a reader: if a reader holds the status at that instant, the cycle skips its
// publication and the next one publishes.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "robot/backend.hpp"
#include "robot/fri_backend.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {

enum class BackendKind { kSimulation, kFri };

/// A parsed backend choice.
struct BackendChoice {
  BackendKind kind = BackendKind::kSimulation;
  std::string text = "sim";   ///< the choice as given, for display
  robot::FriBackendConfig fri;  ///< for kFri: the robot controller's endpoint, defaults otherwise
};

/// "sim", or "fri://HOST:PORT" with HOST a dotted IPv4 address or a host name and PORT in
/// [1, 65535] (the robot controller's UDP endpoint; the KRC sends from it). Throws
/// flexirob::InputError with a one-line reason for anything else (unknown scheme, missing host
/// or port, a path, query or user part, a bad port).
BackendChoice parseBackendChoice(const std::string& text);

/// Link status as the operator sees it: cheap to copy, no references into the backend.
struct LinkStatus {
  BackendKind kind = BackendKind::kSimulation;
  std::string backend;          ///< the choice, e.g. "fri://192.168.0.20:49938"
  /// "simulated", or the FRI link: "waiting", "monitoring", "commanding", "fault".
  std::string link = "simulated";
  std::string state;            ///< FRI interface state ("monitor", "command"); empty for sim
  std::string quality;          ///< FRI quality ("perfect", "ok", "bad", "unacceptable")
  std::string control;          ///< the KRC's controller ("joint impedance", ...)
  bool commanding = true;       ///< commands reach the arm
  bool fault = false;           ///< the watchdog tripped; reconnect needs the operator
  std::string fault_reason;     ///< why, while fault is true
  std::string last_rejection;   ///< why the last refused command was refused ("" if none)
  double cycle = 0.0;           ///< [s]
  double answer_rate = 1.0;     ///< the KRC's statistics of our answers (FRI), 1 for sim
  double latency = 0.0;         ///< [s] the KRC's mean answer latency (FRI)
  double time = 0.0;            ///< [s] backend time of the latest measurement
  std::uint64_t measurements = 0;        ///< measurements taken in (FRI) / steps (sim)
  std::uint64_t lost_measurements = 0;
  std::uint64_t dropped_datagrams = 0;   ///< foreign + short + oversized + malformed + stale
  std::uint64_t commands_rejected = 0;
  std::uint64_t watchdog_trips = 0;
  std::uint64_t reconnects = 0;          ///< operator confirmations that cleared a fault
  std::uint64_t reconnects_refused = 0;  ///< confirmations while no fresh measurement flowed

  /// One line for a status bar, e.g. "fri://10.0.0.2:49938 commanding, quality perfect, 1.0 ms".
  std::string summary() const;
};

/// The chosen backend behind the RobotBackend interface plus the thread-safe link status.
class RobotConnection final : public robot::RobotBackend {
 public:
  /// Creates the backend: the Bullet simulation of `model` in `scene` (may be null; must outlive
  /// the connection) for kSimulation, the FRI backend for kFri (binds its UDP port; throws
  /// InputError if the model is not the 7-joint LWR IV or the port cannot be bound).
  RobotConnection(const BackendChoice& choice, const robot::RobotModel& model, const robot::Scene* scene,
                  const robot::ParameterSet& parameters);
  /// Wraps a backend made elsewhere (tests: an FRI backend on an ephemeral port).
  RobotConnection(BackendChoice choice, std::unique_ptr<robot::RobotBackend> backend);
  ~RobotConnection() override;
  RobotConnection(const RobotConnection&) = delete;
  RobotConnection& operator=(const RobotConnection&) = delete;

  // --- RobotBackend, for the one thread that drives the robot.
  const robot::RobotModel& model() const override { return backend_->model(); }
  double cycleTime() const override { return backend_->cycleTime(); }
  void readState(robot::RobotState& state) const override { backend_->readState(state); }
  robot::CommandStatus writeCommand(const robot::JointImpedanceCommand& command) override;
  /// Steps the backend, then carries out a pending reconnect request and publishes the status.
  void step() override;

  /// The backend itself (control thread only), e.g. to reach the Simulation's hand forces.
  robot::RobotBackend& backend() { return *backend_; }
  /// The FRI backend, or null for the simulation (control thread only).
  robot::FriBackend* fri() { return fri_; }

  // --- Any thread.
  /// A copy of the status published after the latest step (never waits for a control cycle).
  LinkStatus status() const;
  /// The operator's confirmation to resume after a watchdog fault. Carried out on the next
  /// step(); the outcome shows in status() (fault cleared and `reconnects`, or
  /// `reconnects_refused` if no fresh measurement flows yet).
  void requestReconnect() { reconnect_requested_.store(true, std::memory_order_release); }

 private:
  void publish();

  BackendChoice choice_;
  std::unique_ptr<robot::RobotBackend> backend_;
  robot::FriBackend* fri_ = nullptr;
  std::atomic<bool> reconnect_requested_{false};
  std::uint64_t steps_ = 0;
  std::uint64_t reconnects_ = 0;
  std::uint64_t reconnects_refused_ = 0;
  std::uint64_t sim_rejections_ = 0;
  robot::RobotState state_;
  LinkStatus building_;  // filled by the control thread, copied into published_ under the lock

  mutable std::mutex status_mutex_;
  LinkStatus published_;
};

}  // namespace flexirob::app
