#pragma once
// OMPL as a peer of the benchmarks (optional: built only when libompl-dev is present,
// FLEXIROB_HAVE_OMPL): RRTConnect in joint space within the soft limits, with OUR collision
// world (robot/collision) as the state validity checker, so both planners avoid the same
// geometry. The OMPL headers stay inside ompl_planner.cpp.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::bench::peers {

struct JointSpacePath {
  bool solved = false;                     ///< an exact solution within the time limit
  std::vector<Eigen::VectorXd> waypoints;  ///< simplified path, start to goal [rad]
  double plan_ms = 0.0;                    ///< solve + simplification, wall clock
};

class OmplRrtConnect {
 public:
  /// resolution: the longest joint-space segment [rad, Euclidean] checked as one motion step.
  OmplRrtConnect(const robot::RobotModel& model, const robot::Scene& scene, double resolution = 0.05);
  ~OmplRrtConnect();
  OmplRrtConnect(const OmplRrtConnect&) = delete;
  OmplRrtConnect& operator=(const OmplRrtConnect&) = delete;

  /// Seeds OMPL's global random generator; effective only before the first planner exists.
  static void seed(std::uint64_t seed);

  /// Plans from q_start to q_goal; the path is shortened with OMPL's default simplifier (as
  /// MoveIt does) and the time of both is counted.
  JointSpacePath plan(const Eigen::VectorXd& q_start, const Eigen::VectorXd& q_goal, double time_limit_s);
  /// Whether our collision world reports no contact at q.
  bool isValid(const Eigen::VectorXd& q) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace flexirob::bench::peers
