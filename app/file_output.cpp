#include "app/file_output.hpp"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#include "robot/errors.hpp"

namespace flexirob::app {

InterruptionsHeld::InterruptionsHeld() {
  sigset_t held;
  sigemptyset(&held);
  sigaddset(&held, SIGINT);
  sigaddset(&held, SIGTERM);
  active_ = ::pthread_sigmask(SIG_BLOCK, &held, &previous_) == 0;
}

InterruptionsHeld::~InterruptionsHeld() {
  if (active_) ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

std::filesystem::path followLinks(const std::filesystem::path& file) {
  std::filesystem::path path = file;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code error;
    if (!std::filesystem::is_symlink(path, error)) return path;
    const std::filesystem::path target = std::filesystem::read_symlink(path, error);
    if (error) return file;
    // Joined as the kernel reads it: "dirlink/../x" is ".." of the folder dirlink names, which
    // a lexical normalization would take for the folder holding dirlink.
    path = target.is_absolute() ? target : path.parent_path() / target;
  }
  return file;
}

void writeFileReplacing(const std::filesystem::path& requested, const std::string& text, const std::string& option) {
  const std::filesystem::path file = followLinks(requested);
  const InterruptionsHeld held;
  // A temporary of its own (mkstemp) beside the file: a fixed name such as "<file>.tmp" could be
  // another output of the same run, or a file someone keeps.
  std::string temporary = file.string() + ".XXXXXX";
  const int descriptor = ::mkstemp(temporary.data());
  if (descriptor < 0) throw InputError(option + ": cannot write '" + requested.string() + "': " + std::strerror(errno));
  // mkstemp makes the file private; it gets the mode the file it replaces had, or the one a new
  // file gets under the user's umask.
  struct stat existing {};
  mode_t mode = 0;
  if (::stat(file.c_str(), &existing) == 0) {
    mode = existing.st_mode & 07777;
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    mode = 0666 & ~mask;
  }
  bool written = ::fchmod(descriptor, mode) == 0;
  for (std::size_t done = 0; done < text.size() && written;) {
    const ssize_t n = ::write(descriptor, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    written = n > 0;
    if (written) done += static_cast<std::size_t>(n);
  }
  written = ::close(descriptor) == 0 && written;
  std::error_code error;
  if (written) std::filesystem::rename(temporary, file, error);
  if (!written || error) {
    std::filesystem::remove(temporary, error);
    throw InputError(option + ": cannot write '" + requested.string() + "'" + (written ? "" : " (disk full?)"));
  }
}

}  // namespace flexirob::app
