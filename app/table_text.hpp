#pragma once
// Reading the comma-separated tables people hand the tools (learning data, ITM sample streams,
// cluster seeds) and the number lists they type: one set of rules for all of them, so that a
// value one reader refuses is refused by every other.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace flexirob::app {

/// Values of a table beyond this magnitude are a mistake (positions in metres, joint values
/// in radians or metres), and their squares would overflow the learners' sums.
inline constexpr double kLargestTableValue = 1e6;

/// The text without leading and trailing spaces, tabs and carriage returns.
std::string trimmed(const std::string& text);
std::string_view trimmedView(std::string_view text);

/// The comma-separated fields of a line, each trimmed; "a," gives two fields, the second empty.
std::vector<std::string> splitCommaFields(const std::string& line);

std::string lowercase(std::string text);

/// The whole field read as a decimal number; nothing for anything else: an empty field, text
/// after the number, hexadecimal (which strtod would read, and the scene reader refuses), a
/// value beyond the range of a double, inf and nan. A value too small for a double reads as
/// zero of its sign (1e-400 is a number, only not one a double holds).
std::optional<double> parseDecimal(std::string_view field);

/// Prepares the first line of a table read from `file`: a spreadsheet's UTF-8 byte order mark
/// is no part of the first column's name; carriage returns alone as line ends (classic Mac
/// files) would read as one long header line, and are refused with an InputError.
void prepareFirstLine(std::string& line, const std::string& file);

}  // namespace flexirob::app
