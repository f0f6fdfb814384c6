#include "app/file_output.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <map>
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

std::string sameFileKey(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  const std::filesystem::path key = std::filesystem::weakly_canonical(error ? path : absolute, error).lexically_normal();
  // A chain of links that never ends resolves to nothing: the path as given stands for itself.
  return error || key.empty() ? (error ? path : absolute).lexically_normal().string() : key.string();
}

namespace {

// Linux's terminal devices: the virtual consoles and serial lines (4), /dev/tty and /dev/console
// (5), pseudo-terminals (136-143).
bool isTerminal(dev_t device) {
  const unsigned int kind = major(device);
  return kind == 4 || kind == 5 || (kind >= 136 && kind <= 143);
}

bool isNull(const struct stat& status) {
  struct stat null {};
  return S_ISCHR(status.st_mode) && ::stat("/dev/null", &null) == 0 && status.st_rdev == null.st_rdev;
}

}  // namespace

bool writtenInPlace(const std::filesystem::path& file) {
  struct stat status {};
  if (::stat(file.c_str(), &status) != 0) return false;
  // Other character devices (memory, raw flash, a tape) are nothing to write a model over.
  return S_ISFIFO(status.st_mode) || isNull(status) || (S_ISCHR(status.st_mode) && isTerminal(status.st_rdev));
}

bool isExistingFile(const std::filesystem::path& output, const std::filesystem::path& input) {
  std::error_code error;
  return !output.empty() && !input.empty() && std::filesystem::exists(output, error) && std::filesystem::equivalent(input, output, error);
}

bool isNullDevice(const std::filesystem::path& file) {
  struct stat output {};
  return ::stat(file.c_str(), &output) == 0 && isNull(output);
}

void refuseStandardStreams(const std::string& option, const std::filesystem::path& file) {
  struct stat output {};
  if (::stat(file.c_str(), &output) != 0 || isNull(output)) return;
  for (const auto& [descriptor, name] : {std::pair{STDOUT_FILENO, "standard output"}, std::pair{STDERR_FILENO, "standard error"}}) {
    struct stat stream {};
    if (::fstat(descriptor, &stream) != 0) continue;
    const bool same_file = stream.st_dev == output.st_dev && stream.st_ino == output.st_ino;
    // Another node of the same device, or /dev/tty: the terminal the stream shows on.
    const bool same_terminal = S_ISCHR(output.st_mode) && isTerminal(output.st_rdev) && ::isatty(descriptor) == 1 &&
                               (output.st_rdev == stream.st_rdev || output.st_rdev == makedev(5, 0));
    if (same_file || same_terminal) {
      throw InputError(option + ": '" + file.string() + "' is where " + name + " goes" +
                       (descriptor == STDOUT_FILENO ? ", which carries the command's JSON" : "") + "; give another file");
    }
  }
}

namespace {

// The reason of the first failure, or empty.
std::string writeAll(int descriptor, const std::string& text) {
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(descriptor, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::strerror(errno);
    if (n == 0) return "nothing more could be written";
    done += static_cast<std::size_t>(n);
  }
  return "";
}

// Closes the descriptor; the reason it failed, `earlier` first.
std::string closeReporting(int descriptor, std::string earlier) {
  if (::close(descriptor) != 0 && earlier.empty()) earlier = std::strerror(errno);
  return earlier;
}

}  // namespace

void writeFileReplacing(const std::filesystem::path& requested, const std::string& text, const std::string& option) {
  refuseStandardStreams(option, requested);
  const auto failed = [&](const std::string& reason) {
    return InputError(option + ": cannot write '" + requested.string() + "': " + reason);
  };
  // stat and open follow /proc's links to pipes, which followLinks cannot name.
  if (writtenInPlace(requested)) {
    // Renaming over a pipe or a device would put a regular file in its place; it is written as
    // it is, and not held: a pipe nobody reads must stay interruptible.
    const int descriptor = ::open(requested.c_str(), O_WRONLY | O_CLOEXEC);
    if (descriptor < 0) throw failed(std::strerror(errno));
    if (const std::string reason = closeReporting(descriptor, writeAll(descriptor, text)); !reason.empty()) throw failed(reason);
    return;
  }
  // Renamed over, a block device or a socket would be replaced by a regular file.
  if (struct stat status {}; ::stat(requested.c_str(), &status) == 0 && !S_ISREG(status.st_mode) && !S_ISDIR(status.st_mode)) {
    throw InputError(option + ": '" + requested.string() + "' is not a regular file (a device other than a terminal or /dev/null, or a socket)");
  }
  const std::filesystem::path file = followLinks(requested);
  const InterruptionsHeld held;
  // A temporary of its own (mkstemp) beside the file: a fixed name such as "<file>.tmp" could be
  // another output of the same run, or a file someone keeps.
  std::string temporary = file.string() + ".XXXXXX";
  const int descriptor = ::mkstemp(temporary.data());
  if (descriptor < 0) throw failed(std::strerror(errno));
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
  std::string reason = ::fchmod(descriptor, mode) == 0 ? writeAll(descriptor, text) : std::strerror(errno);
  reason = closeReporting(descriptor, reason);
  std::error_code error;
  if (reason.empty()) {
    std::filesystem::rename(temporary, file, error);
    if (error) reason = error.message();
  }
  if (!reason.empty()) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw failed(reason);
  }
}

void writeFilesTogether(const std::vector<OutputFile>& files) {
  // Before any is written: where standard output goes, and two outputs naming one file (the
  // second would replace the first, which the command still reports as written).
  std::map<std::string, std::string> named;
  for (const OutputFile& file : files) {
    refuseStandardStreams(file.option, file.path);
    if (isNullDevice(file.path)) continue;
    if (const auto [where, added] = named.emplace(sameFileKey(file.path), file.option); !added) {
      throw InputError(file.option + ": '" + file.path.string() + "' is the file " + where->second +
                       " names; give each output its own file");
    }
  }
  for (const OutputFile& file : files) {
    if (writtenInPlace(file.path)) writeFileReplacing(file.path, file.text, file.option);
  }
  const InterruptionsHeld held;
  for (const OutputFile& file : files) {
    if (!writtenInPlace(file.path)) writeFileReplacing(file.path, file.text, file.option);
  }
}

}  // namespace flexirob::app
