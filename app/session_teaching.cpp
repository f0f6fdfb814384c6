#include "app/session_teaching.hpp"

#include <limits>
#include <map>

#include "planning/itm_file.hpp"
#include "robot/errors.hpp"

namespace flexirob::app {

RecordedTeaching readRecordedTeaching(const SessionReader& reader, bool read_graph) {
  RecordedTeaching teaching;
  teaching.robot = reader.meta("robot_name");
  teaching.tip = reader.meta("tip_link");
  teaching.scene = reader.meta("scene_name", "empty");

  // Each area's records in time order: their times bound the takes.
  std::map<int, std::vector<AreaRecord>> records;
  for (auto& area : reader.areas()) {
    if (area.area < 0) throw InputError("session: an area record has a negative index");
    if (!area.q_fixed.allFinite()) throw InputError("session: area " + std::to_string(area.area) + " has a non-finite q_fixed");
    records[area.area].push_back(std::move(area));
  }
  std::map<int, std::vector<const SampleRecord*>> taken, unfinished;
  const std::vector<SampleRecord> samples = reader.samples();
  Eigen::Index dof = -1;
  for (const SampleRecord& sample : samples) {
    if (sample.area < 0) throw InputError("session: a sample has a negative area index");
    if (sample.x.size() != 3 || !sample.x.allFinite()) throw InputError("session: a sample has no finite 3D position");
    if (!sample.q.allFinite() || sample.q.size() < 1 || (dof >= 0 && sample.q.size() != dof)) {
      throw InputError("session: a sample has a posture of the wrong size or non-finite values");
    }
    dof = sample.q.size();
    const auto it = records.find(sample.area);
    if (it == records.end() || sample.time > it->second.back().time) {
      unfinished[sample.area].push_back(&sample);
      continue;
    }
    const std::vector<AreaRecord>& takes = it->second;
    const double begin = takes.size() >= 2 ? takes[takes.size() - 2].time : -std::numeric_limits<double>::infinity();
    if (sample.time > begin) taken[sample.area].push_back(&sample);  // older takes were replaced
  }

  std::map<int, RecordedArea> areas;
  for (const auto& [index, takes] : records) {
    RecordedArea& area = areas[index];
    area.index = index;
    area.complete = true;
    area.time = takes.back().time;
    area.q_fixed = takes.back().q_fixed;
  }
  const auto toMatrices = [](const std::vector<const SampleRecord*>& list, Eigen::MatrixXd& X, Eigen::MatrixXd* Q) {
    X.resize(3, static_cast<Eigen::Index>(list.size()));
    if (Q != nullptr && !list.empty()) Q->resize(list.front()->q.size(), static_cast<Eigen::Index>(list.size()));
    for (std::size_t l = 0; l < list.size(); ++l) {
      X.col(static_cast<Eigen::Index>(l)) = list[l]->x;
      if (Q != nullptr) Q->col(static_cast<Eigen::Index>(l)) = list[l]->q;
    }
  };
  for (const auto& [index, list] : taken) {
    RecordedArea& area = areas[index];
    toMatrices(list, area.X, &area.Q);
  }
  for (const auto& [index, list] : unfinished) {
    RecordedArea& area = areas[index];
    area.index = index;
    toMatrices(list, area.unfinished_X, nullptr);
  }
  for (auto& [index, area] : areas) {
    if (area.complete && dof >= 0 && area.q_fixed.size() != dof) {
      throw InputError("session: area " + std::to_string(index) + "'s q_fixed has the wrong size");
    }
    teaching.areas.push_back(std::move(area));
  }

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
