// Saving and loading maps; broken files are refused with a clear error, never a crash.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "planning/itm_file.hpp"
#include "test_streams.hpp"

namespace flexirob::planning {
namespace {

// The folder of this test process, removed with its files when the process ends.
std::filesystem::path scratchFile(const std::string& name) {
  struct RemovedAtExit {
    std::filesystem::path path;
    ~RemovedAtExit() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const RemovedAtExit folder{std::filesystem::temp_directory_path() /
                                    ("flexirob-planning-test-" + std::to_string(::getpid()))};
  std::filesystem::create_directories(folder.path);
  return folder.path / name;
}

// A graph file as the application writes one: the bytes of itmToBytes.
void saveItm(const Itm& graph, const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = itmToBytes(graph);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::vector<char> readBytes(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::uint64_t fnv1a(const std::vector<char>& data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

Itm learnedMap(TaskSpace space = TaskSpace::kPosition) {
  ItmParameters p;
  p.task_space = space;
  p.delta = 4;
  Itm itm(p, 7);
  const auto stream = testing::randomWalk(Eigen::Vector3d(-0.5, -0.5, 0.1), Eigen::Vector3d(0.5, 0.5, 0.8), 3000, 0.006, 7, 11);
  for (const auto& sample : stream) {
    Eigen::VectorXd xi(storedSize(space));
    xi.head<3>() = sample.x;
    if (space == TaskSpace::kPose) xi.tail<4>() = Eigen::Vector4d(1.0, 0.3 * sample.x[0], 0.2 * sample.x[1], 0.0).normalized();
    itm.insert(xi, sample.q);
  }
  return itm;
}

TEST(ItmFile, RoundTripKeepsNodesEdgesJointsAndStatistics) {
  for (const auto space : {TaskSpace::kPosition, TaskSpace::kPose}) {
    const Itm original = learnedMap(space);
    const auto path = scratchFile("round_trip.itm");
    saveItm(original, path);
    const Itm loaded = loadItm(path);
    ASSERT_EQ(loaded.nodeCount(), original.nodeCount());
    EXPECT_EQ(loaded.edgeCount(), original.edgeCount());
    EXPECT_EQ(loaded.parameters().delta, 4);
    EXPECT_EQ(loaded.parameters().task_space, space);
    const auto ids = original.nodeIds();  // loading compacts ids in this order
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const int id = static_cast<int>(i);
      EXPECT_EQ(loaded.prototype(id), original.prototype(ids[i]));
      EXPECT_EQ(loaded.joints(id), original.joints(ids[i]));
      EXPECT_EQ(loaded.isBootstrapped(id), original.isBootstrapped(ids[i]));
      EXPECT_EQ(loaded.neighbors(id).size(), original.neighbors(ids[i]).size());
    }
    const auto a = original.statistics(), b = loaded.statistics();
    EXPECT_EQ(a.max_valence, b.max_valence);
    EXPECT_EQ(a.components, b.components);
    EXPECT_DOUBLE_EQ(a.bootstrap_error_max, b.bootstrap_error_max);
    EXPECT_EQ(a.real_samples, b.real_samples);
  }
}

TEST(ItmFile, RefusesEveryTruncation) {
  const auto path = scratchFile("truncated.itm");
  ItmParameters p;
  Itm small(p, 2);
  for (int k = 0; k < 40; ++k) small.insert(Eigen::Vector3d(0.05 * k, 0.0, 0.3), Eigen::Vector2d(0.0, 0.01 * k));
  saveItm(small, path);
  const auto bytes = readBytes(path);
  // Every length through the header, then a spread of lengths through the body.
  for (std::size_t length = 0; length < bytes.size(); length += length < 160 ? 1 : 11) {
    writeBytes(path, std::vector<char>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(length)));
    EXPECT_THROW(loadItm(path), ItmFileError) << "length " << length;
  }
}

TEST(ItmFile, RefusesDamagedBytesWrongMagicAndNewerVersions) {
  const auto path = scratchFile("damaged.itm");
  saveItm(learnedMap(), path);
  const auto bytes = readBytes(path);
  auto damaged = bytes;
  damaged[bytes.size() / 2] ^= 0x10;
  writeBytes(path, damaged);
  EXPECT_THROW(loadItm(path), ItmFileError);
  damaged = bytes;
  damaged[0] = 'X';
  writeBytes(path, damaged);
  try {
    loadItm(path);
    FAIL() << "loaded a file with a bad magic";
  } catch (const ItmFileError& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos);
  }
  damaged = bytes;
  damaged[8] = 9;  // version
  writeBytes(path, damaged);
  try {
    loadItm(path);
    FAIL() << "loaded a future version";
  } catch (const ItmFileError& e) {
    EXPECT_NE(std::string(e.what()).find("version 9"), std::string::npos);
  }
  EXPECT_THROW(loadItm(scratchFile("does-not-exist.itm")), ItmFileError);
}

TEST(ItmFile, RefusesHugeCountsBeforeAllocating) {
  const auto path = scratchFile("huge.itm");
  saveItm(learnedMap(), path);
  auto bytes = readBytes(path);
  // Node count field: after magic (8), 4 u32 (16), 5 f64 (40), i32 (4) = offset 68.
  const std::uint64_t huge = std::uint64_t{1} << 60;
  std::memcpy(bytes.data() + 68, &huge, 8);
  const std::uint64_t checksum = fnv1a(bytes, bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &checksum, 8);  // a valid checksum over the lie
  writeBytes(path, bytes);
  try {
    loadItm(path);
    FAIL() << "accepted a node count beyond the file's size";
  } catch (const ItmFileError& e) {
    EXPECT_NE(std::string(e.what()).find("node count"), std::string::npos) << e.what();
  }
}

TEST(ItmFile, RefusesSelfEdgesEvenWithAValidChecksum) {
  const auto path = scratchFile("self_edge.itm");
  ItmParameters p;
  Itm two(p, 1);
  const int a = two.addNode(Eigen::Vector3d(0, 0, 0), Eigen::VectorXd::Zero(1));
  const int b = two.addNode(Eigen::Vector3d(1, 0, 0), Eigen::VectorXd::Zero(1));
  two.addEdge(a, b);
  saveItm(two, path);
  auto bytes = readBytes(path);
  // The single edge sits right before the checksum (no kept samples): make it (1, 1).
  const std::uint32_t one = 1;
  std::memcpy(bytes.data() + bytes.size() - 16, &one, 4);
  const std::uint64_t checksum = fnv1a(bytes, bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &checksum, 8);
  writeBytes(path, bytes);
  try {
    loadItm(path);
    FAIL() << "accepted a self-edge";
  } catch (const ItmFileError& e) {
    EXPECT_NE(std::string(e.what()).find("itself"), std::string::npos) << e.what();
  }
}

TEST(ItmFile, RandomDamageBehindAValidChecksumIsRefusedOrLoadedNeverACrash) {
  const auto path = scratchFile("fuzz.itm");
  ItmParameters p;
  Itm small(p, 2);
  for (int k = 0; k < 60; ++k) small.insert(Eigen::Vector3d(0.03 * k, 0.02 * (k % 7), 0.3), Eigen::Vector2d(0.0, 0.01 * k));
  saveItm(small, path);
  const auto original = readBytes(path);
  std::mt19937 rng(99);
  std::uniform_int_distribution<std::size_t> position(8, original.size() - 9);
  std::uniform_int_distribution<int> byte(0, 255);
  int refused = 0;
  for (int trial = 0; trial < 400; ++trial) {
    auto bytes = original;
    for (int flips = 0; flips < 1 + trial % 4; ++flips) bytes[position(rng)] = static_cast<char>(byte(rng));
    const std::uint64_t checksum = fnv1a(bytes, bytes.size() - 8);
    std::memcpy(bytes.data() + bytes.size() - 8, &checksum, 8);
    writeBytes(path, bytes);
    try {
      const Itm loaded = loadItm(path);
      // Whatever loads is a consistent graph.
      EXPECT_EQ(loaded.statistics().nodes, loaded.nodeCount());
    } catch (const ItmFileError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 50);
}

}  // namespace
}  // namespace flexirob::planning
