#include "app/session_reader.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <set>

#include "app/session_schema.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {

namespace {

std::uint32_t bigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
}

// Checks the 100-byte SQLite header against the file's length before SQLite sees the file:
// SQLite opens a truncated database happily and fails (or reads zeros) only on the missing
// pages, which could be deep inside a long recording.
void checkHeader(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw InputError("session file " + name + " does not exist");
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError("session file " + name + " is not a regular file");
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) throw InputError("cannot read session file " + name + ": " + ec.message());
  if (size == 0) throw InputError("session file " + name + " is empty, not a FlexIRob session");

  std::array<unsigned char, 100> header{};
  std::ifstream in(file, std::ios::binary);
  in.read(reinterpret_cast<char*>(header.data()), static_cast<std::streamsize>(header.size()));
  const auto got = static_cast<std::size_t>(in.gcount());
  static const char kMagic[] = "SQLite format 3";  // 16 bytes with its terminating zero
  if (got < 16 || std::memcmp(header.data(), kMagic, 16) != 0) {
    const auto first = std::find_if(header.begin(), header.begin() + static_cast<std::ptrdiff_t>(got),
                                    [](unsigned char c) { return std::isspace(c) == 0; });
    if (first != header.begin() + static_cast<std::ptrdiff_t>(got) && *first == '{') {
      throw InputError("session file " + name +
                       " is a JSON session (teach --out *.json): it keeps the areas and the map, not the recorded "
                       "stream read here; record to a database instead (teach --out " + file.stem().string() + ".flexirob)");
    }
    throw InputError("session file " + name + " is not a FlexIRob session (not an SQLite database)");
  }
  if (got < header.size()) {
    throw InputError("session file " + name + " is truncated (" + std::to_string(size) + " bytes, shorter than its header)");
  }
  const std::uint32_t raw_page_size = (std::uint32_t{header[16]} << 8) | header[17];
  const std::uint64_t page_size = raw_page_size == 1 ? 65536 : raw_page_size;
  const std::uint32_t change_counter = bigEndian32(&header[24]);
  const std::uint32_t pages = bigEndian32(&header[28]);
  const std::uint32_t valid_for = bigEndian32(&header[92]);
  // The in-header page count is valid when version-valid-for matches the change counter.
  if (page_size >= 512 && pages > 0 && change_counter == valid_for) {
    const std::uint64_t expected = page_size * pages;
    if (size < expected) {
      throw InputError("session file " + name + " is truncated (" + std::to_string(size) + " of " +
                       std::to_string(expected) + " bytes)");
    }
  }
}

TrajectoryKind trajectoryKindFromName(const std::string& name) {
  if (name == "teach_in") return TrajectoryKind::TeachIn;
  if (name == "target") return TrajectoryKind::Target;
  if (name == "executed") return TrajectoryKind::Executed;
  throw SqliteError("unknown trajectory kind '" + name + "'", SQLITE_CORRUPT);
}

const char* kStateColumns = "t,dof,q,q_cmd,tau_ext,p_WT,quat_WT";

StateRecord readState(const SqliteStatement& st) {
  StateRecord s;
  s.time = st.columnDouble(0);
  const auto dof = st.columnInt(1);
  if (dof < 1 || dof > kMaxRecordedJoints) throw SqliteError("state row with " + std::to_string(dof) + " joints", SQLITE_CORRUPT);
  s.dof = static_cast<std::int32_t>(dof);
  const auto copy = [&st](int column, double* out, Eigen::Index expected) {
    const Eigen::VectorXd v = st.columnDoubles(column);
    if (v.size() != expected) throw SqliteError("state row with a wrongly sized vector", SQLITE_CORRUPT);
    std::copy_n(v.data(), expected, out);
  };
  copy(2, s.q.data(), dof);
  copy(3, s.q_cmd.data(), dof);
  copy(4, s.tau_ext.data(), dof);
  copy(5, s.p_WT.data(), 3);
  copy(6, s.quat_WT.data(), 4);
  return s;
}

}  // namespace

struct SessionReader::Impl {
  SqliteDatabase db;
};

SessionReader::SessionReader(const std::filesystem::path& file) : file_(file), impl_(std::make_unique<Impl>()) {
  checkHeader(file);
  const std::string name = file.string();
  try {
    impl_->db = SqliteDatabase(name, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
    auto& db = impl_->db;

    // Ours? application_id first: a foreign SQLite database is refused before its tables are read.
    const auto application_id = db.queryInt("PRAGMA application_id");
    if (application_id != kSessionApplicationId) {
      throw InputError("session file " + name + " is not a FlexIRob session (an SQLite database of another application)");
    }
    schema_version_ = static_cast<int>(db.queryInt("PRAGMA user_version"));
    if (schema_version_ > kSessionSchemaVersion) {
      throw InputError("session file " + name + " has schema version " + std::to_string(schema_version_) +
                       "; this build reads up to version " + std::to_string(kSessionSchemaVersion));
    }
    if (schema_version_ < 1) throw InputError("session file " + name + " has no schema version");

    std::set<std::string> tables;
    SqliteStatement list(db, "SELECT name FROM sqlite_master WHERE type='table'");
    while (list.step()) tables.insert(list.columnText(0));
    for (const auto& table : requiredSessionTables()) {
      if (!tables.count(table)) throw InputError("session file " + name + " lacks the table '" + table + "'");
    }

    SqliteStatement meta(db, "SELECT key, value FROM meta");
    while (meta.step()) meta_[meta.columnText(0)] = meta.columnText(1);
    if (this->meta("format") != kSessionFormatName) {
      throw InputError("session file " + name + " is not a FlexIRob session (meta.format is '" + printable(this->meta("format")) + "')");
    }
    // The two records of the version are written together; where they differ, the file was
    // altered by hand or by another tool, and which of its tables' layouts holds is unknown.
    const std::string meta_version = this->meta("schema_version", std::to_string(schema_version_));
    if (meta_version != std::to_string(schema_version_)) {
      throw InputError("session file " + name + " is inconsistent: its schema version is " +
                       std::to_string(schema_version_) + " but meta.schema_version says '" + printable(meta_version) + "'");
    }
    if (schema_version_ >= 2) {
      bool area_names = false;
      SqliteStatement columns(db, "SELECT name FROM pragma_table_info('area')");
      while (columns.step()) area_names = area_names || columns.columnText(0) == "name";
      if (!area_names) {
        throw InputError("session file " + name + " has schema version " + std::to_string(schema_version_) +
                         " but its area table lacks the column 'name'");
      }
    }
    metadata_.robot_name = this->meta("robot_name");
    metadata_.robot_urdf = this->meta("robot_urdf");
    metadata_.tip_link = this->meta("tip_link");
    metadata_.scene_name = this->meta("scene_name");
    metadata_.scene_text = this->meta("scene_text");
    metadata_.mesh_digests = this->meta("mesh_digests");  // none in files written before 2026-12-08
    metadata_.parameters = this->meta("parameters");
    metadata_.software_version = this->meta("software_version");
    metadata_.participant = this->meta("participant");
    metadata_.start_time_utc = this->meta("start_time_utc");

    // Ends of the state table: rowids are consecutive (rows are only appended), so the count
    // is max - min + 1 without a scan; min/max of t come from the index.
    // One aggregate per query: SQLite answers a lone min() or max() from one end of the
    // b-tree, but "min(x), max(x)" together scans the whole table.
    SqliteStatement first_id(db, "SELECT id FROM state ORDER BY id LIMIT 1");
    SqliteStatement last_id(db, "SELECT id FROM state ORDER BY id DESC LIMIT 1");
    if (first_id.step() && last_id.step()) state_count_ = last_id.columnInt(0) - first_id.columnInt(0) + 1;
    SqliteStatement first_t(db, "SELECT t FROM state ORDER BY t LIMIT 1");
    SqliteStatement last_t(db, "SELECT t FROM state ORDER BY t DESC LIMIT 1");
    if (first_t.step() && last_t.step()) {
      start_time_ = first_t.columnDouble(0);
      end_time_ = last_t.columnDouble(0);
    }
    // Read the last state row once: a file cut inside its b-tree fails here, not in review.
    if (state_count_ > 0) stateAt(end_time_);
  } catch (const SqliteError& e) {
    // SQLite's message may quote the damaged bytes or the statement that met them.
    const bool damaged = e.code() == SQLITE_CORRUPT || e.code() == SQLITE_NOTADB || e.code() == SQLITE_ERROR;
    throw InputError("session file " + name + " cannot be read" + (damaged ? " (damaged, or not a session)" : "") + ": " +
                     printable(e.what(), 200));
  }
}

SessionReader::~SessionReader() = default;
SessionReader::SessionReader(SessionReader&&) noexcept = default;
SessionReader& SessionReader::operator=(SessionReader&&) noexcept = default;

std::string SessionReader::meta(const std::string& key, const std::string& fallback) const {
  const auto it = meta_.find(key);
  return it == meta_.end() ? fallback : it->second;
}

std::vector<StateRecord> SessionReader::states(double t0, double t1, int stride) const {
  if (stride < 1) stride = 1;
  std::vector<StateRecord> out;
  SqliteStatement st(impl_->db, std::string("SELECT ") + kStateColumns + " FROM state WHERE t >= ? AND t <= ? ORDER BY t");
  st.bind(1, t0).bind(2, t1);
  int index = 0;
  while (st.step()) {
    if (index++ % stride == 0) out.push_back(readState(st));
  }
  return out;
}

std::vector<StateRecord> SessionReader::statesInRecordedOrder(std::int64_t after_row, std::int64_t limit,
                                                             std::int64_t& last_row) const {
  std::vector<StateRecord> out;
  last_row = after_row;
  SqliteStatement st(impl_->db, std::string("SELECT ") + kStateColumns + ",id FROM state WHERE id > ? ORDER BY id LIMIT ?");
  st.bind(1, after_row).bind(2, std::max<std::int64_t>(limit, 1));
  while (st.step()) {
    out.push_back(readState(st));
    last_row = st.columnInt(7);
  }
  return out;
}

std::optional<StateRecord> SessionReader::stateAt(double time) const {
  SqliteStatement st(impl_->db, std::string("SELECT ") + kStateColumns + " FROM state WHERE t <= ? ORDER BY t DESC LIMIT 1");
  st.bind(1, time);
  if (st.step()) return readState(st);
  SqliteStatement first(impl_->db, std::string("SELECT ") + kStateColumns + " FROM state ORDER BY t LIMIT 1");
  if (first.step()) return readState(first);
  return std::nullopt;
}

std::pair<double, double> SessionReader::recordedTimeSpan() const {
  if (state_count_ > 0) return {start_time_, end_time_};
  std::optional<double> first, last;
  // Each table's own ends, one aggregate per query: from the index where the table has one on t
  // (collision), else by one pass over a table of events, not of states.
  const auto extend = [&](const std::string& low_query, const std::string& high_query) {
    SqliteStatement low(impl_->db, low_query);
    SqliteStatement high(impl_->db, high_query);
    if (low.step() && !low.columnIsNull(0)) first = std::min(first.value_or(low.columnDouble(0)), low.columnDouble(0));
    if (high.step() && !high.columnIsNull(0)) last = std::max(last.value_or(high.columnDouble(0)), high.columnDouble(0));
  };
  for (const std::string table : {"stage", "signal", "area", "sample", "collision", "model", "itm"}) {
    extend("SELECT min(t) FROM " + table, "SELECT max(t) FROM " + table);
  }
  extend("SELECT min(t_start) FROM trajectory", "SELECT max(t_end) FROM trajectory");
  if (!first || !last) return {0.0, 0.0};
  return {*first, *last};
}

std::vector<StageRecord> SessionReader::stages() const {
  std::vector<StageRecord> out;
  SqliteStatement st(impl_->db, "SELECT t, stage, sub_stage FROM stage ORDER BY t, id");
  while (st.step()) out.push_back({st.columnDouble(0), st.columnText(1), st.columnText(2)});
  return out;
}

std::vector<SignalRecord> SessionReader::signals() const {
  std::vector<SignalRecord> out;
  SqliteStatement st(impl_->db, "SELECT t, kind, name FROM signal ORDER BY t, id");
  while (st.step()) {
    out.push_back({st.columnDouble(0), st.columnText(1) == "button" ? SignalKind::Button : SignalKind::Trigger,
                   st.columnText(2)});
  }
  return out;
}

std::vector<CollisionRecord> SessionReader::collisions(double t0, double t1) const {
  std::vector<CollisionRecord> out;
  SqliteStatement st(impl_->db,
                     "SELECT t, body_a, body_b, depth, p_W FROM collision WHERE t >= ? AND t <= ? ORDER BY t, id");
  st.bind(1, t0).bind(2, t1);
  while (st.step()) {
    CollisionRecord c;
    c.time = st.columnDouble(0);
    c.body_a = st.columnText(1);
    c.body_b = st.columnText(2);
    c.depth = st.columnDouble(3);
    const Eigen::VectorXd p = st.columnDoubles(4);
    if (p.size() != 3) throw InputError("session file " + file_.string() + ": a collision row is damaged");
    c.p_W = p;
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<AreaRecord> SessionReader::areas() const {
  std::vector<AreaRecord> out;
  // Version 1 files have no area names.
  const bool named = schema_version_ >= 2;
  SqliteStatement st(impl_->db, named ? "SELECT area, t, x_init, q_fixed, name FROM area ORDER BY t, id"
                                      : "SELECT area, t, x_init, q_fixed FROM area ORDER BY t, id");
  while (st.step()) {
    out.push_back({static_cast<int>(st.columnInt(0)), st.columnDouble(1), st.columnDoubles(2), st.columnDoubles(3),
                   named ? st.columnText(4) : std::string()});
  }
  return out;
}

std::vector<SampleRecord> SessionReader::samples(int area) const {
  std::vector<SampleRecord> out;
  SqliteStatement st(impl_->db, area < 0 ? "SELECT t, area, x, q FROM sample ORDER BY id"
                                         : "SELECT t, area, x, q FROM sample WHERE area = ? ORDER BY id");
  if (area >= 0) st.bind(1, area);
  while (st.step()) {
    out.push_back({st.columnDouble(0), static_cast<int>(st.columnInt(1)), st.columnDoubles(2), st.columnDoubles(3)});
  }
  return out;
}

std::string SessionReader::damageOf(const std::filesystem::path& file) {
  try {
    const SqliteDatabase db(file.string(), SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX);
    SqliteStatement check(db, "PRAGMA quick_check(1)");
    if (!check.step()) return "the check returned nothing";
    std::string finding = check.columnText(0);
    if (finding == "ok") return {};
    // "*** in database main ***\nOn tree page 11 ...": the heading says nothing a reader needs.
    const std::string heading = "*** in database main ***";
    if (finding.rfind(heading, 0) == 0) finding.erase(0, heading.size());
    std::replace(finding.begin(), finding.end(), '\n', ' ');
    const auto first = finding.find_first_not_of(' ');
    return first == std::string::npos ? std::string("damaged") : finding.substr(first);
  } catch (const SqliteError& error) {
    // Only what says the pages are bad is damage; a busy file or too little memory is not.
    if (error.code() == SQLITE_CORRUPT || error.code() == SQLITE_NOTADB) return error.what();
    return {};
  }
}

std::map<int, std::int64_t> SessionReader::sampleCounts() const {
  std::map<int, std::int64_t> out;
  SqliteStatement st(impl_->db, "SELECT area, count(*) FROM sample GROUP BY area");
  while (st.step()) out[static_cast<int>(st.columnInt(0))] = st.columnInt(1);
  return out;
}

std::vector<ModelRecord> SessionReader::models() const {
  std::vector<ModelRecord> out;
  SqliteStatement st(impl_->db, "SELECT t, learner, samples, train_seconds, bytes FROM model ORDER BY id");
  while (st.step()) {
    ModelRecord m;
    m.time = st.columnDouble(0);
    m.learner_kind = st.columnText(1);
    m.samples = static_cast<int>(st.columnInt(2));
    m.train_seconds = st.columnDouble(3);
    m.bytes = st.columnBlob(4);
    out.push_back(std::move(m));
  }
  return out;
}

std::optional<ItmRecord> SessionReader::lastItmSnapshot() const {
  SqliteStatement st(impl_->db, "SELECT t, nodes, edges, bytes FROM itm ORDER BY id DESC LIMIT 1");
  if (!st.step()) return std::nullopt;
  return ItmRecord{st.columnDouble(0), static_cast<int>(st.columnInt(1)), static_cast<int>(st.columnInt(2)), st.columnBlob(3)};
}

std::int64_t SessionReader::itmSnapshotCount() const {
  SqliteStatement st(impl_->db, "SELECT count(*) FROM itm");
  return st.step() ? st.columnInt(0) : 0;
}

std::vector<ItmRecord> SessionReader::itmSnapshots() const {
  std::vector<ItmRecord> out;
  SqliteStatement st(impl_->db, "SELECT t, nodes, edges, bytes FROM itm ORDER BY id");
  while (st.step()) {
    out.push_back({st.columnDouble(0), static_cast<int>(st.columnInt(1)), static_cast<int>(st.columnInt(2)), st.columnBlob(3)});
  }
  return out;
}

namespace {
std::vector<TrajectoryRecord> readTrajectories(const SqliteDatabase& db, const std::string& where, std::int64_t arg,
                                               const std::string& file) {
  std::vector<TrajectoryRecord> out;
  SqliteStatement st(db, "SELECT id, kind, name, reference_id, points, dof, times, positions, postures, outcome "
                         "FROM trajectory " + where + " ORDER BY id");
  if (!where.empty()) st.bind(1, arg);
  while (st.step()) {
    TrajectoryRecord r;
    r.id = st.columnInt(0);
    r.kind = trajectoryKindFromName(st.columnText(1));
    r.name = st.columnText(2);
    r.reference_id = st.columnIsNull(3) ? -1 : st.columnInt(3);
    const auto points = st.columnInt(4);
    const auto dof = st.columnInt(5);
    r.times = st.columnDoubles(6);
    const Eigen::VectorXd positions = st.columnDoubles(7);
    const Eigen::VectorXd postures = st.columnDoubles(8);
    if (points < 0 || dof < 0 || r.times.size() != points || positions.size() != 3 * points ||
        postures.size() != dof * points) {
      throw InputError("session file " + file + ": trajectory " + std::to_string(r.id) + " is damaged");
    }
    r.positions = Eigen::Map<const Eigen::MatrixXd>(positions.data(), 3, points);
    r.postures = Eigen::Map<const Eigen::MatrixXd>(postures.data(), dof, points);
    r.outcome = st.columnText(9);
    out.push_back(std::move(r));
  }
  return out;
}
}  // namespace

std::vector<TrajectoryRecord> SessionReader::trajectories() const {
  return readTrajectories(impl_->db, "", 0, file_.string());
}

std::vector<TrajectoryRecord> SessionReader::trajectories(TrajectoryKind kind) const {
  std::vector<TrajectoryRecord> all = trajectories();
  std::vector<TrajectoryRecord> out;
  for (auto& r : all) {
    if (r.kind == kind) out.push_back(std::move(r));
  }
  return out;
}

std::optional<TrajectoryRecord> SessionReader::trajectory(std::int64_t id) const {
  auto found = readTrajectories(impl_->db, "WHERE id = ?", id, file_.string());
  if (found.empty()) return std::nullopt;
  return std::move(found.front());
}

}  // namespace flexirob::app
