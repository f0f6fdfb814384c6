#pragma once
// Every file a command writes as its output (a model, a graph, an export) goes through here, so
// that one rule holds for all of them: a reader never sees half a file, a failed or interrupted
// write leaves what was there, and nothing beside the output is touched.
#include <filesystem>
#include <string>

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

/// Writes `text` to a new temporary file beside `file` (a name of its own, so that no file kept
/// there is overwritten) and renames it into place. Through a symbolic link it writes the file the
/// link names and keeps the link; the file keeps the mode it had, a new one gets the umask's. SIGINT
/// and SIGTERM wait until the temporary is renamed or removed. Throws robot::InputError naming
/// `option` when the file cannot be written.
void writeFileReplacing(const std::filesystem::path& file, const std::string& text, const std::string& option);

}  // namespace flexirob::app
