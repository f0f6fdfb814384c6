// The FRI wire format, byte by byte. Expected datagrams are built here independently of the
// encoder: every field at an offset counted by hand from the public layout (see
// robot/fri_protocol.hpp), written little-endian with explicit shifts.
#include "robot/fri_protocol.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace flexirob::robot::fri {
namespace {

using Bytes = std::vector<std::uint8_t>;

void putU16(Bytes& b, std::size_t offset, std::uint16_t v) {
  b.at(offset) = static_cast<std::uint8_t>(v & 0xFF);
  b.at(offset + 1) = static_cast<std::uint8_t>(v >> 8);
}
void putU32(Bytes& b, std::size_t offset, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) b.at(offset + i) = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}
void putF32(Bytes& b, std::size_t offset, float v) { putU32(b, offset, std::bit_cast<std::uint32_t>(v)); }

// A distinct, exactly representable value per field and element.
float value(int field, int index) { return static_cast<float>(field) * 100.0F + static_cast<float>(index) + 0.25F; }

struct FloatField {
  std::size_t offset;
  int count;
};

// Measurement: offsets counted from the public layout.
// header 0-7 | KRL 8-139 | intf 140-179 | robot state 180-215 | robot data 216-915.
const FloatField kMeasurementFloatFields[] = {
    {8, 16},    // krl.realData
    {140, 1},   // intf.timestamp
    {148, 1},   // desiredMsrSampleTime
    {152, 1},   // desiredCmdSampleTime
    {156, 1},   // safetyLimits
    {160, 1},   // stat.answerRate
    {164, 1},   // stat.latency
    {168, 1},   // stat.jitter
    {172, 1},   // stat.missRate
    {188, 7},   // robot.temperature
    {216, 7},   // msrJntPos
    {244, 12},  // msrCartPos
    {292, 7},   // cmdJntPos
    {320, 7},   // cmdJntPosFriOffset
    {348, 12},  // cmdCartPos
    {396, 12},  // cmdCartPosFriOffset
    {444, 7},   // msrJntTrq
    {472, 7},   // estExtJntTrq
    {500, 6},   // estExtTcpFT
    {524, 42},  // jacobian
    {692, 49},  // massMatrix
    {888, 7},   // gravity (ends at 916)
};

MeasurementDatagram sampleMeasurement() {
  MeasurementDatagram m;
  m.header.send_seq = 0x1234;
  m.header.refl_seq = 0xBEEF;
  for (int i = 0; i < 16; ++i) m.krl.integer[static_cast<std::size_t>(i)] = -1000 * i - 7;
  m.krl.bools = 0xA5C3;
  m.krl.fill = 0;
  m.intf.state = 2;
  m.intf.quality = 3;
  m.intf.statistics.miss_counter = 0x01020304;
  m.robot.power = 0x007F;
  m.robot.control = 3;
  m.robot.error = 0x0102;
  m.robot.warning = 0x0304;
  // Floats in the order of kMeasurementFloatFields.
  std::vector<float*> fields;
  auto add = [&fields](auto& array) {
    for (auto& x : array) fields.push_back(&x);
  };
  add(m.krl.real);
  fields.push_back(&m.intf.timestamp);
  fields.push_back(&m.intf.desired_msr_sample_time);
  fields.push_back(&m.intf.desired_cmd_sample_time);
  fields.push_back(&m.intf.safety_limits);
  fields.push_back(&m.intf.statistics.answer_rate);
  fields.push_back(&m.intf.statistics.latency);
  fields.push_back(&m.intf.statistics.jitter);
  fields.push_back(&m.intf.statistics.miss_rate);
  add(m.robot.temperature);
  add(m.data.msr_jnt_pos);
  add(m.data.msr_cart_pos);
  add(m.data.cmd_jnt_pos);
  add(m.data.cmd_jnt_pos_fri_offset);
  add(m.data.cmd_cart_pos);
  add(m.data.cmd_cart_pos_fri_offset);
  add(m.data.msr_jnt_trq);
  add(m.data.est_ext_jnt_trq);
  add(m.data.est_ext_tcp_ft);
  add(m.data.jacobian);
  add(m.data.mass_matrix);
  add(m.data.gravity);
  std::size_t k = 0;
  int field = 0;
  for (const auto& f : kMeasurementFloatFields) {
    for (int i = 0; i < f.count; ++i) *fields.at(k++) = value(field, i);
    ++field;
  }
  EXPECT_EQ(k, fields.size());
  return m;
}

Bytes expectedMeasurementBytes() {
  Bytes b(916, 0xEE);  // every byte must be written: 0xEE would show a gap
  putU16(b, 0, 0x1234);
  putU16(b, 2, 0xBEEF);
  putU16(b, 4, 916);
  putU16(b, 6, 0x2006);
  for (int i = 0; i < 16; ++i) putU32(b, 72 + 4 * static_cast<std::size_t>(i), static_cast<std::uint32_t>(-1000 * i - 7));
  putU16(b, 136, 0xA5C3);
  putU16(b, 138, 0);
  putU16(b, 144, 2);  // state
  putU16(b, 146, 3);  // quality
  putU32(b, 176, 0x01020304);
  putU16(b, 180, 0x007F);
  putU16(b, 182, 3);
  putU16(b, 184, 0x0102);
  putU16(b, 186, 0x0304);
  int field = 0;
  for (const auto& f : kMeasurementFloatFields) {
    for (int i = 0; i < f.count; ++i) putF32(b, f.offset + 4 * static_cast<std::size_t>(i), value(field, i));
    ++field;
  }
  return b;
}

// Command: header 0-7 | KRL 8-139 | cmdFlags 140 | block floats 144-375.
const FloatField kCommandFloatFields[] = {
    {8, 16},   // krl.realData
    {144, 7},  // jntPos
    {172, 12}, // cartPos
    {220, 7},  // addJntTrq
    {248, 6},  // addTcpFT
    {272, 7},  // jntStiffness
    {300, 7},  // jntDamping
    {328, 6},  // cartStiffness
    {352, 6},  // cartDamping (ends at 376)
};

CommandDatagram sampleCommand() {
  CommandDatagram c;
  c.header.send_seq = 65535;
  c.header.refl_seq = 1;
  for (int i = 0; i < 16; ++i) c.krl.integer[static_cast<std::size_t>(i)] = 3 * i - 20;
  c.krl.bools = 0x8001;
  c.cmd.flags = command_flags::kJointImpedance;
  std::vector<float*> fields;
  auto add = [&fields](auto& array) {
    for (auto& x : array) fields.push_back(&x);
  };
  add(c.krl.real);
  add(c.cmd.jnt_pos);
  add(c.cmd.cart_pos);
  add(c.cmd.add_jnt_trq);
  add(c.cmd.add_tcp_ft);
  add(c.cmd.jnt_stiffness);
  add(c.cmd.jnt_damping);
  add(c.cmd.cart_stiffness);
  add(c.cmd.cart_damping);
  std::size_t k = 0;
  int field = 0;
  for (const auto& f : kCommandFloatFields) {
    for (int i = 0; i < f.count; ++i) *fields.at(k++) = value(field, i);
    ++field;
  }
  EXPECT_EQ(k, fields.size());
  return c;
}

Bytes expectedCommandBytes() {
  Bytes b(376, 0xEE);
  putU16(b, 0, 65535);
  putU16(b, 2, 1);
  putU16(b, 4, 376);
  putU16(b, 6, 0x1005);
  for (int i = 0; i < 16; ++i) putU32(b, 72 + 4 * static_cast<std::size_t>(i), static_cast<std::uint32_t>(3 * i - 20));
  putU16(b, 136, 0x8001);
  putU16(b, 138, 0);
  putU32(b, 140, 0x31);  // JNTPOS | JNTSTIFF | JNTDAMP
  int field = 0;
  for (const auto& f : kCommandFloatFields) {
    for (int i = 0; i < f.count; ++i) putF32(b, f.offset + 4 * static_cast<std::size_t>(i), value(field, i));
    ++field;
  }
  return b;
}

TEST(FriProtocol, DatagramSizesMatchThePublicLayout) {
  EXPECT_EQ(kMeasurementSize, 916U);
  EXPECT_EQ(kCommandSize, 376U);
  EXPECT_EQ(kMeasurementDataOffset, 216U);
  EXPECT_EQ(kCommandBlockOffset, 140U);
  EXPECT_EQ(kMeasurementDatagramId, 0x2006);
  EXPECT_EQ(kCommandDatagramId, 0x1005);
}

TEST(FriProtocol, EncodesMeasurementByteExact) {
  const MeasurementBytes bytes = encode(sampleMeasurement());
  const Bytes expected = expectedMeasurementBytes();
  ASSERT_EQ(bytes.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(bytes[i], expected[i]) << "byte " << i;
  }
}

TEST(FriProtocol, EncodesCommandByteExact) {
  const CommandBytes bytes = encode(sampleCommand());
  const Bytes expected = expectedCommandBytes();
  ASSERT_EQ(bytes.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(bytes[i], expected[i]) << "byte " << i;
  }
}

TEST(FriProtocol, WritesLittleEndianIeeeSingles) {
  // Literal bytes, independent of any helper: 1.0f = 0x3F800000, -2.5f = 0xC0200000.
  CommandDatagram c;
  c.cmd.jnt_pos[0] = 1.0F;
  c.cmd.jnt_damping[6] = -2.5F;
  c.cmd.flags = command_flags::kJointPosition | command_flags::kCartesianDamping;
  const CommandBytes bytes = encode(c);
  EXPECT_EQ(bytes[4], 0x78);  // packetSize 376 = 0x0178
  EXPECT_EQ(bytes[5], 0x01);
  EXPECT_EQ(bytes[6], 0x05);  // datagramId 0x1005
  EXPECT_EQ(bytes[7], 0x10);
  EXPECT_EQ(bytes[140], 0x01);  // flags 0x2001
  EXPECT_EQ(bytes[141], 0x20);
  EXPECT_EQ(bytes[144], 0x00);
  EXPECT_EQ(bytes[145], 0x00);
  EXPECT_EQ(bytes[146], 0x80);
  EXPECT_EQ(bytes[147], 0x3F);
  EXPECT_EQ(bytes[324], 0x00);  // jntDamping[6] at 300 + 24
  EXPECT_EQ(bytes[325], 0x00);
  EXPECT_EQ(bytes[326], 0x20);
  EXPECT_EQ(bytes[327], 0xC0);
}

TEST(FriProtocol, DecodesMeasurementFromHandBuiltBytes) {
  const Bytes bytes = expectedMeasurementBytes();
  MeasurementDatagram m;
  ASSERT_EQ(decode(bytes, m), DecodeStatus::kOk);
  EXPECT_EQ(m.header.send_seq, 0x1234);
  EXPECT_EQ(m.header.refl_seq, 0xBEEF);
  EXPECT_EQ(m.intf.state, 2);
  EXPECT_EQ(m.intf.quality, 3);
  EXPECT_EQ(m.robot.control, 3);
  EXPECT_EQ(m.intf.statistics.miss_counter, 0x01020304U);
  EXPECT_EQ(m.krl.integer[15], -15007);
  EXPECT_EQ(m.krl.bools, 0xA5C3);
  // Field indices as in kMeasurementFloatFields: 10 msrJntPos, 17 estExtJntTrq, 21 gravity.
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(m.data.msr_jnt_pos[static_cast<std::size_t>(i)], value(10, i));
    EXPECT_EQ(m.data.est_ext_jnt_trq[static_cast<std::size_t>(i)], value(17, i));
    EXPECT_EQ(m.data.gravity[static_cast<std::size_t>(i)], value(21, i));
  }
  EXPECT_EQ(m.intf.timestamp, value(1, 0));
  EXPECT_EQ(m.data.jacobian[41], value(19, 41));
  EXPECT_EQ(m.data.mass_matrix[48], value(20, 48));
}

TEST(FriProtocol, DecodesCommandFromHandBuiltBytes) {
  const Bytes bytes = expectedCommandBytes();
  CommandDatagram c;
  ASSERT_EQ(decode(bytes, c), DecodeStatus::kOk);
  EXPECT_EQ(c.header.send_seq, 65535);
  EXPECT_EQ(c.header.refl_seq, 1);
  EXPECT_EQ(c.cmd.flags, command_flags::kJointImpedance);
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(c.cmd.jnt_pos[static_cast<std::size_t>(i)], value(1, i));
    EXPECT_EQ(c.cmd.jnt_stiffness[static_cast<std::size_t>(i)], value(5, i));
    EXPECT_EQ(c.cmd.jnt_damping[static_cast<std::size_t>(i)], value(6, i));
  }
  EXPECT_EQ(c.cmd.cart_damping[5], value(8, 5));
}

TEST(FriProtocol, RoundTripsBothDatagramsIncludingSpecialFloats) {
  MeasurementDatagram m = sampleMeasurement();
  m.data.msr_cart_pos[3] = std::numeric_limits<float>::denorm_min();
  m.data.gravity[0] = -0.0F;
  m.data.jacobian[0] = std::numeric_limits<float>::infinity();
  MeasurementDatagram m2;
  ASSERT_EQ(decode(encode(m), m2), DecodeStatus::kOk);
  EXPECT_EQ(encode(m2), encode(m));
  EXPECT_TRUE(std::signbit(m2.data.gravity[0]));

  const CommandDatagram c = sampleCommand();
  CommandDatagram c2;
  ASSERT_EQ(decode(encode(c), c2), DecodeStatus::kOk);
  EXPECT_EQ(encode(c2), encode(c));
}

TEST(FriProtocol, RefusesWrongSizesIdsAndPacketSizeFields) {
  const Bytes good = expectedMeasurementBytes();
  MeasurementDatagram m;
  m.header.send_seq = 42;  // must stay untouched on failure

  Bytes shorter(good.begin(), good.end() - 1);
  EXPECT_EQ(decode(shorter, m), DecodeStatus::kTooShort);
  EXPECT_EQ(decode(std::span<const std::uint8_t>(), m), DecodeStatus::kTooShort);
  Bytes longer = good;
  longer.push_back(0);
  EXPECT_EQ(decode(longer, m), DecodeStatus::kTooLong);
  Bytes wrong_id = good;
  putU16(wrong_id, 6, 0x2005);  // another protocol version
  EXPECT_EQ(decode(wrong_id, m), DecodeStatus::kWrongDatagramId);
  Bytes wrong_size_field = good;
  putU16(wrong_size_field, 4, 924);
  EXPECT_EQ(decode(wrong_size_field, m), DecodeStatus::kWrongPacketSize);
  EXPECT_EQ(m.header.send_seq, 42);

  // A command is not a measurement, and vice versa.
  const Bytes command = expectedCommandBytes();
  EXPECT_EQ(decode(command, m), DecodeStatus::kTooShort);
  CommandDatagram c;
  EXPECT_EQ(decode(good, c), DecodeStatus::kTooLong);
  Bytes command_with_measurement_id = command;
  putU16(command_with_measurement_id, 6, 0x2006);
  EXPECT_EQ(decode(command_with_measurement_id, c), DecodeStatus::kWrongDatagramId);
}

TEST(FriProtocol, SequenceDistanceWrapsAround) {
  EXPECT_EQ(sequenceDistance(1, 0), 1);
  EXPECT_EQ(sequenceDistance(0, 65535), 1);
  EXPECT_EQ(sequenceDistance(3, 65534), 5);
  EXPECT_EQ(sequenceDistance(7, 7), 0);
  EXPECT_EQ(sequenceDistance(6, 7), -1);
  EXPECT_EQ(sequenceDistance(65535, 0), -1);
}

TEST(FriProtocol, NamesStatesQualitiesAndModes) {
  EXPECT_STREQ(toString(InterfaceState::kCommand), "command");
  EXPECT_STREQ(toString(Quality::kOk), "ok");
  EXPECT_STREQ(toString(ControlMode::kJointImpedance), "joint_impedance");
  EXPECT_STREQ(interfaceStateName(9), "unknown");
}

}  // namespace
}  // namespace flexirob::robot::fri
