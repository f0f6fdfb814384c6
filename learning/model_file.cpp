#include "learning/model_file.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <system_error>

namespace flexirob::learning {
namespace {

constexpr const char* kMagic = "flexirob-model";

std::string formatDouble(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string hex64(std::uint64_t value) {
  char buffer[17];
  std::snprintf(buffer, sizeof(buffer), "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

bool validName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

// Splits "a b  c" at single spaces (no empty tokens allowed in a well-formed file).
std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (start <= line.size()) {
    const std::size_t end = std::min(line.find(' ', start), line.size());
    out.push_back(line.substr(start, end - start));
    if (end == line.size()) break;
    start = end + 1;
  }
  return out;
}

bool parseDouble(std::string_view token, double& value) {
  if (token.empty()) return false;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size() && std::isfinite(value);
}

bool parseInt(std::string_view token, std::int64_t& value) {
  if (token.empty()) return false;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

}  // namespace

std::uint64_t fnv1a64(const char* data, std::size_t size) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

// ---------------------------------------------------------------------------------------------
ModelWriter::ModelWriter(std::string learner_kind) {
  if (!validName(learner_kind)) throw std::invalid_argument("model writer: invalid learner kind '" + learner_kind + "'");
  body_ = std::string(kMagic) + " " + std::to_string(kModelFileVersion) + "\n";
  body_ += "learner " + learner_kind + "\n";
}

void ModelWriter::set(const std::string& key, const std::string& value) {
  if (!validName(key) || key == "matrix" || key == "checksum" || key == "learner") {
    throw std::invalid_argument("model writer: invalid key '" + key + "'");
  }
  if (value.empty() || value.find('\n') != std::string::npos || value.find('\r') != std::string::npos) {
    throw std::invalid_argument("model writer: value of '" + key + "' must be one non-empty line");
  }
  body_ += key + " " + value + "\n";
}

void ModelWriter::set(const std::string& key, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument("model writer: '" + key + "' is not finite");
  set(key, formatDouble(value));
}

void ModelWriter::set(const std::string& key, std::int64_t value) { set(key, std::to_string(value)); }

void ModelWriter::setMatrix(const std::string& name, const Eigen::MatrixXd& matrix) {
  if (!validName(name)) throw std::invalid_argument("model writer: invalid matrix name '" + name + "'");
  if (!matrix.allFinite()) throw std::invalid_argument("model writer: matrix '" + name + "' has non-finite entries");
  body_ += "matrix " + name + " " + std::to_string(matrix.rows()) + " " + std::to_string(matrix.cols()) + "\n";
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) {
      if (c > 0) body_ += ' ';
      body_ += formatDouble(matrix(r, c));
    }
    body_ += '\n';
  }
}

std::string ModelWriter::text() const {
  return body_ + "checksum " + hex64(fnv1a64(body_.data(), body_.size())) + "\n";
}

// ---------------------------------------------------------------------------------------------
ModelReader ModelReader::fromFile(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) {
    throw ModelFileError("model file '" + file.string() + "' does not exist or is not a regular file");
  }
  const auto size = std::filesystem::file_size(file, error);
  if (error) throw ModelFileError("cannot read model file '" + file.string() + "'");
  if (size > kMaxModelFileBytes) throw ModelFileError("model file '" + file.string() + "' is too large");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ModelFileError("cannot open model file '" + file.string() + "'");
  std::string content(static_cast<std::size_t>(size), '\0');
  in.read(content.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) throw ModelFileError("cannot read model file '" + file.string() + "'");
  return ModelReader(content, file.string());
}

void ModelReader::fail(const std::string& reason) const {
  throw ModelFileError("model file '" + origin_ + "': " + reason);
}

ModelReader::ModelReader(const std::string& content, std::string origin) : origin_(std::move(origin)) {
  // 1. Magic word and version, so that a foreign file is named as such.
  const std::string magic_prefix = std::string(kMagic) + " ";
  if (content.compare(0, magic_prefix.size(), magic_prefix) != 0) fail("not a FlexIRob model file (missing 'flexirob-model' header)");
  const std::size_t first_end = content.find('\n');
  if (first_end == std::string::npos) fail("truncated after the header");
  std::int64_t version = 0;
  if (!parseInt(std::string_view(content).substr(magic_prefix.size(), first_end - magic_prefix.size()), version)) {
    fail("unreadable format version");
  }
  if (version < 1 || version > kModelFileVersion) {
    fail("format version " + std::to_string(version) + " is not supported (this program reads version " +
         std::to_string(kModelFileVersion) + ")");
  }
  version_ = static_cast<int>(version);

  // 2. Checksum: the last line must be "checksum <hex>" over every byte before it.
  if (content.empty() || content.back() != '\n') fail("truncated (the file does not end with its checksum line)");
  const std::size_t last_start = content.rfind('\n', content.size() - 2) + 1;
  const std::string_view last_line = std::string_view(content).substr(last_start, content.size() - 1 - last_start);
  if (last_line.substr(0, 9) != "checksum ") fail("truncated (no checksum line at the end)");
  if (std::string(last_line.substr(9)) != hex64(fnv1a64(content.data(), last_start))) {
    fail("checksum mismatch: the file is corrupted or was edited");
  }

  // 3. Fields and matrices.
  const std::string_view body = std::string_view(content).substr(first_end + 1, last_start - first_end - 1);
  std::size_t position = 0;
  std::size_t line_number = 1;
  const auto nextLine = [&](std::string_view& line) {
    if (position >= body.size()) return false;
    const std::size_t end = body.find('\n', position);
    line = body.substr(position, end - position);
    position = end + 1;
    ++line_number;
    return true;
  };
  std::string_view line;
  while (nextLine(line)) {
    const auto parts = tokens(line);
    const std::string key(parts[0]);
    if (key == "matrix") {
      std::int64_t rows = 0, cols = 0;
      if (parts.size() != 4 || !validName(std::string(parts[1])) || !parseInt(parts[2], rows) || !parseInt(parts[3], cols)) {
        fail("malformed matrix header on line " + std::to_string(line_number));
      }
      const std::string name(parts[1]);
      if (rows < 0 || cols < 0 || rows > kMaxModelMatrixEntries || cols > kMaxModelMatrixEntries ||
          rows * cols > kMaxModelMatrixEntries) {
        fail("matrix '" + name + "' has an implausible size " + std::to_string(rows) + " x " + std::to_string(cols));
      }
      // Each entry takes at least two bytes ("0 "), so a size the rest of the file cannot hold
      // is refused before allocating.
      if (static_cast<std::size_t>(rows * cols) > (body.size() - std::min(position, body.size())) / 2 + 1) {
        fail("matrix '" + name + "' claims more entries than the file holds");
      }
      if (matrices_.count(name) != 0) fail("matrix '" + name + "' appears twice");
      Eigen::MatrixXd matrix(rows, cols);
      for (std::int64_t r = 0; r < rows; ++r) {
        std::string_view row_line;
        if (!nextLine(row_line)) fail("matrix '" + name + "' is truncated");
        const auto values = tokens(row_line);
        if (static_cast<std::int64_t>(values.size()) != cols && !(cols == 0 && values.size() == 1 && values[0].empty())) {
          fail("matrix '" + name + "' row " + std::to_string(r) + ": expected " + std::to_string(cols) + " numbers, got " +
               std::to_string(values.size()));
        }
        for (std::int64_t c = 0; c < cols; ++c) {
          double value = 0.0;
          if (!parseDouble(values[static_cast<std::size_t>(c)], value)) {
            fail("matrix '" + name + "' row " + std::to_string(r) + ": '" + std::string(values[static_cast<std::size_t>(c)]) +
                 "' is not a finite number");
          }
          matrix(r, c) = value;
        }
      }
      matrices_.emplace(name, std::move(matrix));
    } else {
      if (parts.size() < 2 || !validName(key)) fail("malformed line " + std::to_string(line_number));
      const std::string value(line.substr(key.size() + 1));
      if (value.empty()) fail("empty value for '" + key + "'");
      if (!values_.emplace(key, value).second) fail("field '" + key + "' appears twice");
    }
  }
  if (!has("learner")) fail("missing field 'learner'");
  kind_ = values_.at("learner");
}

std::string ModelReader::text(const std::string& key) const {
  const auto it = values_.find(key);
  if (it == values_.end()) fail("missing field '" + key + "'");
  return it->second;
}

double ModelReader::number(const std::string& key) const {
  double value = 0.0;
  if (!parseDouble(text(key), value)) fail("field '" + key + "' is not a finite number");
  return value;
}

std::int64_t ModelReader::integer(const std::string& key, std::int64_t min_value, std::int64_t max_value) const {
  std::int64_t value = 0;
  if (!parseInt(text(key), value)) fail("field '" + key + "' is not an integer");
  if (value < min_value || value > max_value) {
    fail("field '" + key + "' = " + std::to_string(value) + " is outside [" + std::to_string(min_value) + ", " +
         std::to_string(max_value) + "]");
  }
  return value;
}

std::uint64_t ModelReader::unsignedInteger(const std::string& key) const {
  const std::string value = text(key);
  std::uint64_t parsed = 0;
  const auto result = std::from_chars(value.data(), value.data() + value.size(), parsed);
  if (result.ec != std::errc() || result.ptr != value.data() + value.size()) fail("field '" + key + "' is not an unsigned integer");
  return parsed;
}

const Eigen::MatrixXd& ModelReader::matrix(const std::string& name, Eigen::Index rows, Eigen::Index cols) const {
  const auto it = matrices_.find(name);
  if (it == matrices_.end()) fail("missing matrix '" + name + "'");
  const Eigen::MatrixXd& m = it->second;
  if ((rows >= 0 && m.rows() != rows) || (cols >= 0 && m.cols() != cols)) {
    fail("matrix '" + name + "' is " + std::to_string(m.rows()) + " x " + std::to_string(m.cols()) + ", expected " +
         (rows >= 0 ? std::to_string(rows) : std::string("any")) + " x " + (cols >= 0 ? std::to_string(cols) : std::string("any")));
  }
  return m;
}

void ModelReader::expectKind(const std::string& kind) const {
  if (kind_ != kind) fail("holds a '" + kind_ + "' model, expected '" + kind + "'");
}

}  // namespace flexirob::learning
