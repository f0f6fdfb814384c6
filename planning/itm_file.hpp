#pragma once
// The ITM's own file format (versioned, little-endian binary, checksummed). Layout, version 1:
//
//   char[8]  magic "FLXITM\r\n"
//   u32      version (1)
//   u32      variant (0 plain, 1 hybrid)      u32 task space (0 position, 1 pose)
//   u32      joint count N (1..64)
//   f64 x 5  e_max, d_theta_max, d_c_max, eta, alpha      i32 delta
//   u64      node count V, edge count E, kept real-sample count S
//   i64      real samples seen, bootstrapped samples processed
//   V x      { f64 x M' prototype (M' = 3 or 7), f64 x N joints, u8 bootstrapped }
//   E x      { u32 a, u32 b }  (indices into the node list, a != b, no duplicates)
//   S x      { f64 x 3 }       kept real-sample positions (bootstrapping error)
//   u64      FNV-1a 64 checksum of every preceding byte
//
// Loading checks sizes against the file length before allocating anything and refuses
// anything malformed with an ItmFileError naming the file and the defect.
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "planning/itm.hpp"

namespace flexirob::planning {

class ItmFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr std::uint32_t kItmFileVersion = 1;

/// The graph in the file format above, in memory: the content of a graph file (the application
/// writes it; session recordings store these bytes). Node ids are compacted.
std::vector<std::uint8_t> itmToBytes(const Itm& graph);
/// Parses bytes written by itmToBytes with the checks of loadItm; `source` names them in errors.
Itm itmFromBytes(const std::uint8_t* bytes, std::size_t size, const std::string& source);

/// Reads a graph file (the bytes of itmToBytes).
Itm loadItm(const std::filesystem::path& path);

}  // namespace flexirob::planning
