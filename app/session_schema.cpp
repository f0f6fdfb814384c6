#include "app/session_schema.hpp"

#include <sqlite3.h>

#include <array>
#include <bit>
#include <cstring>
#include <fstream>

namespace flexirob::app {

static_assert(std::endian::native == std::endian::little,
              "session blobs are little-endian float64; a big-endian build must byte-swap");

const char* sessionSchemaSql() {
  // Times are session seconds (REAL). Vectors are blobs of little-endian float64.
  return R"sql(
CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE state(
  id INTEGER PRIMARY KEY,
  t REAL NOT NULL,
  dof INTEGER NOT NULL,
  q BLOB NOT NULL,
  q_cmd BLOB NOT NULL,
  tau_ext BLOB NOT NULL,
  p_WT BLOB NOT NULL,
  quat_WT BLOB NOT NULL);
CREATE INDEX state_t ON state(t);
CREATE TABLE stage(id INTEGER PRIMARY KEY, t REAL NOT NULL, stage TEXT NOT NULL,
                   sub_stage TEXT NOT NULL);
CREATE TABLE signal(id INTEGER PRIMARY KEY, t REAL NOT NULL,
                    kind TEXT NOT NULL CHECK(kind IN ('trigger', 'button')), name TEXT NOT NULL);
CREATE TABLE area(id INTEGER PRIMARY KEY, area INTEGER NOT NULL, t REAL NOT NULL,
                  x_init BLOB NOT NULL, q_fixed BLOB NOT NULL, name TEXT NOT NULL DEFAULT '');
CREATE TABLE sample(id INTEGER PRIMARY KEY, t REAL NOT NULL, area INTEGER NOT NULL,
                    x BLOB NOT NULL, q BLOB NOT NULL);
CREATE INDEX sample_area ON sample(area);
CREATE TABLE model(id INTEGER PRIMARY KEY, t REAL NOT NULL, learner TEXT NOT NULL,
                   samples INTEGER NOT NULL, train_seconds REAL NOT NULL, bytes BLOB NOT NULL);
CREATE TABLE itm(id INTEGER PRIMARY KEY, t REAL NOT NULL, nodes INTEGER NOT NULL,
                 edges INTEGER NOT NULL, bytes BLOB NOT NULL);
CREATE TABLE trajectory(
  id INTEGER PRIMARY KEY,
  kind TEXT NOT NULL CHECK(kind IN ('teach_in', 'target', 'executed')),
  name TEXT NOT NULL,
  reference_id INTEGER,
  t_start REAL,
  t_end REAL,
  points INTEGER NOT NULL,
  dof INTEGER NOT NULL,
  times BLOB NOT NULL,
  positions BLOB NOT NULL,
  postures BLOB NOT NULL,
  outcome TEXT NOT NULL);
CREATE TABLE collision(id INTEGER PRIMARY KEY, t REAL NOT NULL, body_a TEXT NOT NULL,
                       body_b TEXT NOT NULL, depth REAL NOT NULL, p_W BLOB NOT NULL);
CREATE INDEX collision_t ON collision(t);
)sql";
}

const std::vector<std::string>& requiredSessionTables() {
  static const std::vector<std::string> tables{"meta",  "state", "stage",      "signal",
                                               "area",  "sample", "model",     "itm",
                                               "trajectory", "collision"};
  return tables;
}

// ---------------------------------------------------------------------------------------------

SqliteDatabase::SqliteDatabase(const std::string& path, int flags) {
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    close();
    throw SqliteError("cannot open " + path + ": " + message, rc);
  }
  sqlite3_extended_result_codes(db_, 0);
  sqlite3_busy_timeout(db_, 2000);
}

SqliteDatabase::~SqliteDatabase() { close(); }

SqliteDatabase::SqliteDatabase(SqliteDatabase&& other) noexcept : db_(other.db_) { other.db_ = nullptr; }

SqliteDatabase& SqliteDatabase::operator=(SqliteDatabase&& other) noexcept {
  if (this != &other) {
    close();
    db_ = other.db_;
    other.db_ = nullptr;
  }
  return *this;
}

void SqliteDatabase::close() {
  if (db_) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
  }
}

void SqliteDatabase::check(int rc, const std::string& context) const {
  if (rc == SQLITE_OK || rc == SQLITE_ROW || rc == SQLITE_DONE) return;
  throw SqliteError(context + ": " + (db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc)), rc & 0xff);
}

void SqliteDatabase::exec(const std::string& sql, const std::string& context) {
  char* message = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message);
  if (rc != SQLITE_OK) {
    std::string text = message ? message : sqlite3_errstr(rc);
    sqlite3_free(message);
    throw SqliteError(context + ": " + text, rc & 0xff);
  }
}

std::int64_t SqliteDatabase::queryInt(const std::string& sql) {
  SqliteStatement statement(*this, sql);
  if (!statement.step()) throw SqliteError(sql + ": no result", SQLITE_ERROR);
  return statement.columnInt(0);
}

std::string SqliteDatabase::queryText(const std::string& sql) {
  SqliteStatement statement(*this, sql);
  if (!statement.step()) throw SqliteError(sql + ": no result", SQLITE_ERROR);
  return statement.columnText(0);
}

// ---------------------------------------------------------------------------------------------

SqliteStatement::SqliteStatement(const SqliteDatabase& db, const std::string& sql) : db_(&db), sql_(sql) {
  db.check(sqlite3_prepare_v2(db.handle(), sql.c_str(), -1, &stmt_, nullptr), "prepare " + sql);
}

SqliteStatement::~SqliteStatement() {
  if (stmt_) sqlite3_finalize(stmt_);
}

SqliteStatement::SqliteStatement(SqliteStatement&& other) noexcept
    : db_(other.db_), stmt_(other.stmt_), sql_(std::move(other.sql_)) {
  other.stmt_ = nullptr;
}

SqliteStatement& SqliteStatement::operator=(SqliteStatement&& other) noexcept {
  if (this != &other) {
    if (stmt_) sqlite3_finalize(stmt_);
    db_ = other.db_;
    stmt_ = other.stmt_;
    sql_ = std::move(other.sql_);
    other.stmt_ = nullptr;
  }
  return *this;
}

SqliteStatement& SqliteStatement::bind(int index, double value) {
  db_->check(sqlite3_bind_double(stmt_, index, value), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::bind(int index, std::int64_t value) {
  db_->check(sqlite3_bind_int64(stmt_, index, value), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::bind(int index, const std::string& value) {
  db_->check(sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT),
             "bind");
  return *this;
}

SqliteStatement& SqliteStatement::bindBlob(int index, const void* data, std::size_t bytes) {
  // A zero-length blob (not NULL) for empty vectors, so NOT NULL columns accept them.
  static const char kEmpty = 0;
  db_->check(sqlite3_bind_blob64(stmt_, index, bytes ? data : &kEmpty, bytes, SQLITE_TRANSIENT), "bind");
  return *this;
}

SqliteStatement& SqliteStatement::bindNull(int index) {
  db_->check(sqlite3_bind_null(stmt_, index), "bind");
  return *this;
}

bool SqliteStatement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  // sqlite3_errmsg describes the failure of the step; reset so the statement can be reused.
  const std::string message = sqlite3_errmsg(db_->handle());
  sqlite3_reset(stmt_);
  throw SqliteError(message, rc & 0xff);
}

void SqliteStatement::run() {
  step();
  reset();
}

void SqliteStatement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

double SqliteStatement::columnDouble(int column) const { return sqlite3_column_double(stmt_, column); }

std::int64_t SqliteStatement::columnInt(int column) const { return sqlite3_column_int64(stmt_, column); }

std::string SqliteStatement::columnText(int column) const {
  const auto* text = sqlite3_column_text(stmt_, column);
  const int bytes = sqlite3_column_bytes(stmt_, column);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(bytes)) : std::string();
}

std::vector<std::uint8_t> SqliteStatement::columnBlob(int column) const {
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_, column));
  const int bytes = sqlite3_column_bytes(stmt_, column);
  if (!data || bytes <= 0) return {};
  return std::vector<std::uint8_t>(data, data + bytes);
}

Eigen::VectorXd SqliteStatement::columnDoubles(int column) const {
  const void* data = sqlite3_column_blob(stmt_, column);
  const int bytes = sqlite3_column_bytes(stmt_, column);
  if (bytes % 8 != 0) {
    throw SqliteError("a float64 array column holds " + std::to_string(bytes) +
                          " bytes, not a multiple of 8",
                      SQLITE_CORRUPT);
  }
  Eigen::VectorXd values(bytes / 8);
  if (bytes > 0) std::memcpy(values.data(), data, static_cast<std::size_t>(bytes));
  return values;
}

bool SqliteStatement::columnIsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

std::vector<std::uint8_t> doublesToBlob(const double* values, std::size_t count) {
  std::vector<std::uint8_t> blob(count * sizeof(double));
  if (count) std::memcpy(blob.data(), values, blob.size());
  return blob;
}

bool isSessionDatabase(const std::filesystem::path& file) {
  // Only a regular file: opening a pipe to read would wait for a writer.
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) return false;
  // The database header: "SQLite format 3\0", then the application_id big-endian at offset 68.
  std::ifstream in(file, std::ios::binary);
  std::array<char, 72> header{};
  if (!in.read(header.data(), header.size())) return false;
  if (std::memcmp(header.data(), "SQLite format 3", 16) != 0) return false;
  std::uint32_t id = 0;
  for (int i = 68; i < 72; ++i) id = (id << 8) | static_cast<std::uint8_t>(header[static_cast<std::size_t>(i)]);
  if (id == static_cast<std::uint32_t>(kSessionApplicationId)) return true;
  // A recording still being written, or one that ended in a crash, holds its application_id in
  // its write-ahead log until SQLite copies the log back: SQLite itself reads it there.
  if (std::filesystem::file_size(file.string() + "-wal", error) == 0 || error) return false;
  try {
    SqliteDatabase db(file.string(), SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
    return db.queryInt("PRAGMA application_id") == kSessionApplicationId;
  } catch (const SqliteError&) {
    return false;
  }
}

}  // namespace flexirob::app
