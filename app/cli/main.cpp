#include <signal.h>
#include <unistd.h>

#include <cstring>

#include "app/cli/cli_support.hpp"

namespace {

// A command stopped by SIGINT or SIGTERM says so in one line and still ends by the signal (exit
// status 128 + n for the shell). Files are written through temporaries that hold these signals
// back (app/file_output.hpp), so what it says holds: what was written is whole, what was not is
// as it was. A pipe or a device is written in place and stays interruptible (one nobody reads
// would hold the command): its reader may have got part of an output. teach installs its own
// handler, which stops the tutor and closes the session.
void sayStoppedAndEnd(int signal_number) {
  const char* text = signal_number == SIGTERM
                         ? "flexirob-cli: stopped by SIGTERM; files not written yet are as they were\n"
                         : "flexirob-cli: stopped by SIGINT; files not written yet are as they were\n";
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, text, std::strlen(text));
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

void sayWhenStopped() {
  for (const int signal_number : {SIGINT, SIGTERM}) {
    // A signal the caller ignores (a job started in the background) stays ignored.
    if (::signal(signal_number, sayStoppedAndEnd) == SIG_IGN) ::signal(signal_number, SIG_IGN);
  }
}

}  // namespace

int main(int argc, char** argv) {
  sayWhenStopped();
  // A pipe whose reader went away (an output into a named pipe, the JSON into `| head`) is a
  // write error with a reason (EPIPE), not a silent death by SIGPIPE.
  ::signal(SIGPIPE, SIG_IGN);
  return flexirob::cli::runCli(argc, argv);
}
