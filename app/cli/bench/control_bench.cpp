// One control cycle as the 1 kHz loop runs it: the hierarchical controller (Eq. 2.11) with the
// command limiter, a learned redundancy map q_c(x) (an ELM trained on the robot's own postures)
// and a collision query of the simulator's world. Target: median <= 100 µs (a tenth of FRI's cycle).
#include <benchmark/benchmark.h>

#include <random>

#include "app/cli/bench/benchmarks.hpp"
#include "app/control_thread.hpp"
#include "learning/elm.hpp"
#include "robot/collision.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::bench {
namespace {

void controlCycle(benchmark::State& state, const char* robot_name, bool with_simulation) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath(robot_name));
  const int n = model.dof();
  // A learner like the one the workflow embeds: an ELM on 300 (x, q) samples.
  std::mt19937 rng(3);
  learning::TrainingSet data;
  data.X.resize(3, 300);
  data.Y.resize(n, 300);
  const Eigen::VectorXd lower = model.softLowerLimits(), upper = model.softUpperLimits();
  for (int l = 0; l < 300; ++l) {
    Eigen::VectorXd q(n);
    for (int j = 0; j < n; ++j) q[j] = std::uniform_real_distribution<double>(0.5 * lower[j], 0.5 * upper[j])(rng);
    data.X.col(l) = robot::tipPose(model, q).translation();
    data.Y.col(l) = q;
  }
  learning::Elm elm(3, n);
  elm.fit(data);
  app::LearnerRedundancyMap map(elm, n);

  std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  const robot::ParameterSet parameters(declarations);
  robot::HierarchicalController controller(model, parameters);
  robot::CommandLimiter limiter(model, parameters, 1e-3);
  // A scene with two obstacles near the arm, as in setup II.
  robot::Scene scene;
  for (double side : {-1.0, 1.0}) {
    robot::Obstacle box;
    box.name = side < 0 ? "left" : "right";
    box.size = Eigen::Vector3d(0.2, 0.2, 0.8);
    box.X_WO.translation() = Eigen::Vector3d(-0.4, side * 0.35, 0.4);
    scene.obstacles.push_back(box);
  }
  robot::CollisionWorld world(model, scene);
  robot::Simulation sim(model, &scene, parameters);
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  q0[1] = 0.5;
  q0[3 % n] = -1.0;
  limiter.reset(q0);
  sim.reset(q0);
  robot::JointImpedanceCommand command;
  command.resize(n);
  command.stiffness.setConstant(300.0);
  command.damping.setConstant(0.95);
  Eigen::VectorXd q_c(n), qd(n);
  const Eigen::Vector3d centre = robot::tipPose(model, q0).translation();
  double phase = 0.0;
  std::size_t contacts = 0;
  for (auto _ : state) {
    // A moving target: a 5 cm circle at 0.5 Hz.
    phase += 2e-3 * 3.14159265358979;
    const Eigen::Vector3d target = centre + 0.05 * Eigen::Vector3d(std::cos(phase), std::sin(phase), 0.0);
    map.predict(target, q_c);
    controller.velocity(limiter.command(), target, q_c, qd, &limiter);
    command.q_cmd = limiter.updateVelocity(qd);
    if (with_simulation) {
      sim.writeCommand(command);
      sim.step();
      contacts += sim.contacts().size();
    } else {
      world.update(command.q_cmd);
      contacts += world.contacts().size();
    }
    benchmark::DoNotOptimize(command.q_cmd.data());
  }
  benchmark::DoNotOptimize(contacts);
}

}  // namespace

void registerControlBenchmarks() {
  benchmark::RegisterBenchmark("control/cycle/lwr4", controlCycle, "lwr4", false);
  benchmark::RegisterBenchmark("control/cycle/arm9", controlCycle, "arm9", false);
  benchmark::RegisterBenchmark("control/cycle_with_sim_step/lwr4", controlCycle, "lwr4", true);
}

}  // namespace flexirob::bench
