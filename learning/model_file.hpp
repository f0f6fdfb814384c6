#pragma once
// The learners' own model file format: a small, versioned, self-describing text format.
//
//   flexirob-model <version>
//   learner <kind>
//   <key> <value>                 (hyper-parameters, dimensions, seed, ...)
//   matrix <name> <rows> <cols>
//   <rows lines of cols numbers>  (shortest round-trip decimal, so values survive exactly)
//   checksum <16 hex digits>      (FNV-1a 64 of every byte before this line)
//
// Readers check the magic word and version first, sizes against fixed limits before
// allocating, every number for finiteness and the checksum last, so that a truncated,
// corrupted or foreign file is refused with a one-line reason instead of yielding a
// silently wrong model.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace flexirob::learning {

/// A model file that cannot be read, is damaged, or does not fit what the caller expects.
class ModelFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kModelFileVersion = 1;
/// Limits checked before any allocation (a corrupted size must not allocate gigabytes).
inline constexpr std::int64_t kMaxModelMatrixEntries = 64LL * 1024 * 1024;
inline constexpr std::uintmax_t kMaxModelFileBytes = 1024ULL * 1024 * 1024;

/// Collects the fields of one model and writes them in order.
class ModelWriter {
 public:
  explicit ModelWriter(std::string learner_kind);
  void set(const std::string& key, const std::string& value);
  void set(const std::string& key, double value);
  void set(const std::string& key, std::int64_t value);
  void set(const std::string& key, int value) { set(key, static_cast<std::int64_t>(value)); }
  void setMatrix(const std::string& name, const Eigen::MatrixXd& matrix);
  /// The complete file content including the checksum line (the application writes it to a
  /// file; this library reads files but never writes them).
  std::string text() const;

 private:
  std::string body_;
};

/// Parses and validates a complete model file; typed access throws ModelFileError naming the
/// file and the field.
class ModelReader {
 public:
  /// Parses `content`; `origin` names the source in error messages.
  ModelReader(const std::string& content, std::string origin);
  static ModelReader fromFile(const std::filesystem::path& file);

  const std::string& learnerKind() const { return kind_; }
  int version() const { return version_; }
  const std::string& origin() const { return origin_; }

  bool has(const std::string& key) const { return values_.count(key) != 0; }
  std::string text(const std::string& key) const;
  double number(const std::string& key) const;
  /// An integer in [min_value, max_value].
  std::int64_t integer(const std::string& key, std::int64_t min_value, std::int64_t max_value) const;
  /// An unsigned 64-bit integer (seeds).
  std::uint64_t unsignedInteger(const std::string& key) const;
  /// A matrix of exactly rows x cols (a negative expectation means "any").
  const Eigen::MatrixXd& matrix(const std::string& name, Eigen::Index rows, Eigen::Index cols) const;

  /// Throws unless the file holds a model of `kind`.
  void expectKind(const std::string& kind) const;
  [[noreturn]] void fail(const std::string& reason) const;

 private:
  std::string origin_;
  std::string kind_;
  int version_ = 0;
  std::map<std::string, std::string> values_;
  std::map<std::string, Eigen::MatrixXd> matrices_;
};

/// FNV-1a 64-bit hash.
std::uint64_t fnv1a64(const char* data, std::size_t size);

}  // namespace flexirob::learning
