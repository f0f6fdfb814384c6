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

/// The file a path names, spelt one way ("./a.csv", "a.csv" and "dir/../a.csv" alike), whether
/// it exists yet or not: compare two of these to see whether two paths name one file.
std::string sameFileKey(const std::filesystem::path& path);

/// True where `file` (after its links, /proc's to pipes too) is a pipe, the null device or a
/// terminal: written in place. Other devices and sockets are no output at all (checkOutputPath
/// refuses them).
bool writtenInPlace(const std::filesystem::path& file);

/// True where `output` already exists and is the file `input` names (through links, or by
/// another spelling): writing it would replace what a run reads.
bool isExistingFile(const std::filesystem::path& output, const std::filesystem::path& input);

/// True where `file` is the null device (/dev/null): it takes any number of outputs.
bool isNullDevice(const std::filesystem::path& file);

/// Throws robot::InputError naming `option` where `file` is what standard output or standard error
/// goes to (`--out /dev/stdout`, `--out f > f`, /dev/tty on the terminal they show on), the null
/// device aside: the command's JSON or its messages would go into the output, or, renamed over,
/// nowhere.
void refuseStandardStreams(const std::string& option, const std::filesystem::path& file);

/// Writes `text` to a new temporary file beside `file` (a name of its own, so that no file kept
/// there is overwritten) and renames it into place. Through a symbolic link it writes the file the
/// link names and keeps the link; the file keeps the mode it had, a new one gets the umask's. SIGINT
/// and SIGTERM wait until the temporary is renamed or removed. A pipe or a character device is
/// written in place, interruptibly (writtenInPlace). Refuses the file standard output or error
/// goes to (refuseStandardStreams). Throws robot::InputError naming `option` and the reason when
/// the file cannot be written.
void writeFileReplacing(const std::filesystem::path& file, const std::string& text, const std::string& option);

/// One of several outputs of a command that belong together.
struct OutputFile {
  std::string option;  ///< the command-line option that named it, for messages
  std::filesystem::path path;
  std::string text;
};

/// Writes outputs that belong together (export's files, sweep's tables, a study's CSV files and
/// plot): pipes and character devices first,
/// in place and interruptible, so that a pipe nobody reads cannot hold the process; then the
/// regular files, each through writeFileReplacing and all under one hold of SIGINT and SIGTERM, so
/// that an interruption leaves all of them or none.
void writeFilesTogether(const std::vector<OutputFile>& files);

}  // namespace flexirob::app
