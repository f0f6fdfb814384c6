// Controller + limiter commands always inside the limits (position, velocity, acceleration),
// for both robots, for random parameter values anywhere in their declared ranges, from start
// postures outside the limits, and under random and hostile targets (NaN, infinities, huge
// values, wrong sizes). Complements CommandLimiter.NoCommandLeavesTheLimitsForTenThousandHostileInputs
// (LWR IV, default parameters).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "robot/controllers.hpp"
#include "robot/resources.hpp"

namespace flexirob::robot {
namespace {

constexpr double kDt = 1e-3;

ParameterSet randomParameters(std::mt19937& rng) {
  std::vector<ParameterDeclaration> all(hierarchicalParameters().begin(), hierarchicalParameters().end());
  all.insert(all.end(), limiterParameters().begin(), limiterParameters().end());
  ParameterSet parameters(all);
  std::uniform_int_distribution<int> choice(0, 2);
  for (const auto& declaration : all) {
    // The bounds of each range and a value inside, at random.
    std::uniform_real_distribution<double> inside(declaration.min_value, declaration.max_value);
    const int pick = choice(rng);
    parameters.set(declaration.name, pick == 0 ? declaration.min_value : pick == 1 ? declaration.max_value : inside(rng));
  }
  return parameters;
}

void checkRobot(const std::string& robot, std::uint32_t seed) {
  const RobotModel model = RobotModel::fromUrdfFile(resolveRobotPath(robot));
  const int n = model.dof();
  std::mt19937 rng(seed);
  const ParameterSet parameters = randomParameters(rng);
  HierarchicalController controller(model, parameters);
  CommandLimiter limiter(model, parameters, kDt);
  const Eigen::VectorXd lower = model.softLowerLimits();
  const Eigen::VectorXd upper = model.softUpperLimits();
  // Start outside the limits: reset clamps it.
  Eigen::VectorXd start = model.midPosture();
  start[0] = upper[0] + 1.0;
  start[n - 1] = std::numeric_limits<double>::quiet_NaN();
  limiter.reset(start);
  const Eigen::VectorXd v_max = limiter.velocityLimit();
  const double a_max = limiter.accelerationLimit();
  std::uniform_real_distribution<double> reach(-1.5, 1.5);
  std::uniform_real_distribution<double> anywhere(-10.0, 10.0);
  std::uniform_int_distribution<int> kind(0, 11);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::VectorXd previous = limiter.command();
  ASSERT_TRUE(previous.allFinite());
  ASSERT_TRUE((previous.array() >= lower.array()).all() && (previous.array() <= upper.array()).all());
  Eigen::VectorXd previous_velocity = Eigen::VectorXd::Zero(n);
  Eigen::Vector3d p_des(0.3, 0.2, 0.6);
  Eigen::VectorXd q_c = model.midPosture();
  for (int k = 0; k < 4000; ++k) {
    const int input = kind(rng);
    // A new target every 200 cycles, hostile ones in between.
    if (k % 200 == 0) {
      p_des = Eigen::Vector3d(reach(rng), reach(rng), reach(rng));
      for (int i = 0; i < n; ++i) q_c[i] = anywhere(rng);
    }
    Eigen::Vector3d p = p_des;
    Eigen::VectorXd c = q_c;
    if (input == 0) p[k % 3] = k % 2 == 0 ? nan : -inf;
    if (input == 1) c[k % n] = inf;
    if (input == 2) p *= 1e200;
    if (input == 3) c = Eigen::VectorXd::Constant(n + 1, 0.0);  // wrong size
    const Eigen::VectorXd* q_cmd = nullptr;
    if (input == 4) {
      Eigen::VectorXd q_target = Eigen::VectorXd::Constant(n, k % 2 == 0 ? 1e300 : -1e300);
      q_cmd = &limiter.update(q_target);
    } else if (input == 5) {
      q_cmd = &limiter.update(Eigen::VectorXd::Constant(n, nan));
    } else if (input == 6) {
      q_cmd = &limiter.updateVelocity(Eigen::VectorXd::Constant(n, 1e9));
    } else {
      Eigen::VectorXd qd(n);
      controller.velocity(limiter.command(), p, c, qd, input == 7 ? nullptr : &limiter);
      ASSERT_TRUE(qd.allFinite()) << robot << " step " << k;
      q_cmd = &limiter.updateVelocity(qd);
    }
    ASSERT_TRUE(q_cmd->allFinite()) << robot << " step " << k;
    ASSERT_TRUE((q_cmd->array() >= lower.array()).all() && (q_cmd->array() <= upper.array()).all())
        << robot << " step " << k << ": " << q_cmd->transpose();
    const Eigen::VectorXd velocity = (*q_cmd - previous) / kDt;
    ASSERT_TRUE((velocity.array().abs() <= v_max.array() * (1 + 1e-9) + 1e-12).all())
        << robot << " step " << k << " velocity " << velocity.transpose();
    ASSERT_TRUE(((velocity - previous_velocity).array().abs() <= a_max * kDt * (1 + 1e-6) + 1e-9).all())
        << robot << " step " << k << " acceleration " << ((velocity - previous_velocity) / kDt).transpose();
    previous = *q_cmd;
    previous_velocity = velocity;
  }
}

TEST(ControllerProperty, CommandsStayInsideTheLimitsOfTheLwr4ForRandomParameters) {
  for (std::uint32_t seed = 1; seed <= 3; ++seed) checkRobot("lwr4", seed);
}

TEST(ControllerProperty, CommandsStayInsideTheLimitsOfTheArm9ForRandomParameters) {
  for (std::uint32_t seed = 4; seed <= 6; ++seed) checkRobot("arm9", seed);
}

}  // namespace
}  // namespace flexirob::robot
