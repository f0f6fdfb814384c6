#pragma once
// The wire format of the KUKA LWR IV Fast Research Interface (FRI): the measurement datagram the
// robot controller (KRC) sends every cycle and the command datagram the PC answers with.
//
// The layout lives in exactly one place: visitMeasurementFields() and visitCommandFields() below
// list every field in wire order. The encoder, the decoder and the static size checks all walk
// these two functions, so they cannot disagree. Bytes are written one by one in little-endian
// order (floats through std::bit_cast), independent of the host's byte order and alignment.
//
// Figures verified against a second public description (DESIGN §9 is the first): the public
// FRI header friComm.h (KUKA/DLR, revision 1.17, 2010) as found in public LWR driver
// repositories; read, not copied. What it confirms:
//   - little-endian, IEEE-754 single floats, 4-byte aligned structs, u16 sequence counters that
//     wrap from 65535 to 0;
//   - header 8 bytes; KRL data 132 (16 float, 16 int32, u16 bools, u16 fill); interface
//     statistics 20 (answerRate, latency, jitter, missRate float; missCounter u32); interface
//     state 40; robot state 36; robot data 175 floats = 700 bytes; measurement 916 bytes, id
//     0x2006; command block 59 × 4 = 236 bytes; command datagram 376 bytes, id 0x1005;
//   - command flags JNTPOS 0x1, JNTTRQ 0x4, JNTSTIFF 0x10, JNTDAMP 0x20, CARTPOS 0x100,
//     TCPFT 0x400, CARTSTIFF 0x1000, CARTDAMP 0x2000;
//   - states OFF 0, MON 1, CMD 2; quality UNACCEPTABLE 0, BAD 1, OK 2, PERFECT 3; controller
//     POSITION 1, CART_IMP 2, JNT_IMP 3 (OTHER 0);
//   - jntDamping is normalized (a damping ratio), jntStiffness in Nm/rad; the Jacobian is
//     row-major 6 × 7 with rows [x y z rz ry rx].
// One deviation from DESIGN §9: the interface timestamp is a float (seconds), not a u32. Both
// are 4 bytes, so offsets and sizes are unchanged; the decoder reads it as a float.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string_view>

namespace flexirob::robot::fri {

inline constexpr int kJoints = 7;          ///< LBR_MNJ: joints of the LWR IV
inline constexpr int kUserSize = 16;       ///< KRL exchange values per type
inline constexpr int kFrameSize = 12;      ///< a 3 × 4 homogeneous frame, row-major [R | p]
inline constexpr int kCartesianSize = 6;   ///< a Cartesian vector (force/torque, stiffness)
inline constexpr std::uint16_t kMeasurementDatagramId = 0x2006;
inline constexpr std::uint16_t kCommandDatagramId = 0x1005;
inline constexpr std::size_t kMeasurementSize = 916;  ///< bytes on the wire, KRC → PC
inline constexpr std::size_t kCommandSize = 376;      ///< bytes on the wire, PC → KRC
inline constexpr std::uint16_t kDefaultPcPort = 49938;

/// FRI interface state reported by the KRC.
enum class InterfaceState : std::uint16_t { kOff = 0, kMonitor = 1, kCommand = 2 };
/// Link quality the KRC derives from our answer rate and timing.
enum class Quality : std::uint16_t { kUnacceptable = 0, kBad = 1, kOk = 2, kPerfect = 3 };
/// The KRC's active controller (robot.control).
enum class ControlMode : std::uint16_t {
  kOther = 0,
  kPosition = 1,
  kCartesianImpedance = 2,
  kJointImpedance = 3
};

/// Bits of CommandBlock::flags: which commanded values the KRC shall use.
namespace command_flags {
inline constexpr std::uint32_t kJointPosition = 0x0001;
inline constexpr std::uint32_t kJointTorque = 0x0004;
inline constexpr std::uint32_t kJointStiffness = 0x0010;
inline constexpr std::uint32_t kJointDamping = 0x0020;
inline constexpr std::uint32_t kCartesianPosition = 0x0100;
inline constexpr std::uint32_t kTcpForceTorque = 0x0400;
inline constexpr std::uint32_t kCartesianStiffness = 0x1000;
inline constexpr std::uint32_t kCartesianDamping = 0x2000;
/// What a joint impedance command sets (thesis App. A.3).
inline constexpr std::uint32_t kJointImpedance = kJointPosition | kJointStiffness | kJointDamping;
}  // namespace command_flags

const char* toString(InterfaceState state);
const char* toString(Quality quality);
const char* toString(ControlMode mode);
/// Names for raw wire values; unknown values read "unknown".
const char* interfaceStateName(std::uint16_t raw);
const char* qualityName(std::uint16_t raw);
const char* controlModeName(std::uint16_t raw);

template <class T, int N>
using Array = std::array<T, static_cast<std::size_t>(N)>;

struct Header {
  std::uint16_t send_seq = 0;  ///< sender's counter, +1 per datagram, wraps at 65535
  std::uint16_t refl_seq = 0;  ///< the other side's send_seq of the last datagram received
  std::uint16_t packet_size = 0;
  std::uint16_t datagram_id = 0;
};

/// Values exchanged with the KRL program ($FRI_FRM_REA/INT/BOOL, $FRI_TO_REA/INT/BOOL).
struct KrlData {
  Array<float, kUserSize> real{};
  Array<std::int32_t, kUserSize> integer{};
  std::uint16_t bools = 0;  ///< 16 flags, one bit each
  std::uint16_t fill = 0;   ///< padding to 4 bytes
};

/// Averages over the KRC's last 100 packets.
struct InterfaceStatistics {
  float answer_rate = 0.0F;  ///< fraction of measurements we answered in time (ideal 1)
  float latency = 0.0F;      ///< [s]
  float jitter = 0.0F;       ///< [s]
  float miss_rate = 0.0F;    ///< fraction of missing answers
  std::uint32_t miss_counter = 0;  ///< missing answers since start
};

struct InterfaceStatus {
  float timestamp = 0.0F;  ///< KRC system time [s]
  std::uint16_t state = 0;    ///< InterfaceState, raw (unknown values are kept)
  std::uint16_t quality = 0;  ///< Quality, raw
  float desired_msr_sample_time = 0.0F;  ///< [s] the measurement period the KRL script set
  float desired_cmd_sample_time = 0.0F;  ///< [s] the command period the KRL script set
  float safety_limits = 0.0F;
  InterfaceStatistics statistics;
};

struct RobotStatus {
  std::uint16_t power = 0;    ///< drive power, one bit per joint
  std::uint16_t control = 0;  ///< ControlMode, raw
  std::uint16_t error = 0;    ///< drive errors, one bit per joint
  std::uint16_t warning = 0;  ///< drive warnings, one bit per joint
  Array<float, kJoints> temperature{};
};

struct RobotData {
  Array<float, kJoints> msr_jnt_pos{};           ///< measured q [rad]
  Array<float, kFrameSize> msr_cart_pos{};       ///< measured tool frame [m], 3 × 4 row-major
  Array<float, kJoints> cmd_jnt_pos{};           ///< KRL's commanded q [rad] (before FRI)
  Array<float, kJoints> cmd_jnt_pos_fri_offset{};  ///< offset added by FRI commands [rad]
  Array<float, kFrameSize> cmd_cart_pos{};
  Array<float, kFrameSize> cmd_cart_pos_fri_offset{};
  Array<float, kJoints> msr_jnt_trq{};           ///< measured joint torques [Nm]
  Array<float, kJoints> est_ext_jnt_trq{};       ///< estimated external joint torques [Nm]
  Array<float, kCartesianSize> est_ext_tcp_ft{};  ///< [N, Nm] Fx Fy Fz Tz Ty Tx
  Array<float, kCartesianSize * kJoints> jacobian{};  ///< 6 × 7 row-major
  Array<float, kJoints * kJoints> mass_matrix{};      ///< 7 × 7 [kg m²]
  Array<float, kJoints> gravity{};                    ///< gravity torques [Nm]
};

/// KRC → PC every cycle (id 0x2006, 916 bytes).
struct MeasurementDatagram {
  Header header{0, 0, static_cast<std::uint16_t>(kMeasurementSize), kMeasurementDatagramId};
  KrlData krl;
  InterfaceStatus intf;
  RobotStatus robot;
  RobotData data;
};

struct CommandBlock {
  std::uint32_t flags = 0;  ///< command_flags bits
  Array<float, kJoints> jnt_pos{};                ///< [rad]
  Array<float, kFrameSize> cart_pos{};            ///< [m]
  Array<float, kJoints> add_jnt_trq{};            ///< [Nm]
  Array<float, kCartesianSize> add_tcp_ft{};      ///< [N, Nm]
  Array<float, kJoints> jnt_stiffness{};          ///< [Nm/rad]
  Array<float, kJoints> jnt_damping{};            ///< normalized (damping ratio)
  Array<float, kCartesianSize> cart_stiffness{};  ///< [N/m, Nm/rad]
  Array<float, kCartesianSize> cart_damping{};    ///< normalized
};

/// PC → KRC, the answer to every measurement (id 0x1005, 376 bytes).
struct CommandDatagram {
  Header header{0, 0, static_cast<std::uint16_t>(kCommandSize), kCommandDatagramId};
  KrlData krl;
  CommandBlock cmd;
};

// ---- The layout: every field in wire order, the single source for encoder, decoder and sizes.

template <class H, class V>
constexpr void visitHeaderFields(H& h, V& v) {
  v(h.send_seq);
  v(h.refl_seq);
  v(h.packet_size);
  v(h.datagram_id);
}

template <class K, class V>
constexpr void visitKrlFields(K& k, V& v) {
  v(k.real);
  v(k.integer);
  v(k.bools);
  v(k.fill);
}

template <class M, class V>
constexpr void visitMeasurementFields(M& m, V& v) {
  visitHeaderFields(m.header, v);
  visitKrlFields(m.krl, v);
  v(m.intf.timestamp);
  v(m.intf.state);
  v(m.intf.quality);
  v(m.intf.desired_msr_sample_time);
  v(m.intf.desired_cmd_sample_time);
  v(m.intf.safety_limits);
  v(m.intf.statistics.answer_rate);
  v(m.intf.statistics.latency);
  v(m.intf.statistics.jitter);
  v(m.intf.statistics.miss_rate);
  v(m.intf.statistics.miss_counter);
  v(m.robot.power);
  v(m.robot.control);
  v(m.robot.error);
  v(m.robot.warning);
  v(m.robot.temperature);
  v(m.data.msr_jnt_pos);
  v(m.data.msr_cart_pos);
  v(m.data.cmd_jnt_pos);
  v(m.data.cmd_jnt_pos_fri_offset);
  v(m.data.cmd_cart_pos);
  v(m.data.cmd_cart_pos_fri_offset);
  v(m.data.msr_jnt_trq);
  v(m.data.est_ext_jnt_trq);
  v(m.data.est_ext_tcp_ft);
  v(m.data.jacobian);
  v(m.data.mass_matrix);
  v(m.data.gravity);
}

template <class C, class V>
constexpr void visitCommandFields(C& c, V& v) {
  visitHeaderFields(c.header, v);
  visitKrlFields(c.krl, v);
  v(c.cmd.flags);
  v(c.cmd.jnt_pos);
  v(c.cmd.cart_pos);
  v(c.cmd.add_jnt_trq);
  v(c.cmd.add_tcp_ft);
  v(c.cmd.jnt_stiffness);
  v(c.cmd.jnt_damping);
  v(c.cmd.cart_stiffness);
  v(c.cmd.cart_damping);
}

namespace detail {
/// Counts wire bytes; fields are scalars of 2 or 4 bytes or arrays of them.
struct ByteCounter {
  std::size_t bytes = 0;
  template <class T>
  constexpr void operator()(const T&) {
    bytes += sizeof(T);
  }
  template <class T, std::size_t N>
  constexpr void operator()(const std::array<T, N>&) {
    bytes += sizeof(T) * N;
  }
};

template <class Part, class Visit>
constexpr std::size_t wireBytes(Visit visit) {
  Part part{};
  ByteCounter counter;
  visit(part, counter);
  return counter.bytes;
}
}  // namespace detail

// Static size checks, section by section (figures as in the public header, see top).
static_assert(detail::wireBytes<Header>([](auto& p, auto& v) { visitHeaderFields(p, v); }) == 8);
static_assert(detail::wireBytes<KrlData>([](auto& p, auto& v) { visitKrlFields(p, v); }) == 132);
static_assert(detail::wireBytes<MeasurementDatagram>([](auto& p, auto& v) { visitMeasurementFields(p, v); }) ==
              kMeasurementSize);
static_assert(detail::wireBytes<CommandDatagram>([](auto& p, auto& v) { visitCommandFields(p, v); }) == kCommandSize);
static_assert(8 + 132 + 40 + 36 + 175 * 4 == kMeasurementSize, "header, KRL, intf, robot state, robot data");
static_assert(8 + 132 + 59 * 4 == kCommandSize, "header, KRL, command block");
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559, "FRI floats are IEEE-754 single");

/// Byte offsets of the sections (for diagnostics and tests).
inline constexpr std::size_t kMeasurementIntfOffset = 8 + 132;          // 140
inline constexpr std::size_t kMeasurementRobotOffset = 8 + 132 + 40;    // 180
inline constexpr std::size_t kMeasurementDataOffset = 8 + 132 + 40 + 36;  // 216
inline constexpr std::size_t kCommandBlockOffset = 8 + 132;             // 140

/// Why a datagram was refused.
enum class DecodeStatus {
  kOk,
  kTooShort,           ///< fewer bytes than the datagram has
  kTooLong,            ///< more bytes than the datagram has
  kWrongDatagramId,    ///< another datagram type or protocol version
  kWrongPacketSize,    ///< the header's packetSize disagrees with the bytes received
};
const char* toString(DecodeStatus status);

using MeasurementBytes = std::array<std::uint8_t, kMeasurementSize>;
using CommandBytes = std::array<std::uint8_t, kCommandSize>;

/// Writes every field as it is (the header too: tests need malformed datagrams).
void encode(const MeasurementDatagram& datagram, MeasurementBytes& bytes);
void encode(const CommandDatagram& datagram, CommandBytes& bytes);
MeasurementBytes encode(const MeasurementDatagram& datagram);
CommandBytes encode(const CommandDatagram& datagram);

/// Reads a datagram; on anything but kOk `datagram` is left unchanged. Checks size, id and the
/// header's packetSize; the content (NaN, unknown states) is for the caller to judge.
DecodeStatus decode(std::span<const std::uint8_t> bytes, MeasurementDatagram& datagram);
DecodeStatus decode(std::span<const std::uint8_t> bytes, CommandDatagram& datagram);

/// Signed distance from `older` to `newer` of two wrapping u16 sequence counters:
/// 1 for the next datagram, <= 0 for a repeated or out-of-order one.
constexpr int sequenceDistance(std::uint16_t newer, std::uint16_t older) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(newer - older));
}

}  // namespace flexirob::robot::fri
