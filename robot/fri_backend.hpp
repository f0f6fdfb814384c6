#pragma once
// The real KUKA LWR IV behind the RobotBackend interface, over FRI (DESIGN §9, thesis App. A.2).
//
// Every cycle the robot controller (KRC) sends a measurement; step() waits for it and the
// backend answers it with exactly one command datagram: right away in writeCommand() (the
// friRemote pattern receive → compute → send), or, if the caller wrote no command this cycle,
// at the start of the next step().
//
// Monitor mode mirrors the arm: q = msrJntPos, q_cmd = cmdJntPos + cmdJntPosFriOffset,
// tau_ext = estExtJntTrq, X_WT from our own kinematics of q. Command mode sends joint
// impedance commands (JNTPOS | JNTSTIFF | JNTDAMP, thesis App. A.3).
//
// Safety, in the order a datagram meets it:
//  - datagrams from any endpoint other than the configured robot are dropped (counted);
//  - short, oversized, malformed (wrong id or packetSize, non-finite joint values) datagrams are
//    dropped (counted); repeated or out-of-order ones too;
//  - a controller command leaves only while the KRC reports CMD state, joint impedance control
//    and quality >= OK, and only if it lies inside the software position limits; a command
//    that would move a joint faster than its velocity limit over one cycle is forwarded moved
//    towards at the velocity limit (FriVelocityPolicy::kRateLimit, the default) or rejected
//    (kReject); anything else is rejected and the previous posture is held;
//  - the watchdog: `watchdog_cycles` measurements in a row missing (lost in transit, none for
//    (watchdog_cycles + 0.5) cycles after the later of the last measurement and our answer to
//    it, or left unanswered because our loop was late) trip it (with a lockstep robot side the
//    cycles are counted by the KRC's sequence counter only, see FriBackendConfig::lockstep):
//    the backend stops forwarding commands, answers the KRC with the held posture, and reports
//    the fault until the operator calls confirmReconnect().
// Not thread-safe: one control thread calls step(), readState(), writeCommand() and reads
// status(); the application publishes status() to the GUI through its snapshot.
#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "robot/backend.hpp"
#include "robot/fri_protocol.hpp"
#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"
#include "robot/udp_socket.hpp"

namespace flexirob::robot {

/// What writeCommand() does with a command that would move a joint faster than its velocity
/// limit within one cycle.
enum class FriVelocityPolicy {
  kRateLimit,  ///< forward the posture moved towards it at the velocity limit (counted)
  kReject,     ///< refuse it; the previous posture is held
};

struct FriBackendConfig {
  std::string local_address = "0.0.0.0";           ///< where to listen
  std::uint16_t local_port = fri::kDefaultPcPort;  ///< 0: ephemeral (tests)
  /// The robot controller. Datagrams from any other address are dropped; port 0 accepts any
  /// source port of that address. Answers go to the source endpoint of the measurement.
  UdpEndpoint robot;
  /// Measurements that may go missing in a row before the watchdog trips (lost, late or
  /// unanswered). The timeout is (watchdog_cycles + 0.5) cycles.
  int watchdog_cycles = 3;
  /// Cycle [s] assumed until the KRC reports its own (desiredMsrSampleTime).
  double nominal_cycle = 1e-3;
  /// Lowest link quality at which commands are forwarded.
  fri::Quality min_quality = fri::Quality::kOk;
  /// Joint impedance held when no controller command was accepted yet (CMD state).
  double hold_stiffness = 300.0;  ///< [Nm/rad], hierarchical control in Tab. A.1
  double hold_damping = 0.7;      ///< normalized
  /// Our cap on commanded joint stiffness [Nm/rad]; the KRC applies its own limits as well.
  double max_stiffness = 5000.0;
  /// Slack on the velocity check for float rounding: |Δq| <= v_max·T·(1 + tolerance).
  double velocity_tolerance = 1e-6;
  FriVelocityPolicy velocity_policy = FriVelocityPolicy::kRateLimit;
  /// The robot side waits for each of our answers before it sends the next measurement (the
  /// simulated controller's lockstep mode, tests only; never the real KRC). Its cycles then
  /// pass in computing time, not in wall-clock time, so the watchdog counts missing
  /// measurements by the KRC's sequence counter only (gaps of more than watchdog_cycles) and
  /// its wall-clock timeout is off: a slow stand-in (a sanitizer build, a loaded machine) is no
  /// fault. A robot side silent for `lockstep_timeout` [s] counts as gone (measurement timeout).
  bool lockstep = false;
  double lockstep_timeout = 10.0;
};

/// The backend choice "fri://HOST[:PORT]" (the GUI's and flexirob's --backend) as a
/// configuration: HOST[:PORT] is the robot controller (without a port, any source port of that
/// host); everything else keeps its default. Throws InputError for anything else.
FriBackendConfig friConfigFromUri(const std::string& uri);

/// Link condition as the operator sees it.
enum class FriLink {
  kWaiting,     ///< no measurement from the robot yet
  kMonitoring,  ///< measurements flow; commands are not forwarded (MON, quality, mode)
  kCommanding,  ///< measurements flow and commands are forwarded
  kFault,       ///< the watchdog tripped: holding; needs confirmReconnect()
};
const char* toString(FriLink link);

enum class FriFault {
  kNone,
  kMeasurementTimeout,  ///< no measurement for more than watchdog_cycles cycles
  kMeasurementsLost,    ///< the sequence counter skipped more than watchdog_cycles measurements
  kControlLoopLate,     ///< watchdog_cycles measurements piled up unanswered
};
const char* toString(FriFault fault);

/// Why writeCommand() refused a command (the last reason is kept in FriStatus).
enum class FriRejection {
  kNone,
  kInvalid,          ///< wrong size, non-finite, negative or excessive stiffness/damping
  kPositionLimit,    ///< outside the software position limits
  kVelocityLimit,    ///< a joint would move faster than its velocity limit in one cycle (kReject), or
                     ///< the last command was forwarded at the velocity limit (kRateLimit)
  kNotPermitted,     ///< not CMD state, quality below minimum, not joint impedance, or fault
};
const char* toString(FriRejection rejection);

/// Everything the backend counted, since construction.
struct FriCounters {
  std::uint64_t datagrams_received = 0;    ///< every datagram read from the socket
  std::uint64_t measurements_accepted = 0; ///< valid measurements from the robot
  std::uint64_t foreign_dropped = 0;       ///< from another address or port
  std::uint64_t short_dropped = 0;
  std::uint64_t oversized_dropped = 0;
  std::uint64_t malformed_dropped = 0;     ///< wrong id, packetSize or non-finite joint values
  std::uint64_t out_of_order_dropped = 0;  ///< repeated or older sequence numbers
  std::uint64_t stale_skipped = 0;         ///< older measurements drained unanswered in one step
  std::uint64_t lost_measurements = 0;     ///< gaps in the KRC's sequence counter
  std::uint64_t replies_sent = 0;          ///< command datagrams sent (every answer)
  std::uint64_t commands_sent = 0;         ///< answers carrying an accepted controller command
  std::uint64_t hold_replies = 0;          ///< answers carrying the held posture
  std::uint64_t send_failures = 0;
  std::uint64_t commands_rejected = 0;     ///< writeCommand() calls refused
  std::uint64_t commands_rate_limited = 0; ///< commands forwarded at the velocity limit (kRateLimit)
  std::uint64_t watchdog_trips = 0;
  std::uint64_t quality_holds = 0;         ///< CMD-state cycles held because of low quality
  std::uint64_t step_timeouts = 0;         ///< step() calls that returned without a measurement
};

/// A copyable snapshot for the GUI and the CLI (no allocation).
struct FriStatus {
  FriLink link = FriLink::kWaiting;
  FriFault fault = FriFault::kNone;          ///< the fault that tripped the watchdog last
  FriRejection last_rejection = FriRejection::kNone;
  std::uint16_t state = 0;    ///< fri::InterfaceState, raw, of the latest measurement
  std::uint16_t quality = 0;  ///< fri::Quality, raw
  std::uint16_t control = 0;  ///< fri::ControlMode, raw
  std::uint16_t power = 0, error = 0, warning = 0;
  fri::InterfaceStatistics statistics;       ///< the KRC's view of our answers
  double cycle = 0.0;                        ///< [s] current cycle time
  std::uint16_t last_measurement_seq = 0;    ///< KRC's sendSeqCount of the latest measurement
  std::uint16_t last_reflected_seq = 0;      ///< the KRC's reflection of our counter
  std::uint16_t last_reply_seq = 0;          ///< our sendSeqCount of the latest answer
  FriCounters counters;
};

class FriBackend final : public RobotBackend {
 public:
  /// Binds the socket. The model must have 7 joints (the LWR IV); throws InputError otherwise
  /// or if the socket cannot be bound or the configuration is out of range.
  FriBackend(RobotModel model, FriBackendConfig config);
  /// As above on a socket the caller bound already (config.local_* are then ignored): lets a
  /// caller learn the port before it starts the robot side, e.g. with port 0 in tests.
  FriBackend(RobotModel model, FriBackendConfig config, UdpSocket socket);
  FriBackend(const FriBackend&) = delete;  // Kinematics points into model_
  FriBackend& operator=(const FriBackend&) = delete;

  const RobotModel& model() const override { return model_; }
  double cycleTime() const override { return cycle_; }
  void readState(RobotState& state) const override;
  /// Checks and stores a joint impedance command; it leaves with the answer to the current
  /// measurement (at once if that one is still unanswered). Rejected commands change nothing.
  CommandStatus writeCommand(const JointImpedanceCommand& command) override;
  /// Answers the current measurement if still unanswered, then waits for the next one (at most
  /// the watchdog timeout) and takes it in. Returns early without a measurement on a timeout.
  void step() override;

  /// The operator's confirmation after a fault: clears it if measurements flow again (one
  /// arrived within the watchdog timeout). Commands must be written anew afterwards; the held
  /// posture is the reference for their velocity check. Returns whether the fault was cleared.
  bool confirmReconnect();

  const FriStatus& status() const { return status_; }
  /// True if a measurement was taken in since construction.
  bool hasMeasurement() const { return has_measurement_; }
  /// The latest accepted measurement as it came off the wire.
  const fri::MeasurementDatagram& lastMeasurement() const { return measurement_; }
  /// The local endpoint (the actual port if bound to port 0).
  UdpEndpoint localEndpoint() const { return socket_.localEndpoint(); }
  /// The joint posture the backend answers with while not forwarding commands [rad].
  const Eigen::VectorXd& heldPosture() const { return reference_q_; }

 private:
  using Clock = std::chrono::steady_clock;

  void sendReply();
  bool drainSocket();  // true if a new measurement was taken in
  bool accept(const fri::MeasurementDatagram& measurement, int gap);
  void tripWatchdog(FriFault fault);
  bool commandingPermitted() const;
  void updateLink();
  /// [s] of wall-clock silence that trips the watchdog: (watchdog_cycles + 0.5) cycles, or in
  /// lockstep the time after which the robot side counts as gone.
  double watchdogTimeout() const {
    return config_.lockstep ? config_.lockstep_timeout : (config_.watchdog_cycles + 0.5) * cycle_;
  }

  RobotModel model_;
  FriBackendConfig config_;
  UdpSocket socket_;
  Kinematics kinematics_;
  double cycle_;

  fri::MeasurementDatagram measurement_;
  fri::CommandDatagram reply_;
  fri::CommandBytes reply_bytes_{};
  std::array<std::uint8_t, 2048> receive_buffer_{};
  UdpEndpoint reply_to_;
  bool has_measurement_ = false;
  bool has_sequence_ = false;   // last_sequence_ is valid; false again after a timeout (resync)
  std::uint16_t last_sequence_ = 0;  // newest valid KRC sequence number seen
  std::uint16_t reply_sequence_ = 0;
  bool reply_pending_ = false;
  int unanswered_ = 0;          // measurements taken in since the last answer
  Clock::time_point last_measurement_time_;
  Clock::time_point last_reply_time_;
  std::uint64_t cycles_since_start_ = 0;

  // The measured state, converted once per measurement.
  RobotState state_;
  Eigen::VectorXd previous_q_;

  // What the next answer carries.
  Eigen::VectorXd reference_q_;          // joint positions of the last answer, or the hold
  Eigen::VectorXd reference_stiffness_;
  Eigen::VectorXd reference_damping_;
  Eigen::VectorXd limited_q_;            // the posture that leaves after the velocity check
  bool command_active_ = false;          // the reference is an accepted controller command
  bool fault_ = false;

  FriStatus status_;
};

}  // namespace flexirob::robot
