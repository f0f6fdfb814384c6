#pragma once
// Keeps two processes from writing the same session file at once.
//
// Without it, a second `teach --out x` replaced the file the first was still writing and both
// ended "successfully": the session that finished first was silently lost.
#include <filesystem>
#include <string>

namespace flexirob::app {

/// An advisory lock (flock) on "<session>.lock", held while the object lives. The operating
/// system releases it when the process ends, crash or kill -9 included, so a stale lock file
/// never blocks a later run.
class SessionWriteLock {
 public:
  /// Throws flexirob::InputError (one line, naming `option`) if another process, or another
  /// lock in this one, is writing `session`.
  SessionWriteLock(const std::filesystem::path& session, const std::string& option);
  ~SessionWriteLock();
  SessionWriteLock(const SessionWriteLock&) = delete;
  SessionWriteLock& operator=(const SessionWriteLock&) = delete;

  static std::filesystem::path lockFileFor(const std::filesystem::path& session);

 private:
  std::filesystem::path lock_file_;
  int fd_ = -1;
};

}  // namespace flexirob::app
