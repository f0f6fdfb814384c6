#include <benchmark/benchmark.h>

#include "app/cli/bench/benchmarks.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"

namespace flexirob::bench {
namespace {

void forwardKinematicsAndJacobian(benchmark::State& state, const char* robot_name) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot_name));
  robot::Kinematics kinematics(model);
  robot::Matrix6Xd J_WT(6, model.dof());
  Eigen::VectorXd q = model.midPosture();
  for (auto _ : state) {
    q[0] += 1e-6;
    kinematics.update(q);
    kinematics.tipJacobian(J_WT);
    benchmark::DoNotOptimize(J_WT.data());
  }
}

}  // namespace

void registerKinematicsBenchmarks() {
  benchmark::RegisterBenchmark("kinematics/fk_jacobian/lwr4", forwardKinematicsAndJacobian, "lwr4");
  benchmark::RegisterBenchmark("kinematics/fk_jacobian/arm9", forwardKinematicsAndJacobian, "arm9");
}

}  // namespace flexirob::bench
