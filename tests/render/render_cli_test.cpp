// `flexirob-cli render`, run in-process: its JSON, its picture, its errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "app/cli/cli_support.hpp"

namespace flexirob::cli {
namespace {

struct Result {
  int exit_code = 0;
  std::string out;
  std::string err;
};

Result run(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "flexirob-cli");
  std::vector<const char*> argv;
  for (const auto& a : arguments) argv.push_back(a.c_str());
  std::ostringstream out;
  std::ostringstream err;
  std::streambuf* old_out = std::cout.rdbuf(out.rdbuf());
  std::streambuf* old_err = std::cerr.rdbuf(err.rdbuf());
  Result result;
  result.exit_code = runCli(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old_out);
  std::cerr.rdbuf(old_err);
  result.out = out.str();
  result.err = err.str();
  return result;
}

std::filesystem::path tempPng(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("flexirob-render-cli-" + std::to_string(::getpid()) + "-" + name);
}

TEST(RenderCommand, WritesThePictureAndReportsItsSizeAndTipPixel) {
  const auto file = tempPng("lwr4.png");
  const Result result = run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "320", "--height", "200",
                             "--q", "0.3,0.6,0,-1.2,0,0.8,0", "--supersample", "1"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const auto json = nlohmann::json::parse(result.out);
  EXPECT_EQ(json.at("width"), 320);
  EXPECT_EQ(json.at("height"), 200);
  EXPECT_EQ(json.at("file"), file.string());
  ASSERT_TRUE(std::filesystem::exists(file));
  // PNG signature and the IHDR size match what was reported.
  std::ifstream in(file, std::ios::binary);
  std::vector<unsigned char> head(24);
  in.read(reinterpret_cast<char*>(head.data()), 24);
  EXPECT_EQ(head[1], 'P');
  EXPECT_EQ((head[16] << 24) | (head[17] << 16) | (head[18] << 8) | head[19], 320);
  EXPECT_EQ((head[20] << 24) | (head[21] << 16) | (head[22] << 8) | head[23], 200);
  const auto& tip = json.at("tip_pixel");
  EXPECT_GT(tip[0].get<double>(), 0.0);
  EXPECT_LT(tip[0].get<double>(), 320.0);
  EXPECT_GT(tip[1].get<double>(), 0.0);
  EXPECT_LT(tip[1].get<double>(), 200.0);
  std::filesystem::remove(file);
}

TEST(RenderCommand, RejectsBadInputWithExitCodeTwo) {
  const auto file = tempPng("bad.png");
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--q", "0,0,0"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--width", "0"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--out", file.string(), "--camera", "1,2"}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "no_such_robot", "--out", file.string()}).exit_code, 2);
  EXPECT_EQ(run({"render", "--robot", "lwr4", "--scene", "no_such_scene", "--out", file.string()}).exit_code, 2);
  const Result unwritable = run({"render", "--robot", "lwr4", "--width", "16", "--height", "16", "--out",
                                 "/nonexistent-folder/x.png"});
  EXPECT_EQ(unwritable.exit_code, 2);
  EXPECT_NE(unwritable.err.find("cannot write"), std::string::npos) << unwritable.err;
  EXPECT_FALSE(std::filesystem::exists(file));
}

}  // namespace
}  // namespace flexirob::cli
