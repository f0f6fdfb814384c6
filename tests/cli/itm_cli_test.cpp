// The command-line contract of `itm build` and `itm path` (DESIGN section 6), exercised through
// the real binary; broken inputs give exit code 2 and a one-line reason.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>

#include "cli_test_support.hpp"

namespace flexirob {
namespace {

using testing::runCliBinary;

std::filesystem::path scratchDir() { return testing::scratchDir("itm-cli-test"); }
using testing::writeText;

// A U-shaped stream: down the left arm, along the bottom, up the right arm (x,y,z,q1..q7).
std::filesystem::path writeUStream() {
  const auto path = scratchDir() / "u_stream.csv";
  std::ofstream file(path);
  file << "x,y,z,q1,q2,q3,q4,q5,q6,q7\n";
  const auto line = [&](Eigen::Vector3d a, Eigen::Vector3d b) {
    const int steps = static_cast<int>((b - a).norm() / 0.004);
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector3d p = a + (b - a) * k / steps;
      file << p.x() << "," << p.y() << "," << p.z();
      for (int j = 0; j < 7; ++j) file << "," << 0.1 * j + 0.2 * p.x();
      file << "\n";
    }
  };
  line({-0.3, 0.8, 0.5}, {-0.3, 0.0, 0.5});
  line({-0.3, 0.0, 0.5}, {0.3, 0.0, 0.5});
  line({0.3, 0.0, 0.5}, {0.3, 0.8, 0.5});
  return path;
}

void expectOneLineError(const testing::CliResult& result, const std::string& fragment) {
  EXPECT_EQ(result.exit_code, 2) << result.out << result.err;
  EXPECT_TRUE(result.out.empty()) << result.out;
  EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_NE(result.err.find(fragment), std::string::npos) << result.err;
}

TEST(ItmCli, BuildPrintsGraphStatisticsAndWritesTheGraph) {
  const auto data = writeUStream();
  const auto graph = scratchDir() / "u.itm";
  const auto result = runCliBinary("itm build --data " + data.string() + " --out " + graph.string() + " --delta 4 --dcmax 0");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  const int nodes = json["nodes"], edges = json["edges"];
  EXPECT_GT(nodes, 18);  // 2.2 m of corridor at e_max = 0.1 m
  EXPECT_LT(nodes, 40);
  EXPECT_GE(edges, nodes - 1);
  EXPECT_NEAR(json["mean_valence"].get<double>(), 2.0 * edges / nodes, 1e-12);
  EXPECT_GE(json["max_valence"].get<int>(), 2);
  EXPECT_GT(json["mean_insert_us"].get<double>(), 0.0);
  std::ifstream file(data);
  const auto rows = std::count(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>(), '\n') - 1;
  EXPECT_EQ(json["samples"].get<long>(), rows);
  EXPECT_EQ(json["joints"], 7);
  EXPECT_EQ(json["parameters"]["delta"], 4);
  EXPECT_EQ(json["components"], 1);
  EXPECT_TRUE(std::filesystem::exists(graph));
}

TEST(ItmCli, PathGoesAroundTheUFromStartToGoal) {
  const auto data = writeUStream();
  const auto graph = scratchDir() / "u_path.itm";
  ASSERT_EQ(runCliBinary("itm build --data " + data.string() + " --out " + graph.string() + " --dcmax 0").exit_code, 0);
  const auto result = runCliBinary("itm path --graph " + graph.string() + " --from -0.3,0.78,0.5 --to 0.3,0.78,0.5 --dt 0.01");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  ASSERT_TRUE(json["found"].get<bool>());
  const auto& waypoints = json["waypoints"];
  ASSERT_GE(waypoints.size(), 10U);
  EXPECT_NEAR(waypoints.front()[1].get<double>(), 0.78, 1e-12);
  EXPECT_NEAR(waypoints.back()[0].get<double>(), 0.3, 1e-12);
  double length = 0.0;
  for (std::size_t k = 1; k < waypoints.size(); ++k) {
    ASSERT_EQ(waypoints[k].size(), 3U);
    double squared = 0.0;
    for (int i = 0; i < 3; ++i) squared += std::pow(waypoints[k][i].get<double>() - waypoints[k - 1][i].get<double>(), 2);
    length += std::sqrt(squared);
    const bool in_gap = std::abs(waypoints[k][0].get<double>()) < 0.2 && waypoints[k][1].get<double>() > 0.15;
    EXPECT_FALSE(in_gap) << "waypoint " << k << " lies in the U's gap";
  }
  EXPECT_NEAR(json["length_m"].get<double>(), length, 1e-9);
  EXPECT_GT(length, 2.0);
  EXPECT_EQ(json["node_joint_configurations"].size(), json["nodes"].size());
  EXPECT_EQ(json["node_joint_configurations"][0].size(), 7U);
  EXPECT_LE(json["max_speed"].get<double>(), json["limits"]["max_speed"].get<double>() * (1 + 1e-9));
  EXPECT_NEAR(json["trajectory"]["positions"].back()[0].get<double>(), 0.3, 1e-12);
}

TEST(ItmCli, AGoalFarFromEveryExploredPositionHasNoPath) {
  const auto data = writeUStream();
  const auto graph = scratchDir() / "u_far.itm";
  ASSERT_EQ(runCliBinary("itm build --data " + data.string() + " --out " + graph.string() + " --dcmax 0").exit_code, 0);
  const std::string far = " --from -0.3,0.78,0.5 --to 8,0.78,0.5";
  const auto refused = runCliBinary("itm path --graph " + graph.string() + far);
  ASSERT_EQ(refused.exit_code, 0) << refused.err;
  const auto json = refused.json();
  EXPECT_FALSE(json["found"].get<bool>());
  EXPECT_NE(json["reason"].get<std::string>().find("goal"), std::string::npos) << json["reason"];
  EXPECT_GT(json["goal_gap_m"].get<double>(), 7.0);
  EXPECT_TRUE(json["waypoints"].empty());
  EXPECT_FALSE(json.contains("duration_s"));
  // The start is held to the same bound; a wider bound lets the far goal through.
  const auto far_start = runCliBinary("itm path --graph " + graph.string() + " --from 8,0.78,0.5 --to 0.3,0.78,0.5");
  EXPECT_NE(far_start.json()["reason"].get<std::string>().find("start"), std::string::npos) << far_start.out;
  const auto allowed = runCliBinary("itm path --graph " + graph.string() + far + " --max-gap 10");
  ASSERT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_TRUE(allowed.json()["found"].get<bool>());
  EXPECT_FALSE(allowed.json().contains("reason"));
}

TEST(ItmCli, RefusesBrokenGraphFiles) {
  const auto dir = scratchDir();
  writeText(dir / "garbage.itm", "this is not a graph\n");
  expectOneLineError(runCliBinary("itm path --graph " + (dir / "garbage.itm").string() + " --from 0,0,0 --to 1,0,0"), "bad magic");
  // A real graph cut in half.
  const auto data = writeUStream();
  const auto graph = dir / "cut.itm";
  ASSERT_EQ(runCliBinary("itm build --data " + data.string() + " --out " + graph.string()).exit_code, 0);
  std::filesystem::resize_file(graph, std::filesystem::file_size(graph) / 2);
  expectOneLineError(runCliBinary("itm path --graph " + graph.string() + " --from 0,0,0 --to 1,0,0"), "cut.itm");
  expectOneLineError(runCliBinary("itm path --graph " + (dir / "missing.itm").string() + " --from 0,0,0 --to 1,0,0"), "missing.itm");
}

TEST(ItmCli, RefusesBrokenStreamsNamingTheLine) {
  const auto dir = scratchDir();
  const auto out = (dir / "never.itm").string();
  writeText(dir / "no_header.csv", "0.1,0.2,0.3,0.4\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "no_header.csv").string() + " --out " + out), "header");
  writeText(dir / "short_row.csv", "x,y,z,q1,q2\n0,0,0,0,0\n0.1,0,0,0\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "short_row.csv").string() + " --out " + out), "line 3");
  writeText(dir / "not_a_number.csv", "x,y,z,q1\n0,0,0,0\n0.1,abc,0,0\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "not_a_number.csv").string() + " --out " + out), "line 3");
  writeText(dir / "nan.csv", "x,y,z,q1\n0,0,nan,0\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "nan.csv").string() + " --out " + out), "line 2");
  writeText(dir / "mac.csv", "x,y,z,q1\r0,0,0.1,0\r0,0.1,0.1,0\r");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "mac.csv").string() + " --out " + out), "carriage return alone");
  writeText(dir / "huge.csv", "x,y,z,q1\n0,0,0.1,0\n0,1e300,0.1,0\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "huge.csv").string() + " --out " + out), "line 3: column 2 ('1e300') is beyond ±1e6");
  // Decimal only, as the scene reader and the command line read numbers.
  writeText(dir / "hex.csv", "x,y,z,q1\n0,0,0.1,0\n0x1,0,0.1,0\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "hex.csv").string() + " --out " + out),
                     "line 3: column 1 ('0x1') is not a finite number");
  writeText(dir / "header_only.csv", "x,y,z,q1\n");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "header_only.csv").string() + " --out " + out), "no samples");
  writeText(dir / "empty.csv", "");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "empty.csv").string() + " --out " + out), "empty");
  expectOneLineError(runCliBinary("itm build --data " + (dir / "missing.csv").string() + " --out " + out), "missing.csv");
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(ItmCli, RefusesBadParametersAndPoints) {
  const auto data = writeUStream();
  const auto graph = scratchDir() / "params.itm";
  expectOneLineError(runCliBinary("itm build --data " + data.string() + " --out " + graph.string() + " --emax -1"), "e_max");
  expectOneLineError(runCliBinary("itm build --data " + data.string() + " --out " + graph.string() + " --delta -2"), "delta");
  ASSERT_EQ(runCliBinary("itm build --data " + data.string() + " --out " + graph.string()).exit_code, 0);
  expectOneLineError(runCliBinary("itm path --graph " + graph.string() + " --from 0,0 --to 1,0,0"), "--from");
  expectOneLineError(runCliBinary("itm path --graph " + graph.string() + " --from 0,0,0 --to 1,x,0"), "--to");
}

TEST(ItmCli, PoseStreamsBuildAPoseMap) {
  const auto path = scratchDir() / "pose.csv";
  {
    std::ofstream file(path);
    file << "x,y,z,qw,qx,qy,qz,q1,q2\n";
    for (int k = 0; k <= 400; ++k) {
      const double angle = 0.0075 * k;
      file << 0.001 * k << ",0,0.5," << std::cos(angle / 2) << ",0,0," << std::sin(angle / 2) << ",0," << 0.001 * k << "\n";
    }
  }
  const auto graph = scratchDir() / "pose.itm";
  const auto result = runCliBinary("itm build --data " + path.string() + " --out " + graph.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(result.json()["task_space"], "pose");
  EXPECT_GE(result.json()["nodes"].get<int>(), 3);
  const auto planned = runCliBinary("itm path --graph " + graph.string() + " --from 0,0,0.5 --to 0.4,0,0.5,0,0,0,1");
  ASSERT_EQ(planned.exit_code, 0) << planned.err;
  EXPECT_TRUE(planned.json()["found"].get<bool>());
  EXPECT_EQ(planned.json()["orientations"].size(), planned.json()["waypoints"].size());
}

}  // namespace
}  // namespace flexirob
