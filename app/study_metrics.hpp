#pragma once
// Study metrics of Sect. 3.3, 4.3.3 and 5.2.2: task-space error E_task (Eq. 3.20), maximum
// deviation from a target trajectory, Procrustes distance after time normalization, jerk and
// time per phase. Positions are in metres in the world frame, times in seconds; a trajectory
// is a 3 x K matrix of points (one column per point).
#include <Eigen/Core>
#include <map>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include "app/session_recorder.hpp"

namespace flexirob::app {

/// Eq. 3.20: E_task = 1/L Σ_l ‖x_l − x̂_l‖ for targets and reached points (both 3 x L, L >= 1)
/// [m]. Throws std::invalid_argument for mismatched or empty inputs.
double taskSpaceError(const Eigen::MatrixXd& targets, const Eigen::MatrixXd& reached);

/// Largest distance [m] of a point of `trajectory` (3 x K) from the polyline through `target`
/// (3 x T, T >= 1): the maximum Cartesian deviation of Sect. 5.2.2.
double maxDeviation(const Eigen::MatrixXd& trajectory, const Eigen::MatrixXd& target);

/// Removes the velocity profile: `count` points (>= 2) equally spaced in arc length along the
/// polyline through `points` (3 x K, K >= 1). A polyline of zero length gives `count` copies.
Eigen::MatrixXd resampleByArcLength(const Eigen::MatrixXd& points, int count);

struct ProcrustesResult {
  double distance = 0.0;  ///< [m] mean Euclidean distance after superposition
  Eigen::Matrix3d R_TU = Eigen::Matrix3d::Identity();  ///< rotation applied to the user trajectory
  Eigen::Vector3d p_TU = Eigen::Vector3d::Zero();      ///< translation applied after R_TU [m]
};

/// Sect. 5.2.2: both trajectories are normalized in time (resampleByArcLength to `count`
/// points), the user trajectory is superimposed on the target by the rotation and translation
/// that minimize the squared distances (Kabsch, no scaling, no reflection), and the distance
/// is the mean Euclidean distance between corresponding points.
ProcrustesResult procrustesDistance(const Eigen::MatrixXd& user, const Eigen::MatrixXd& target, int count = 200);

struct JerkStatistics {
  double mean = 0.0;  ///< [m/s³] mean of ‖d³p/dt³‖
  double rms = 0.0;   ///< [m/s³] root mean square of ‖d³p/dt³‖
  double max = 0.0;   ///< [m/s³]
  int samples = 0;    ///< jerk values (K − 3)
};

/// Jerk, the third time derivative of the positions (3 x K at strictly increasing `times`,
/// K >= 4): 3!·(third divided difference) over each four consecutive points, exact for cubic
/// motion on any time grid.
JerkStatistics jerk(const Eigen::VectorXd& times, const Eigen::MatrixXd& positions);

/// Seconds spent in each stage and in each "stage/sub_stage", from the stage records (in
/// time order) until `end_time` [s]. Keys: "CONFIGURATION", "CONFIGURATION/RECORDING", ...
std::map<std::string, double> timePerPhase(const std::vector<StageRecord>& stages, double end_time);

/// The targets of an executed motion's points: the reference trajectory's positions paired
/// index by index when the point counts agree, otherwise interpolated at the same normalized
/// time (0 at the first point, 1 at the last). 3 x K like executed.positions.
Eigen::MatrixXd targetsForExecution(const TrajectoryRecord& executed, const TrajectoryRecord& reference);

/// Which recorded trajectory each one is judged against: an executed motion against the
/// reference it names; a teach-in against the target it names, or else the session's first
/// target (Sect. 5.2.2). Keeps pointers into `trajectories`, which must outlive it.
class TrajectoryReferences {
 public:
  explicit TrajectoryReferences(const std::vector<TrajectoryRecord>& trajectories);
  /// The trajectory `trajectory` names as its reference, if the session holds it.
  const TrajectoryRecord* referenceOf(const TrajectoryRecord& trajectory) const;
  /// The reference, or else the session's first target; nullptr if neither.
  const TrajectoryRecord* targetOf(const TrajectoryRecord& teach_in) const;
  /// E_task (Eq. 3.20) of an executed motion against its reference and the points it counts
  /// with; nothing without a reference or without points.
  std::optional<std::pair<double, Eigen::Index>> executionError(const TrajectoryRecord& executed) const;

 private:
  std::map<std::int64_t, const TrajectoryRecord*> by_id_;
  const TrajectoryRecord* first_target_ = nullptr;
};

}  // namespace flexirob::app
