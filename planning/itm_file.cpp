#include "planning/itm_file.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace flexirob::planning {
namespace {

static_assert(std::endian::native == std::endian::little, "the ITM file format is written as little-endian");

constexpr char kMagic[8] = {'F', 'L', 'X', 'I', 'T', 'M', '\r', '\n'};
// Refused before reading: a graph of 1 GiB already holds ~9 million pose nodes of a 7-DoF arm,
// far beyond any teaching session, while reading a hostile 16 GiB file would exhaust memory.
constexpr std::uint64_t kMaxFileBytes = std::uint64_t{1} << 30;  // 1 GiB

std::uint64_t fnv1a(const char* data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

class Writer {
 public:
  template <class T>
  void put(const T& value) {
    const auto* bytes = reinterpret_cast<const char*>(&value);
    buffer_.insert(buffer_.end(), bytes, bytes + sizeof(T));
  }
  std::vector<char>& buffer() { return buffer_; }

 private:
  std::vector<char> buffer_;
};

class Reader {
 public:
  Reader(const char* data, std::size_t end, std::string source) : data_(data), end_(end), source_(std::move(source)) {}
  template <class T>
  T get() {
    if (end_ - position_ < sizeof(T)) fail("file ends early (truncated)");
    T value;
    std::memcpy(&value, data_ + position_, sizeof(T));
    position_ += sizeof(T);
    return value;
  }
  std::size_t remaining() const { return end_ - position_; }
  [[noreturn]] void fail(const std::string& what) const { throw ItmFileError(source_ + ": " + what); }

 private:
  const char* data_;
  std::size_t end_;
  std::size_t position_ = 0;
  std::string source_;
};

// Parses a whole encoded graph; `source` names it in errors (a file, a session record).
Itm decodeItm(const char* data, std::size_t size, const std::string& source);

}  // namespace

std::vector<std::uint8_t> itmToBytes(const Itm& graph) {
  const ItmParameters& p = graph.parameters();
  const std::vector<int> ids = graph.nodeIds();
  std::vector<int> index_of(static_cast<std::size_t>(graph.slotCount()), -1);
  for (std::size_t i = 0; i < ids.size(); ++i) index_of[static_cast<std::size_t>(ids[i])] = static_cast<int>(i);
  const auto& samples = graph.keptSamplePositions();
  const ItmStatistics stats = graph.statistics();

  Writer out;
  for (char c : kMagic) out.put(c);
  out.put(kItmFileVersion);
  out.put(static_cast<std::uint32_t>(p.variant == ItmVariant::kHybrid ? 1 : 0));
  out.put(static_cast<std::uint32_t>(p.task_space == TaskSpace::kPose ? 1 : 0));
  out.put(static_cast<std::uint32_t>(graph.jointCount()));
  out.put(p.e_max);
  out.put(p.d_theta_max);
  out.put(p.d_c_max);
  out.put(p.eta);
  out.put(p.alpha);
  out.put(static_cast<std::int32_t>(p.delta));
  out.put(static_cast<std::uint64_t>(ids.size()));
  out.put(static_cast<std::uint64_t>(graph.edgeCount()));
  out.put(static_cast<std::uint64_t>(samples.size() / 3));
  out.put(static_cast<std::int64_t>(stats.real_samples));
  out.put(static_cast<std::int64_t>(stats.bootstrap_samples));
  for (int id : ids) {
    const auto omega = graph.prototype(id);
    for (Eigen::Index i = 0; i < omega.size(); ++i) out.put(omega[i]);
    const auto q = graph.joints(id);
    for (Eigen::Index i = 0; i < q.size(); ++i) out.put(q[i]);
    out.put(static_cast<std::uint8_t>(graph.isBootstrapped(id) ? 1 : 0));
  }
  for (int id : ids) {
    for (int c : graph.neighbors(id)) {
      if (c < id) continue;  // each undirected edge once
      out.put(static_cast<std::uint32_t>(index_of[static_cast<std::size_t>(id)]));
      out.put(static_cast<std::uint32_t>(index_of[static_cast<std::size_t>(c)]));
    }
  }
  for (double value : samples) out.put(value);
  const std::uint64_t checksum = fnv1a(out.buffer().data(), out.buffer().size());
  out.put(checksum);
  return std::vector<std::uint8_t>(out.buffer().begin(), out.buffer().end());
}

Itm loadItm(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw ItmFileError("ITM graph file '" + name + "' does not exist or is not a file");
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw ItmFileError("cannot read ITM graph file '" + name + "'");
  if (size > kMaxFileBytes) throw ItmFileError("ITM graph file '" + name + "': larger than 1 GiB");
  std::vector<char> data;
  {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw ItmFileError("cannot read ITM graph file '" + name + "'");
    // The magic word first, so that a large foreign file is refused without being read.
    char magic[sizeof kMagic] = {};
    file.read(magic, sizeof magic);
    if (static_cast<std::size_t>(file.gcount()) != sizeof magic || std::memcmp(magic, kMagic, sizeof kMagic) != 0) {
      throw ItmFileError("ITM graph file '" + name + "': not an ITM graph (bad magic)");
    }
    file.seekg(0);
    data.resize(static_cast<std::size_t>(size));
    file.read(data.data(), static_cast<std::streamsize>(data.size()));
    if (static_cast<std::uintmax_t>(file.gcount()) != size) throw ItmFileError("cannot read ITM graph file '" + name + "'");
  }
  return decodeItm(data.data(), data.size(), "ITM graph file '" + name + "'");
}

Itm itmFromBytes(const std::uint8_t* bytes, std::size_t size, const std::string& source) {
  if (size > kMaxFileBytes) throw ItmFileError(source + ": larger than 1 GiB");
  return decodeItm(reinterpret_cast<const char*>(bytes), size, source);
}

namespace {

Itm decodeItm(const char* data, std::size_t size, const std::string& source) {
  Reader in(data, size, source);
  if (size < sizeof kMagic || std::memcmp(data, kMagic, sizeof kMagic) != 0) {
    in.fail("not an ITM graph (bad magic)");
  }
  for (std::size_t i = 0; i < sizeof kMagic; ++i) in.get<char>();
  const auto version = in.get<std::uint32_t>();
  if (version != kItmFileVersion) {
    in.fail("unsupported version " + std::to_string(version) + " (expected " + std::to_string(kItmFileVersion) + ")");
  }
  if (size < 8) in.fail("file ends early (truncated)");
  // Checksum before interpreting any count, so that a damaged file never drives an allocation.
  std::uint64_t stored_checksum;
  std::memcpy(&stored_checksum, data + size - 8, 8);
  const auto variant = in.get<std::uint32_t>();
  const auto task_space = in.get<std::uint32_t>();
  const auto joint_count = in.get<std::uint32_t>();
  ItmParameters p;
  p.e_max = in.get<double>();
  p.d_theta_max = in.get<double>();
  p.d_c_max = in.get<double>();
  p.eta = in.get<double>();
  p.alpha = in.get<double>();
  p.delta = in.get<std::int32_t>();
  const auto node_count = in.get<std::uint64_t>();
  const auto edge_count = in.get<std::uint64_t>();
  const auto sample_count = in.get<std::uint64_t>();
  const auto real_samples = in.get<std::int64_t>();
  const auto bootstrap_samples = in.get<std::int64_t>();
  if (variant > 1) in.fail("unknown ITM variant " + std::to_string(variant));
  if (task_space > 1) in.fail("unknown task space " + std::to_string(task_space));
  if (joint_count < 1 || joint_count > 64) in.fail("expected 1 to 64 joints, got " + std::to_string(joint_count));
  p.variant = variant == 1 ? ItmVariant::kHybrid : ItmVariant::kPlain;
  p.task_space = task_space == 1 ? TaskSpace::kPose : TaskSpace::kPosition;
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    in.fail(e.what());
  }
  if (real_samples < 0 || bootstrap_samples < 0) in.fail("negative sample counters");

  // Sizes: every count must fit the bytes that are actually there (checked by division, so no
  // product can overflow), before anything is allocated.
  const std::size_t task_size = static_cast<std::size_t>(storedSize(p.task_space));
  const std::size_t node_bytes = (task_size + joint_count) * 8 + 1;
  if (in.remaining() < 8) in.fail("file ends early (truncated)");
  std::size_t budget = in.remaining() - 8;
  if (node_count > budget / node_bytes) in.fail("node count " + std::to_string(node_count) + " exceeds the file's size (truncated?)");
  budget -= static_cast<std::size_t>(node_count) * node_bytes;
  if (edge_count > budget / 8) in.fail("edge count " + std::to_string(edge_count) + " exceeds the file's size (truncated?)");
  budget -= static_cast<std::size_t>(edge_count) * 8;
  if (sample_count > budget / 24) in.fail("sample count " + std::to_string(sample_count) + " exceeds the file's size (truncated?)");
  budget -= static_cast<std::size_t>(sample_count) * 24;
  if (budget != 0) in.fail(std::to_string(budget) + " unexpected bytes after the samples");
  if (node_count > 0x7fffffffULL) in.fail("too many nodes");
  if (fnv1a(data, size - 8) != stored_checksum) in.fail("checksum mismatch (the file is damaged)");

  Itm graph(p, static_cast<int>(joint_count));
  Eigen::VectorXd omega(static_cast<Eigen::Index>(task_size));
  Eigen::VectorXd q(static_cast<Eigen::Index>(joint_count));
  for (std::uint64_t i = 0; i < node_count; ++i) {
    for (Eigen::Index k = 0; k < omega.size(); ++k) omega[k] = in.get<double>();
    for (Eigen::Index k = 0; k < q.size(); ++k) q[k] = in.get<double>();
    const auto flag = in.get<std::uint8_t>();
    if (flag > 1) in.fail("node " + std::to_string(i) + ": bad bootstrapped flag");
    if (!omega.allFinite() || !q.allFinite()) in.fail("node " + std::to_string(i) + " has non-finite values");
    if (task_size == 7 && std::abs(omega.tail<4>().norm() - 1.0) > 1e-6) in.fail("node " + std::to_string(i) + ": quaternion not unit");
    try {
      graph.addNode(omega, q, flag == 1);
    } catch (const std::invalid_argument& e) {
      in.fail("node " + std::to_string(i) + ": " + e.what());
    }
  }
  for (std::uint64_t i = 0; i < edge_count; ++i) {
    const auto a = in.get<std::uint32_t>();
    const auto b = in.get<std::uint32_t>();
    if (a >= node_count || b >= node_count) in.fail("edge " + std::to_string(i) + " refers to a missing node");
    if (a == b) in.fail("edge " + std::to_string(i) + " joins node " + std::to_string(a) + " to itself");
    if (graph.hasEdge(static_cast<int>(a), static_cast<int>(b))) in.fail("edge " + std::to_string(i) + " is a duplicate");
    graph.addEdge(static_cast<int>(a), static_cast<int>(b));
  }
  std::vector<double> samples(static_cast<std::size_t>(sample_count) * 3);
  for (double& value : samples) {
    value = in.get<double>();
    if (!std::isfinite(value) || std::abs(value) > 1e5) in.fail("kept sample with a non-finite or out-of-range value");
  }
  graph.restoreSamples(std::move(samples), real_samples, bootstrap_samples);
  return graph;
}

}  // namespace

}  // namespace flexirob::planning
