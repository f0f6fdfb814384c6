#include "app/simulated_tutor.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <thread>

#include "app/evaluation.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::app {
namespace {

// The tutor's hands: a joint-space PD realized by forces on several links (a person pushes the
// upper arm, the elbow and the wrist); the single simulated hand visits the points in turn, each
// with its share scaled up, so that the mean torque is the PD torque.
constexpr double kJointStiffness = 36.0;  // [1/s²] times the joint inertia: about 1 Hz
constexpr double kJointDamping = 12.0;    // [1/s] times the joint inertia: critically damped
constexpr double kJointIntegral = 60.0;   // [1/s³] times the joint inertia
constexpr double kMaxPointForce = 150.0;  // [N]
// [rad] how far the tutor's reference may run ahead of the arm (largest joint): a person leads the
// arm along the way and waits where it lags, rather than pulling it across the corners.
// Unbounded, its lead reached 0.5 rad on the 9-DoF arm and the links cut across the planned way
// into the bridge and into the arm's own base.
constexpr double kMaxLead = 0.05;
// [rad] of any joint between the arm and the tutor's reference at which the tutor lets go.
constexpr double kRunOffError = 0.5;
// [rad] (largest joint) an arm that on_converged poses at the end of the way may stand off the
// chosen posture and still be taken as there, as a person sees it.
constexpr double kPosedTolerance = 0.02;
constexpr double kTipStiffness = 1500.0;  // [N/m] of the hand drawing circles
constexpr double kTipDamping = 60.0;      // [Ns/m]
constexpr double kMaxTipForce = 60.0;     // [N]
// Assistance blending (Eq. 6.2) weighs the learned posture by α = C(x) everywhere. Below this
// confidence the tutor's pushes on the links take over from leading the tip: the hands then
// move the null space at four fifths of their push or more (0.1 and 0.4 made more contacts in
// setups I, A, II, B and C, docs/WORKFLOW.md).
constexpr double kYieldingConfidence = 0.2;
// A released arm's null space drifts towards q_c wherever C(x) > 0; above this it takes seconds.
constexpr double kDriftingConfidence = 1e-3;
constexpr double kLeadSpeed = 0.1;  // [m/s] of the tip led out of the assistance
// The fastest a small helix is drawn, as a multiple of TutorOptions::circle_period's pace.
constexpr double kMaxHelixPace = 8.0;
// A recording spanning less than this fraction of the helix drawn is a spot, not an area: the arm
// did not follow the hands (held at its joint limits, or by its own links).
constexpr double kMinSpanOfTheHelix = 0.25;
// [N] of a hand's touch at the tip that starts an approach or a recording; where the robot does
// not notice it (a tip near the base, a small arm), a person presses harder, up to the firmest.
constexpr double kFirmPush = 15.0;
constexpr double kFirmestPush = 60.0;

// Twice the largest distance of a column of X from the columns' mean [m].
double spanOf(const Eigen::MatrixXd& X) {
  if (X.cols() == 0) return 0.0;
  const Eigen::Vector3d mean = X.rowwise().mean();
  return 2.0 * (X.colwise() - mean).colwise().norm().maxCoeff();
}

}  // namespace

std::string failureKinds(const std::vector<TutorAreaReport>& areas) {
  std::vector<std::pair<std::string, int>> kinds;  // in the order first met
  for (const TutorAreaReport& area : areas) {
    if (area.taught || area.failure.empty()) continue;
    const std::string kind = area.failure.substr(0, std::min(area.failure.find(" ("), area.failure.find(": ")));
    const auto known = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == kind; });
    if (known == kinds.end()) {
      kinds.emplace_back(kind, 1);
    } else {
      ++known->second;
    }
  }
  std::stable_sort(kinds.begin(), kinds.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string text;
  for (const auto& [kind, count] : kinds) text += (text.empty() ? "" : ", ") + std::to_string(count) + " × " + kind;
  return text;
}

SimulatedTutor::SimulatedTutor(robot::Simulation& sim, Workflow& workflow, const robot::Scene& scene,
                               const robot::ParameterSet& parameters, TutorOptions options)
    : sim_(&sim),
      workflow_(&workflow),
      scene_(&scene),
      model_(&sim.model()),
      parameters_(parameters),
      options_(std::move(options)),
      world_(std::make_unique<robot::CollisionWorld>(sim.model(), scene)),
      kinematics_(sim.model()),
      arm_reach_(armReach(sim.model())),
      arm_scale_(workflow.armScale()),
      min_clearance_(arm_scale_.length * options_.min_clearance),
      circle_diameter_(std::max(kSmallestCircleDiameter, arm_scale_.length * options_.circle_diameter)),
      home_(options_.home ? *options_.home : homePosture(sim.model(), scene)),
      random_(options_.seed),
      second_round_random_(options_.seed + 0x5ec0d) {
  if (home_.size() != model_->dof()) throw InputError("tutor: the home posture has the wrong number of joints");
  if (!(options_.circle_diameter >= kSmallestCircleDiameter) || options_.circle_diameter > kLargestCircleDiameter) {
    std::ostringstream message;
    message << "tutor: circle diameter must be in [" << kSmallestCircleDiameter << ", " << kLargestCircleDiameter
            << "] m, got " << options_.circle_diameter;
    throw InputError(message.str());
  }
  if (options_.circles < 1 || options_.posture_candidates < 1 || options_.posture_attempts < 1) {
    throw InputError("tutor: circles, candidates and posture attempts must be >= 1");
  }
  if (options_.check_points < 0) throw InputError("tutor: check points must be >= 0");
  state_.resize(model_->dof());
}

SimulatedTutor::~SimulatedTutor() = default;

void SimulatedTutor::tick() {
  workflow_->step();
  ++ticks_;
  if (options_.realtime) {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    if (wall_start_ < 0.0) wall_start_ = now - arm()->time();
    const double ahead = arm()->time() - (now - wall_start_);
    if (ahead > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(ahead));
  }
  const LockedArm held = arm();
  held->readState(state_);
  if (options_.on_cycle) options_.on_cycle(state_);
  stopIfAsked();
}

void SimulatedTutor::stopIfAsked() const {
  if (options_.stop_requested && options_.stop_requested()) throw StopRequested{};
}

void SimulatedTutor::updateReport() {
  report_.collisions = arm()->collisions().events();
  report_.colliding_steps = arm()->collisions().collidingSteps();
  report_.simulated_time = arm()->time();
}

double SimulatedTutor::pathClearance(const std::vector<Eigen::VectorXd>& path) {
  double clearance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const double length = (path[i + 1] - path[i]).cwiseAbs().maxCoeff();
    const int samples = std::max(2, static_cast<int>(std::ceil(length / 0.02)));
    for (int s = 0; s <= samples; ++s) {
      const Eigen::VectorXd q = path[i] + (path[i + 1] - path[i]) * (static_cast<double>(s) / samples);
      world_->update(q);
      if (!world_->contacts().empty()) return -1.0;
      clearance = std::min(clearance, world_->clearance(0.5).distance);
    }
  }
  return clearance;
}

bool SimulatedTutor::postureFree(const Eigen::VectorXd& q, double margin) {
  world_->update(q);
  if (!world_->contacts().empty()) return false;
  // A person leading the arm keeps its links apart as well as off the obstacles: the hands
  // lag behind the joint-space path, and a fold planned with zero margin ends in a contact.
  return world_->clearance(std::max(0.05, 2.0 * margin)).distance >= margin &&
         world_->selfClearance(3, 2.0 * margin) >= margin;
}

std::string SimulatedTutor::describePosture(const Eigen::VectorXd& q) {
  world_->update(q);
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  if (!world_->contacts().empty()) {
    const robot::Contact& contact = world_->contacts().front();
    out << "a posture in contact (" << world_->bodyName(contact.body) << " on " << world_->otherName(contact) << ", "
        << 1000.0 * contact.depth << " mm deep)";
    return out.str();
  }
  const robot::Clearance clearance = world_->clearance(0.5);
  if (clearance.obstacle < 0) return "a posture more than 50 cm from every obstacle";
  out << "a posture " << 100.0 * clearance.distance << " cm from " << world_->obstacleName(clearance.obstacle) << " ("
      << world_->bodyName(clearance.body) << "), ";
  const double links = world_->selfClearance(3, 0.5);
  if (std::isfinite(links)) {
    out << 100.0 * links << " cm between its links";
  } else {
    out << "its links more than 50 cm apart";
  }
  return out.str();
}

bool SimulatedTutor::helixFree(const Eigen::VectorXd& q_fixed, const std::vector<Eigen::Vector3d>& helix, double margin) {
  robot::HierarchicalController controller(*model_, parameters_);
  controller.useForKinematicSearch();
  const Eigen::VectorXd lower = model_->softLowerLimits();
  const Eigen::VectorXd upper = model_->softUpperLimits();
  Eigen::VectorXd q = q_fixed, q_target(q.size());
  for (const Eigen::Vector3d& p : helix) {
    // π_rec: Eq. 2.11 with q_fixed as null-space target; iterated to its rest posture at p.
    for (int it = 0; it < 200; ++it) {
      controller.target(q, p, q_fixed, 0.02, q_target);
      q = q_target.cwiseMax(lower).cwiseMin(upper);
      if (controller.taskError() < 1e-4 && it > 10) break;
    }
    if (!postureFree(q, margin)) return false;
  }
  return true;
}

bool SimulatedTutor::segmentFree(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double margin) {
  // Samples every 0.02 rad of the largest joint motion: at the LWR's 1.1 m reach a tip moves
  // at most about 2 cm between samples, the order of the margin.
  const double length = (b - a).cwiseAbs().maxCoeff();
  const int samples = std::max(1, static_cast<int>(std::ceil(length / 0.02)));
  for (int s = 1; s <= samples; ++s) {
    if (!postureFree(a + (b - a) * (static_cast<double>(s) / samples), margin)) return false;
  }
  return true;
}

std::vector<Eigen::VectorXd> SimulatedTutor::planApproach(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                                         double margin) {
  if (segmentFree(from, to, margin)) return {from, to};
  // The start may itself lie closer to an obstacle than the margin (the arm rests where the
  // last recording ended): edges leaving it need only be contact-free, their ends keep the margin.
  const int dof = model_->dof();
  // Random samples; one turn for an unbounded joint.
  const Eigen::VectorXd sample_lower = model_->sampleLowerLimits();
  const Eigen::VectorXd sample_upper = model_->sampleUpperLimits();
  constexpr double kStep = 0.25;  // [rad] largest joint change per tree edge
  struct Tree {
    std::vector<Eigen::VectorXd> nodes;
    std::vector<int> parent;
  };
  Tree start_tree{{from}, {-1}};
  Tree goal_tree{{to}, {-1}};
  const auto nearest = [](const Tree& tree, const Eigen::VectorXd& q) {
    int best = 0;
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
      const double d = (tree.nodes[i] - q).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best = static_cast<int>(i);
      }
    }
    return best;
  };
  // One step from the nearest node towards q; returns the new node's index or -1.
  const auto extend = [&](Tree& tree, const Eigen::VectorXd& q, bool& arrived) {
    const int near = nearest(tree, q);
    const Eigen::VectorXd& q_near = tree.nodes[static_cast<std::size_t>(near)];
    const Eigen::VectorXd delta = q - q_near;
    const double length = delta.cwiseAbs().maxCoeff();
    arrived = length <= kStep;
    const Eigen::VectorXd q_new = arrived ? q : Eigen::VectorXd(q_near + delta * (kStep / length));
    // The first edge out of a start closer than the margin may only move away from the obstacle.
    const bool from_start = near == 0 && &tree == &start_tree && !postureFree(q_near, margin);
    if (from_start ? !segmentFree(q_near, q_new, 0.0) || !postureFree(q_new, margin) : !segmentFree(q_near, q_new, margin)) {
      arrived = false;
      return -1;
    }
    tree.nodes.push_back(q_new);
    tree.parent.push_back(near);
    return static_cast<int>(tree.nodes.size()) - 1;
  };
  Tree* a = &start_tree;
  Tree* b = &goal_tree;
  Eigen::VectorXd q_rand(dof);
  for (int it = 0; it < options_.approach_iterations; ++it) {
    q_rand = random_.uniform(sample_lower, sample_upper);
    bool arrived = false;
    const int added = extend(*a, q_rand, arrived);
    if (added >= 0) {
      // Connect: the other tree grows towards the new node until it arrives or is blocked.
      const Eigen::VectorXd target = a->nodes[static_cast<std::size_t>(added)];
      int last = -1;
      bool connected = false;
      for (int k = 0; k < 200; ++k) {
        const int grown = extend(*b, target, connected);
        if (grown < 0) break;
        last = grown;
        if (connected) break;
      }
      if (connected && last >= 0) {
        const auto branch = [](const Tree& tree, int node) {
          std::vector<Eigen::VectorXd> out;
          for (int i = node; i >= 0; i = tree.parent[static_cast<std::size_t>(i)]) out.push_back(tree.nodes[static_cast<std::size_t>(i)]);
          return out;
        };
        std::vector<Eigen::VectorXd> from_side = branch(start_tree, a == &start_tree ? added : last);
        std::vector<Eigen::VectorXd> to_side = branch(goal_tree, a == &start_tree ? last : added);
        std::reverse(from_side.begin(), from_side.end());
        std::vector<Eigen::VectorXd> path = from_side;
        path.insert(path.end(), to_side.begin() + 1, to_side.end());
        // Shortcuts: a person takes the direct way where it is free.
        for (int s = 0; s < 150 && path.size() > 2; ++s) {
          const std::size_t i = random_.index(path.size() - 2);
          const std::size_t k = i + 2 + random_.index(path.size() - i - 2);
          if (k >= path.size()) continue;
          if (i == 0 && !postureFree(path[0], margin)) continue;
          if (segmentFree(path[i], path[k], margin)) path.erase(path.begin() + static_cast<std::ptrdiff_t>(i + 1), path.begin() + static_cast<std::ptrdiff_t>(k));
        }
        return path;
      }
    }
    std::swap(a, b);
  }
  return {};
}

double SimulatedTutor::signedClearance(const Eigen::VectorXd& q) {
  constexpr double kRange = 0.2;  // [m] beyond it every posture is as good (and the value finite)
  world_->update(q);
  // Inside, the depths of every touching pair summed, the pairs postureFree counts included:
  // climbing the deepest alone stalls where two links are in equally deep.
  if (!world_->contacts().empty()) {
    double depth = 0.0;
    for (const robot::Contact& contact : world_->contacts()) depth += contact.depth;
    return -depth;
  }
  return std::min({world_->clearance(kRange).distance, world_->selfClearance(3, kRange), kRange});
}

std::vector<Eigen::VectorXd> SimulatedTutor::planRetreat(const Eigen::VectorXd& from, double margin) {
  const int dof = model_->dof();
  const Eigen::VectorXd lower = model_->softLowerLimits();
  const Eigen::VectorXd upper = model_->softUpperLimits();
  constexpr double kProbe = 0.005;  // [rad] central differences
  constexpr double kStepOut = 0.02;  // [rad] of the largest joint per step, as segmentFree samples
  std::vector<Eigen::VectorXd> path{from};
  Eigen::VectorXd q = from.cwiseMax(lower).cwiseMin(upper);
  double clearance = signedClearance(q);
  Eigen::VectorXd gradient(dof), probe(dof);
  // Where the climb stalls short of the margin (the nearest pair changes, and every step along
  // the gradient ends lower), an arm already out of every contact is free: the way on may leave
  // a start nearer than its margin (planApproach).
  const auto outOrNothing = [&]() -> std::vector<Eigen::VectorXd> {
    if (clearance > 0.0 && path.size() > 1 && postureFree(q, 0.0)) return path;
    return {};
  };
  for (int it = 0; it < 150; ++it) {
    if (clearance >= margin && postureFree(q, margin)) return path;
    for (int j = 0; j < dof; ++j) {
      probe = q;
      probe[j] = std::min(q[j] + kProbe, upper[j]);
      const double up = signedClearance(probe);
      probe[j] = std::max(q[j] - kProbe, lower[j]);
      const double down = signedClearance(probe);
      gradient[j] = (up - down) / std::max(1e-9, std::min(q[j] + kProbe, upper[j]) - std::max(q[j] - kProbe, lower[j]));
    }
    if (gradient.cwiseAbs().maxCoeff() < 1e-6) return outOrNothing();
    // The step shrinks until the clearance grows at its end and nowhere on it falls (looked at
    // every quarter): the nearest pairs may change on the way.
    bool improved = false;
    for (double step = kStepOut; step > 1e-3 && !improved; step *= 0.5) {
      probe = (q + gradient * (step / gradient.cwiseAbs().maxCoeff())).cwiseMax(lower).cwiseMin(upper);
      const double next = signedClearance(probe);
      if (!(next > clearance)) continue;
      improved = true;
      for (int k = 1; k < 4 && improved; ++k) improved = signedClearance(q + (probe - q) * (0.25 * k)) >= clearance;
      if (improved) {
        q = probe;
        clearance = next;
      }
    }
    if (!improved) return outOrNothing();
    path.push_back(q);
  }
  return outOrNothing();
}

std::vector<Eigen::VectorXd> SimulatedTutor::planWay(const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  // An approach that was given up can leave the arm resting on an obstacle (a let-go under
  // assistance blending, setup_B): a person first pulls it free, then leads it on. Every way
  // planned from inside the contact fails, and every later area with it.
  std::vector<Eigen::VectorXd> retreat;
  Eigen::VectorXd start = from;
  if (!postureFree(from, 0.0)) {
    retreat = planRetreat(from, 0.5 * min_clearance_);
    if (retreat.empty()) return {};
    start = retreat.back();
  }
  std::vector<Eigen::VectorXd> path = planApproach(start, to, min_clearance_);
  if (path.empty()) path = planApproach(start, to, 0.5 * min_clearance_);
  if (path.empty() || retreat.empty()) return path;
  retreat.insert(retreat.end(), path.begin() + 1, path.end());
  return retreat;
}

std::vector<PostureChoice> SimulatedTutor::choosePostures(const Eigen::Vector3d& p_W, const std::optional<Eigen::VectorXd>& suggested,
                                                          int* reaching, bool push_links_clear, const Eigen::VectorXd& known_to_reach) {
  if (reaching != nullptr) *reaching = 0;
  too_heavy_candidates_ = 0;
  lightest_rejected_ = {};
  // A person does not choose a posture the arm cannot hold up against gravity.
  const auto holdable = [&](const Eigen::VectorXd& q_candidate) {
    const robot::Simulation::GravityLoad load = arm()->gravityLoad(q_candidate);
    if (load.ratio <= kHoldableLoad) return true;
    ++too_heavy_candidates_;
    if (too_heavy_candidates_ == 1 || load.ratio < lightest_rejected_.ratio) lightest_rejected_ = load;
    return false;
  };
  const int dof = model_->dof();
  const Eigen::VectorXd lower = model_->softLowerLimits();
  const Eigen::VectorXd upper = model_->softUpperLimits();
  const Eigen::VectorXd sample_lower = model_->sampleLowerLimits();
  const Eigen::VectorXd sample_upper = model_->sampleUpperLimits();
  robot::HierarchicalController controller(*model_, parameters_);
  controller.useForKinematicSearch();
  struct Candidate {
    PostureChoice choice;
    double score;
  };
  std::vector<Candidate> candidates;
  Eigen::VectorXd q(dof), q_target(dof);
  // A person leads the arm on from the posture of the nearest area already taught and changes
  // the arm's configuration only where the obstacles ask for it (Sect. 4.2.1: the tutor's
  // postures share q2 ≈ π/2 over the whole setup): consistent postures let the learner
  // interpolate between areas instead of averaging different IK families.
  Eigen::VectorXd q_reference = state_.q.size() == dof ? state_.q : model_->midPosture();
  double nearest_area = std::numeric_limits<double>::infinity();
  for (const TrainingArea& area : workflow_->areas()) {
    const double d = (area.centre - p_W).norm();
    if (d < nearest_area && area.q_fixed.size() == dof) {
      nearest_area = d;
      q_reference = area.q_fixed;
    }
  }
  // Asked to, the scene's suggested posture is the reference: the one its author wants shown.
  if (options_.follow_scene_postures && suggested && suggested->size() == dof) q_reference = *suggested;
  // Clearance up to a comfortable 8 cm counts; beyond it, the posture nearest the reference
  // (joint-space distance, 0.2 per rad: 4 cm less clearance weigh as much as 2.5 rad) wins.
  // Postures near a joint limit are penalized: they would warn, and the hands' deflections
  // under π_rec would run the joint into its stop. Near: within 0.2 rad (a little beyond the
  // warning's 0.17), a slide as the warning counts it (2 cm), each at most a tenth of the travel
  // (0.2 m had put every posture of a short slide near, and the slide was parked at its stop).
  const auto near_limit = [&](const Eigen::VectorXd& q_candidate) {
    for (int j = 0; j < dof; ++j) {
      const robot::Joint& joint = model_->joints()[static_cast<std::size_t>(j)];
      const double near = joint.type == robot::JointType::kPrismatic
                              ? nearLimitMargin(joint, workflow_->options())
                              : std::min(0.2, 0.1 * (joint.limits.soft_upper - joint.limits.soft_lower));
      if (std::min(q_candidate[j] - lower[j], upper[j] - q_candidate[j]) < near) return true;
    }
    return false;
  };
  const auto score = [&](const Eigen::VectorXd& q_candidate, double clearance) {
    return std::min(clearance, scaled(0.08)) / scaled(0.08) - 0.2 * (q_candidate - q_reference).norm() - (near_limit(q_candidate) ? 0.5 : 0.0);
  };
  // A second round of draws over the joints' whole range where the first found no posture
  // that reaches the place without a contact: a place near the edge of the arm's reach may take
  // a joint beyond the middle of its range, and the places the tutor chooses itself were found
  // reachable from the start posture or over the whole range (accessibleWithoutCollision).
  const int draws = options_.posture_candidates;
  for (int c = 0; c < 2 * draws; ++c) {
    stopIfAsked();
    if (c == draws && !candidates.empty()) break;
    // Null-space targets: the scene's suggestion, the reference posture, the current posture,
    // then random postures drawn inside the limits (kept away from them by a fifth of the range
    // in the first round).
    Eigen::VectorXd q_null(dof);
    if (c >= draws) {
      if (c == draws && known_to_reach.size() == dof) {
        q_null = known_to_reach;
      } else if (c == draws + 1 && home_.size() == dof) {
        q_null = home_;
      } else {
        q_null = second_round_random_.uniform(sample_lower, sample_upper);
      }
    } else if (c == 0 && suggested && suggested->size() == dof) {
      q_null = *suggested;
    } else if (c <= 1) {
      q_null = q_reference;
    } else if (c == 2) {
      q_null = state_.q.size() == dof ? state_.q : model_->midPosture();
    } else {
      const Eigen::VectorXd margin = 0.2 * (sample_upper - sample_lower);
      q_null = random_.uniform(sample_lower + margin, sample_upper - margin);
    }
    // Kinematic IK with the hierarchical controller (Eq. 2.11), started at the null target.
    q = q_null.cwiseMax(lower).cwiseMin(upper);
    for (int it = 0; it < 400; ++it) {
      controller.target(q, p_W, q_null, 0.02, q_target);
      q = q_target.cwiseMax(lower).cwiseMin(upper);
      if (controller.taskError() < 1e-5 && it > 50) break;
    }
    kinematics_.update(q);
    if ((kinematics_.p_WT() - p_W).norm() > 1e-3) continue;
    if (reaching != nullptr) ++*reaching;
    world_->update(q);
    if (!world_->contacts().empty() || !holdable(q)) continue;
    const double clearance = world_->clearance(0.5).distance;
    candidates.push_back({PostureChoice{clearance >= min_clearance_, q, clearance}, score(q, clearance)});
  }
  // Where no candidate keeps the clearance, a person takes the best postures found and pushes
  // the links away from what they come close to; they stay in the family the score chose.
  const auto keeps_clearance = [](const Candidate& candidate) { return candidate.choice.found; };
  if (push_links_clear && options_.clearing_candidates > 0 && !candidates.empty() &&
      std::none_of(candidates.begin(), candidates.end(), keeps_clearance)) {
    std::vector<Candidate> best = candidates;
    std::stable_sort(best.begin(), best.end(), [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    best.resize(std::min(best.size(), static_cast<std::size_t>(options_.clearing_candidates)));
    for (const Candidate& start : best) {
      q = postureClearOfObstacles(p_W, start.choice.q);
      kinematics_.update(q);
      if ((kinematics_.p_WT() - p_W).norm() > 1e-3) continue;
      world_->update(q);
      if (!world_->contacts().empty() || !holdable(q)) continue;
      const double clearance = world_->clearance(0.5).distance;
      if (clearance <= start.choice.clearance) continue;
      candidates.push_back({PostureChoice{clearance >= min_clearance_, q, clearance}, score(q, clearance)});
    }
  }
  // A posture with the clearance asked for beats every one without it, however near the
  // reference that one lies; otherwise the area would be given up with a usable posture found.
  // Among equals the higher score wins, and the earlier candidate on a tie.
  std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.choice.found != b.choice.found ? a.choice.found : a.score > b.score;
  });
  std::vector<PostureChoice> ranked;
  for (const Candidate& candidate : candidates) {
    if (static_cast<int>(ranked.size()) >= std::max(1, options_.posture_attempts)) break;
    if (!ranked.empty() && !candidate.choice.found) break;
    // IK from different null-space targets often lands on the same posture.
    const bool distinct = std::all_of(ranked.begin(), ranked.end(), [&](const PostureChoice& taken) {
      return (candidate.choice.q - taken.q).norm() > 0.05;
    });
    if (distinct) ranked.push_back(candidate.choice);
  }
  return ranked;
}

Eigen::VectorXd SimulatedTutor::postureClearOfObstacles(const Eigen::Vector3d& p_W, const Eigen::VectorXd& q_start) {
  const double influence = scaled(0.08);  // [m] obstacles farther away do not push
  constexpr double kPush = 1.0;        // [rad per m of intrusion into influence, per unit of the Jacobian]
  constexpr double kMaxStep = 0.05;    // [rad] per iteration, and [m] of task error corrected per iteration
  const int dof = model_->dof();
  const Eigen::VectorXd lower = model_->softLowerLimits();
  const Eigen::VectorXd upper = model_->softUpperLimits();
  Eigen::VectorXd q = q_start.cwiseMax(lower).cwiseMin(upper);
  robot::Matrix3Xd J(3, dof), J_point(3, dof);
  for (int it = 0; it < 1500; ++it) {
    kinematics_.update(q);
    kinematics_.tipPositionJacobian(J);
    Eigen::Vector3d error = p_W - kinematics_.p_WT();
    if (error.norm() > kMaxStep) error *= kMaxStep / error.norm();
    // Damped pseudo-inverse of the tip's Jacobian, and its null space (Eq. 2.11).
    const Eigen::Matrix3d JJt = J * J.transpose() + 1e-4 * Eigen::Matrix3d::Identity();
    const Eigen::MatrixXd J_pinv = J.transpose() * JJt.inverse();
    Eigen::VectorXd dq = J_pinv * error;
    world_->update(q);
    const robot::Clearance nearest = world_->clearance(influence);
    if (nearest.body >= 1 && nearest.obstacle >= 0 && nearest.distance < influence) {
      // Apart, the witness points lead from the obstacle to the link; in contact, the other way.
      Eigen::Vector3d away = nearest.p_body_W - nearest.p_obstacle_W;
      if (nearest.distance < 0.0) away = -away;
      if (away.norm() > 1e-9) {
        kinematics_.pointJacobian(nearest.body, nearest.p_body_W, J_point);
        const Eigen::VectorXd push = J_point.transpose() * away.normalized() * (kPush * (influence - nearest.distance));
        dq += push - J_pinv * (J * push);
      }
    }
    if (dq.norm() > kMaxStep) dq *= kMaxStep / dq.norm();
    q = (q + dq).cwiseMax(lower).cwiseMin(upper);
    if (error.norm() < 1e-6 && dq.norm() < 1e-5) break;
  }
  return q;
}

bool SimulatedTutor::waitFor(SubStage sub_stage, double max_time) {
  arm()->clearHandForce();
  const double until = arm()->time() + max_time;
  while (workflow_->subStage() != sub_stage) {
    if (arm()->time() > until) return false;
    tick();
  }
  return true;
}

bool SimulatedTutor::grab(SubStage sub_stage, const Eigen::Vector3d& direction) {
  // A firm touch at the tip, held until the workflow takes it (on_affected, which fires for a
  // touch that began on a still arm; one that began while the arm moved waits until the arm has
  // come to rest under the hand, a second or two on an 80 Nm/rad arm).
  // 15 N for up to 3 s; if the robot has not noticed (a tip near the base, a small arm: the
  // torques stay under the trigger's threshold), a person presses harder, up to 60 N, enough
  // for twice the threshold at some joint, for 3 s more.
  Eigen::Vector3d push = direction.normalized();
  kinematics_.update(state_.q);
  robot::Matrix3Xd Jp(3, model_->dof());
  kinematics_.tipPositionJacobian(Jp);
  double torque_per_newton = (Jp.transpose() * push).cwiseAbs().maxCoeff();
  // A push no joint feels (an arm standing straight up, pushed in a vertical plane through its
  // base: every joint axis meets or parallels the line of the force) cannot be noticed at any
  // force; a person pushes where the arm gives instead, the direction the tip moves most
  // easily (towards the way to go where that has a part along it; either way where not).
  const double firm = kFirmPush * arm_scale_.force(), firmest = kFirmestPush * arm_scale_.force();
  if (firmest * torque_per_newton < workflow_->affectedTorque()) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jp, Eigen::ComputeThinU);
    Eigen::Vector3d gives = svd.matrixU().col(0);
    if (gives.dot(push) < 0.0) gives = -gives;
    push = gives;
    torque_per_newton = (Jp.transpose() * push).cwiseAbs().maxCoeff();
  }
  const double firmer =
      std::clamp(2.0 * workflow_->affectedTorque() / std::max(torque_per_newton, 1e-6), firm, firmest);
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (attempt == 1 && firmer <= firm) break;
    const double force = attempt == 0 ? firm : firmer;
    const double until = arm()->time() + 3.0;
    while (workflow_->subStage() == sub_stage && arm()->time() <= until) {
      arm()->setHandForce(model_->dof(), state_.p_WT(), force * push);
      tick();
    }
    if (workflow_->subStage() != sub_stage) return true;
  }
  arm()->clearHandForce();
  return false;
}

bool SimulatedTutor::pushAlong(const std::vector<Eigen::VectorXd>& path, double speed) {
  const int dof = model_->dof();
  // Points the hands push: every body but the first, 6 cm off the body's origin (alternately
  // along its x and y axes, so that rotations about any link axis can be pushed), never along
  // the body's own joint axis: a push at a point on that axis cannot turn the joint (a 3-DoF
  // arm with two parallel y axes stalled 0.05 rad short of every posture).
  std::vector<int> bodies;
  std::vector<Eigen::Vector3d> offsets;
  for (int b = 2; b <= dof; ++b) {
    const bool even = bodies.size() % 2 == 0;
    Eigen::Vector3d along = even ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    if (std::abs(along.dot(model_->joints()[static_cast<std::size_t>(b - 1)].axis_J)) > 0.9) {
      along = even ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    }
    bodies.push_back(b);
    offsets.push_back(scaled(0.06) * along);
  }
  const auto m = static_cast<int>(bodies.size());
  const auto offset = [&offsets](int i) { return offsets[static_cast<std::size_t>(i)]; };
  std::vector<Eigen::Vector3d> forces(static_cast<std::size_t>(m));
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(m));
  robot::Matrix3Xd Jp(3, dof);
  Eigen::MatrixXd A(dof, 3 * m);
  Eigen::VectorXd q_ref = state_.q;
  Eigen::VectorXd integral = Eigen::VectorXd::Zero(dof);
  std::size_t next = 1;
  const double dt = arm()->cycleTime();
  double path_length = 0.0;  // [rad] of the largest joint, what the reference needs speed for
  for (std::size_t i = 0; i + 1 < path.size(); ++i) path_length += (path[i + 1] - path[i]).cwiseAbs().maxCoeff();
  const double deadline = arm()->time() + path_length / speed + options_.max_phase_time;
  int phase = 0;
  // The hands push one body per cycle, which leaves light links of a long arm vibrating slightly
  // at rest: averaged over 0.1 s the joint speed tells whether the arm still moves.
  Eigen::VectorXd qd_mean = state_.qd;
  while (true) {
    qd_mean += (dt / 0.1) * (state_.qd - qd_mean);
    if (arm()->time() > deadline) {
      arm()->clearHandForce();
      std::ostringstream detail;
      detail << "timed out in " << workflow_->stateName() << ", at path point " << next << "/" << path.size() << ", posture error "
             << std::setprecision(3) << (state_.q - q_ref).cwiseAbs().maxCoeff() << " rad, joint speed "
             << state_.qd.cwiseAbs().maxCoeff() << " rad/s (" << qd_mean.cwiseAbs().maxCoeff() << " over 0.1 s)";
      last_failure_detail_ = detail.str();
      return false;
    }
    if (workflow_->subStage() == SubStage::kPosed) {
      // on_converged fired under the hands: the arm crept so slowly (below the triggers' still
      // speed for converged_time) that it counts as posed. A person who sees that lets go at
      // once, since any further push would start a recording here. At the end of the way,
      // close to the posture, that is the posture; short of it, the approach failed.
      arm()->clearHandForce();
      const double error = (state_.q - path.back()).cwiseAbs().maxCoeff();
      if (next >= path.size() && error < kPosedTolerance) return true;
      std::ostringstream detail;
      detail << "on_converged fired " << std::setprecision(3) << error << " rad short of the posture, at path point " << next << "/"
             << path.size();
      last_failure_detail_ = detail.str();
      return false;
    }
    // Move the reference along the path at the tutor's pace, waiting where the arm lags.
    const double lead = (state_.q - q_ref).cwiseAbs().maxCoeff();
    if (lead > kRunOffError) {
      // The arm went its own way (a robot's assistance or a contact turned it): a person lets
      // go rather than wrestle with it.
      arm()->clearHandForce();
      std::ostringstream detail;
      detail << "the arm ran off the way, " << std::setprecision(3) << lead << " rad from it, at path point " << next << "/" << path.size()
             << "; let go";
      last_failure_detail_ = detail.str();
      return false;
    }
    if (next < path.size()) report_.max_approach_lead = std::max(report_.max_approach_lead, lead);
    if (next < path.size() && lead <= kMaxLead) {
      const Eigen::VectorXd to = path[next] - q_ref;
      const double step = speed * dt;
      if (to.cwiseAbs().maxCoeff() <= step) {
        q_ref = path[next];
        ++next;
      } else {
        q_ref += to * (step / to.cwiseAbs().maxCoeff());
      }
    } else if ((state_.q - q_ref).cwiseAbs().maxCoeff() < 0.005 &&
               (state_.qd.cwiseAbs().maxCoeff() < 0.01 || qd_mean.cwiseAbs().maxCoeff() < 0.01)) {
      arm()->clearHandForce();
      return true;
    }
    // Every few cycles, the forces that realize the PD torque (minimum norm).
    if (phase % m == 0) {
      // Scaled by the joint inertia, as a person pushes a light wrist more gently than the
      // shoulder (and so that the explicit PD stays stable on light joints).
      // A person who feels the arm lag pushes harder: an integral term, bounded.
      const Eigen::VectorXd inertia = arm()->inertiaDiagonal();
      const Eigen::VectorXd error = q_ref - state_.q;
      integral = (integral + error * (dt * m)).cwiseMax(-1.0).cwiseMin(1.0);
      const Eigen::VectorXd push =
          inertia.cwiseMax(0.2 * arm_scale_.inertia).cwiseProduct(kJointStiffness * error + kJointIntegral * integral);
      const Eigen::VectorXd tau = push - inertia.cwiseProduct(kJointDamping * state_.qd);
      kinematics_.update(state_.q);
      for (int i = 0; i < m; ++i) {
        const Eigen::Isometry3d& X_WB = kinematics_.X_WB(bodies[static_cast<std::size_t>(i)]);
        points[static_cast<std::size_t>(i)] = X_WB * offset(i);
        kinematics_.pointJacobian(bodies[static_cast<std::size_t>(i)], points[static_cast<std::size_t>(i)], Jp);
        A.middleCols(3 * i, 3) = Jp.transpose();
      }
      const Eigen::MatrixXd AAt = A * A.transpose() + 1e-4 * Eigen::MatrixXd::Identity(dof, dof);
      const Eigen::VectorXd F = A.transpose() * AAt.ldlt().solve(tau);
      for (int i = 0; i < m; ++i) {
        Eigen::Vector3d f = F.segment<3>(3 * i) * m;
        const double most = kMaxPointForce * arm_scale_.force();
        if (f.norm() > most) f *= most / f.norm();
        forces[static_cast<std::size_t>(i)] = f;
      }
    }
    const auto i = static_cast<std::size_t>(phase % m);
    kinematics_.update(state_.q);
    const Eigen::Vector3d p = kinematics_.X_WB(bodies[i]) * offset(static_cast<int>(i));
    arm()->setHandForce(bodies[i], p, forces[i]);
    ++phase;
    tick();
  }
}

void SimulatedTutor::pushTip(const std::function<Eigen::Vector3d(double)>& p_ref, double duration,
                             const std::function<bool()>& done) {
  const double start = arm()->time();
  Eigen::Vector3d p_last = state_.p_WT();
  while (arm()->time() - start < duration && !(done && done())) {
    const Eigen::Vector3d p = state_.p_WT();
    const Eigen::Vector3d v = (p - p_last) / arm()->cycleTime();
    p_last = p;
    // A lighter arm is led with a lighter hand (ArmScale): the LWR IV's would ring a light tip.
    Eigen::Vector3d F = arm_scale_.mass() * (kTipStiffness * (p_ref(arm()->time() - start) - p) - kTipDamping * v);
    const double most = kMaxTipForce * arm_scale_.force();
    if (F.norm() > most) F *= most / F.norm();
    arm()->setHandForce(model_->dof(), p, F);
    tick();
  }
  arm()->clearHandForce();
}

void SimulatedTutor::pushTipAlong(const std::vector<Eigen::Vector3d>& line, double speed, double extra_time,
                                  const std::function<bool()>& done) {
  std::vector<double> at{0.0};  // [s] when the reference passes each point
  for (std::size_t i = 1; i < line.size(); ++i) at.push_back(at.back() + (line[i] - line[i - 1]).norm() / speed);
  pushTip(
      [&](double t) {
        for (std::size_t i = 1; i < line.size(); ++i) {
          if (t <= at[i]) return Eigen::Vector3d(line[i - 1] + (line[i] - line[i - 1]) * ((t - at[i - 1]) / std::max(1e-9, at[i] - at[i - 1])));
        }
        return line.back();
      },
      at.back() + extra_time, done);
}

double SimulatedTutor::assistanceAtTip() const {
  if (workflow_->controller() != InteractionController::kAssistanceBlending) return 0.0;
  const double c = workflow_->confidence().evaluate(state_.p_WT());
  return std::isfinite(c) ? c : 0.0;  // as the controller reads it
}

void SimulatedTutor::leadTipOutOfAssistance(const std::vector<Eigen::VectorXd>& path) {
  // The tip's way on the path, every 0.02 rad of the largest joint motion.
  std::vector<Eigen::Vector3d> way;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const int samples = std::max(1, static_cast<int>(std::ceil((path[i + 1] - path[i]).cwiseAbs().maxCoeff() / 0.02)));
    for (int k = i == 0 ? 0 : 1; k <= samples; ++k) {
      kinematics_.update(path[i] + (path[i + 1] - path[i]) * (static_cast<double>(k) / samples));
      way.push_back(kinematics_.p_WT());
    }
  }
  if (way.size() < 2) return;
  // The arm's posture is the robot's along the way, not the path's: a person stops where it
  // comes near an obstacle (looked at every 20 ms). A stall long enough for on_converged ends
  // the lead too: a touch in POSED would start a recording.
  int cycle = 0;
  const long look_every = std::max(1L, std::lround(0.02 / arm()->cycleTime()));
  const double margin = 0.5 * min_clearance_;
  pushTipAlong(way, scaled(kLeadSpeed), 2.0, [&] {
    if (workflow_->subStage() != SubStage::kApproaching) return true;
    if (assistanceAtTip() < kYieldingConfidence || (state_.p_WT() - way.back()).norm() < scaled(0.02)) return true;
    if (++cycle % look_every != 0) return false;
    world_->update(state_.q);
    return !world_->contacts().empty() || world_->clearance(2.0 * margin).distance < margin;
  });
}

bool SimulatedTutor::teachArea(TutorAreaReport& area, const std::optional<Eigen::VectorXd>& suggested) {
  if (suggested) area.q_suggested = *suggested;
  // What a person sees at once, said as such instead of as a failed posture search.
  if (const robot::Obstacle* obstacle = robot::obstacleAt(*scene_, area.target)) {
    area.failure = "the area's centre lies inside " + obstacle->name;
    return false;
  }
  const double reach = arm_reach_.reach;
  if (arm_reach_.fromShoulder(area.target) > reach) {
    std::ostringstream failure;
    failure << std::fixed << std::setprecision(2) << "out of the arm's reach (" << arm_reach_.fromShoulder(area.target)
            << " m from the shoulder, reach " << reach << " m)";
    area.failure = failure.str();
    return false;
  }
  // A touch in POSED would not start an approach but a recording where the arm happens to be.
  // The arm can come to be posed without the tutor's doing (after a let-go the settling arm's
  // torques may read as a touch, and its coming to rest as on_converged): a person records that
  // pose away and takes it back, then starts the area, rather than giving the area up.
  if (workflow_->subStage() == SubStage::kRecording) waitFor(SubStage::kWaiting, 10.0);
  if (workflow_->subStage() == SubStage::kPosed) {
    discardPose();
    workflow_->nameNextArea(area.name);  // the recording taken back used up the name
  }
  if (workflow_->subStage() == SubStage::kPosed || workflow_->subStage() == SubStage::kRecording) {
    area.failure = std::string("the workflow is in ") + workflow_->stateName() + ", not ready for an approach";
    return false;
  }
  int reaching = 0;
  const std::vector<PostureChoice> postures = choosePostures(area.target, suggested, &reaching, !area.automatic, place_posture_);
  if (postures.empty()) {
    if (reaching == 0) {
      area.failure = "no posture within the joint limits puts the tip there (" + std::to_string(2 * options_.posture_candidates) + " IK searches)";
    } else if (too_heavy_candidates_ > 0) {
      area.failure = "the joints cannot hold the arm up there (a posture may take at most " +
                     std::to_string(static_cast<int>(std::lround(100.0 * kHoldableLoad))) +
                     " % of an effort limit): of the postures found that reach it without a contact, the lightest needs " +
                     arm()->describe(lightest_rejected_);
    } else {
      area.failure = "every posture found that reaches it makes a contact";
    }
    return false;
  }
  if (!postures.front().found) {
    area.q_chosen = postures.front().q;
    area.clearance = postures.front().clearance;
    std::ostringstream failure;
    world_->update(postures.front().q);
    const robot::Clearance nearest = world_->clearance(min_clearance_);
    failure << std::fixed << std::setprecision(1) << "no posture with " << 100.0 * min_clearance_
            << " cm clearance (the best found keeps " << 100.0 * postures.front().clearance << " cm";
    if (nearest.obstacle >= 0) failure << ", " << world_->bodyName(nearest.body) << " to " << world_->obstacleName(nearest.obstacle);
    failure << ")";
    area.failure = failure.str();
    return false;
  }
  PostureChoice choice = postures.front();
  // The way there: straight in joint space where that keeps the clearance, otherwise around
  // the obstacles (RRT-Connect in the collision world), keeping the full margin if possible;
  // the next posture where no way to this one is found.
  std::vector<Eigen::VectorXd> path;
  for (const PostureChoice& posture : postures) {
    path = planWay(state_.q, posture.q);
    if (!path.empty()) {
      choice = posture;
      break;
    }
  }
  if (path.empty()) {
    area.failure = "no collision-free way to the posture (" + std::to_string(postures.size()) + " tried) from " + describePosture(state_.q);
    return false;
  }
  area.q_chosen = choice.q;
  area.clearance = choice.clearance;
  // Touch (on_affected -> APPROACHING), push the links there, let go (on_converged -> POSED).
  kinematics_.update(choice.q);
  if (!grab(SubStage::kWaiting, kinematics_.p_WT() - state_.p_WT() + Eigen::Vector3d(0, 0, 1e-3))) {
    area.failure = "the arm did not take the hand's push as a touch (on_affected never fired: the external torques stayed "
                   "below the trigger's threshold, or the arm never stood still)";
    return false;
  }
  if (assistanceAtTip() >= kYieldingConfidence) {
    // Where the robot is already confident, assistance blending keeps the null space at what
    // it learned: lead the tip away first, then push the links on from where the arm is.
    const Eigen::Vector3d lead_from = state_.p_WT();
    leadTipOutOfAssistance(path);
    area.assistance_lead = (state_.p_WT() - lead_from).norm();
    if (workflow_->subStage() != SubStage::kApproaching) {
      area.failure = std::string("the arm stalled under the assistance while the tip was led (") + workflow_->stateName() + ")";
      return false;
    }
    path = planWay(state_.q, choice.q);
    if (path.empty()) {
      area.failure = "no collision-free way to the posture from where the assistance let the arm go, " + describePosture(state_.q);
      return false;
    }
  }
  // A person moves slowly where the arm passes close to an obstacle.
  const double speed = options_.approach_speed * std::clamp(std::max(0.0, pathClearance(path)) / scaled(0.15), 0.1, 1.0);
  if (!pushAlong(path, speed)) {
    area.failure = "the posture was not reached (" + last_failure_detail_ + ")";
    return false;
  }
  // Where assistance blending offers the learned posture, the released arm's null space drifts
  // towards it before it comes to rest (the tip stays where it is).
  if (!waitFor(SubStage::kPosed, assistanceAtTip() > kDriftingConfidence ? 30.0 : 6.0)) {
    area.failure = "on_converged did not fire after the approach";
    return false;
  }
  // A helix around the rest position under π_rec, as the participants explored an area
  // (Sect. 3.3.1: "a 3D helix-like trajectory" of 150-300 points): turns about an axis tilted
  // randomly by up to about 27° from the vertical, rising and falling by half the height range
  // about the rest height (starting and ending there), the radius growing from a
  // third to the full one so the inside of the area is covered as well. Starting off-centre makes
  // the first touch firm enough for on_affected. Like a person who sees the arm, the tutor draws
  // it smaller where the deflected posture would come near an obstacle.
  const Eigen::Vector3d p0 = state_.p_WT();
  const Eigen::VectorXd q_fixed = state_.q;
  Eigen::Vector3d axis(random_.uniform(-0.5, 0.5), random_.uniform(-0.5, 0.5), 1.0);
  axis.normalize();
  const Eigen::Vector3d u = axis.unitOrthogonal();
  const Eigen::Vector3d w = axis.cross(u);
  double omega = 2.0 * std::numbers::pi / options_.circle_period;
  const double duration = options_.circles * options_.circle_period;
  double scale = 1.0;
  const auto helix = [&](double t) {
    const double s = std::clamp(t / duration, 0.0, 1.0);
    const double radius = scale * 0.5 * circle_diameter_ * (1.0 / 3.0 + 2.0 / 3.0 * s);
    return Eigen::Vector3d(p0 + radius * (std::cos(omega * t) * u + std::sin(omega * t) * w) +
                           scale * 0.5 * options_.helix_height * circle_diameter_ * std::sin(2.0 * std::numbers::pi * s) * axis);
  };
  const double smallest = std::min(1.0, scaled(0.02) / circle_diameter_);
  bool room = false;
  for (;; scale = std::max(smallest, scale * 0.7)) {
    std::vector<Eigen::Vector3d> points;
    for (double t = 0.0; t <= duration; t += 0.05 * options_.circle_period) points.push_back(helix(t));
    room = helixFree(q_fixed, points, 0.5 * min_clearance_);
    if (room || scale <= smallest) break;
  }
  area.helix_diameter = scale * circle_diameter_;
  // At a listed place the scene's author asked for an area, and the smallest helix is drawn; a
  // place the tutor picked itself it leaves for a roomier one, as a person would (a two-armed
  // robot's own torso 5 cm from the tip: the wrist touched it while recording).
  if (!room && area.automatic) {
    std::ostringstream failure;
    failure << std::fixed << std::setprecision(1) << "no room there for even a " << 100.0 * area.helix_diameter
            << " cm helix (a posture on it comes within " << 50.0 * min_clearance_
            << " cm of an obstacle or of the arm itself)";
    area.failure = failure.str();
    return false;
  }
  // The workflow counts the arm as still while no joint moves faster than its still speed; a
  // helix shrunk near obstacles and drawn at the usual pace moved the tip so slowly that the
  // joints stayed below it, and on_converged ended the recording after 2 s (setup_II's II10: 114
  // samples, the rest of the helix recorded into the next area). A person draws a small circle
  // faster: the turns speed up until the slowest stretch asks the joints for 1.25 times the still
  // speed, taking the π_rec motion as the minimum-norm joint velocity of the tip's.
  {
    kinematics_.update(q_fixed);
    robot::Matrix6Xd J_WT;
    kinematics_.tipJacobian(J_WT);
    const Eigen::MatrixXd Jp = J_WT.topRows<3>();
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> inverse(Jp);
    double slowest = std::numeric_limits<double>::infinity();
    const double dt = 1e-3 * options_.circle_period;
    for (double t = 0.0; t <= duration; t += 0.01 * options_.circle_period) {
      const Eigen::Vector3d v = (helix(t + dt) - helix(t)) / dt;
      slowest = std::min(slowest, Eigen::VectorXd(inverse.solve(v)).cwiseAbs().maxCoeff());
    }
    const double wanted = 1.25 * workflow_->options().still_velocity;
    if (slowest > 0.0 && slowest < wanted) omega *= std::min(kMaxHelixPace, wanted / slowest);
  }
  // The recording starts as a person starts it: press the tip and hold until the arm stands
  // still (on_affected needs τ_ext above threshold while the arm is not moving). A push drawn
  // from the first cycle on would have the arm moving by the time a robot measures the force.
  if (!grab(SubStage::kPosed, u)) {
    area.failure = "the arm did not take the hand's push at the posture as a touch, so no recording started (on_affected "
                   "never fired)";
    return false;
  }
  pushTip(helix, duration);
  if (!waitFor(SubStage::kWaiting, 8.0)) {
    area.failure = "on_converged did not fire after the recording";
    return false;
  }
  area.taught = true;
  return true;
}

void SimulatedTutor::drawCheckPoints() {
  const robot::EvaluationGrid grid = scene_->grid.value_or(robot::EvaluationGrid{});
  learning::UniformRandom draw(options_.seed + 0x5eed);
  const Eigen::VectorXd& q_start = home_;
  check_points_.clear();
  check_postures_.clear();
  Eigen::VectorXd q_found;
  const int budget = 100 * options_.check_points;
  // An arm that reaches none of the grid (joints held in a narrow range) would spend the whole
  // budget, minutes, on failed searches. Where a draw in 20 or more succeeds, a run of this
  // many failures is next to impossible (0.95^500 < 1e-11), so stopping there changes no run
  // of an arm that reaches the grid.
  constexpr int kFailedDrawsInARowToGiveUp = 500;
  int failed_in_a_row = 0;
  for (int k = 0; static_cast<int>(check_points_.size()) < options_.check_points && k < budget &&
                  failed_in_a_row < kFailedDrawsInARowToGiveUp;
       ++k) {
    // Where the arm reaches little of the grid every draw is a failed search of 24 IK runs: this
    // takes minutes, so it says how far it is and yields to a stop.
    stopIfAsked();
    if (options_.progress && k % 50 == 0) {
      options_.progress("teach (check points)",
                        std::max(static_cast<double>(check_points_.size()) / options_.check_points, static_cast<double>(k) / budget));
    }
    const Eigen::Vector3d x = draw.uniform(grid.lower, grid.upper);
    if (arm_reach_.fromShoulder(x) > arm_reach_.reach || grid.excludes(x)) continue;
    // Only where some posture reaches without a contact (a person sees the arm cannot get there).
    if (robot::obstacleAt(*scene_, x, scaled(0.05)) == nullptr && accessibleWithoutCollision(*model_, parameters_, *world_, x, q_start, 24, draw, &q_found)) {
      check_points_.push_back(x);
      check_postures_.push_back(q_found);
      failed_in_a_row = 0;
    } else {
      ++failed_in_a_row;
    }
  }
  check_failed_.assign(check_points_.size(), true);
  if (options_.progress) options_.progress("teach (check points)", 1.0);
}

int SimulatedTutor::mapFailures() {
  check_failed_.assign(check_points_.size(), true);
  if (workflow_->areas().empty()) return static_cast<int>(check_points_.size());
  std::unique_ptr<learning::Learner> map = makeLearner(workflow_->options(), model_->dof());
  map->fit(workflow_->trainingSet());
  const double tolerance = scene_->grid.value_or(robot::EvaluationGrid{}).tolerance;
  int failures = 0;
  for (std::size_t i = 0; i < check_points_.size(); ++i) {
    stopIfAsked();
    const Eigen::Vector3d& x = check_points_[i];
    const MotionOutcome outcome = approachTarget(*model_, parameters_, *map, learnedPosture(*model_, *map, x), x, world_.get());
    check_failed_[i] = outcome.collided || outcome.final_error_m > tolerance;
    if (check_failed_[i]) ++failures;
  }
  // The simulation stood still while the tutor checked; --realtime paces on from here instead of
  // racing to catch up with the wall clock.
  wall_start_ = -1.0;
  return failures;
}

std::optional<Eigen::Vector3d> SimulatedTutor::nextAutomaticTarget(const robot::EvaluationGrid& grid,
                                                                   const std::vector<Eigen::Vector3d>& tried, bool where_it_fails) {
  const double apart = scaled(0.1);
  const auto near_tried = [&tried, apart](const Eigen::Vector3d& x) {
    return std::any_of(tried.begin(), tried.end(), [&](const Eigen::Vector3d& t) { return (t - x).norm() < apart; });
  };
  int best = -1;
  int best_neighbours = -1;
  if (where_it_fails && !workflow_->areas().empty()) {
    for (std::size_t i = 0; i < check_points_.size(); ++i) {
      if (!check_failed_[i] || near_tried(check_points_[i])) continue;
      // An area needs room for the arm around the tip (the random places keep 0.1 m as well).
      if (!roomyForAnArea(check_points_[i])) continue;
      int neighbours = 0;
      for (std::size_t j = 0; j < check_points_.size(); ++j) {
        if (check_failed_[j] && (check_points_[j] - check_points_[i]).norm() < scaled(0.2)) ++neighbours;
      }
      if (neighbours > best_neighbours) {
        best_neighbours = neighbours;
        best = static_cast<int>(i);
      }
    }
  }
  if (best >= 0) {
    place_posture_ = check_postures_[static_cast<std::size_t>(best)];
    return check_points_[static_cast<std::size_t>(best)];
  }
  // A point of the workspace box away from the obstacles that some collision-free posture
  // reaches (near the base the joint limits leave holes a person would not ask the arm into).
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  learning::UniformRandom ik_seeds(options_.seed + 0xacce55);
  const Eigen::VectorXd& q_home = home_;
  // Over the whole box first; where the box lies mostly beyond the arm (a small arm in a large
  // box missed its reach a hundred times over), in the part of it within reach.
  const Eigen::Vector3d reach = Eigen::Vector3d::Constant(arm_reach_.reach);
  const Eigen::Vector3d within_lower = grid.lower.cwiseMax(arm_reach_.shoulder - reach);
  const Eigen::Vector3d within_upper = grid.upper.cwiseMin(arm_reach_.shoulder + reach);
  const bool box_reaches = (within_lower.array() <= within_upper.array()).all();
  places_passed_over_.clear();
  for (int tries = 0; tries < 200; ++tries) {
    const bool within = tries >= 100 && box_reaches;
    target = within ? random_.uniform(within_lower, within_upper) : random_.uniform(grid.lower, grid.upper);
    if (const char* why = whyNoRoom(target)) {
      ++places_passed_over_[why];
    } else if (near_tried(target)) {
      ++places_passed_over_["near a place tried before"];
    } else if (int reaching = 0; !accessibleWithoutCollision(*model_, parameters_, *world_, target, q_home, 8, ik_seeds,
                                                             &place_posture_, &reaching)) {
      ++places_passed_over_[reaching == 0 ? "where no posture found reaches it" : "where every posture found that reaches it makes a contact"];
    } else {
      return target;
    }
  }
  return std::nullopt;
}

std::string SimulatedTutor::placesPassedOver() const {
  std::vector<std::pair<std::string, int>> reasons(places_passed_over_.begin(), places_passed_over_.end());
  std::stable_sort(reasons.begin(), reasons.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string text;
  for (const auto& [reason, count] : reasons) text += (text.empty() ? "" : ", ") + std::to_string(count) + " " + reason;
  return text;
}

const char* SimulatedTutor::whyNoRoom(const Eigen::Vector3d& p_W) const {
  // Room for the arm around the tip: 0.1 m from every obstacle, off the robot's own base and
  // the table it stands on, where the hands cannot lead the arm through a helix, and 5 cm inside
  // the arm's reach (the workspace box reaches beyond it, and a person does not pick a place the
  // arm cannot get to).
  if (robot::obstacleAt(*scene_, p_W, scaled(0.1)) != nullptr) return "near an obstacle";
  if (scene_->grid && scene_->grid->excludes(p_W)) return "in an excluded box";
  if (p_W.z() < scaled(0.08)) return "too near the table";
  if (!arm_reach_.roomFor(p_W, scaled(0.05))) return "beyond the arm's reach or at its base";
  return nullptr;
}

TutorReport SimulatedTutor::configure(int area_count) {
  try {
    return configureAreas(area_count);
  } catch (const StopRequested&) {
    arm()->clearHandForce();
    // A fit under way is part of what was taught: the session keeps its model.
    workflow_->waitForLearning();
    updateReport();
    report_.interrupted = true;
    return report_;
  }
}

TutorReport SimulatedTutor::configureAreas(int area_count) {
  if (area_count < 1 || area_count > 200) throw InputError("areas: expected 1..200, got " + std::to_string(area_count));
  arm()->readState(state_);
  // No way out of an obstacle can be planned; without this every area would fail the same way.
  world_->update(state_.q);
  if (!world_->contacts().empty()) {
    const robot::Contact contact = world_->contacts().front();
    const std::string body = world_->bodyName(contact.body), other = world_->otherName(contact);
    const std::string start = scene_->home_posture ? "the scene's home_posture" : "the freest posture found around the middle of the joint limits";
    // An obstacle over the robot's base holds a link in every posture: no home_posture helps.
    const Eigen::VectorXd lower = model_->sampleLowerLimits(), upper = model_->sampleUpperLimits();
    bool in_every_posture = true;
    for (int sample = 0; sample < 16 && in_every_posture; ++sample) {
      world_->update(random_.uniform(lower, upper));
      in_every_posture = std::any_of(world_->contacts().begin(), world_->contacts().end(), [&](const robot::Contact& c) {
        return world_->bodyName(c.body) == body && world_->otherName(c) == other;
      });
    }
    throw InputError("tutor: the start posture (" + start + ") puts " + body + " into " + other +
                     (in_every_posture ? ", as every posture tried does; move " + other + " off the robot"
                                       : "; give the scene a collision-free home_posture"));
  }
  const RequestResult started = workflow_->press(Button::kStartConfiguration);
  if (!started) throw InputError("tutor: " + started.reason);
  const robot::EvaluationGrid grid = scene_->grid.value_or(robot::EvaluationGrid{});
  int listed = 0;
  int attempts = 0;
  int failures = -1;  // check points the map misses; -1: not counted yet
  std::vector<Eigen::Vector3d> tried;
  bool last_automatic_taught = true;
  while (static_cast<int>(workflow_->areas().size()) < area_count && attempts < 4 * area_count + 8) {
    ++attempts;
    // The robot refits its map after an area (OS-ELM) and checks the transitions between the
    // areas in the background (Sect. 4.3.4); a person moves on once it has reported. The
    // simulation stands still meanwhile, so when the new map takes over no longer depends on
    // how fast the machine learns: runs stay deterministic.
    workflow_->waitForLearning();
    TutorAreaReport area;
    std::optional<Eigen::VectorXd> suggested;
    place_posture_.resize(0);
    const bool automatic = listed >= static_cast<int>(scene_->training_areas.size());
    if (!automatic) {
      const robot::Area& scene_area = scene_->training_areas[static_cast<std::size_t>(listed++)];
      area.name = scene_area.name;
      area.target = scene_area.p_WA;
      if (scene_area.posture) suggested = model_->withinOneTurn(*scene_area.posture);  // as the start is
    } else {
      // Sect. 3.3.2: the tutor taught the areas "he found to be relevant", looking at where the
      // robot failed; a place taught for its own sake can bend the map into an obstacle for
      // its neighbours, so the area is checked and taken back if the map got worse (kept if it
      // is no worse: it adds taught space).
      area.name = "auto_" + std::to_string(attempts);
      if (options_.check_points > 0 && failures < 0) {
        drawCheckPoints();
        failures = mapFailures();
      }
      area.automatic = true;
      // Where the map fails may be where no posture can be taught (cramped, or out of the
      // hands' reach): after a place that could not be taught, a random one.
      const std::optional<Eigen::Vector3d> place = nextAutomaticTarget(grid, tried, last_automatic_taught);
      if (!place) {
        // Every place drawn was near an obstacle, excluded, beyond the arm or without a free
        // posture: a person would not teach the arm just anywhere.
        std::ostringstream failure;
        failure << std::fixed << std::setprecision(1) << "no place of its own found: of 200 random points of the evaluation grid, "
                << placesPassedOver() << " (near: within " << 100.0 * scaled(0.1) << " cm; too near the table: under "
                << 100.0 * scaled(0.08) << " cm)";
        area.failure = failure.str();
        report_.areas.push_back(area);
        break;
      }
      area.target = *place;
      tried.push_back(area.target);
    }
    const std::size_t areas_before = workflow_->areas().size();
    workflow_->nameNextArea(area.name);
    teachArea(area, suggested);
    // A recording that has not come to rest holds the arm under π_rec, against which the next
    // approach cannot lead it: hands off until it ends.
    if (workflow_->subStage() == SubStage::kRecording) waitFor(SubStage::kWaiting, 10.0);
    // Where it came to rest later than the tutor waited, the workflow made the area after all:
    // the report says what the workflow holds (and an automatic area is checked like any other).
    if (!area.taught && workflow_->areas().size() > areas_before) {
      area.taught = true;
      area.failure.clear();
    }
    if (area.taught && workflow_->areas().size() > areas_before) {
      const TrainingArea& recorded = workflow_->areas().back();
      area.samples = recorded.X.cols();
      area.span = spanOf(recorded.X);
      // A person looks at what the arm did and takes a spot back, so that `teach` does not
      // report an area that was never explored (the learner would read it as a posture to keep).
      if (area.helix_diameter > 0.0 && area.span < kMinSpanOfTheHelix * area.helix_diameter) {
        std::ostringstream spot;
        spot << std::fixed << std::setprecision(1) << "the recording spans " << 100.0 * area.span << " cm of the "
             << 100.0 * area.helix_diameter << " cm helix drawn (the arm did not follow the hands)";
        // The online learner refits after a removal in the background; removal waits for it.
        workflow_->waitForLearning();
        const RequestResult removed = workflow_->removeArea(static_cast<int>(workflow_->areas().size()) - 1);
        area.taught = !removed;
        area.failure = removed ? "taken back: " + spot.str() : spot.str() + ", and it could not be taken back: " + removed.reason;
      }
    }
    // An approach let go of halfway leaves the arm in APPROACHING, and under assistance blending
    // it moves on by itself: a person waits for it to come to rest before taking it again
    // (grabbed while it still moved, the next approach ran off its way at once, area after area).
    if (!area.taught && workflow_->subStage() == SubStage::kApproaching) waitFor(SubStage::kPosed, 30.0);
    if (!area.taught) discardPose();
    if (automatic) last_automatic_taught = area.taught;
    if (automatic && area.taught && options_.check_points > 0) {
      workflow_->waitForLearning();  // the map with the new area, whenever its refit ends
      const std::vector<bool> failed_without = check_failed_;
      const int with_area = mapFailures();
      area.map_failures_before = failures;
      area.map_failures_with = with_area;
      if (with_area > failures && workflow_->removeArea(static_cast<int>(workflow_->areas().size()) - 1)) {
        area.taught = false;
        area.failure = "taken back: the learned map missed " + std::to_string(with_area) + " of " +
                       std::to_string(check_points_.size()) + " check points with it, " + std::to_string(failures) + " without";
        check_failed_ = failed_without;
      } else {
        failures = with_area;
      }
    }
    report_.areas.push_back(area);
    if (options_.progress) options_.progress("teach", static_cast<double>(workflow_->areas().size()) / area_count);
  }
  workflow_->press(Button::kFinishedConfiguration);
  workflow_->waitForLearning();
  tick();
  updateReport();
  return report_;
}

void SimulatedTutor::discardPose() {
  if (workflow_->subStage() != SubStage::kPosed) return;
  const std::size_t areas_before = workflow_->areas().size();
  arm()->readState(state_);
  if (!grab(SubStage::kPosed, Eigen::Vector3d::UnitZ())) return;
  waitFor(SubStage::kWaiting, 10.0);
  if (workflow_->areas().size() > areas_before) workflow_->removeArea(static_cast<int>(workflow_->areas().size()) - 1);
}

bool SimulatedTutor::program(const std::vector<Eigen::Vector3d>& waypoints) {
  try {
    return programWaypoints(waypoints);
  } catch (const StopRequested&) {
    arm()->clearHandForce();
    return false;
  }
}

bool SimulatedTutor::programWaypoints(const std::vector<Eigen::Vector3d>& waypoints) {
  if (waypoints.empty()) throw InputError("tutor: a trajectory needs at least one waypoint");
  arm()->readState(state_);
  if (!workflow_->press(Button::kStartProgramming)) return false;
  const double speed = 0.05;  // [m/s] of the tutor's hand
  auto guide = [&](const std::vector<Eigen::Vector3d>& points) {
    // Piecewise linear reference from the current tip position through the points.
    std::vector<Eigen::Vector3d> line{state_.p_WT()};
    line.insert(line.end(), points.begin(), points.end());
    pushTipAlong(line, speed, 1.0);
  };
  const Eigen::Vector3d first = waypoints.front();
  bool ok = grab(SubStage::kWaiting, first - state_.p_WT() + Eigen::Vector3d(0, 0, 1e-3));
  if (ok) guide({first});
  ok = ok && waitFor(SubStage::kPosed, 6.0);
  if (ok && waypoints.size() > 1) {
    ok = grab(SubStage::kPosed, waypoints[1] - state_.p_WT() + Eigen::Vector3d(0, 0, 1e-3));
    if (ok) guide(std::vector<Eigen::Vector3d>(waypoints.begin() + 1, waypoints.end()));
    ok = ok && waitFor(SubStage::kWaiting, 6.0);
  }
  workflow_->press(Button::kFinishedProgramming);
  updateReport();
  return ok;
}

}  // namespace flexirob::app
