#include "app/study_metrics.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flexirob::app {

namespace {

void requirePoints(const Eigen::MatrixXd& points, const char* what, Eigen::Index min_count) {
  if (points.rows() != 3 || points.cols() < min_count) {
    throw std::invalid_argument(std::string(what) + ": expected 3 x K points with K >= " + std::to_string(min_count) +
                                ", got " + std::to_string(points.rows()) + " x " + std::to_string(points.cols()));
  }
  if (!points.allFinite()) throw std::invalid_argument(std::string(what) + ": points must be finite");
}

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double length_sq = ab.squaredNorm();
  if (length_sq == 0.0) return (p - a).norm();
  const double s = std::clamp((p - a).dot(ab) / length_sq, 0.0, 1.0);
  return (p - (a + s * ab)).norm();
}

// Linear interpolation of the columns of `points` at parameters `s` in [0, 1] along `knots`
// (increasing, knots(0) = 0, knots(end) = 1).
Eigen::MatrixXd interpolateColumns(const Eigen::MatrixXd& points, const Eigen::VectorXd& knots,
                                   const Eigen::VectorXd& s) {
  Eigen::MatrixXd out(points.rows(), s.size());
  Eigen::Index segment = 0;
  const Eigen::Index last = points.cols() - 1;
  for (Eigen::Index i = 0; i < s.size(); ++i) {
    while (segment < last - 1 && knots(segment + 1) < s(i)) ++segment;
    const double span = knots(segment + 1) - knots(segment);
    const double w = span > 0.0 ? std::clamp((s(i) - knots(segment)) / span, 0.0, 1.0) : 0.0;
    out.col(i) = (1.0 - w) * points.col(segment) + w * points.col(segment + 1);
  }
  return out;
}

}  // namespace

double taskSpaceError(const Eigen::MatrixXd& targets, const Eigen::MatrixXd& reached) {
  requirePoints(targets, "taskSpaceError targets", 1);
  requirePoints(reached, "taskSpaceError reached", 1);
  if (targets.cols() != reached.cols()) {
    throw std::invalid_argument("taskSpaceError: " + std::to_string(targets.cols()) + " targets but " +
                                std::to_string(reached.cols()) + " reached points");
  }
  // Eq. 3.20
  return (targets - reached).colwise().norm().mean();
}

double maxDeviation(const Eigen::MatrixXd& trajectory, const Eigen::MatrixXd& target) {
  requirePoints(trajectory, "maxDeviation trajectory", 1);
  requirePoints(target, "maxDeviation target", 1);
  double worst = 0.0;
  for (Eigen::Index k = 0; k < trajectory.cols(); ++k) {
    const Eigen::Vector3d p = trajectory.col(k);
    double nearest = (p - target.col(0)).norm();
    for (Eigen::Index j = 0; j + 1 < target.cols(); ++j) {
      nearest = std::min(nearest, distanceToSegment(p, target.col(j), target.col(j + 1)));
    }
    worst = std::max(worst, nearest);
  }
  return worst;
}

Eigen::MatrixXd resampleByArcLength(const Eigen::MatrixXd& points, int count) {
  requirePoints(points, "resampleByArcLength", 1);
  if (count < 2) throw std::invalid_argument("resampleByArcLength: expected at least 2 points, got " + std::to_string(count));
  const Eigen::Index k = points.cols();
  if (k == 1) return points.replicate(1, count);
  // Cumulative arc length, normalized to [0, 1].
  Eigen::VectorXd knots = Eigen::VectorXd::Zero(k);
  for (Eigen::Index i = 1; i < k; ++i) knots(i) = knots(i - 1) + (points.col(i) - points.col(i - 1)).norm();
  const double length = knots(k - 1);
  if (length == 0.0) return points.col(0).replicate(1, count);
  knots /= length;
  return interpolateColumns(points, knots, Eigen::VectorXd::LinSpaced(count, 0.0, 1.0));
}

ProcrustesResult procrustesDistance(const Eigen::MatrixXd& user, const Eigen::MatrixXd& target, int count) {
  const Eigen::MatrixXd A = resampleByArcLength(user, count);
  const Eigen::MatrixXd B = resampleByArcLength(target, count);
  const Eigen::Vector3d a_mean = A.rowwise().mean();
  const Eigen::Vector3d b_mean = B.rowwise().mean();
  const Eigen::MatrixXd A0 = A.colwise() - a_mean;
  const Eigen::MatrixXd B0 = B.colwise() - b_mean;
  // Kabsch: R = V diag(1, 1, det(V Uᵀ)) Uᵀ maximizes tr(R A0 B0ᵀ) over proper rotations.
  const Eigen::Matrix3d H = A0 * B0.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  ProcrustesResult result;
  result.R_TU = svd.matrixV() * D * svd.matrixU().transpose();
  result.p_TU = b_mean - result.R_TU * a_mean;
  const Eigen::MatrixXd A_superimposed = (result.R_TU * A).colwise() + result.p_TU;
  result.distance = (A_superimposed - B).colwise().norm().mean();
  return result;
}

JerkStatistics jerk(const Eigen::VectorXd& times, const Eigen::MatrixXd& positions) {
  requirePoints(positions, "jerk", 4);
  if (times.size() != positions.cols()) {
    throw std::invalid_argument("jerk: " + std::to_string(times.size()) + " times for " +
                                std::to_string(positions.cols()) + " points");
  }
  for (Eigen::Index i = 1; i < times.size(); ++i) {
    if (!(times(i) > times(i - 1))) throw std::invalid_argument("jerk: times must increase strictly");
  }
  // Divided differences: f[t_i..t_{i+m}] = (f[t_{i+1}..t_{i+m}] − f[t_i..t_{i+m−1}]) / (t_{i+m} − t_i).
  Eigen::MatrixXd diff = positions;
  for (int order = 1; order <= 3; ++order) {
    Eigen::MatrixXd next(3, diff.cols() - 1);
    for (Eigen::Index i = 0; i < next.cols(); ++i) {
      next.col(i) = (diff.col(i + 1) - diff.col(i)) / (times(i + order) - times(i));
    }
    diff = std::move(next);
  }
  const Eigen::VectorXd magnitude = 6.0 * diff.colwise().norm().transpose();
  JerkStatistics stats;
  stats.samples = static_cast<int>(magnitude.size());
  stats.mean = magnitude.mean();
  stats.rms = std::sqrt(magnitude.squaredNorm() / static_cast<double>(magnitude.size()));
  stats.max = magnitude.maxCoeff();
  return stats;
}

std::map<std::string, double> timePerPhase(const std::vector<StageRecord>& stages, double end_time) {
  std::map<std::string, double> seconds;
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const double until = i + 1 < stages.size() ? stages[i + 1].time : end_time;
    const double span = std::max(0.0, until - stages[i].time);
    seconds[stages[i].stage] += span;
    if (!stages[i].sub_stage.empty()) seconds[stages[i].stage + "/" + stages[i].sub_stage] += span;
  }
  return seconds;
}

Eigen::MatrixXd targetsForExecution(const TrajectoryRecord& executed, const TrajectoryRecord& reference) {
  requirePoints(executed.positions, "executed motion", 1);
  requirePoints(reference.positions, "reference trajectory", 1);
  const Eigen::Index k = executed.positions.cols();
  const Eigen::Index r = reference.positions.cols();
  if (k == r) return reference.positions;
  if (r == 1) return reference.positions.replicate(1, k);
  // Normalized time: from the recorded times when they span a positive interval, otherwise
  // from the point index.
  const auto normalized = [](const Eigen::VectorXd& times, Eigen::Index count) -> Eigen::VectorXd {
    if (times.size() == count && count > 1 && times(count - 1) > times(0)) {
      return (times.array() - times(0)) / (times(count - 1) - times(0));
    }
    if (count == 1) return Eigen::VectorXd::Ones(1);
    return Eigen::VectorXd::LinSpaced(count, 0.0, 1.0);
  };
  return interpolateColumns(reference.positions, normalized(reference.times, r), normalized(executed.times, k));
}

TrajectoryReferences::TrajectoryReferences(const std::vector<TrajectoryRecord>& trajectories) {
  for (const TrajectoryRecord& trajectory : trajectories) {
    by_id_[trajectory.id] = &trajectory;
    if (trajectory.kind == TrajectoryKind::Target && first_target_ == nullptr) first_target_ = &trajectory;
  }
}

const TrajectoryRecord* TrajectoryReferences::referenceOf(const TrajectoryRecord& trajectory) const {
  const auto found = by_id_.find(trajectory.reference_id);
  return found == by_id_.end() ? nullptr : found->second;
}

const TrajectoryRecord* TrajectoryReferences::targetOf(const TrajectoryRecord& teach_in) const {
  const TrajectoryRecord* reference = referenceOf(teach_in);
  return reference != nullptr ? reference : first_target_;
}

std::optional<std::pair<double, Eigen::Index>> TrajectoryReferences::executionError(const TrajectoryRecord& executed) const {
  const TrajectoryRecord* reference = referenceOf(executed);
  if (reference == nullptr || executed.positions.cols() == 0 || reference->positions.cols() == 0) return std::nullopt;
  return std::make_pair(taskSpaceError(targetsForExecution(executed, *reference), executed.positions), executed.positions.cols());
}

}  // namespace flexirob::app
