#pragma once
// The session database's schema (version 2, documented in docs/SESSIONS.md) and a thin RAII
// layer over the SQLite C API shared by the recorder and the reader.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace flexirob::app {

/// PRAGMA application_id of every session database: "FIRB" in ASCII.
inline constexpr std::int32_t kSessionApplicationId = 0x46495242;
/// PRAGMA user_version and meta.schema_version of the schema this build writes, and the
/// newest it reads (it reads every older one). Version 2 added area.name.
inline constexpr int kSessionSchemaVersion = 2;
/// meta.format of every session database.
inline constexpr std::string_view kSessionFormatName = "flexirob-session";

/// The CREATE statements of the schema kSessionSchemaVersion (tables and indices), as one SQL script.
const char* sessionSchemaSql();
/// Tables a readable session must have.
const std::vector<std::string>& requiredSessionTables();

/// Whether `file` is a session database (SQLite with kSessionApplicationId), judged by its
/// header alone; false for anything that cannot be read.
bool isSessionDatabase(const std::filesystem::path& file);

/// An SQLite error: `what()` is "<context>: <sqlite message>"; code() the primary result code.
class SqliteError : public std::runtime_error {
 public:
  SqliteError(const std::string& what, int code) : std::runtime_error(what), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};

/// An open connection. Closing happens in the destructor.
class SqliteDatabase {
 public:
  SqliteDatabase() = default;
  /// sqlite3_open_v2 with `flags`; throws SqliteError.
  SqliteDatabase(const std::string& path, int flags);
  ~SqliteDatabase();
  SqliteDatabase(SqliteDatabase&& other) noexcept;
  SqliteDatabase& operator=(SqliteDatabase&& other) noexcept;
  SqliteDatabase(const SqliteDatabase&) = delete;
  SqliteDatabase& operator=(const SqliteDatabase&) = delete;

  sqlite3* handle() const { return db_; }
  bool isOpen() const { return db_ != nullptr; }
  void close();
  /// Runs one or more statements without results; throws SqliteError naming `context`.
  void exec(const std::string& sql, const std::string& context = "sql");
  /// Runs a statement returning one integer (e.g. a PRAGMA); throws SqliteError.
  std::int64_t queryInt(const std::string& sql);
  std::string queryText(const std::string& sql);
  /// Throws SqliteError(context + ": " + sqlite3_errmsg) for a result code other than ok.
  void check(int rc, const std::string& context) const;

 private:
  sqlite3* db_ = nullptr;
};

/// A prepared statement with positional binding (1-based, as SQLite) and 0-based columns.
class SqliteStatement {
 public:
  SqliteStatement() = default;
  SqliteStatement(const SqliteDatabase& db, const std::string& sql);
  ~SqliteStatement();
  SqliteStatement(SqliteStatement&& other) noexcept;
  SqliteStatement& operator=(SqliteStatement&& other) noexcept;
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  SqliteStatement& bind(int index, double value);
  SqliteStatement& bind(int index, std::int64_t value);
  SqliteStatement& bind(int index, int value) { return bind(index, static_cast<std::int64_t>(value)); }
  SqliteStatement& bind(int index, const std::string& value);
  SqliteStatement& bindBlob(int index, const void* data, std::size_t bytes);
  SqliteStatement& bindNull(int index);
  /// True while a row is available; throws SqliteError on failure.
  bool step();
  /// step() for statements without a result, then reset().
  void run();
  void reset();

  double columnDouble(int column) const;
  std::int64_t columnInt(int column) const;
  std::string columnText(int column) const;
  std::vector<std::uint8_t> columnBlob(int column) const;
  /// A blob of little-endian float64 values; throws SqliteError if its size is not a multiple of 8.
  Eigen::VectorXd columnDoubles(int column) const;
  bool columnIsNull(int column) const;

 private:
  const SqliteDatabase* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

/// Float64 arrays as blobs: the host's byte order, which the schema fixes to little-endian
/// (every platform FlexIRob builds on).
std::vector<std::uint8_t> doublesToBlob(const double* values, std::size_t count);

}  // namespace flexirob::app
