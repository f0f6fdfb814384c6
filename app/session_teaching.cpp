#include "app/session_teaching.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "planning/itm_file.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {

namespace {

// Area indices beyond this are refused: a hostile file must not make the replay allocate.
constexpr int kMaxAreaIndex = 100000;

struct Slot {
  bool complete = false;
  double time = 0.0;
  Eigen::VectorXd q_fixed;
  std::string name;
  std::vector<const SampleRecord*> take, pending;
};

Eigen::MatrixXd columns(const std::vector<const SampleRecord*>& list, bool postures) {
  Eigen::MatrixXd out(postures && !list.empty() ? list.front()->q.size() : 3, static_cast<Eigen::Index>(list.size()));
  for (std::size_t l = 0; l < list.size(); ++l) out.col(static_cast<Eigen::Index>(l)) = postures ? list[l]->q : list[l]->x;
  return out;
}

}  // namespace

std::vector<RecordedArea> replayTeaching(const std::vector<AreaRecord>& areas, const std::vector<SampleRecord>& samples,
                                         const std::vector<SignalRecord>& signals, double until) {
  // Every record in time order; at equal times samples (0) before area records (1) before
  // removals (2), each kind in its recorded order.
  struct Item {
    double time;
    int kind;
    std::size_t index;
  };
  std::vector<Item> items;
  Eigen::Index dof = -1;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const SampleRecord& sample = samples[i];
    if (sample.area < 0 || sample.area > kMaxAreaIndex) throw InputError("session: a sample has an area index out of range");
    if (sample.x.size() != 3 || !sample.x.allFinite()) throw InputError("session: a sample has no finite 3D position");
    if (!sample.q.allFinite() || sample.q.size() < 1 || (dof >= 0 && sample.q.size() != dof)) {
      throw InputError("session: a sample has a posture of the wrong size or non-finite values");
    }
    dof = sample.q.size();
    if (sample.time <= until) items.push_back({sample.time, 0, i});
  }
  for (std::size_t i = 0; i < areas.size(); ++i) {
    const AreaRecord& area = areas[i];
    if (area.area < 0 || area.area > kMaxAreaIndex) throw InputError("session: an area record has an index out of range");
    if (!area.q_fixed.allFinite() || (dof >= 0 && area.q_fixed.size() != dof)) {
      throw InputError("session: area " + std::to_string(area.area) + " has a q_fixed of the wrong size or non-finite values");
    }
    if (area.time <= until) items.push_back({area.time, 1, i});
  }
  std::vector<int> removed(signals.size(), -1);
  const std::string prefix = "remove_area ";
  for (std::size_t i = 0; i < signals.size(); ++i) {
    const SignalRecord& signal = signals[i];
    if (signal.kind != SignalKind::Button || signal.name.rfind(prefix, 0) != 0 || signal.time > until) continue;
    const std::string number = signal.name.substr(prefix.size());
    if (number.empty() || number.size() > 6 || number.find_first_not_of("0123456789") != std::string::npos) continue;
    removed[i] = std::stoi(number);
    items.push_back({signal.time, 2, i});
  }
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return a.time < b.time || (a.time == b.time && a.kind < b.kind);
  });

  std::vector<Slot> slots;
  const auto slot = [&slots](int index) -> Slot& {
    if (static_cast<std::size_t>(index) >= slots.size()) slots.resize(static_cast<std::size_t>(index) + 1);
    return slots[static_cast<std::size_t>(index)];
  };
  for (const Item& item : items) {
    if (item.kind == 0) {
      slot(samples[item.index].area).pending.push_back(&samples[item.index]);
    } else if (item.kind == 1) {
      const AreaRecord& record = areas[item.index];
      Slot& area = slot(record.area);
      area.complete = true;
      area.time = record.time;
      area.q_fixed = record.q_fixed;
      area.name = record.name;
      area.take = std::move(area.pending);  // the samples since its last record
      area.pending.clear();
    } else if (const int k = removed[item.index]; k >= 0 && static_cast<std::size_t>(k) < slots.size()) {
      slots.erase(slots.begin() + k);
    }
  }

  std::vector<RecordedArea> out;
  for (std::size_t k = 0; k < slots.size(); ++k) {
    const Slot& area = slots[k];
    if (!area.complete && area.pending.empty()) continue;
    RecordedArea recorded;
    recorded.index = static_cast<int>(k);
    recorded.complete = area.complete;
    recorded.time = area.time;
    recorded.q_fixed = area.q_fixed;
    recorded.name = area.name;
    recorded.X = columns(area.take, false);
    recorded.Q = area.take.empty() ? Eigen::MatrixXd(dof > 0 ? dof : 0, 0) : columns(area.take, true);
    recorded.unfinished_X = columns(area.pending, false);
    out.push_back(std::move(recorded));
  }
  return out;
}

RecordedTeaching readRecordedTeaching(const SessionReader& reader, bool read_graph) {
  RecordedTeaching teaching;
  teaching.robot = reader.meta("robot_name");
  teaching.tip = reader.meta("tip_link");
  teaching.scene = reader.meta("scene_name", "empty");
  teaching.robot_urdf = reader.metadata().robot_urdf;
  teaching.scene_text = reader.metadata().scene_text;
  teaching.mesh_digests = reader.metadata().mesh_digests;
  teaching.closed_cleanly = !reader.meta("end_time_utc").empty();
  teaching.areas = replayTeaching(reader.areas(), reader.samples(), reader.signals());

  const std::optional<ItmRecord> graph = read_graph ? reader.lastItmSnapshot() : std::nullopt;
  if (graph) {
    try {
      teaching.itm = planning::itmFromBytes(graph->bytes.data(), graph->bytes.size(), "the session's ITM snapshot");
    } catch (const planning::ItmFileError& e) {
      throw InputError(std::string("session: ") + e.what());
    }
  }
  return teaching;
}

}  // namespace flexirob::app
