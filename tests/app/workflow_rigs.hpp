#pragma once
// What the workflow's test suites share: the LWR IV, a simulated one standing bent, options that
// learn in the calling thread, and running the workflow's cycles for a while.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "app/workflow.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app::workflow_rigs {

inline const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

/// Learning in the calling thread (update() returns with the model), `hidden` ELM neurons.
inline WorkflowOptions syncOptions(int hidden = 30) {
  WorkflowOptions options;
  options.background_learning = false;
  options.elm.hidden = hidden;
  return options;
}

/// `seconds` of 1 ms cycles.
inline void run(Workflow& workflow, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / 1e-3));
  for (int i = 0; i < steps; ++i) workflow.step();
}

/// The simulated LWR IV without a scene, at rest with shoulder, elbow and wrist bent.
struct SimulatedLwr4 {
  SimulatedLwr4() : declarations(robot::reachParameters()), parameters(declarations), sim(lwr4(), nullptr, parameters) {
    Eigen::VectorXd q = lwr4().midPosture();
    q[1] = 0.6;
    q[3] = -1.4;
    q[5] = 0.7;
    sim.reset(q);
  }
  WorkflowOptions options() const { return syncOptions(); }
  robot::RobotState state() const {
    robot::RobotState s;
    s.resize(lwr4().dof());
    sim.readState(s);
    return s;
  }
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
  robot::Simulation sim;
};

}  // namespace flexirob::app::workflow_rigs
