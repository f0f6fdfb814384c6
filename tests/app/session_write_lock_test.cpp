// Two runs writing the same session: the second is refused while the first holds the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "app/session_write_lock.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {
namespace {

namespace fs = std::filesystem;

fs::path scratchSession() { return fs::temp_directory_path() / ("flexirob-lock-test-" + std::to_string(::getpid()) + ".db"); }

TEST(SessionWriteLock, ASecondWriterIsRefusedWhileTheFirstHoldsTheSessionAndAllowedAfterItEnds) {
  const fs::path session = scratchSession();
  std::optional<SessionWriteLock> first(std::in_place, session, "--out");
  try {
    SessionWriteLock second(session, "--out");
    FAIL() << "a second writer of the same session was allowed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is being written by another run"), std::string::npos) << e.what();
  }
  first.reset();
  EXPECT_NO_THROW(SessionWriteLock again(session, "--out"));
  EXPECT_FALSE(fs::exists(SessionWriteLock::lockFileFor(session)));  // no lock file left behind
}

TEST(SessionWriteLock, ALockFileLeftByACrashedRunDoesNotBlock) {
  const fs::path session = scratchSession();
  { std::ofstream(SessionWriteLock::lockFileFor(session)) << ""; }  // no process holds it
  EXPECT_NO_THROW(SessionWriteLock writer(session, "--out"));
}

}  // namespace
}  // namespace flexirob::app
