// Hostile files and arguments through the real flexirob-cli: every one ends with exit code 2
// and exactly one line "error: ..." on stderr, quickly and without exhausting memory
// (docs/RELIABILITY.md).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/cli/cli_test_support.hpp"

namespace flexirob {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::runCliBinary;

class HostileCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flexirob-hostile-cli-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path write(const std::string& name, const std::string& content) const {
    const fs::path file = dir_ / name;
    std::ofstream(file, std::ios::binary) << content;
    return file;
  }
  /// A file of `bytes` bytes that starts with `head` and occupies no disk space beyond it.
  fs::path sparse(const std::string& name, const std::string& head, std::uintmax_t bytes) const {
    const fs::path file = write(name, head);
    fs::resize_file(file, bytes);
    return file;
  }
  static void expectRefused(const CliResult& result, const std::string& expected_part) {
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_TRUE(result.out.empty()) << result.out;
    ASSERT_FALSE(result.err.empty());
    EXPECT_EQ(result.err.rfind("error: ", 0), 0U) << result.err;
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "not one line: " << result.err;
    EXPECT_LE(result.err.size(), 400U) << result.err;
    EXPECT_NE(result.err.find(expected_part), std::string::npos) << result.err;
  }
  fs::path dir_;
};

TEST_F(HostileCli, TwoGigabyteMeshInARobotIsRefusedBeforeLoading) {
  const fs::path mesh = sparse("huge.stl", "solid huge\n", 2ULL * 1024 * 1024 * 1024);
  const fs::path urdf = write("bigmesh.urdf",
                              "<robot name=\"b\"><link name=\"base\"/><link name=\"l1\"><collision><geometry><mesh filename=\"" +
                                  mesh.string() +
                                  "\"/></geometry></collision></link><joint name=\"j1\" type=\"revolute\"><parent "
                                  "link=\"base\"/><child link=\"l1\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" "
                                  "velocity=\"1\" effort=\"1\"/></joint></robot>");
  expectRefused(runCliBinary("reach --robot " + urdf.string() + " --target 0.1,0,0 --max-time 0.01"), "larger than 256 MB");
}

TEST_F(HostileCli, TwoGigabyteMeshObstacleInASceneIsRefused) {
  const fs::path mesh = sparse("huge.stl", "solid huge\n", 2ULL * 1024 * 1024 * 1024);
  const fs::path scene = write("big.yaml", "name: big\nobstacles:\n  - name: m\n    shape: mesh\n    file: " + mesh.string() +
                                               "\n    position: [0.5, 0, 0]\n");
  expectRefused(runCliBinary("reach --scene " + scene.string() + " --target 0.4,0,0.5 --max-time 0.01"), "larger than");
}

TEST_F(HostileCli, MillionJointUrdfIsRefused) {
  const fs::path urdf = dir_ / "million.urdf";
  {
    std::ofstream out(urdf);
    out << "<robot name=\"million\"><link name=\"l0\"/>\n";
    for (int i = 1; i <= 1'000'000; ++i) {
      out << "<link name=\"l" << i << "\"/><joint name=\"j" << i << "\" type=\"continuous\"><parent link=\"l" << i - 1
          << "\"/><child link=\"l" << i << "\"/></joint>\n";
    }
    out << "</robot>\n";
  }
  expectRefused(runCliBinary("robot info --robot " + urdf.string()), "larger than 64 MB");
}

TEST_F(HostileCli, DeeplyNestedUrdfIsRefused) {
  std::string xml = "<robot name=\"deep\"><link name=\"base\">";
  for (int i = 0; i < 300000; ++i) xml += "<visual>";
  for (int i = 0; i < 300000; ++i) xml += "</visual>";
  xml += "</link></robot>";
  expectRefused(runCliBinary("robot info --robot " + write("deep.urdf", xml).string()), "nested deeper");
}

TEST_F(HostileCli, SceneWithNanPoseIsRefusedNamingTheLine) {
  const fs::path scene = write("nan.yaml",
                               "name: nan\nobstacles:\n  - name: box\n    shape: box\n    size: [0.1, 0.1, 0.1]\n"
                               "    position: [.nan, 0, 0.2]\n");
  expectRefused(runCliBinary("reach --scene " + scene.string() + " --target 0.4,0,0.5 --max-time 0.01"),
                "nan.yaml:6");
}

TEST_F(HostileCli, DeeplyNestedSceneIsRefused) {
  const fs::path scene = write("deep.yaml", "name: deep\nobstacles: " + std::string(100000, '[') + std::string(100000, ']') + "\n");
  expectRefused(runCliBinary("reach --scene " + scene.string() + " --target 0.4,0,0.5 --max-time 0.01"), "deep.yaml");
}

TEST_F(HostileCli, HugeNumericListIsRefusedWithAShortMessage) {
  // 100 kB, below the kernel's 128 kB limit for one argument.
  std::string list = "0.1";
  while (list.size() < 100'000) list += ",0.1";
  expectRefused(runCliBinary("fk --q " + list), "--q");
  std::string garbage(100'000, '9');
  garbage += "x";
  expectRefused(runCliBinary("fk --q 0,0,0," + garbage + ",0,0,0"), "is not a finite number");
}

TEST_F(HostileCli, NonFiniteAndOverflowingNumbersAreRefused) {
  expectRefused(runCliBinary("fk --q 0,0,0,nan,0,0,0"), "not a finite number");
  expectRefused(runCliBinary("fk --q 0,0,0,1e999,0,0,0"), "not a finite number");
  expectRefused(runCliBinary("reach --target 0.4,inf,0.5"), "not a finite number");
  // Hexadecimal is refused as the scene reader refuses it (strtod reads 0x1 as 1).
  expectRefused(runCliBinary("fk --q 0x1,0,0,0,0,0,0"), "'0x1' is not a finite number");
  expectRefused(runCliBinary("reach --target 0x1p-1,0,0.5"), "'0x1p-1' is not a finite number");
}

TEST_F(HostileCli, ReachRefusesTargetsUnderTheTableAndPosturesOutsideTheLimits) {
  expectRefused(runCliBinary("reach --target -0.5,0.2,-0.4"), "below the table top");
  expectRefused(runCliBinary("reach --target 1e300,0,0.5"), "--target: coordinates beyond 1000 m");
  // The value as given, not its 300 digits.
  expectRefused(runCliBinary("fri simulate --peer 127.0.0.1:49999 --seconds 1e300"), "--seconds: expected a duration in (0, 86400], got 1e+300");
  expectRefused(runCliBinary("bench --filter ["), "--filter: '[' is not a valid regular expression");
  // One line: neither Google Benchmark's own words nor progress, stderr being no terminal.
  expectRefused(runCliBinary("bench --filter nomatch"), "no benchmark matches 'nomatch'");
  expectRefused(runCliBinary("reach --target -0.5,0.2,0.4 --posture 0,0,0,0,0,0,10"), "--posture: joint 7");
  expectRefused(runCliBinary("reach --target -0.5,0.2,0.4 --from 0,0,0,0,0,0,10"), "--from: joint 7");
}

// A session is SQLite's, kept open through the run: a pipe at --out cannot hold one. --out naming
// the --data file would destroy what the run reads.
TEST_F(HostileCli, ASessionIntoAPipeOrAnOutputOntoTheInputFileIsRefused) {
  const fs::path pipe = dir_ / "pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  expectRefused(runCliBinary("teach --scene setup_A --areas 1 --overwrite --out " + pipe.string()), "is not a regular file");
  EXPECT_FALSE(fs::is_regular_file(pipe)) << "still the pipe";
  std::string rows = "area,x,y,z,q1,q2\n";
  for (int i = 0; i < 20; ++i) rows += "0," + std::to_string(0.01 * i) + ",0.2,0.3," + std::to_string(0.02 * i) + ",0.5\n";
  const fs::path data = write("data.csv", rows);
  expectRefused(runCliBinary("learn fit --data " + data.string() + " --out " + data.string()), "is the --data file the run reads");
  std::string stream = "x,y,z,q1\n";
  for (int i = 0; i < 20; ++i) stream += std::to_string(0.05 * i) + ",0.2,0.3," + std::to_string(0.1 * i) + "\n";
  const fs::path samples = write("stream.csv", stream);
  expectRefused(runCliBinary("itm build --data " + samples.string() + " --out " + samples.string()), "is the --data file the run reads");
  const fs::path scene = write("scene.yaml", "name: kept\n");
  expectRefused(runCliBinary("render --scene " + scene.string() + " --out " + scene.string()), "is the --scene file the run reads");
  EXPECT_EQ(fs::file_size(scene), 11U) << "the scene is as it was";
  std::ifstream kept(data);
  std::string header;
  std::getline(kept, header);
  EXPECT_EQ(header, "area,x,y,z,q1,q2") << "the data file is as it was";
}

// Any other output goes through a pipe as it is (`--out /dev/stdout | ...`, a named pipe): a
// file renamed into its place would leave the reader with nothing.
TEST_F(HostileCli, AModelOrAPictureWrittenIntoAPipeReachesItsReader) {
  std::string rows = "area,x,y,z,q1,q2\n";
  for (int i = 0; i < 20; ++i) rows += "0," + std::to_string(0.01 * i) + ",0.2,0.3," + std::to_string(0.02 * i) + ",0.5\n";
  const fs::path data = write("pipe-data.csv", rows);
  const fs::path pipe = dir_ / "out.pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const auto readFile = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const fs::path model = dir_ / "model-through-pipe.txt";
  const fs::path picture = dir_ / "picture-through-pipe.png";
  const std::string cli = FLEXIROB_CLI_EXECUTABLE;
  for (const auto& [command, received] :
       std::vector<std::pair<std::string, fs::path>>{{"learn fit --data " + data.string() + " --out " + pipe.string(), model},
                                                     {"render --scene empty --width 32 --height 24 --out " + pipe.string(), picture}}) {
    // timeout: a command that refused before opening the pipe would leave cat waiting for ever.
    const int status = std::system(("timeout 60 cat " + pipe.string() + " > " + received.string() + " & " + cli + " " + command +
                                    " > /dev/null 2>&1; code=$?; wait; exit $code").c_str());
    ASSERT_TRUE(WIFEXITED(status)) << command;
    EXPECT_EQ(WEXITSTATUS(status), 0) << command;
    EXPECT_TRUE(fs::is_fifo(pipe)) << command << ": still the pipe";
  }
  const std::string model_text = readFile(model);
  EXPECT_GT(model_text.size(), 100U);
  const fs::path kept = dir_ / "model-in-a-file.txt";
  ASSERT_EQ(runCliBinary("learn fit --data " + data.string() + " --out " + kept.string()).exit_code, 0);
  EXPECT_EQ(model_text, readFile(kept)) << "the model through the pipe is the one a file gets";
  EXPECT_EQ(readFile(picture).substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
}

// A reader that goes away before the output is through: a write error with its reason and exit
// code 2, not a silent death by SIGPIPE (exit 141, no line).
TEST_F(HostileCli, AnOutputWhosePipeReaderLeftEndsWithOneLine) {
  const fs::path pipe = dir_ / "short.pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const fs::path err = dir_ / "short-stderr.txt";
  const int status = std::system(("(exec 3< " + pipe.string() + "; timeout 60 head -c 1 <&3 > /dev/null) & " +
                                  std::string(FLEXIROB_CLI_EXECUTABLE) +
                                  " render --scene setup_I --width 1500 --height 1500 --supersample 1 --out " + pipe.string() +
                                  " > /dev/null 2> " + err.string() + "; code=$?; wait; exit $code")
                                     .c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream in(err);
  std::string said((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(said.find("error: --out: cannot write '" + pipe.string() + "': Broken pipe"), std::string::npos) << said;
}

// /dev/stdout with standard output redirected to a file names that file: renamed over, the
// command's JSON went to the unlinked old file and the output took the JSON's place. Into a pipe,
// the output and the JSON came out one after the other.
TEST_F(HostileCli, AnOutputThatIsWhereStandardOutputGoesIsRefused) {
  std::string rows = "area,x,y,z,q1,q2\n";
  for (int i = 0; i < 20; ++i) rows += "0," + std::to_string(0.01 * i) + ",0.2,0.3," + std::to_string(0.02 * i) + ",0.5\n";
  const fs::path data = write("stdout-data.csv", rows);
  const fs::path out = dir_ / "stdout.json";
  const fs::path err = dir_ / "stderr.txt";
  for (const std::string& command : std::vector<std::string>{"learn fit --data " + data.string() + " --out /dev/stdout",
                                     "sweep --tables 7.1 --markdown /dev/stdout",
                                     "render --scene empty --width 32 --height 24 --out /dev/stdout"}) {
    const int status = std::system((std::string(FLEXIROB_CLI_EXECUTABLE) + " " + command + " > " + out.string() + " 2> " + err.string()).c_str());
    ASSERT_TRUE(WIFEXITED(status)) << command;
    EXPECT_EQ(WEXITSTATUS(status), 2) << command;
    std::ifstream in(err);
    std::string line;
    std::getline(in, line);
    EXPECT_NE(line.find("is where standard output goes"), std::string::npos) << command << ": " << line;
    EXPECT_TRUE(fs::exists(out));
    const fs::path code = dir_ / "code.txt";
    const int piped = std::system(("(" + std::string(FLEXIROB_CLI_EXECUTABLE) + " " + command + " 2> " + err.string() + "; echo $? > " +
                                   code.string() + ") | cat > " + out.string())
                                      .c_str());
    ASSERT_TRUE(WIFEXITED(piped)) << command;
    std::ifstream exit_code(code);
    int value = -1;
    exit_code >> value;
    EXPECT_EQ(value, 2) << command << " into a pipe";
    std::ifstream piped_err(err);
    std::getline(piped_err, line);
    EXPECT_NE(line.find("is where standard output goes"), std::string::npos) << command << ": " << line;
  }
  // The null device takes any output, also where standard output goes too.
  const int discarded =
      std::system((std::string(FLEXIROB_CLI_EXECUTABLE) + " learn fit --data " + data.string() + " --out /dev/null > /dev/null 2>&1").c_str());
  ASSERT_TRUE(WIFEXITED(discarded));
  EXPECT_EQ(WEXITSTATUS(discarded), 0);
}

// /dev/null and a terminal lie in folders only root may write in: an output written in place is
// checked for itself, not for its folder. A block device is no output (it had been written over).
TEST_F(HostileCli, TheNullDeviceIsAnOutputForEveryUserABlockDeviceForNone) {
  std::string rows = "area,x,y,z,q1,q2\n";
  for (int i = 0; i < 20; ++i) rows += "0," + std::to_string(0.01 * i) + ",0.2,0.3," + std::to_string(0.02 * i) + ",0.5\n";
  const fs::path data = write("null-data.csv", rows);
  fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const std::string cli = FLEXIROB_CLI_EXECUTABLE;
  if (::geteuid() == 0 && std::system(("command -v runuser > /dev/null 2>&1 && runuser -u nobody -- test -r " + data.string()).c_str()) == 0) {
    const int status = std::system(("runuser -u nobody -- " + cli + " learn fit --data " + data.string() + " --out /dev/null > /dev/null").c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "learn fit --out /dev/null as nobody";
  }
  // Nor is any device but a terminal and the null device (memory, raw flash, a tape).
  expectRefused(runCliBinary("learn fit --data " + data.string() + " --out /dev/zero"), "is not a regular file (a device other than");
  const fs::path block = dir_ / "block";
  if (::mknod(block.c_str(), S_IFBLK | 0600, makedev(7, 250)) != 0) GTEST_SKIP() << "no device node can be made here";
  expectRefused(runCliBinary("learn fit --data " + data.string() + " --out " + block.string()), "is not a regular file (a device other than");
}

// The sweep keeps its tables until it ends: stopped half-way it leaves the last sweep's files
// whole (it had emptied --markdown at its start), and one file for both outputs is refused.
TEST_F(HostileCli, ASweepStoppedHalfWayLeavesTheLastTablesWhole) {
  const fs::path markdown = write("sweep.md", "# the last sweep\n");
  const fs::path said = dir_ / "sweep-stderr.txt";
  // SIGTERM once the sweep has said it began its first row (teaching it takes seconds); SIGINT
  // would be ignored by a command a shell starts in the background.
  const std::string script = std::string(FLEXIROB_CLI_EXECUTABLE) +
                             " sweep --tables 3.3 --max-areas 1 --spacing 0.3 --markdown " + markdown.string() +
                             " > /dev/null 2> " + said.string() + " & pid=$!; for i in $(seq 1200); do grep -qs 'sweep: Tab. 3.3' " +
                             said.string() + " && break; sleep 0.05; done; kill -TERM $pid; wait $pid";
  const int status = std::system(script.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << "the sweep was not stopped by the signal";
  std::ifstream in(markdown);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "# the last sweep\n");
  // It says why it ended, in its last line.
  std::ifstream messages(said);
  std::string line, last;
  while (std::getline(messages, line)) last = line;
  EXPECT_EQ(last, "flexirob-cli: stopped by SIGTERM; files not written yet are as they were");
  fs::remove(said);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_)) ++files;
  // A link to a file in a folder that is not there: refused before the sweep, not after it.
  fs::create_symlink(dir_ / "no-such-folder" / "t.md", dir_ / "dangling.md");
  expectRefused(runCliBinary("sweep --tables 7.1 --markdown " + (dir_ / "dangling.md").string()), "does not exist");
  fs::remove(dir_ / "dangling.md");
  expectRefused(runCliBinary("sweep --tables 7.1 --json " + markdown.string() + " --markdown ./" + markdown.lexically_relative(fs::current_path()).string()),
                "is the file --json names");
  std::size_t after = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_)) ++after;
  EXPECT_EQ(after, files) << "no temporary left";
}

TEST_F(HostileCli, GarbageModelGraphAndSessionFilesAreRefused) {
  const fs::path garbage = write("garbage.bin", std::string("\x00\xff\x13garbage\n", 11));
  const fs::path data = write("data.csv", "x,y,z\n0.4,0,0.5\n");
  expectRefused(runCliBinary("learn predict --model " + garbage.string() + " --data " + data.string()), "garbage.bin");
  expectRefused(runCliBinary("itm path --graph " + garbage.string() + " --from 0,0,0 --to 1,0,0"), "garbage.bin");
  expectRefused(runCliBinary("review --session " + garbage.string()), "garbage.bin");
  // Sparse files of 2 GB with a plausible start: refused by their headers or sizes, not read.
  expectRefused(runCliBinary("review --session " +
                             sparse("huge.session", std::string("SQLite format 3\0", 16), 2ULL * 1024 * 1024 * 1024).string()),
                "huge.session");
  expectRefused(runCliBinary("itm path --graph " + sparse("huge.itm", "FLXITM\r\n", 2ULL * 1024 * 1024 * 1024).string() +
                             " --from 0,0,0 --to 1,0,0"),
                "huge.itm");
  expectRefused(runCliBinary("learn predict --model " +
                             sparse("huge.model", "flexirob-model 1\n", 2ULL * 1024 * 1024 * 1024).string() + " --data " +
                             data.string()),
                "huge.model");
}

}  // namespace
}  // namespace flexirob
