#include "robot/sim/reach.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "robot/errors.hpp"
#include "robot/interaction.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::robot {

std::vector<ParameterDeclaration> reachParameters() {
  std::vector<ParameterDeclaration> all;
  for (auto declarations : {hierarchicalParameters(), limiterParameters(), simulationParameters()}) {
    all.insert(all.end(), declarations.begin(), declarations.end());
  }
  return all;
}

std::vector<ParameterDeclaration> sceneTunableParameters() {
  std::vector<ParameterDeclaration> all = reachParameters();
  const auto interaction = interactionParameters();
  all.insert(all.end(), interaction.begin(), interaction.end());
  return all;
}

ReachResult reach(const RobotModel& model, const Scene* scene, const ParameterSet& parameters,
                  const ReachRequest& request) {
  if (!request.target.allFinite()) throw InputError("target: expected three finite numbers");
  const Eigen::VectorXd start = model.withinOneTurn(request.start.size() == 0 ? model.midPosture() : request.start);
  model.checkPosture(start);
  const Eigen::VectorXd posture = model.withinOneTurn(request.posture.size() == 0 ? start : request.posture);
  model.checkPosture(posture);
  if (!(request.tolerance > 0.0) || !(request.max_time > 0.0) || !(request.stall_time > 0.0)) {
    throw InputError("reach: tolerance, max_time and stall_time must be positive");
  }

  Simulation sim(model, scene, parameters);
  sim.reset(start);
  HierarchicalController controller(model, parameters);
  CommandLimiter limiter(model, parameters, sim.cycleTime());
  limiter.reset(start);

  // Hierarchical control gains of Tab. A.1: 300 Nm/rad, damping 0.95; for an arm lighter than
  // the LWR IV in proportion to its joints' inertia, as the workflow scales them.
  JointImpedanceCommand command;
  command.resize(model.dof());
  command.stiffness.setConstant(300.0 * inertiaScaleToLwr(model));
  command.damping.setConstant(0.95);
  RobotState state;
  state.resize(model.dof());
  Eigen::VectorXd qd(model.dof());

  ReachResult result;
  result.best_error_m = std::numeric_limits<double>::infinity();
  double progress_error = std::numeric_limits<double>::infinity();  // best reference error at the last progress
  double progress_time = 0.0;
  double reached_since = -1.0;
  const auto max_steps = static_cast<std::uint64_t>(std::ceil(request.max_time / sim.cycleTime()));
  // A joint allowed 0.02 rad/s needs 50 s where the LWR IV's need 1: judge progress on the arm's
  // own time scale (the LWR IV's slowest joint allows 1.9 rad/s, and keeps the stall time unless
  // limits.velocity_scale slows it below 1 rad/s).
  const double slowest = limiter.velocityLimit().minCoeff();
  const double stall_time = request.stall_time * std::max(1.0, 1.0 / std::max(slowest, 1e-6));
  result.status = "timeout";
  for (std::uint64_t k = 0; k < max_steps; ++k) {
    // Eq. 2.11 integrated on the previous command, smoothed and clamped (Sect. 8.1).
    controller.velocity(limiter.command(), request.target, posture, qd, &limiter);
    command.q_cmd = limiter.updateVelocity(qd);
    if (sim.writeCommand(command) != CommandStatus::kAccepted) ++result.rejected_commands;
    sim.step();
    sim.readState(state);
    const double error = (state.p_WT() - request.target).norm();
    result.best_error_m = std::min(result.best_error_m, error);
    // Progress of the controller's own reference (its task error at the command).
    const double reference_error = controller.taskError();
    if (k == 0 || reference_error < progress_error - std::max(1e-6, 0.01 * progress_error)) {
      progress_error = reference_error;
      progress_time = state.time;
    }
    const bool at_rest = limiter.velocity().norm() < 1e-3 && state.qd.norm() < 1e-3;
    if (error <= request.tolerance) {
      if (reached_since < 0) reached_since = state.time;
      // Done once the null-space motion has settled too, or the tip has held for a while.
      if (at_rest || state.time - reached_since > 1.0) {
        result.status = "reached";
        break;
      }
    } else {
      reached_since = -1.0;
      if (reference_error > request.tolerance && state.time - progress_time > stall_time) {
        result.status = "unreachable";
        break;
      }
    }
  }
  result.steps = sim.steps();
  result.time_s = sim.time();
  result.q = state.q;
  result.position = state.p_WT();
  result.error_m = (state.p_WT() - request.target).norm();
  result.posture_error_rad = model.postureDifference(state.q, posture).norm();
  // The command, which the limiter holds on a limit exactly, not the measured posture around it.
  const Eigen::VectorXd& commanded = limiter.command();
  for (int j = 0; j < model.dof(); ++j) {
    if (std::min(commanded[j] - model.softLowerLimits()[j], model.softUpperLimits()[j] - commanded[j]) < 1e-6) {
      result.joints_at_limits.push_back(model.joints()[static_cast<std::size_t>(j)].name);
    }
  }
  result.collisions = sim.collisions().events();
  result.colliding_steps = sim.collisions().collidingSteps();
  const CollisionWorld& world = *sim.collisionWorld();
  for (const auto& event : sim.collisions().eventLog()) {
    if (result.collision_events.size() >= 20) break;
    result.collision_events.push_back(
        {event.time, world.bodyName(event.contact.body), world.otherName(event.contact), event.contact.isSelfCollision()});
  }
  result.clamps = controller.counters();
  result.clamps += limiter.counters();
  result.null_space_scaled = controller.nullSpaceScaled();
  result.torque_saturations = sim.torqueSaturations();
  result.max_substeps = sim.maxSubsteps();
  const std::array<std::pair<const Eigen::VectorXd*, const char*>, 2> checked = {
      {{&start, "the start"}, {&result.q, "the final posture"}}};
  for (const auto& [checked_q, where] : checked) {
    const Simulation::GravityLoad load = sim.gravityLoad(*checked_q);
    if (load.ratio > 1.0) {
      result.gravity_overload = std::string("at ") + where + " the arm needs " + sim.describe(load);
      break;
    }
  }
  return result;
}

}  // namespace flexirob::robot
