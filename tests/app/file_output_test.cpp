// app::writeFileReplacing: how every output file of the commands is written.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "app/file_output.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

// A folder of this test's own, emptied and removed when the test ends.
class FileOutput : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() /
              ("flexirob-file-output-" + std::to_string(::getpid()) + "-" +
               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  static std::string read(const fs::path& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  std::set<std::string> names() const {
    std::set<std::string> out;
    for (const auto& entry : fs::directory_iterator(folder_)) out.insert(entry.path().filename().string());
    return out;
  }

  fs::path folder_;
};

TEST_F(FileOutput, ReplacesTheFileWholeAndLeavesNoTemporary) {
  writeFileReplacing(folder_ / "out.csv", "old\n", "--samples");
  writeFileReplacing(folder_ / "out.csv", "new\n", "--samples");
  EXPECT_EQ(read(folder_ / "out.csv"), "new\n");
  EXPECT_EQ(names(), std::set<std::string>{"out.csv"});
}

TEST_F(FileOutput, RefusesAFolderThatIsNotThereNamingTheOption) {
  try {
    writeFileReplacing(folder_ / "no-such-folder" / "x.csv", "x", "--stream");
    FAIL() << "expected InputError";
  } catch (const flexirob::InputError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("--stream: cannot write", 0), 0u) << error.what();
  }
}

// The model and graph writers had written "<file>.tmp" and renamed it: a file of that name,
// kept by someone, was overwritten and gone.
TEST_F(FileOutput, NeverTouchesAFileBesideTheOutput) {
  for (const char* kept : {"model.flm.tmp", "model.flm.XXXXXX", "model.flm~"}) {
    std::ofstream(folder_ / kept) << "kept\n";
  }
  writeFileReplacing(folder_ / "model.flm", "model\n", "--out");
  EXPECT_EQ(read(folder_ / "model.flm"), "model\n");
  for (const char* kept : {"model.flm.tmp", "model.flm.XXXXXX", "model.flm~"}) EXPECT_EQ(read(folder_ / kept), "kept\n") << kept;
  EXPECT_EQ(names().size(), 4u);
}

// mkstemp makes a private file; the file written must not be more or less private than the
// one it replaces, or than a new file under the user's umask.
TEST_F(FileOutput, KeepsTheReplacedFilesModeAndGivesANewOneTheUmasks) {
  const mode_t previous = ::umask(077);
  writeFileReplacing(folder_ / "new.csv", "x\n", "--samples");
  ::umask(previous);
  EXPECT_EQ(fs::status(folder_ / "new.csv").permissions() & fs::perms::all, fs::perms::owner_read | fs::perms::owner_write);
  writeFileReplacing(folder_ / "kept.csv", "old\n", "--samples");
  fs::permissions(folder_ / "kept.csv", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  writeFileReplacing(folder_ / "kept.csv", "new\n", "--samples");
  EXPECT_EQ(fs::status(folder_ / "kept.csv").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
}

// A rename onto a symbolic link replaces the link; the file it named kept the old content.
TEST_F(FileOutput, WritesTheFileASymbolicLinkNamesAndKeepsTheLink) {
  fs::create_directories(folder_ / "real");
  writeFileReplacing(folder_ / "real" / "graph.itm", "old\n", "--out");
  fs::create_symlink(folder_ / "real" / "graph.itm", folder_ / "link.itm");
  fs::create_symlink("link.itm", folder_ / "link-to-link.itm");
  writeFileReplacing(folder_ / "link-to-link.itm", "new\n", "--out");
  EXPECT_TRUE(fs::is_symlink(folder_ / "link.itm"));
  EXPECT_TRUE(fs::is_symlink(folder_ / "link-to-link.itm"));
  EXPECT_EQ(read(folder_ / "real" / "graph.itm"), "new\n");
  EXPECT_EQ(names(), (std::set<std::string>{"link-to-link.itm", "link.itm", "real"}));
  // A link to a file not yet there: the file is made where the link points.
  fs::create_symlink(folder_ / "real" / "later.itm", folder_ / "dangling.itm");
  writeFileReplacing(folder_ / "dangling.itm", "made\n", "--out");
  EXPECT_TRUE(fs::is_symlink(folder_ / "dangling.itm"));
  EXPECT_EQ(read(folder_ / "real" / "later.itm"), "made\n");
}

// A relative link in a folder reached through a linked folder: "../x" is read from the folder
// the link lies in, as the kernel reads it (not from the folder holding the folder's link).
TEST_F(FileOutput, ALinkInALinkedFolderWritesTheFileTheKernelWouldOpen) {
  fs::create_directories(folder_ / "d1" / "real");
  std::ofstream(folder_ / "d1" / "target.flm") << "old\n";
  fs::create_symlink("../target.flm", folder_ / "d1" / "real" / "out.flm");
  fs::create_symlink(folder_ / "d1" / "real", folder_ / "dirlink");
  writeFileReplacing(folder_ / "dirlink" / "out.flm", "new\n", "--out");
  EXPECT_EQ(read(folder_ / "d1" / "target.flm"), "new\n");
  EXPECT_TRUE(fs::is_symlink(folder_ / "d1" / "real" / "out.flm"));
  EXPECT_FALSE(fs::exists(folder_ / "target.flm"));
}

// Killed by SIGTERM while it writes (200 MB), a process leaves the output whole or not at all,
// and no temporary beside it; the signal still ends the process, once the write is done.
TEST_F(FileOutput, AnInterruptedWriteLeavesNoTemporaryAndNoHalfFile) {
  const std::string text(200u << 20, 'x');
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGTERM, SIG_DFL);
    try {
      writeFileReplacing(folder_ / "big.bin", text, "--out");
    } catch (...) {
      ::_exit(3);
    }
    for (;;) ::pause();
  }
  ::usleep(20000);
  ASSERT_EQ(::kill(child, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  const std::set<std::string> left = names();
  EXPECT_TRUE(left.empty() || left == std::set<std::string>{"big.bin"}) << left.size() << " files, first " << *left.begin();
  if (left.count("big.bin") > 0) {
    EXPECT_EQ(fs::file_size(folder_ / "big.bin"), text.size());
  }
}

// /dev/stdout into a pipe, or a named pipe: renaming a file over it would leave a regular file
// where the pipe was, and the reader would get nothing.
TEST_F(FileOutput, APipeIsWrittenInPlaceAndStaysAPipe) {
  const fs::path pipe = folder_ / "pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const int reader = ::open(pipe.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  writeFileReplacing(pipe, "through the pipe\n", "--json");
  char buffer[64] = {};
  const ssize_t n = ::read(reader, buffer, sizeof buffer);
  ::close(reader);
  EXPECT_EQ(std::string(buffer, n > 0 ? static_cast<std::size_t>(n) : 0), "through the pipe\n");
  EXPECT_TRUE(fs::is_fifo(pipe));
  EXPECT_EQ(names(), std::set<std::string>{"pipe"});
}

// Outputs written together: a pipe nobody reads blocks its writer, and a Ctrl-C must still end
// the command, before the regular files (all or none) are written.
TEST_F(FileOutput, OutputsWrittenTogetherStayInterruptibleWhileAPipeWaitsForItsReader) {
  const fs::path pipe = folder_ / "pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGTERM, SIG_DFL);
    try {
      writeFilesTogether({{"--json", folder_ / "table.json", "{}\n"}, {"--markdown", pipe, "# table\n"}});
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  ::usleep(100000);
  ASSERT_EQ(::kill(child, SIGTERM), 0);
  int status = 0;
  pid_t ended = 0;
  for (int wait = 0; wait < 100 && ended == 0; ++wait) {
    ended = ::waitpid(child, &status, WNOHANG);
    if (ended == 0) ::usleep(50000);
  }
  if (ended == 0) {
    ::kill(child, SIGKILL);
    ::waitpid(child, &status, 0);
    FAIL() << "SIGTERM did not end a writer waiting for the pipe's reader";
  }
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_EQ(names(), std::set<std::string>{"pipe"});
}

// Read end open: the pipe gets its text in place and every regular file is written.
TEST_F(FileOutput, OutputsWrittenTogetherAreAllWritten) {
  const fs::path pipe = folder_ / "pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  const int reader = ::open(pipe.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  writeFilesTogether({{"--samples", folder_ / "a.csv", "a\n"}, {"--stream", pipe, "p\n"}, {"--model", folder_ / "m.flm", "m\n"}});
  char buffer[8] = {};
  const ssize_t n = ::read(reader, buffer, sizeof buffer);
  ::close(reader);
  EXPECT_EQ(std::string(buffer, n > 0 ? static_cast<std::size_t>(n) : 0), "p\n");
  EXPECT_EQ(read(folder_ / "a.csv"), "a\n");
  EXPECT_EQ(read(folder_ / "m.flm"), "m\n");
  EXPECT_EQ(names(), (std::set<std::string>{"a.csv", "m.flm", "pipe"}));
}

// A study's plot named as one of its tables: the second would have replaced the first, which the
// command still listed as written. Refused before either is written; /dev/null takes both.
TEST_F(FileOutput, OutputsWrittenTogetherMayNotNameOneFileButTheNullDevice) {
  try {
    writeFilesTogether({{"--csv-dir", folder_ / "participants.csv", "a\n"}, {"--plot", folder_ / "." / "participants.csv", "png"}});
    FAIL() << "expected InputError";
  } catch (const flexirob::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("--plot: '"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("is the file --csv-dir names"), std::string::npos) << error.what();
  }
  EXPECT_TRUE(names().empty());
  writeFilesTogether({{"--samples", "/dev/null", "a\n"}, {"--stream", "/dev/null", "b\n"}});
}

// Renamed over, a socket (or a block device) would have been replaced by a regular file.
TEST_F(FileOutput, RefusesASocketAndLeavesIt) {
  const fs::path socket_file = folder_ / "control.sock";
  const int listening = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(listening, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socket_file.string().size(), sizeof(address.sun_path));
  std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", socket_file.c_str());
  ASSERT_EQ(::bind(listening, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  try {
    writeFileReplacing(socket_file, "x\n", "--out");
    FAIL() << "expected InputError";
  } catch (const flexirob::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("is not a regular file"), std::string::npos) << error.what();
  }
  ::close(listening);
  EXPECT_TRUE(fs::is_socket(socket_file));
  EXPECT_EQ(names(), std::set<std::string>{"control.sock"});
}

}  // namespace
}  // namespace flexirob::app
