#include "app/session_export.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "app/table_text.hpp"
#include "app/workflow.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {

namespace {

// Recorded states are replayed this many at a time (about 2 MB), so that a long session is not
// read into memory at once.
constexpr std::int64_t kReplayPage = 10000;

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
// state on. Workflow::update reads a state, fires a trigger and takes the position in one cycle,
// so a trigger's change (a sub-stage within the same stage: APPROACHING, POSED, RECORDING,
// TEACH-IN, back to WAITING) holds for the state it fired at. A button acts between cycles, after
// the state of its time was taken, so its change (another stage: CONFIGURATION, PROGRAMMING,
// IDLE, EXECUTION) holds from the next state on; a button at or before the first state (the
// start) holds from the first, which the workflow reads after it.
struct StageChange {
  double time = 0.0;
  bool from_this_state = false;
  std::string stage, sub_stage;
};

std::vector<StageChange> stageChanges(const SessionReader& reader, double first_state_time) {
  std::vector<StageChange> changes;
  std::string stage = toString(Stage::kIdle);
  for (const StageRecord& record : reader.stages()) {  // in time order
    const bool by_trigger = record.stage == stage;
    changes.push_back({record.time, by_trigger || record.time <= first_state_time, record.stage, record.sub_stage});
    stage = record.stage;
  }
  return changes;
}

bool begins(const StageChange& change, double state_time) {
  return change.from_this_state ? change.time <= state_time : change.time < state_time;
}

}  // namespace

ConfigurationStream configurationStream(const SessionReader& reader, double sample_period, robot::CollisionWorld* world,
                                        const std::function<void(double)>& progress) {
  if (!(sample_period > 0.0) || !std::isfinite(sample_period)) throw InputError("stream: the sample period must be > 0 s");
  std::int64_t first_row = 0;
  const std::vector<StateRecord> first = reader.statesInRecordedOrder(0, 1, first_row);
  const std::vector<StageChange> changes = stageChanges(reader, first.empty() ? 0.0 : first.front().time);
  ConfigurationStream stream;
  std::vector<Eigen::VectorXd> positions, postures;
  Eigen::Index dof = -1;
  std::size_t next_change = 0;
  std::string stage, sub_stage;
  double last_sample_time = -1e9;  // as Workflow::last_sample_time_
  // The names the workflow records its stages under.
  const std::string configuration = toString(Stage::kConfiguration), programming = toString(Stage::kProgramming);
  const std::string recording = toString(SubStage::kRecording), teach_in = toString(SubStage::kTeachIn);
  const double total = static_cast<double>(std::max<std::int64_t>(reader.stateCount(), 1));
  std::int64_t row = 0;
  for (;;) {
    // In recorded order, page by page: the workflow read them in this order, and a damaged
    // file's times (1e300, out of order) cannot make the replay loop or skip.
    std::int64_t last_row = row;
    const std::vector<StateRecord> page = reader.statesInRecordedOrder(row, kReplayPage, last_row);
    if (page.empty()) break;
    row = last_row;
    for (const StateRecord& state : page) {
      ++stream.states_read;
      while (next_change < changes.size() && begins(changes[next_change], state.time)) {
        const StageChange& change = changes[next_change++];
        const bool recording_begins = (change.sub_stage == recording || change.sub_stage == teach_in) &&
                                      (change.sub_stage != sub_stage || change.stage != stage);
        stage = change.stage;
        sub_stage = change.sub_stage;
        if (recording_begins) last_sample_time = -1e9;
      }
      if (stage != configuration && stage != programming) continue;
      if (state.time - last_sample_time < sample_period - 1e-9) continue;  // Workflow::recordSample
      last_sample_time = state.time;
      if (stage != configuration) continue;
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
    if (progress) progress(std::min(1.0, static_cast<double>(stream.states_read) / total));
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
      // A value learn would refuse is refused here: the file is written for it to read.
      const double largest = std::max(area.X.col(l).cwiseAbs().maxCoeff(), area.Q.col(l).cwiseAbs().maxCoeff());
      if (!(largest <= kLargestTableValue)) {
        throw InputError("session: area " + std::to_string(area.index) + ", sample " + std::to_string(l + 1) +
                         ": a value beyond ±1e6 or not finite, which learn does not read");
      }
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

}  // namespace flexirob::app
