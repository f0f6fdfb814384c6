#pragma once
// What a recorded session taught: its training areas (the samples of each area's latest take and
// q_fixed) and its last ITM snapshot, read back from a SessionReader (docs/SESSIONS.md). Used by
// every consumer that re-learns, renders or evaluates a recording, so that they agree on which
// samples belong to an area.
//
// Samples are recorded while a RECORDING runs, the area record when it ends (time T). An area
// re-taught later has records at T_1 < T_2 < ...; its latest take is the samples with
// T_{n-1} < t <= T_n. Samples after an area's last record (or of an area without any record)
// are a RECORDING the session ended in (a crash, kill -9): kept as an incomplete take.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "app/session_reader.hpp"
#include "planning/itm.hpp"

namespace flexirob::app {

struct RecordedArea {
  int index = 0;                ///< the area's index in the session
  bool complete = false;        ///< its RECORDING ended (an area record exists)
  double time = 0.0;            ///< [s] when its latest RECORDING ended (complete areas)
  Eigen::VectorXd q_fixed;      ///< [rad] (complete areas; empty otherwise)
  Eigen::MatrixXd X;            ///< 3 x L sample positions of the latest (complete) take [m, W]
  Eigen::MatrixXd Q;            ///< N x L sample postures [rad]
  Eigen::MatrixXd unfinished_X; ///< 3 x U samples of a RECORDING the session ended in (may be empty)
};

struct RecordedTeaching {
  std::string robot, tip, scene;
  std::vector<RecordedArea> areas;  ///< by index, ascending
  std::optional<planning::Itm> itm; ///< the last ITM snapshot, if any
};

/// Reads the teaching of a session (the ITM snapshot only with read_graph). Throws InputError on
/// samples or areas of the wrong size or with non-finite values and on a damaged ITM snapshot.
RecordedTeaching readRecordedTeaching(const SessionReader& reader, bool read_graph = true);

}  // namespace flexirob::app
