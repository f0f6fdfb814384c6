#pragma once
// Helpers shared by the fuzz targets.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace flexirob::fuzz {

/// A file holding the fuzz input, for parsers that read from a path (ITM graphs, sessions,
/// meshes). One per process, rewritten for every input; removed at exit. Lives in /dev/shm when
/// it exists so that fuzzing does not wear the disk.
class InputFile {
 public:
  explicit InputFile(const std::string& extension) {
    const std::filesystem::path dir =
        std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    path_ = dir / ("flexirob-fuzz-" + std::to_string(::getpid()) + extension);
  }
  ~InputFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::filesystem::path& write(const std::uint8_t* data, std::size_t size) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) {
      std::fprintf(stderr, "fuzz: cannot write %s\n", path_.c_str());
      std::abort();
    }
    return path_;
  }

 private:
  std::filesystem::path path_;
};

/// The fuzz target found a broken invariant: report and abort so that libFuzzer keeps the input.
[[noreturn]] inline void invariantBroken(const char* what) {
  std::fprintf(stderr, "fuzz: invariant broken: %s\n", what);
  std::abort();
}

/// FNV-1a 64, the checksum of model files and ITM graph files.
inline std::uint64_t fnv1a64(const char* data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

// The parsers verify a checksum before interpreting anything, so almost every mutation would
// stop there. The fuzz targets therefore try each input twice: as it is, and with its checksum
// made valid, which lets mutations reach the field, size and matrix checks behind it.

/// A model file text with its last line replaced by (or extended with) a valid checksum line.
inline std::string withValidModelChecksum(std::string text) {
  if (!text.empty() && text.back() == '\n') {
    const std::size_t last_start = text.size() < 2 ? 0 : text.rfind('\n', text.size() - 2) + 1;
    if (text.compare(last_start, 9, "checksum ") == 0) text.resize(last_start);
  } else {
    text += '\n';
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(text.data(), text.size())));
  return text + "checksum " + hex + "\n";
}

/// ITM graph file bytes with the trailing 8-byte checksum (little-endian) made valid.
inline std::string withValidItmChecksum(std::string bytes) {
  if (bytes.size() < 8) return bytes;
  std::uint64_t hash = fnv1a64(bytes.data(), bytes.size() - 8);
  for (std::size_t i = bytes.size() - 8; i < bytes.size(); ++i) {
    bytes[i] = static_cast<char>(hash & 0xffU);
    hash >>= 8;
  }
  return bytes;
}

/// The resource directory (robots, meshes), from FLEXIROB_RESOURCES or the source tree.
inline std::filesystem::path resourceDir() {
  if (const char* env = std::getenv("FLEXIROB_RESOURCES")) return env;
  return std::filesystem::path(__FILE__).parent_path().parent_path() / "resources";
}

}  // namespace flexirob::fuzz
