#include "app/session_write_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "robot/errors.hpp"

namespace flexirob::app {

std::filesystem::path SessionWriteLock::lockFileFor(const std::filesystem::path& session) {
  std::filesystem::path lock = session;
  lock += ".lock";
  return lock;
}

SessionWriteLock::SessionWriteLock(const std::filesystem::path& session, const std::string& option)
    : lock_file_(lockFileFor(session)) {
  const std::string busy = option + ": '" + session.string() +
                           "' is being written by another run; wait for it to end or choose another path";
  // A holder that ends unlinks the lock file: a lock taken on the unlinked file would not
  // exclude a third run that creates a new one, so the file locked must still be the one at the path.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const int fd = ::open(lock_file_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw InputError(option + ": cannot create '" + lock_file_.string() + "': " + std::strerror(errno));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      ::close(fd);
      if (error == EWOULDBLOCK) throw InputError(busy);
      throw InputError(option + ": cannot lock '" + lock_file_.string() + "': " + std::strerror(error));
    }
    struct stat locked {}, at_path {};
    if (::fstat(fd, &locked) == 0 && ::stat(lock_file_.c_str(), &at_path) == 0 && locked.st_ino == at_path.st_ino &&
        locked.st_dev == at_path.st_dev) {
      fd_ = fd;
      return;
    }
    ::close(fd);
  }
  throw InputError(busy);
}

SessionWriteLock::~SessionWriteLock() {
  if (fd_ < 0) return;
  ::unlink(lock_file_.c_str());  // while still held, so no other run holds a lock on this file
  ::close(fd_);
}

}  // namespace flexirob::app
