// Kinematic evaluations: motions with the hierarchical controller and a learned map, the
// reachable-workspace count and the explored fraction.
#include <gtest/gtest.h>

#include "app/evaluation.hpp"
#include "learning/elm.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/sim/reach.hpp"

namespace flexirob::app {
namespace {

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

Eigen::VectorXd ready() {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  q[1] = 0.6;
  q[3] = -1.6;
  q[5] = 0.9;
  return q;
}

// A map that gives (about) the ready posture everywhere: an ELM fitted on it at a few points.
std::unique_ptr<learning::Learner> constantMap() {
  learning::TrainingSet data;
  data.X.resize(3, 8);
  data.Y.resize(7, 8);
  for (int l = 0; l < 8; ++l) {
    data.X.col(l) = Eigen::Vector3d(-0.5 + 0.1 * (l % 2), -0.3 + 0.2 * ((l / 2) % 2), 0.2 + 0.2 * (l / 4));
    data.Y.col(l) = ready();
  }
  auto elm = std::make_unique<learning::Elm>(3, 7);
  elm->fit(data);
  return elm;
}

struct Parameters {
  Parameters() : declarations(robot::reachParameters()), parameters(declarations) {}
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
};

TEST(Evaluation, MotionReachesAFreeTargetWithoutCollision) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  robot::CollisionWorld world(lwr4(), empty);
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = start + Eigen::Vector3d(0.0, 0.15, 0.05);
  const MotionOutcome outcome = executeMotion(lwr4(), s.parameters, *map, ready(), [&](double) { return target; }, 0.0, 3.0, &world);
  EXPECT_FALSE(outcome.collided);
  EXPECT_LT(outcome.final_error_m, 1e-3);
  EXPECT_LT((robot::tipPose(lwr4(), outcome.q).translation() - target).norm(), 1e-3);
}

TEST(Evaluation, MotionThroughAnObstacleCountsAsCollision) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene scene;
  const Eigen::Vector3d start = robot::tipPose(lwr4(), ready()).translation();
  const Eigen::Vector3d target = start + Eigen::Vector3d(0.0, 0.3, 0.0);
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.6, 0.04, 0.6);
  wall.X_WO.translation() = start + Eigen::Vector3d(0.0, 0.15, 0.0);
  scene.obstacles.push_back(wall);
  robot::CollisionWorld world(lwr4(), scene);
  const MotionOutcome outcome = executeMotion(lwr4(), s.parameters, *map, ready(), [&](double) { return target; }, 0.0, 3.0, &world);
  EXPECT_TRUE(outcome.collided);
}

TEST(Evaluation, ExploredFractionCountsCellsHoldingSamples) {
  Parameters s;
  const auto map = constantMap();
  robot::Scene empty;
  robot::EvaluationGrid grid;
  grid.lower = Eigen::Vector3d(-0.6, -0.2, 0.3);
  grid.upper = Eigen::Vector3d(-0.4, 0.2, 0.3);
  grid.spacing = 0.2;
  const std::vector<Eigen::Vector3d> points = grid.points();
  ASSERT_EQ(points.size(), 6U);
  // Samples near (within a third of a cell of) the first three points.
  Eigen::MatrixXd X(3, 3);
  for (int i = 0; i < 3; ++i) X.col(i) = points[static_cast<std::size_t>(i)] + Eigen::Vector3d::Constant(0.03);
  const ReachableResult result = evaluateReachable(lwr4(), empty, s.parameters, *map, ready(), grid, X);
  EXPECT_EQ(result.grid_points, 6);
  EXPECT_EQ(result.targets, 6);  // all within reach, no obstacles
  EXPECT_DOUBLE_EQ(result.explored_fraction, 0.5);
  EXPECT_EQ(result.collided, 0);
  EXPECT_EQ(result.reached, 6);  // free space in front of the robot
}

}  // namespace
}  // namespace flexirob::app
