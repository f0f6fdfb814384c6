#include "app/file_output.hpp"

#include <fcntl.h>
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

bool isDeviceOrPipe(const std::filesystem::path& file) {
  struct stat status {};
  return ::stat(file.c_str(), &status) == 0 && !S_ISREG(status.st_mode) && !S_ISDIR(status.st_mode);
}

namespace {

bool writeAll(int descriptor, const std::string& text) {
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(descriptor, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

void writeFileReplacing(const std::filesystem::path& requested, const std::string& text, const std::string& option) {
  // stat and open follow /proc's links to pipes, which followLinks cannot name.
  if (isDeviceOrPipe(requested)) {
    // Renaming over a device or a pipe would put a regular file in its place; it is written as it
    // is, and not held: a pipe nobody reads must stay interruptible.
    const int descriptor = ::open(requested.c_str(), O_WRONLY | O_CLOEXEC);
    if (descriptor < 0) throw InputError(option + ": cannot write '" + requested.string() + "': " + std::strerror(errno));
    const bool written = writeAll(descriptor, text);
    if (!(::close(descriptor) == 0 && written)) throw InputError(option + ": cannot write '" + requested.string() + "'");
    return;
  }
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
  bool written = ::fchmod(descriptor, mode) == 0 && writeAll(descriptor, text);
  written = ::close(descriptor) == 0 && written;
  std::error_code error;
  if (written) std::filesystem::rename(temporary, file, error);
  if (!written || error) {
    std::filesystem::remove(temporary, error);
    throw InputError(option + ": cannot write '" + requested.string() + "'" + (written ? "" : " (disk full?)"));
  }
}

void writeFilesTogether(const std::vector<OutputFile>& files) {
  for (const OutputFile& file : files) {
    if (isDeviceOrPipe(file.path)) writeFileReplacing(file.path, file.text, file.option);
  }
  const InterruptionsHeld held;
  for (const OutputFile& file : files) {
    if (!isDeviceOrPipe(file.path)) writeFileReplacing(file.path, file.text, file.option);
  }
}

}  // namespace flexirob::app
