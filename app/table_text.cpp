#include "app/table_text.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "robot/errors.hpp"

namespace flexirob::app {

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

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

std::optional<double> parseDecimal(const std::string& field) {
  if (field.empty() || field.find_first_of("xX") != std::string::npos) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(field.c_str(), &end);
  if (end != field.c_str() + field.size() || errno == ERANGE || !std::isfinite(value)) return std::nullopt;
  return value;
}

void prepareFirstLine(std::string& line, const std::string& file) {
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  if (const std::size_t cr = line.find('\r'); cr != std::string::npos && cr + 1 < line.size()) {
    throw InputError(file + ": lines end in a carriage return alone; expected LF or CRLF line ends");
  }
}

}  // namespace flexirob::app
