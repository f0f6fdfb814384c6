// Fuzz target: FRI datagrams as they arrive on the UDP socket. decode() must accept exactly the
// well-formed ones, and re-encoding an accepted datagram must reproduce its bytes.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz/fuzz_support.hpp"
#include "robot/fri_protocol.hpp"

namespace fri = flexirob::robot::fri;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  fri::MeasurementDatagram measurement;
  if (fri::decode(bytes, measurement) == fri::DecodeStatus::kOk) {
    if (size != fri::kMeasurementSize) flexirob::fuzz::invariantBroken("measurement of the wrong size accepted");
    const auto again = fri::encode(measurement);
    if (!std::equal(again.begin(), again.end(), data)) flexirob::fuzz::invariantBroken("measurement does not re-encode");
    (void)fri::interfaceStateName(measurement.intf.state);
    (void)fri::qualityName(measurement.intf.quality);
    (void)fri::controlModeName(measurement.robot.control);
  }
  fri::CommandDatagram command;
  if (fri::decode(bytes, command) == fri::DecodeStatus::kOk) {
    if (size != fri::kCommandSize) flexirob::fuzz::invariantBroken("command of the wrong size accepted");
    const auto again = fri::encode(command);
    if (!std::equal(again.begin(), again.end(), data)) flexirob::fuzz::invariantBroken("command does not re-encode");
  }
  return 0;
}
