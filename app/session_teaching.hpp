#pragma once
// What a recorded session taught: its training areas (the samples of each area's latest take and
// q_fixed) and its last ITM snapshot, read back from a SessionReader (docs/SESSIONS.md). Used by
// every consumer that re-learns, renders or evaluates a recording, so that they agree on which
// samples belong to an area.
//
// Samples are recorded while a RECORDING runs, the area record when it ends; a removed area is
// a button signal "remove_area k" (later indices shift down by one, as in the workflow). The
// records are replayed in time order (at equal times samples before area records before
// removals): an area record closes the take of the samples of that area since its last record;
// samples not closed by a record are a RECORDING the session ended in (a crash, kill -9), kept
// as an unfinished take. Files that stamp every sample with its area's time read the same way.
#include <Eigen/Core>
#include <limits>
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
  std::string name;             ///< as its latest record names it (empty: unnamed)
  Eigen::MatrixXd X;            ///< 3 x L sample positions of the latest (complete) take [m, W]
  Eigen::MatrixXd Q;            ///< N x L sample postures [rad]
  Eigen::MatrixXd unfinished_X; ///< 3 x U samples of a RECORDING the session ended in (may be empty)
};

struct RecordedTeaching {
  std::string robot, tip, scene;
  /// The URDF and scene text the session was taught with (empty in sessions that predate them).
  std::string robot_urdf, scene_text;
  std::string mesh_digests;  ///< SessionMetadata::mesh_digests
  /// False while the session is being written or after it was interrupted (no end_time_utc).
  bool closed_cleanly = false;
  std::vector<RecordedArea> areas;  ///< by index, ascending
  std::optional<planning::Itm> itm; ///< the last ITM snapshot, if any
};

/// The replay on records already read, up to and including `until` [s] (the review of a moment).
/// Areas without any record or sample are left out. Throws InputError like readRecordedTeaching.
std::vector<RecordedArea> replayTeaching(const std::vector<AreaRecord>& areas, const std::vector<SampleRecord>& samples,
                                         const std::vector<SignalRecord>& signals,
                                         double until = std::numeric_limits<double>::infinity());

/// Reads the teaching of a session (the ITM snapshot only with read_graph). Throws InputError on
/// samples or areas of the wrong size or with non-finite values and on a damaged ITM snapshot.
RecordedTeaching readRecordedTeaching(const SessionReader& reader, bool read_graph = true);

}  // namespace flexirob::app
