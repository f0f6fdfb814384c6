#include "app/cli/number_list.hpp"

#include <algorithm>
#include <optional>
#include <vector>

#include "app/table_text.hpp"
#include "robot/errors.hpp"

namespace flexirob::cli {

namespace {

/// The text as quoted in an error message: at most 64 characters, elided in the middle.
std::string excerpt(const std::string& text) {
  constexpr std::size_t kMaxQuoted = 64;
  if (text.size() <= kMaxQuoted) return text;
  return text.substr(0, kMaxQuoted / 2) + "..." + text.substr(text.size() - kMaxQuoted / 2) + " (" +
         std::to_string(text.size()) + " characters)";
}

}  // namespace

Eigen::VectorXd parseNumberList(const std::string& text, const std::string& what, std::size_t max_count) {
  std::vector<double> values;
  std::size_t start = 0;
  if (text.empty()) throw InputError(what + ": expected comma-separated numbers, got an empty value");
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    std::string token = text.substr(start, end - start);
    // Allow spaces around entries ("0.1, 0.2"), nothing else.
    const auto first = token.find_first_not_of(" \t");
    const auto last = token.find_last_not_of(" \t");
    token = first == std::string::npos ? std::string() : token.substr(first, last - first + 1);
    if (token.empty()) throw InputError(what + ": empty entry in '" + excerpt(text) + "'");
    const std::optional<double> value = app::parseDecimal(token);
    if (!value) throw InputError(what + ": '" + excerpt(token) + "' is not a finite number");
    values.push_back(*value);
    if (values.size() > max_count) throw InputError(what + ": more than " + std::to_string(max_count) + " entries");
    start = end + 1;
    if (end == text.size()) break;
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

Eigen::VectorXd parseNumberList(const std::string& text, const std::string& what, int count) {
  // Every entry is read, so that the error says how many were given, also when too many were.
  const auto given = static_cast<std::size_t>(std::count(text.begin(), text.end(), ',')) + 1;
  Eigen::VectorXd values = parseNumberList(text, what, given);
  if (values.size() != count) {
    throw InputError(what + ": expected " + std::to_string(count) + " values, got " + std::to_string(values.size()));
  }
  return values;
}

}  // namespace flexirob::cli
