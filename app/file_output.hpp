#pragma once
// Every file a command writes as its output (a model, a graph, an export) goes through here, so
// that one rule holds for all of them: a reader never sees half a file, a failed or interrupted
// write leaves what was there, and nothing beside the output is touched.
#include <filesystem>
#include <string>
#include <vector>

#include <signal.h>

namespace flexirob::app {

/// Holds SIGINT and SIGTERM back while it lives; one that came meanwhile is delivered when it
/// ends. Around the writing of several outputs that belong together (export's files), so that an
/// interruption leaves all of them or none.
class InterruptionsHeld {
 public:
  InterruptionsHeld();
  ~InterruptionsHeld();
  InterruptionsHeld(const InterruptionsHeld&) = delete;
  InterruptionsHeld& operator=(const InterruptionsHeld&) = delete;

 private:
  sigset_t previous_{};
  bool active_ = false;
};

/// The file a symbolic link (or a chain of them) names, whether it exists yet or not; the path
/// itself where it is no link (or the chain does not end). What writeFileReplacing writes.
std::filesystem::path followLinks(const std::filesystem::path& file);

/// True where `file` (after its links, /proc's to pipes too) exists and is neither a regular file nor a folder: a device
/// or a pipe, such as /dev/stdout into a pipe.
bool isDeviceOrPipe(const std::filesystem::path& file);

/// Writes `text` to a new temporary file beside `file` (a name of its own, so that no file kept
/// there is overwritten) and renames it into place. Through a symbolic link it writes the file the
/// link names and keeps the link; the file keeps the mode it had, a new one gets the umask's. SIGINT
/// and SIGTERM wait until the temporary is renamed or removed. A device or a pipe is written in
/// place, interruptibly. Throws robot::InputError naming `option` when the file cannot be written.
void writeFileReplacing(const std::filesystem::path& file, const std::string& text, const std::string& option);

/// One of several outputs of a command that belong together.
struct OutputFile {
  std::string option;  ///< the command-line option that named it, for messages
  std::filesystem::path path;
  std::string text;
};

/// Writes outputs that belong together (export's files, sweep's tables): devices and pipes first,
/// in place and interruptible, so that a pipe nobody reads cannot hold the process; then the
/// regular files, each through writeFileReplacing and all under one hold of SIGINT and SIGTERM, so
/// that an interruption leaves all of them or none.
void writeFilesTogether(const std::vector<OutputFile>& files);

}  // namespace flexirob::app
