#include "app/table_text.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

#include "robot/errors.hpp"

namespace flexirob::app {

std::string_view trimmedView(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::string trimmed(const std::string& text) { return std::string(trimmedView(text)); }

std::vector<std::string> splitCommaFields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = line.find(',', start);
    fields.push_back(trimmed(line.substr(start, end == std::string::npos ? std::string::npos : end - start)));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return fields;
}

std::string lowercase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::optional<double> parseDecimal(std::string_view field) {
  // from_chars reads no sign '+' (strtod did, and "+7" stays a number), no hexadecimal in its
  // general format, and needs no terminating NUL: the ITM stream parses its lines in place.
  if (!field.empty() && field.front() == '+') {
    field.remove_prefix(1);
    if (!field.empty() && field.front() == '-') return std::nullopt;  // "+-5"
  }
  if (field.empty()) return std::nullopt;
  double value = 0.0;
  const char* const end = field.data() + field.size();
  const auto [stop, error] = std::from_chars(field.data(), end, value, std::chars_format::general);
  if (stop != end) return std::nullopt;
  if (error == std::errc::result_out_of_range) {
    // Beyond the largest double is no number here; below the smallest, zero.
    const auto exponent = field.find_first_of("eE");
    const bool tiny = exponent != std::string_view::npos && exponent + 1 < field.size() && field[exponent + 1] == '-';
    if (!tiny) return std::nullopt;
    return field.front() == '-' ? -0.0 : 0.0;
  }
  if (error != std::errc() || !std::isfinite(value)) return std::nullopt;
  return value;
}

void prepareFirstLine(std::string& line, const std::string& file) {
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  if (const std::size_t cr = line.find('\r'); cr != std::string::npos && cr + 1 < line.size()) {
    throw InputError(file + ": lines end in a carriage return alone; expected LF or CRLF line ends");
  }
}

}  // namespace flexirob::app
