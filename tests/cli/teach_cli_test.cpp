// `flexirob-cli teach`: the simulated tutor teaches through the direct simulation and through the
// FRI backend against the in-process controller stand-in (`--backend fri-sim`), and writes a
// session; bad backends are refused with one line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <vector>

#include "cli_test_support.hpp"

namespace flexirob {
namespace {

namespace fs = std::filesystem;
using flexirob::testing::runCliBinary;

fs::path scratch(const std::string& name) {
  return fs::temp_directory_path() / ("flexirob-teach-cli-" + std::to_string(::getpid()) + "-" + name);
}

TEST(TeachCli, TeachesOneAreaOverTheFriLinkWithNothingLost) {
  const fs::path out = scratch("fri.json");
  const auto result = runCliBinary("teach --backend fri-sim --scene setup_A --areas 1 --seed 3 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = result.json();
  EXPECT_EQ(json.at("backend"), "fri-sim");
  EXPECT_EQ(json.at("areas").get<int>(), 1);
  EXPECT_GT(json.at("samples").get<int>(), 100);
  EXPECT_TRUE(json.at("model_learned").get<bool>());
  EXPECT_EQ(json.at("collisions").get<int>(), 0);
  const auto& link = json.at("fri_link");
  // One measurement per simulated millisecond, each answered, none lost, no fault.
  const double simulated_ms = 1e3 * json.at("simulated_time_s").get<double>();
  EXPECT_NEAR(link.at("measurements").get<double>(), simulated_ms, 0.01 * simulated_ms);
  EXPECT_EQ(link.at("lost_measurements").get<int>(), 0);
  EXPECT_EQ(link.at("watchdog_trips").get<int>(), 0);
  EXPECT_EQ(link.at("commands_rejected").get<int>(), 0);
  EXPECT_EQ(link.at("commands_refused_by_controller").get<int>(), 0);
  EXPECT_GT(link.at("commands_applied_by_controller").get<double>(), 0.9 * simulated_ms);
  EXPECT_TRUE(fs::exists(out));
  fs::remove(out);
}

TEST(TeachCli, TheSameSeedTeachesTheSameAreaOnBothBackends) {
  const fs::path sim_out = scratch("sim.json");
  const fs::path fri_out = scratch("fri2.json");
  const auto sim = runCliBinary("teach --backend sim --scene setup_A --areas 1 --seed 3 --out " + sim_out.string());
  const auto fri = runCliBinary("teach --backend fri-sim --scene setup_A --areas 1 --seed 3 --out " + fri_out.string());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  ASSERT_EQ(fri.exit_code, 0) << fri.err;
  EXPECT_TRUE(sim.json().at("fri_link").is_null());
  // The tutor chooses the same posture and leads the arm there through either path; the FRI
  // link adds a cycle of delay, not a different teaching.
  const auto read = [](const fs::path& file) {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
  };
  const auto sim_session = read(sim_out);
  const auto fri_session = read(fri_out);
  ASSERT_EQ(sim_session.at("areas").size(), 1U);
  ASSERT_EQ(fri_session.at("areas").size(), 1U);
  const auto q_sim = sim_session.at("areas")[0].at("q_fixed").get<std::vector<double>>();
  const auto q_fri = fri_session.at("areas")[0].at("q_fixed").get<std::vector<double>>();
  ASSERT_EQ(q_sim.size(), 7U);
  ASSERT_EQ(q_fri.size(), 7U);
  for (std::size_t j = 0; j < 7; ++j) EXPECT_NEAR(q_sim[j], q_fri[j], 0.02) << "joint " << j + 1;
  fs::remove(sim_out);
  fs::remove(fri_out);
}

TEST(TeachCli, RefusesAnUnknownBackendAndFriForTheNineJointArmWithOneLine) {
  for (const std::string arguments : {"teach --backend carrier-pigeon --scene setup_A --areas 1",
                                      "teach --backend fri-sim --robot arm9 --scene arm9_areas --areas 1"}) {
    const auto result = runCliBinary(arguments + " --out " + scratch("refused.json").string());
    EXPECT_NE(result.exit_code, 0) << arguments;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(fs::exists(scratch("refused.json")));
  }
}

}  // namespace
}  // namespace flexirob
