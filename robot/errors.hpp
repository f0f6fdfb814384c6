#pragma once
// Errors that stem from the user's input (files, command-line values). Programs report them
// as a one-line message and exit code 2; they are never a crash.
#include <cstddef>
#include <stdexcept>
#include <string>

namespace flexirob {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Text taken from an input file as a single line for a message: control characters replaced,
/// long text cut, so a hostile file cannot flood or split the one-line error.
inline std::string printable(const std::string& text, std::size_t max_length = 60) {
  std::string out;
  for (const char c : text) {
    if (out.size() >= max_length) {
      out += "...";
      break;
    }
    const auto byte = static_cast<unsigned char>(c);
    out += (byte < 0x20 || byte == 0x7F) ? '?' : c;
  }
  return out;
}

}  // namespace flexirob
