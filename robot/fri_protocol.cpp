#include "robot/fri_protocol.hpp"

#include <bit>

namespace flexirob::robot::fri {
namespace {

// Little-endian writer: byte by byte, so neither the host's byte order nor alignment matters.
struct Writer {
  std::uint8_t* out;
  std::size_t pos = 0;

  void put(std::uint32_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) out[pos++] = static_cast<std::uint8_t>(value >> (8 * i));
  }
  void operator()(std::uint16_t value) { put(value, 2); }
  void operator()(std::uint32_t value) { put(value, 4); }
  void operator()(std::int32_t value) { put(static_cast<std::uint32_t>(value), 4); }
  void operator()(float value) { put(std::bit_cast<std::uint32_t>(value), 4); }
  template <class T, std::size_t N>
  void operator()(const std::array<T, N>& values) {
    for (const T& value : values) (*this)(value);
  }
};

struct Reader {
  const std::uint8_t* in;
  std::size_t pos = 0;

  std::uint32_t get(int bytes) {
    std::uint32_t value = 0;
    for (int i = 0; i < bytes; ++i) value |= static_cast<std::uint32_t>(in[pos++]) << (8 * i);
    return value;
  }
  void operator()(std::uint16_t& value) { value = static_cast<std::uint16_t>(get(2)); }
  void operator()(std::uint32_t& value) { value = get(4); }
  void operator()(std::int32_t& value) { value = static_cast<std::int32_t>(get(4)); }
  void operator()(float& value) { value = std::bit_cast<float>(get(4)); }
  template <class T, std::size_t N>
  void operator()(std::array<T, N>& values) {
    for (T& value : values) (*this)(value);
  }
};

// Peeks the header without decoding the rest: bytes 4-5 packetSize, 6-7 datagramId.
std::uint16_t peekU16(std::span<const std::uint8_t> bytes, std::size_t offset) {
  return static_cast<std::uint16_t>(bytes[offset] | (bytes[offset + 1] << 8));
}

template <class Datagram, class Visit>
DecodeStatus decodeDatagram(std::span<const std::uint8_t> bytes, std::size_t size, std::uint16_t id,
                            Datagram& datagram, Visit visit) {
  if (bytes.size() < size) return DecodeStatus::kTooShort;
  if (bytes.size() > size) return DecodeStatus::kTooLong;
  if (peekU16(bytes, 6) != id) return DecodeStatus::kWrongDatagramId;
  if (peekU16(bytes, 4) != size) return DecodeStatus::kWrongPacketSize;
  Datagram decoded;
  Reader reader{bytes.data()};
  visit(decoded, reader);
  datagram = decoded;
  return DecodeStatus::kOk;
}

}  // namespace

const char* toString(InterfaceState state) { return interfaceStateName(static_cast<std::uint16_t>(state)); }
const char* toString(Quality quality) { return qualityName(static_cast<std::uint16_t>(quality)); }
const char* toString(ControlMode mode) { return controlModeName(static_cast<std::uint16_t>(mode)); }

const char* interfaceStateName(std::uint16_t raw) {
  switch (raw) {
    case 0: return "off";
    case 1: return "monitor";
    case 2: return "command";
    default: return "unknown";
  }
}

const char* qualityName(std::uint16_t raw) {
  switch (raw) {
    case 0: return "unacceptable";
    case 1: return "bad";
    case 2: return "ok";
    case 3: return "perfect";
    default: return "unknown";
  }
}

const char* controlModeName(std::uint16_t raw) {
  switch (raw) {
    case 0: return "other";
    case 1: return "position";
    case 2: return "cartesian_impedance";
    case 3: return "joint_impedance";
    default: return "unknown";
  }
}

const char* toString(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk: return "ok";
    case DecodeStatus::kTooShort: return "too short";
    case DecodeStatus::kTooLong: return "too long";
    case DecodeStatus::kWrongDatagramId: return "wrong datagram id";
    case DecodeStatus::kWrongPacketSize: return "wrong packet size field";
  }
  return "unknown";
}

void encode(const MeasurementDatagram& datagram, MeasurementBytes& bytes) {
  Writer writer{bytes.data()};
  visitMeasurementFields(datagram, writer);
}

void encode(const CommandDatagram& datagram, CommandBytes& bytes) {
  Writer writer{bytes.data()};
  visitCommandFields(datagram, writer);
}

MeasurementBytes encode(const MeasurementDatagram& datagram) {
  MeasurementBytes bytes{};
  encode(datagram, bytes);
  return bytes;
}

CommandBytes encode(const CommandDatagram& datagram) {
  CommandBytes bytes{};
  encode(datagram, bytes);
  return bytes;
}

DecodeStatus decode(std::span<const std::uint8_t> bytes, MeasurementDatagram& datagram) {
  return decodeDatagram(bytes, kMeasurementSize, kMeasurementDatagramId, datagram,
                        [](auto& d, auto& r) { visitMeasurementFields(d, r); });
}

DecodeStatus decode(std::span<const std::uint8_t> bytes, CommandDatagram& datagram) {
  return decodeDatagram(bytes, kCommandSize, kCommandDatagramId, datagram,
                        [](auto& d, auto& r) { visitCommandFields(d, r); });
}

}  // namespace flexirob::robot::fri
