#include "app/session_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <system_error>

#include "robot/errors.hpp"

namespace flexirob::app {

namespace {

// Recorded states are replayed this many seconds at a time (a 1 kHz recording: 10 000 states,
// about 2 MB), so that a long session is not read into memory at once.
constexpr double kReplayWindow = 10.0;

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

void appendRow(std::string& out, const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& q) {
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (i > 0) out += ',';
    out += number(x(i));
  }
  for (Eigen::Index j = 0; j < q.size(); ++j) {
    out += ',';
    out += number(q(j));
  }
  out += '\n';
}

std::string jointHeader(Eigen::Index joints) {
  std::string header;
  for (Eigen::Index j = 1; j <= joints; ++j) header += ",q" + std::to_string(j);
  return header;
}

// Where the workflow stands, replayed from its stage records: which stage holds from which
// state on. Workflow::update fires a trigger and takes the position of the same state, so a stage
// a trigger entered holds for the state it fired at; a button acts between control cycles, after
// the state of its time was taken, so its stage holds from the next state on.
struct StageChange {
  double time = 0.0;
  bool from_this_state = false;
  std::string stage, sub_stage;
};

std::vector<StageChange> stageChanges(const SessionReader& reader) {
  std::vector<double> trigger_times;
  for (const SignalRecord& signal : reader.signals()) {
    if (signal.kind == SignalKind::Trigger) trigger_times.push_back(signal.time);
  }
  std::sort(trigger_times.begin(), trigger_times.end());
  std::vector<StageChange> changes;
  for (const StageRecord& record : reader.stages()) {
    const bool by_trigger = std::binary_search(trigger_times.begin(), trigger_times.end(), record.time);
    changes.push_back({record.time, by_trigger, record.stage, record.sub_stage});
  }
  std::stable_sort(changes.begin(), changes.end(), [](const StageChange& a, const StageChange& b) { return a.time < b.time; });
  return changes;
}

bool begins(const StageChange& change, double state_time) {
  return change.from_this_state ? change.time <= state_time : change.time < state_time;
}

}  // namespace

ConfigurationStream configurationStream(const SessionReader& reader, double sample_period, robot::CollisionWorld* world,
                                        const std::function<void(double)>& progress) {
  if (!(sample_period > 0.0) || !std::isfinite(sample_period)) throw InputError("stream: the sample period must be > 0 s");
  const std::vector<StageChange> changes = stageChanges(reader);
  ConfigurationStream stream;
  std::vector<Eigen::VectorXd> positions, postures;
  Eigen::Index dof = -1;
  std::size_t next_change = 0;
  std::string stage, sub_stage;
  double last_sample_time = -1e9;  // as Workflow::last_sample_time_
  const double start = reader.startTime();
  const double end = reader.endTime();
  for (double window = start; reader.stateCount() > 0 && window <= end; window += kReplayWindow) {
    // Windows share no state: the upper bound of one is excluded by the next one's lower bound.
    const double window_end = std::nextafter(window + kReplayWindow, -1e300);
    for (const StateRecord& state : reader.states(window, window_end)) {
      ++stream.states_read;
      while (next_change < changes.size() && begins(changes[next_change], state.time)) {
        const StageChange& change = changes[next_change++];
        const bool recording_begins = (change.sub_stage == "RECORDING" || change.sub_stage == "TEACH-IN") &&
                                      (change.sub_stage != sub_stage || change.stage != stage);
        stage = change.stage;
        sub_stage = change.sub_stage;
        if (recording_begins) last_sample_time = -1e9;
      }
      if (stage != "CONFIGURATION" && stage != "PROGRAMMING") continue;
      if (state.time - last_sample_time < sample_period - 1e-9) continue;  // Workflow::recordSample
      last_sample_time = state.time;
      if (stage != "CONFIGURATION") continue;
      const Eigen::VectorXd q = state.qVector();
      const Eigen::Vector3d p = state.position();
      if (q.size() < 1 || (dof >= 0 && q.size() != dof)) throw InputError("session: recorded states of varying joint counts");
      if (!q.allFinite() || !p.allFinite()) throw InputError("session: a recorded state has non-finite values");
      dof = q.size();
      if (world != nullptr) {
        if (world->model().dof() != dof) throw InputError("session: the recorded states do not fit the robot's joints");
        world->update(q);
        if (!world->contacts().empty()) {
          ++stream.left_out_in_contact;
          continue;
        }
      }
      stream.times.push_back(state.time);
      positions.push_back(p);
      postures.push_back(q);
    }
    if (progress && end > start) progress(std::min(1.0, (window + kReplayWindow - start) / (end - start)));
  }
  stream.X.resize(3, static_cast<Eigen::Index>(positions.size()));
  stream.Q.resize(dof < 0 ? 0 : dof, static_cast<Eigen::Index>(postures.size()));
  for (std::size_t k = 0; k < positions.size(); ++k) {
    stream.X.col(static_cast<Eigen::Index>(k)) = positions[k];
    stream.Q.col(static_cast<Eigen::Index>(k)) = postures[k];
  }
  return stream;
}

std::string trainingSamplesCsv(const RecordedTeaching& teaching) {
  std::string out;
  Eigen::Index joints = -1;
  for (const RecordedArea& area : teaching.areas) {
    if (!area.complete || area.X.cols() == 0) continue;
    if (joints < 0) {
      joints = area.Q.rows();
      out = "area,x,y,z" + jointHeader(joints) + "\n";
    }
    for (Eigen::Index l = 0; l < area.X.cols(); ++l) {
      out += std::to_string(area.index);
      out += ',';
      appendRow(out, area.X.col(l), area.Q.col(l));
    }
  }
  if (joints < 0) throw InputError("session: no complete training area (no RECORDING ended)");
  return out;
}

std::string configurationStreamCsv(const ConfigurationStream& stream) {
  std::string out = "x,y,z" + jointHeader(stream.Q.rows()) + "\n";
  for (Eigen::Index k = 0; k < stream.X.cols(); ++k) appendRow(out, stream.X.col(k), stream.Q.col(k));
  return out;
}

void writeFileReplacing(const std::filesystem::path& file, const std::string& text, const std::string& option) {
  std::filesystem::path temporary = file;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(option + ": cannot write '" + file.string() + "'");
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw InputError(option + ": cannot write '" + file.string() + "' (disk full?)");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, file, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw InputError(option + ": cannot write '" + file.string() + "'");
  }
}

}  // namespace flexirob::app
