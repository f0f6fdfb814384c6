#pragma once
// Errors that stem from the user's input (files, command-line values). Programs report them
// as a one-line message and exit code 2; they are never a crash.
#include <stdexcept>
#include <string>

namespace flexirob {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace flexirob
