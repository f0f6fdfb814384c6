#pragma once
// Errors that stem from the user's input (files, command-line values). Programs report them
// as a one-line message and exit code 2; they are never a crash.
#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

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

/// A number from the user's input as a message shows it: six significant digits at most, so a
/// value such as 1e300 reads "1e+300" rather than its 300 digits.
inline std::string printableNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

/// The name among `names` that `given` most likely meant, for "did you mean ...?" in a one-line
/// error: the one `given` is the start of, else the nearest by edit distance (letters inserted,
/// dropped or changed) if at most `max_slip` edits away; "" where none is, or where two are
/// equally likely (no guess between kappa_x and kappa_q).
inline std::string closestName(const std::string& given, const std::vector<std::string>& names, std::size_t max_slip) {
  std::string started;
  int starts = 0;
  for (const std::string& name : names) {
    if (name == given) return name;
    if (!given.empty() && name.rfind(given, 0) == 0) {
      started = name;
      ++starts;
    }
  }
  if (starts == 1) return started;
  if (starts > 1) return "";
  std::string closest;
  std::size_t closest_distance = std::numeric_limits<std::size_t>::max();
  bool tied = false;
  std::vector<std::size_t> row;
  for (const std::string& name : names) {
    row.resize(name.size() + 1);
    for (std::size_t j = 0; j <= name.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= given.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= name.size(); ++j) {
        const std::size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (given[i - 1] == name[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    if (row[name.size()] < closest_distance) {
      closest_distance = row[name.size()];
      closest = name;
      tied = false;
    } else if (row[name.size()] == closest_distance) {
      tied = true;
    }
  }
  return closest_distance <= max_slip && !tied ? closest : std::string();
}

}  // namespace flexirob
