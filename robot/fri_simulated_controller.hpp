#pragma once
// A stand-in for the KUKA robot controller (KRC) side of FRI, for tests and demos: it sends a
// measurement datagram every cycle to the PC, takes the PC's command datagrams in, and moves a
// simulated arm with the LWR IV's joint impedance law. Loopback only.
//
// The arm: per joint j, m·q̈ = K_j (q_d,j − q_j) − D_j q̇_j − c q̇_j + τ_ext,j with
// D_j = 2 ζ_j sqrt(K_j m) (FRI's normalized damping ζ), a nominal joint inertia m, a small
// viscous term c so that a released arm comes to rest, and gravity taken as compensated by the
// controller (as the KRC does). Joints stop at the hardware limits.
//
// The controller's side of the session, as a KRL script would run it: monitor mode first;
// once the answer quality has been at least OK for 10 cycles, command mode (friStart); back to
// monitor mode when the quality becomes UNACCEPTABLE. In command mode joint impedance commands
// move the arm; a command that jumps faster than the velocity limits or outside the hardware
// limits is refused and counted (the real KRC stops with an error there).
//
// Fault injection: random measurement and command loss, a fixed extra delay on measurements,
// random reordering of consecutive measurements, explicit drops of the next n measurements and
// raw datagrams sent from the controller's own endpoint (for hostile-packet tests).
#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "robot/backend.hpp"
#include "robot/fri_protocol.hpp"
#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"
#include "robot/udp_socket.hpp"

namespace flexirob::robot {

struct FriSimulatedControllerConfig {
  std::uint16_t port = 0;  ///< local port on 127.0.0.1; 0: ephemeral
  UdpEndpoint peer;        ///< the PC (must be a loopback address)
  double cycle = 1e-3;     ///< [s] measurement period, FRI allows 1-10 ms
  double loss = 0.0;       ///< probability that a datagram (either direction) is lost
  double delay = 0.0;      ///< [s] extra latency of every measurement
  double reorder = 0.0;    ///< probability that a measurement is overtaken by the next one
  std::uint64_t seed = 1;
  Eigen::VectorXd q_initial;  ///< initial posture; empty: the model's mid posture
  fri::ControlMode control = fri::ControlMode::kJointImpedance;
  bool enter_command_mode = true;  ///< switch to CMD once the quality allows it
  double joint_inertia = 0.5;      ///< [kg m²] per joint
  double viscous_damping = 0.5;    ///< [Nm s/rad] the extra term c
  double krl_stiffness = 1000.0;   ///< [Nm/rad] impedance the KRL script holds in monitor mode
  double krl_damping = 0.7;
  /// Faster than real time, for tests of whole teaching runs: the next measurement leaves as
  /// soon as the PC has answered the previous one, and the measurement timestamps count
  /// simulated cycles. The controller waits for that answer as long as the PC takes (the PC may
  /// plan, learn or run under a sanitizer in between), unless the answer cannot come: the
  /// measurement or the answer was dropped by the loss injection, or the measurement is held
  /// back for reordering. Loss, delay and reordering act as in real time otherwise. The PC's
  /// backend must be told (FriBackendConfig::lockstep), so that its watchdog counts missing
  /// measurements by the sequence counter rather than by the wall clock.
  bool lockstep = false;
  /// [s] of wall-clock time after which a lockstep controller stops waiting for an answer and
  /// goes on like the KRC (next cycle, the answer counts as missed); 0: wait as long as it takes.
  double lockstep_patience = 0.0;
};

struct FriSimulatedControllerStats {
  std::uint64_t cycles = 0;
  std::uint64_t measurements_sent = 0;
  std::uint64_t measurements_lost = 0;      ///< dropped by the loss injection or dropNext
  std::uint64_t measurements_reordered = 0;
  std::uint64_t commands_received = 0;      ///< valid command datagrams from the peer
  std::uint64_t commands_lost = 0;          ///< dropped by the loss injection
  std::uint64_t commands_foreign = 0;       ///< from another endpoint
  std::uint64_t commands_malformed = 0;
  std::uint64_t commands_refused = 0;       ///< jumps or limit violations the KRC refused
  std::uint64_t commands_applied = 0;       ///< commands that moved the arm (CMD state)
  std::uint64_t answers_matched = 0;        ///< commands whose reflSeqCount named a recent measurement
  std::uint64_t answers_unmatched = 0;      ///< reflSeqCount naming no measurement sent recently
  std::uint64_t command_mode_entries = 0;
  std::uint64_t command_mode_exits = 0;
  std::uint16_t last_measurement_seq = 0;   ///< our sendSeqCount of the latest measurement
  std::uint16_t last_command_seq = 0;       ///< the PC's sendSeqCount of the latest command
  std::uint16_t last_reflected_seq = 0;     ///< the PC's reflection of our counter
  fri::InterfaceState state = fri::InterfaceState::kMonitor;
  fri::Quality quality = fri::Quality::kUnacceptable;
  double answer_rate = 0.0;
  Eigen::VectorXd q;          ///< simulated posture [rad]
  Eigen::VectorXd q_desired;  ///< the posture the impedance pulls to [rad]
  Eigen::VectorXd stiffness;  ///< [Nm/rad]
};

class FriSimulatedController {
 public:
  /// Binds 127.0.0.1:port. Throws InputError if the peer is not a loopback address, the model
  /// is not 7-DoF, or a parameter is out of range.
  FriSimulatedController(RobotModel model, FriSimulatedControllerConfig config);
  /// As above, with the arm simulated by another backend, e.g. the Bullet Simulation of
  /// robot/sim/, instead of the built-in per-joint model: every cycle the controller hands it
  /// the joint impedance command in force and steps it cycle / arm->cycleTime() times (the
  /// cycle must be a whole multiple). The arm starts where it is (config.q_initial is not used)
  /// and reports τ_ext itself (setExternalTorque() has no effect then).
  FriSimulatedController(RobotModel model, FriSimulatedControllerConfig config, std::unique_ptr<RobotBackend> arm);
  ~FriSimulatedController();
  FriSimulatedController(const FriSimulatedController&) = delete;
  FriSimulatedController& operator=(const FriSimulatedController&) = delete;

  UdpEndpoint localEndpoint() const { return socket_.localEndpoint(); }

  /// Runs the controller on a background thread until stop() (or destruction).
  void start();
  void stop();
  /// Runs on the calling thread for `seconds` of wall-clock time.
  void runFor(double seconds);

  /// Thread-safe snapshot of the counters and the arm.
  FriSimulatedControllerStats stats() const;
  /// Drops the next n measurements (a burst loss); thread-safe.
  void dropNextMeasurements(int n) { drop_next_ += n; }
  /// Sends these bytes from the controller's endpoint at the next cycle; thread-safe.
  void injectRaw(std::vector<std::uint8_t> bytes);
  /// External joint torques [Nm] on the arm, e.g. a hand pushing it; thread-safe.
  void setExternalTorque(const Eigen::VectorXd& tau_ext);
  /// The external arm is stepped by the controller's thread. Another thread that touches it
  /// (a simulated person's hands: SimulatedTutor, TutorOptions::arm_mutex) holds this mutex
  /// while it does, briefly; the controller takes it for each cycle's integration.
  std::mutex& armMutex() { return arm_mutex_; }

 private:
  struct Outgoing {
    double due = 0.0;  // [s] since start
    fri::MeasurementBytes bytes{};
  };
  struct SentRecord {
    std::uint16_t seq = 0;
    double time = 0.0;
    bool answered = false;
    bool valid = false;
  };

  void run(double seconds);
  void runLockstep(double seconds);
  void cycle(double now);
  void receiveCommands(double now);
  void applyCommand(const fri::CommandDatagram& command);
  void integrate(double dt);
  void sendDue(double now);
  void updateQuality();
  void fillMeasurement(fri::MeasurementDatagram& m, double now);

  RobotModel model_;
  FriSimulatedControllerConfig config_;
  UdpSocket socket_;
  Kinematics kinematics_;
  std::mt19937_64 random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};

  // Arm and controller state (owned by the running thread).
  Eigen::VectorXd q_, qd_, q_desired_, stiffness_, damping_, tau_ext_;
  Eigen::VectorXd krl_q_;  // KRL's commanded posture (cmdJntPos)
  fri::InterfaceState state_ = fri::InterfaceState::kMonitor;
  fri::Quality quality_ = fri::Quality::kUnacceptable;
  int good_quality_cycles_ = 0;
  std::uint16_t send_seq_ = 0;
  std::uint16_t last_command_seq_ = 0;
  std::uint16_t last_reflected_seq_ = 0;  // the PC's reflection of our counter, latest command
  std::uint16_t lost_answer_seq_ = 0;     // what the latest answer dropped by the loss injection reflected
  bool answer_lost_ = false;              // lost_answer_seq_ is valid
  std::uint64_t lockstep_cycles_ = 0;     // cycles run in lockstep: the simulated clock
  bool measurement_left_ = false;         // this cycle's measurement was sent (not lost, not held)
  std::vector<SentRecord> sent_;  // ring of the last measurements, for the answer rate
  std::size_t sent_next_ = 0;
  double latency_sum_ = 0.0;
  std::vector<Outgoing> outgoing_;
  std::optional<Outgoing> held_back_;  // a measurement waiting to be overtaken
  std::array<std::uint8_t, 2048> buffer_{};

  // An external arm model (optional).
  std::unique_ptr<RobotBackend> arm_;
  int arm_steps_per_cycle_ = 1;
  RobotState arm_state_;
  JointImpedanceCommand arm_command_;
  std::mutex arm_mutex_;

  mutable std::mutex mutex_;  // guards stats_, injected_, external_torque_
  FriSimulatedControllerStats stats_;
  std::vector<std::vector<std::uint8_t>> injected_;
  Eigen::VectorXd external_torque_;
  std::atomic<int> drop_next_{0};
  std::atomic<bool> stop_requested_{false};
  std::thread thread_;
};

}  // namespace flexirob::robot
