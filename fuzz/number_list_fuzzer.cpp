// Fuzz target: numeric lists typed on the command line (--q 0.1,0.2,... and the like). Either
// an InputError with a short one-line message, or at most max_count finite numbers.
#include <cstddef>
#include <cstdint>
#include <string>

#include "app/cli/number_list.hpp"
#include "fuzz/fuzz_support.hpp"
#include "robot/errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  constexpr std::size_t kMaxCount = 64;
  try {
    const Eigen::VectorXd values = flexirob::cli::parseNumberList(text, "--q", kMaxCount);
    if (values.size() < 1 || static_cast<std::size_t>(values.size()) > kMaxCount) {
      flexirob::fuzz::invariantBroken("entry count outside [1, max_count]");
    }
    if (!values.allFinite()) flexirob::fuzz::invariantBroken("non-finite value accepted");
  } catch (const flexirob::InputError& e) {
    const std::string message = e.what();
    if (message.find('\n') != std::string::npos && text.find('\n') == std::string::npos) {
      flexirob::fuzz::invariantBroken("multi-line message");
    }
    if (message.size() > 512) flexirob::fuzz::invariantBroken("error message longer than 512 characters");
  }
  return 0;
}
