// The peer adapters of `bench --peers`: KDL sees the same kinematics as ours (so the reaching
// comparison is fair), our controller used as a position solver reaches reachable targets, and
// OMPL with our collision world plans around an obstacle that blocks the straight motion.
#include <gtest/gtest.h>

#include <random>

#include "app/cli/bench/peers/reaching_peers.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

#ifdef FLEXIROB_HAVE_KDL
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_nr_jl.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>

#include "app/cli/bench/peers/kdl_chain.hpp"
#endif
#ifdef FLEXIROB_HAVE_OMPL
#include "app/cli/bench/peers/ompl_planner.hpp"
#include "robot/collision.hpp"
#endif

namespace flexirob {
namespace {

Eigen::VectorXd randomPosture(const robot::RobotModel& model, std::mt19937& rng) {
  const Eigen::VectorXd lower = model.softLowerLimits(), upper = model.softUpperLimits();
  Eigen::VectorXd q(model.dof());
  for (int j = 0; j < model.dof(); ++j) q[j] = std::uniform_real_distribution<double>(lower[j], upper[j])(rng);
  return q;
}

// A posture within ±0.3 rad of the benchmark's start posture.
Eigen::VectorXd postureNearStart(const robot::RobotModel& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> offset(-0.3, 0.3);
  Eigen::VectorXd q = bench::peers::bentStartPosture(model);
  for (int j = 0; j < model.dof(); ++j) q[j] += offset(rng);
  return q.cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
}

TEST(BenchReachingPeer, OurControllerAsSolverReachesTipPositionsOfPosturesNearTheStartInsideTheLimits) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const Eigen::VectorXd q_start = bench::peers::bentStartPosture(model);
  bench::peers::ControllerPositionSolver task_only(model, 1e-5, 100, 0.0);
  bench::peers::ControllerPositionSolver hierarchical(model, 1e-5, 100, 0.5);
  std::mt19937 rng(7);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d target = robot::tipPose(model, postureNearStart(model, rng)).translation();
    const auto plain = task_only.solve(q_start, target);
    EXPECT_LT((robot::tipPose(model, plain.q).translation() - target).norm(), 1e-5) << "target " << k;
    EXPECT_LT(plain.iterations, 100);
    const auto pulled = hierarchical.solve(q_start, target);
    EXPECT_LT((robot::tipPose(model, pulled.q).translation() - target).norm(), 1e-3) << "target " << k;
    for (const auto* q : {&plain.q, &pulled.q}) {
      EXPECT_TRUE(((*q - model.softLowerLimits()).array() >= 0.0).all());
      EXPECT_TRUE(((model.softUpperLimits() - *q).array() >= 0.0).all());
    }
  }
}

#ifdef FLEXIROB_HAVE_KDL
TEST(BenchReachingPeer, KdlChainTipPoseEqualsOurKinematicsOnTheSameUrdf) {
  for (const char* robot_name : {"lwr4", "arm9"}) {
    const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot_name));
    const KDL::Chain chain = bench::peers::kdlChainFromModel(model);
    ASSERT_EQ(static_cast<int>(chain.getNrOfJoints()), model.dof());
    KDL::ChainFkSolverPos_recursive fk(chain);
    std::mt19937 rng(3);
    for (int k = 0; k < 50; ++k) {
      const Eigen::VectorXd q = randomPosture(model, rng);
      KDL::Frame frame;
      ASSERT_GE(fk.JntToCart(bench::peers::toKdl(q), frame), 0);
      const Eigen::Isometry3d ours = robot::tipPose(model, q);
      const Eigen::Isometry3d theirs = bench::peers::fromKdl(frame);
      EXPECT_LT((ours.translation() - theirs.translation()).norm(), 1e-9) << robot_name;
      EXPECT_LT((ours.linear() - theirs.linear()).norm(), 1e-9) << robot_name;
    }
  }
}

TEST(BenchReachingPeer, KdlNrJlSolutionsMeetTheirPoseUnderOurKinematics) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  const KDL::Chain chain = bench::peers::kdlChainFromModel(model);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainIkSolverVel_pinv velocity(chain);
  KDL::ChainIkSolverPos_NR_JL solver(chain, bench::peers::toKdl(model.softLowerLimits()),
                                     bench::peers::toKdl(model.softUpperLimits()), fk, velocity, 100, 1e-6);
  std::mt19937 rng(5);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Isometry3d target = robot::tipPose(model, postureNearStart(model, rng));
    KDL::JntArray q_out(static_cast<unsigned int>(model.dof()));
    ASSERT_GE(solver.CartToJnt(bench::peers::toKdl(bench::peers::bentStartPosture(model)), bench::peers::toKdl(target), q_out), 0);
    const Eigen::Isometry3d reached = robot::tipPose(model, bench::peers::fromKdl(q_out));
    EXPECT_LT((reached.translation() - target.translation()).norm(), 1e-5);
    EXPECT_LT((reached.linear() - target.linear()).norm(), 1e-5);
  }
}
#endif

#ifdef FLEXIROB_HAVE_OMPL
TEST(BenchPlanningPeer, OmplWithOurCollisionWorldPlansAroundAnObstacleOnTheStraightMotion) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  // The arm leaning forward, swinging joint 1 from -1.2 to 1.2 rad: halfway (q1 = 0) its
  // forearm passes where a box now stands.
  ASSERT_EQ(model.dof(), 7);
  Eigen::VectorXd q_start(7);
  q_start << 0.0, 1.0, 0.0, 0.8, 0.0, 0.0, 0.0;
  Eigen::VectorXd q_goal = q_start, q_middle = q_start;
  q_start[0] = -1.2;
  q_goal[0] = 1.2;
  robot::Kinematics kinematics(model);
  kinematics.update(q_middle);
  robot::Scene scene;
  robot::Obstacle box;
  box.name = "block";
  box.size = Eigen::Vector3d(0.12, 0.12, 0.12);
  box.X_WO.translation() = 0.5 * (kinematics.X_WB(4).translation() + kinematics.p_WT());
  scene.obstacles.push_back(box);

  bench::peers::OmplRrtConnect::seed(1);
  bench::peers::OmplRrtConnect planner(model, scene, 0.02);
  ASSERT_TRUE(planner.isValid(q_start));
  ASSERT_TRUE(planner.isValid(q_goal));
  ASSERT_FALSE(planner.isValid(q_middle));  // the straight motion is blocked
  const auto path = planner.plan(q_start, q_goal, 10.0);
  ASSERT_TRUE(path.solved);
  ASSERT_GE(path.waypoints.size(), 2U);
  EXPECT_LT((path.waypoints.front() - q_start).norm(), 1e-9);
  EXPECT_LT((path.waypoints.back() - q_goal).norm(), 1e-9);
  // Densely re-checked with the same collision world: free everywhere.
  for (std::size_t w = 1; w < path.waypoints.size(); ++w) {
    const Eigen::VectorXd& a = path.waypoints[w - 1];
    const Eigen::VectorXd& b = path.waypoints[w];
    for (int s = 0; s <= 50; ++s) EXPECT_TRUE(planner.isValid(a + (b - a) * (s / 50.0))) << "segment " << w;
  }
}
#endif

}  // namespace
}  // namespace flexirob
