#include "app/cli/bench/peers/ompl_planner.hpp"

#include <chrono>

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "robot/collision.hpp"

namespace flexirob::bench::peers {

namespace ob = ompl::base;
namespace og = ompl::geometric;

struct OmplRrtConnect::Impl {
  Impl(const robot::RobotModel& model_in, const robot::Scene& scene, double resolution)
      : model(&model_in), world(model_in, scene), q(model_in.dof()) {
    const int n = model_in.dof();
    auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned int>(n));
    ob::RealVectorBounds bounds(static_cast<unsigned int>(n));
    const Eigen::VectorXd lower = model_in.softLowerLimits(), upper = model_in.softUpperLimits();
    for (int j = 0; j < n; ++j) {
      bounds.setLow(static_cast<unsigned int>(j), lower[j]);
      bounds.setHigh(static_cast<unsigned int>(j), upper[j]);
    }
    space->setBounds(bounds);
    setup = std::make_unique<og::SimpleSetup>(space);
    setup->setStateValidityChecker([this](const ob::State* state) {
      const auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
      for (Eigen::Index j = 0; j < q.size(); ++j) q[j] = values[j];
      return isValid(q);
    });
    setup->getSpaceInformation()->setStateValidityCheckingResolution(resolution / space->getMaximumExtent());
    setup->setPlanner(std::make_shared<og::RRTConnect>(setup->getSpaceInformation()));
    setup->setup();
  }

  bool isValid(const Eigen::VectorXd& posture) {
    world.update(posture);
    return world.contacts().empty();
  }

  const robot::RobotModel* model;
  robot::CollisionWorld world;
  Eigen::VectorXd q;
  std::unique_ptr<og::SimpleSetup> setup;
};

OmplRrtConnect::OmplRrtConnect(const robot::RobotModel& model, const robot::Scene& scene, double resolution) {
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  impl_ = std::make_unique<Impl>(model, scene, resolution);
}
OmplRrtConnect::~OmplRrtConnect() = default;

void OmplRrtConnect::seed(std::uint64_t seed) { ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(seed)); }

bool OmplRrtConnect::isValid(const Eigen::VectorXd& q) const { return impl_->isValid(q); }

JointSpacePath OmplRrtConnect::plan(const Eigen::VectorXd& q_start, const Eigen::VectorXd& q_goal, double time_limit_s) {
  og::SimpleSetup& setup = *impl_->setup;
  const auto space = setup.getStateSpace();
  ob::ScopedState<> start(space), goal(space);
  for (Eigen::Index j = 0; j < q_start.size(); ++j) {
    start[static_cast<unsigned int>(j)] = q_start[j];
    goal[static_cast<unsigned int>(j)] = q_goal[j];
  }
  setup.clear();
  setup.setStartAndGoalStates(start, goal);
  JointSpacePath path;
  const auto t0 = std::chrono::steady_clock::now();
  const ob::PlannerStatus status = setup.solve(time_limit_s);
  path.solved = status == ob::PlannerStatus::EXACT_SOLUTION;
  if (path.solved) setup.simplifySolution();
  path.plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!path.solved) return path;
  const og::PathGeometric& solution = setup.getSolutionPath();
  for (std::size_t k = 0; k < solution.getStateCount(); ++k) {
    const auto* values = solution.getState(k)->as<ob::RealVectorStateSpace::StateType>()->values;
    path.waypoints.push_back(Eigen::Map<const Eigen::VectorXd>(values, q_start.size()));
  }
  return path;
}

}  // namespace flexirob::bench::peers
