#pragma once
// What a recorded session holds, as the files the offline tools read (docs/SESSIONS.md): the
// training samples of its areas as `learn fit` reads them, the positions its configuration
// stage fed the ITM as `itm build` reads them, so that a teaching can be learned, mapped and
// compared again with other parameters without teaching it again.
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "robot/collision.hpp"

namespace flexirob::app {

/// The positions a workflow fed its ITM during a recorded session (Chap. 7), in time order.
struct ConfigurationStream {
  std::vector<double> times;  ///< [s] session time of each position
  Eigen::MatrixXd X;          ///< 3 x K tip positions [m, W]
  Eigen::MatrixXd Q;          ///< N x K postures [rad]
  int left_out_in_contact = 0;  ///< positions taken but left out: the arm touched something
  std::int64_t states_read = 0; ///< recorded states replayed
};

/// Replays the session's recorded states, in the order they were recorded, with its stage
/// records as Workflow::recordSample takes positions: every `sample_period` [s] while in
/// CONFIGURATION or PROGRAMMING, the period restarted where a RECORDING or TEACH-IN begins, kept
/// while in CONFIGURATION. A sub-stage change within a stage (a trigger's) counts from the state
/// at its time, a change of stage (a button's, between control cycles) from the next state; one
/// at or before the first state from the first. With a collision world of the session's robot
/// and scene, positions where the arm touches anything are left out, as the workflow leaves out
/// a simulated arm that sank into an obstacle; without one (a session over FRI) every position
/// is kept. States are read a page at a time, so a long session needs no more memory than its
/// stream. `progress` (may be empty) gets the fraction of the states replayed. Throws
/// InputError for sample_period <= 0, for recorded postures of varying size or with non-finite
/// values.
ConfigurationStream configurationStream(const SessionReader& reader, double sample_period, robot::CollisionWorld* world,
                                        const std::function<void(double)>& progress = {});

/// The complete areas' training samples (their latest takes) as CSV: header
/// `area,x,y,z,q1,…,qN`, one sample per row, numbers with 17 significant digits (read back
/// exactly). Areas are numbered by their index in the session. Throws InputError when no area
/// is complete.
std::string trainingSamplesCsv(const RecordedTeaching& teaching);

/// The stream as CSV: header `x,y,z,q1,…,qN`, one position per row in time order.
std::string configurationStreamCsv(const ConfigurationStream& stream);

}  // namespace flexirob::app
