#include "app/evaluation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "planning/path_planner.hpp"
#include "planning/path_postures.hpp"
#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::app {

namespace {

// Grid points this close to the edge of the arm's reach (or beyond) are out of reach: only the
// fully stretched, singular arm touches them. A fixed 1 cm, the precision of Sect. 3.3.2, and not
// the grid's tolerance, so that a looser "reached" does not shrink T.
constexpr double kReachEdgeMargin = 0.01;

// Grid points computed as lower + i * spacing land a rounding error off an obstacle's face; a
// point this close to one lies on it (and the tip cannot stand there without touching it).
constexpr double kOnObstacleFace = 1e-6;

}  // namespace

MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const learning::Learner& map, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world, AtContact at_contact) {
  return executeMotion(
      model, parameters, [&map](const Eigen::Vector3d& p_W, Eigen::VectorXd& q) { map.predict(p_W, q); }, q_start,
      p_des, duration, settle, world, at_contact);
}

MotionOutcome executeMotion(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                            const PostureAt& posture_at, const Eigen::VectorXd& q_start,
                            const std::function<Eigen::Vector3d(double)>& p_des, double duration, double settle,
                            robot::CollisionWorld* world, AtContact at_contact) {
  constexpr double kDt = 1e-3;
  robot::HierarchicalController controller(model, parameters);
  robot::CommandLimiter limiter(model, parameters, kDt);
  limiter.reset(q_start);
  robot::Kinematics kinematics(model);
  Eigen::VectorXd qd(model.dof()), q_c(model.dof());
  MotionOutcome outcome;
  const auto steps = static_cast<int>(std::ceil((duration + settle) / kDt));
  Eigen::Vector3d target = p_des(0.0);
  double error_sum = 0.0;
  int error_samples = 0;
  for (int k = 1; k <= steps; ++k) {
    const Eigen::Vector3d previous_target = target;
    target = p_des(std::min(duration, k * kDt));
    // The path's velocity over this cycle, fed forward (zero once the path has ended).
    const Eigen::Vector3d target_velocity = (target - previous_target) / kDt;
    posture_at(target, q_c);
    controller.velocity(limiter.command(), target, target_velocity, q_c, qd, &limiter);
    limiter.updateVelocity(qd);
    if (k % 10 == 0) {
      if (k * kDt <= duration) {
        kinematics.update(limiter.command());
        const double error = (kinematics.p_WT() - target).norm();
        error_sum += error;
        if (error > outcome.max_error_m) {
          outcome.max_error_m = error;
          outcome.max_error_time = k * kDt;
        }
        ++error_samples;
      }
      if (world != nullptr) {
        world->update(limiter.command());
        if (!world->contacts().empty()) {
          ++outcome.colliding_checks;
          if (!outcome.collided) {
            outcome.collided = true;
            const robot::Contact& contact = world->contacts().front();
            outcome.contact = world->bodyName(contact.body) + "/" + world->otherName(contact);
            outcome.contact_time = k * kDt;
            kinematics.update(limiter.command());
            outcome.contact_task_error = (kinematics.p_WT() - target).norm();
          }
          if (at_contact == AtContact::kStop) break;  // a collision ends the motion as on the real robot
        }
      }
      // Settled: at the end of the path, at rest and on target.
      if (k * kDt > duration && limiter.velocity().norm() < 1e-3 && controller.taskError() < 1e-4) break;
    }
  }
  kinematics.update(limiter.command());
  outcome.final_error_m = (kinematics.p_WT() - target).norm();
  outcome.mean_error_m = error_samples > 0 ? error_sum / error_samples : outcome.final_error_m;
  if (error_samples == 0) outcome.max_error_m = outcome.final_error_m;
  outcome.q = limiter.command();
  return outcome;
}

Eigen::VectorXd learnedPosture(const robot::RobotModel& model, const learning::Learner& map, const Eigen::Vector3d& p_W) {
  Eigen::VectorXd q_c(model.dof());
  map.predict(p_W, q_c);
  return q_c.cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
}

MotionOutcome approachTarget(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                             const learning::Learner& map, const Eigen::VectorXd& q_start, const Eigen::Vector3d& p_W,
                             robot::CollisionWorld* world) {
  return executeMotion(model, parameters, map, q_start, [&p_W](double) { return p_W; }, 0.0, 3.0, world);
}

Eigen::VectorXd homePosture(const robot::RobotModel& model, const robot::Scene& scene) {
  if (scene.home_posture && scene.home_posture->size() == model.dof()) return model.withinOneTurn(*scene.home_posture);
  const Eigen::VectorXd mid = model.midPosture();
  robot::CollisionWorld world(model, scene);
  world.update(mid);
  if (world.contacts().empty()) return mid;
  // The middle of the limits touches something (a wrist hanging into the table, a ceiling over
  // a stretched arm): the nearest posture with 5 cm clearance, searched outwards from it in
  // rings of growing joint-space radius; failing that, the freest posture met. Seeded, so a
  // scene always starts in the same posture.
  const Eigen::VectorXd lower = model.sampleLowerLimits();
  const Eigen::VectorXd upper = model.sampleUpperLimits();
  std::mt19937_64 bits(20090601);
  const auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  constexpr int kRings = 20;
  constexpr int kPerRing = 50;
  Eigen::VectorXd freest = mid;
  double freest_clearance = -1.0;
  for (int ring = 1; ring <= kRings; ++ring) {
    const double scale = static_cast<double>(ring) / kRings;
    std::optional<Eigen::VectorXd> nearest;
    for (int i = 0; i < kPerRing; ++i) {
      Eigen::VectorXd q(model.dof());
      for (int j = 0; j < model.dof(); ++j) q[j] = mid[j] + scale * (lower[j] + uniform() * (upper[j] - lower[j]) - mid[j]);
      world.update(q);
      if (!world.contacts().empty()) continue;
      const double clearance = world.clearance(0.05).distance;
      if (clearance > freest_clearance) {
        freest_clearance = clearance;
        freest = q;
      }
      if (clearance >= 0.05 && (!nearest || (q - mid).norm() < (*nearest - mid).norm())) nearest = q;
    }
    if (nearest) return *nearest;
  }
  return freest;
}

FittedScene fitSceneToRobot(const robot::Scene& scene, const robot::RobotModel& model) {
  FittedScene fitted{scene, {}};
  // Postures of another joint count (a scene made for another arm) are one reason, not one
  // line per posture: twelve near-equal lines hid the arm and said nothing more.
  int other_count = 0;
  std::set<long> written_counts;
  const auto dropOtherCount = [&](std::optional<Eigen::VectorXd>& posture) {
    if (!posture || posture->size() == model.dof()) return;
    written_counts.insert(posture->size());
    ++other_count;
    posture.reset();
  };
  dropOtherCount(fitted.scene.home_posture);
  for (robot::Area& area : fitted.scene.training_areas) dropOtherCount(area.posture);
  for (robot::Area& area : fitted.scene.working_areas) dropOtherCount(area.posture);
  fitted.other_joint_count = other_count;
  if (other_count > 0) {
    std::string counts;
    for (const long count : written_counts) counts += (counts.empty() ? "" : " or ") + std::to_string(count);
    fitted.left_out.push_back(
        "scene '" + printable(scene.name, 200) + "': " + (other_count == 1 ? std::string("1 posture has ") : std::to_string(other_count) + " postures have ") +
        counts + " joint values, the robot '" + printable(model.name(), 200) + "' has " + std::to_string(model.dof()) +
        " joints" + (scene.robot.empty() ? std::string() : " (the scene was made for '" + printable(scene.robot, 200) + "')"));
  }
  // Each posture checked alone, in a scene holding only it: one that does not fit costs no other.
  const auto fits = [&](const auto& place_only_it) {
    robot::Scene single;
    single.name = scene.name;
    single.robot = scene.robot;
    place_only_it(single);
    try {
      robot::checkPosturesFit(single, model, model.name());
      return true;
    } catch (const InputError& error) {
      fitted.left_out.emplace_back(error.what());
      return false;
    }
  };
  if (fitted.scene.home_posture && !fits([&](robot::Scene& single) {
        single.home_posture = scene.home_posture;
        single.home_posture_in_degrees = scene.home_posture_in_degrees;
      })) {
    fitted.scene.home_posture.reset();
  }
  for (robot::Area& area : fitted.scene.training_areas) {
    if (area.posture && !fits([&](robot::Scene& single) { single.training_areas = {area}; })) area.posture.reset();
  }
  for (robot::Area& area : fitted.scene.working_areas) {
    if (area.posture && !fits([&](robot::Scene& single) { single.working_areas = {area}; })) area.posture.reset();
  }
  return fitted;
}

planning::ItmParameters itmParametersForArm(planning::ItmParameters parameters, const ArmScale& scale) {
  if (scale.length >= 1.0) return parameters;
  parameters.e_max *= scale.length;
  parameters.d_c_max *= scale.length;
  return parameters;
}

bool crossesObstacle(const robot::Scene& scene, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  // Between the ends: a way from or to a point inside an obstacle is another matter (`impossible`).
  const int steps = std::max(2, static_cast<int>(std::ceil((b - a).norm() / 0.005)));
  for (int i = 1; i < steps; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(i) / steps);
    if (robot::obstacleAt(scene, p, 0.0) != nullptr) return true;
  }
  return false;
}

ArmReach armReach(const robot::RobotModel& model) {
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.dof())
                                .cwiseMax(model.softLowerLimits())
                                .cwiseMin(model.softUpperLimits());
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  ArmReach result;
  if (model.dof() == 0) return result;
  // A joint turns its body about its own axis, so the axis reads the same in the body frame.
  const auto axis_W = [&](int body) -> Eigen::Vector3d {
    return (kinematics.X_WB(body).linear() * model.joints()[static_cast<std::size_t>(body - 1)].axis_J).normalized();
  };
  result.base_point = kinematics.X_WB(1).translation();
  result.base_axis = axis_W(1);
  // The shoulder: the first joint that does not turn about the same axis as the first (the
  // LWR IV's A2 over A1); an arm whose joints all turn about parallel axes swings from its first.
  int shoulder = 1;
  for (int b = 2; b <= model.dof(); ++b) {
    if (axis_W(b).cross(result.base_axis).norm() > 1e-6) {
      shoulder = b;
      break;
    }
  }
  const auto is_prismatic = [&](int body) {
    return model.joints()[static_cast<std::size_t>(body - 1)].type == robot::JointType::kPrismatic;
  };
  const Eigen::VectorXd lower = model.sampleLowerLimits(), upper = model.sampleUpperLimits();
  // The farthest the tip gets from `centre` within the limits with joints first_free.. free,
  // the others where q has them: body origins in q, then seeded random postures, the best of
  // them climbed joint by joint. (The posture nearest zero need not be the stretched one: an
  // arm with elbow offsets stands folded at zero, and its reach would read 0.15 m short.)
  // Seeded, so every caller gets the same reach.
  const auto farthest = [&](const Eigen::Vector3d& centre, int first_body, int first_free) {
    kinematics.update(q);
    double farthest_distance = (kinematics.p_WT() - centre).norm();
    for (int b = first_body; b <= model.dof(); ++b) {
      farthest_distance = std::max(farthest_distance, (kinematics.X_WB(b).translation() - centre).norm());
    }
    const auto tipDistance = [&](const Eigen::VectorXd& posture) {
      kinematics.update(posture);
      return (kinematics.p_WT() - centre).norm();
    };
    learning::UniformRandom random(1);
    Eigen::VectorXd best = q;
    double best_distance = tipDistance(q);
    for (int sample = 0; sample < 2000; ++sample) {
      Eigen::VectorXd candidate = q;
      const int free_joints = model.dof() - first_free;
      candidate.tail(free_joints) = random.uniform(lower.tail(free_joints), upper.tail(free_joints));
      if (const double distance = tipDistance(candidate); distance > best_distance) {
        best_distance = distance;
        best = candidate;
      }
    }
    for (double step = 0.2; step > 1e-3; step *= 0.5) {
      for (bool improved = true; improved;) {
        improved = false;
        for (int j = first_free; j < model.dof(); ++j) {
          for (const double sign : {-1.0, 1.0}) {
            Eigen::VectorXd candidate = best;
            candidate[j] = std::clamp(candidate[j] + sign * step, lower[j], upper[j]);
            if (const double distance = tipDistance(candidate); distance > best_distance + 1e-9) {
              best_distance = distance;
              best = candidate;
              improved = true;
            }
          }
        }
      }
    }
    return std::max(farthest_distance, best_distance);
  };
  result.shoulder = kinematics.X_WB(shoulder).translation();
  // The joints before the shoulder stay as they are: they move the shoulder itself (off the
  // first axis on an arm with a shoulder offset), and the reach is measured from where it is.
  result.reach = farthest(result.shoulder, shoulder, shoulder - 1);
  // A sphere about the shoulder describes an arm whose joints before it turn it about the first
  // axis, near which it lies. Where a joint before it slides (a lifting column), or the joints
  // before it swing it far about the base (a SCARA's tilting wrist), the sphere is the wrong
  // shape: the reach is then taken from the first joint with every joint free, a sphere that
  // holds all the arm can reach.
  bool sliding_before = false;
  for (int b = 1; b <= shoulder; ++b) sliding_before = sliding_before || is_prismatic(b);
  const Eigen::Vector3d shoulder_offset = result.shoulder - result.base_point;
  const double shoulder_off_axis = (shoulder_offset - shoulder_offset.dot(result.base_axis) * result.base_axis).norm();
  if (sliding_before || shoulder_off_axis > 0.5 * result.reach) {
    shoulder = 1;
    result.shoulder = result.base_point;
    result.reach = farthest(result.shoulder, 1, 0);
  }
  // Without a joint turning the rest about another axis there is no base column around an axis
  // of the first joint; the arm sweeps through it.
  result.base_radius = shoulder == 1 ? 0.0 : std::min(0.2, 0.25 * result.reach);
  return result;
}

double ArmScale::mass() const { return inertia / (length * length); }

ArmScale armScale(const robot::RobotModel& model) {
  ArmScale scale;
  const ArmReach reach = armReach(model);
  if (reach.reach > 0.0 && std::isfinite(reach.reach)) scale.length = std::min(1.0, reach.reach / kLwrShoulderReach);
  scale.inertia = robot::inertiaScaleToLwr(model);
  return scale;
}

bool ArmReach::roomFor(const Eigen::Vector3d& p_W, double margin) const {
  const Eigen::Vector3d offset = p_W - base_point;
  const double off_axis = (offset - offset.dot(base_axis) * base_axis).norm();
  return fromShoulder(p_W) <= reach - margin && off_axis >= base_radius;
}

namespace {

// Points of the arm in posture q: body origins, the tip and every 2 cm between consecutive ones.
void armPoints(robot::Kinematics& kinematics, int dof, std::vector<Eigen::Vector3d>& out) {
  std::vector<Eigen::Vector3d> chain;
  for (int b = 1; b <= dof; ++b) chain.push_back(kinematics.X_WB(b).translation());
  chain.push_back(kinematics.p_WT());
  out.push_back(chain.front());
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
    const double length = (chain[i + 1] - chain[i]).norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(length / 0.02)));
    for (int s = 1; s <= steps; ++s) out.push_back(chain[i] + (chain[i + 1] - chain[i]) * (static_cast<double>(s) / steps));
  }
}

}  // namespace

bool accessibleWithoutCollision(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                robot::CollisionWorld& world, const Eigen::Vector3d& p_W,
                                const Eigen::VectorXd& q_start, int seeds, learning::UniformRandom& random,
                                Eigen::VectorXd* posture_found, int* postures_reaching, double tolerance_m) {
  if (postures_reaching != nullptr) *postures_reaching = 0;
  const int dof = model.dof();
  const Eigen::VectorXd lower = model.softLowerLimits();
  const Eigen::VectorXd upper = model.softUpperLimits();
  const Eigen::VectorXd sample_lower = model.sampleLowerLimits();
  const Eigen::VectorXd sample_upper = model.sampleUpperLimits();
  robot::HierarchicalController controller(model, parameters);
  controller.useForKinematicSearch();
  robot::Kinematics kinematics(model);
  Eigen::VectorXd q(dof), q_null(dof), q_target(dof);
  for (int seed = 0; seed < seeds; ++seed) {
    if (seed == 0) {
      q_null = q_start;
    } else {
      q_null = random.uniform(sample_lower, sample_upper);
    }
    q = q_null.cwiseMax(lower).cwiseMin(upper);
    for (int it = 0; it < 300; ++it) {
      controller.target(q, p_W, q_null, 0.02, q_target);
      q = q_target.cwiseMax(lower).cwiseMin(upper);
      if (controller.taskError() < 1e-4 && it > 30) break;
    }
    kinematics.update(q);
    if ((kinematics.p_WT() - p_W).norm() > tolerance_m) continue;
    if (postures_reaching != nullptr) ++*postures_reaching;
    world.update(q);
    if (world.contacts().empty()) {
      if (posture_found != nullptr) *posture_found = q;
      return true;
    }
  }
  return false;
}

TrajectorySource parseTrajectorySource(const std::string& name) {
  if (name == "auto") return TrajectorySource::kAuto;
  if (name == "scene") return TrajectorySource::kScene;
  if (name == "training-data") return TrajectorySource::kTrainingData;
  throw InputError("trajectories: expected the source auto, scene or training-data, got '" + printable(name) + "'");
}

ApproachFrom parseApproach(const std::string& name) {
  if (name == "learned") return ApproachFrom::kLearnedPosture;
  if (name == "start") return ApproachFrom::kStartPosture;
  if (name == "previous") return ApproachFrom::kPreviousTarget;
  if (name == "nearest") return ApproachFrom::kNearestReached;
  if (name == "visited") return ApproachFrom::kNearestVisited;
  throw InputError("approach: expected learned, start, previous, nearest or visited, got '" + name + "'");
}

std::string approachName(ApproachFrom approach) {
  switch (approach) {
    case ApproachFrom::kLearnedPosture: return "learned";
    case ApproachFrom::kStartPosture: return "start";
    case ApproachFrom::kPreviousTarget: return "previous";
    case ApproachFrom::kNearestVisited: return "visited";
    case ApproachFrom::kNearestReached: return "nearest";
  }
  return "learned";
}

Eigen::VectorXd demonstratedPosture(const robot::RobotModel& model, const learning::TrainingSet& training, Eigen::Index l) {
  return training.Y.col(l).cwiseMax(model.softLowerLimits()).cwiseMin(model.softUpperLimits());
}

std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> demonstratedStandingPostures(const robot::RobotModel& model,
                                                                                     const learning::TrainingSet& training) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> standing;
  if (training.size() == 0 || training.X.rows() < 3 || training.Y.rows() != model.dof() || training.Y.cols() != training.X.cols()) {
    return standing;
  }
  for (Eigen::Index l = 0; l < training.X.cols(); ++l) {
    if (!training.X.col(l).head<3>().allFinite() || !training.Y.col(l).allFinite()) continue;
    standing.emplace_back(training.X.col(l).head<3>(), demonstratedPosture(model, training, l));
  }
  return standing;
}

const Eigen::VectorXd& nearestStandingPosture(const std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>>& standing,
                                              const Eigen::Vector3d& p_W, const Eigen::VectorXd& fallback) {
  const Eigen::VectorXd* best = &fallback;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const auto& [tip, q] : standing) {
    if ((tip - p_W).squaredNorm() < best_distance) {
      best_distance = (tip - p_W).squaredNorm();
      best = &q;
    }
  }
  return *best;
}

namespace {

// Which of the grid points `candidates` (within reach and outside the obstacles) some
// collision-free posture puts the tip at. T belongs to the scene, the robot and the grid
// (Sect. 3.3.2: T_I, T_II), never to the session evaluated, so the learned map plays no part and
// the search is made thorough enough not to depend on the order or the random draws: each point
// starts at the posture found for its nearest grid neighbour already accessible, then at the scene's home
// posture and 23 seeded random postures; then, until nothing changes, every point still without
// one starts at the postures found for its grid neighbours (a neighbour's posture is a small
// step from one for the point, where a random start may fall in another redundancy family).
std::vector<bool> accessibleGridPoints(const robot::RobotModel& model, const robot::ParameterSet& parameters,
                                       const robot::Scene& scene, robot::CollisionWorld& world,
                                       const std::vector<Eigen::Vector3d>& candidates, double spacing,
                                       double tolerance_m, const ProgressCallback& progress) {
  if (candidates.empty()) return {};
  learning::UniformRandom random(7);
  const Eigen::VectorXd q_home =
      scene.home_posture && scene.home_posture->size() == model.dof() ? *scene.home_posture : model.midPosture();
  // Grid neighbours: the 26 points of the surrounding cube, by integer cell.
  std::map<std::tuple<long, long, long>, std::size_t> by_cell;
  const auto cellOf = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d cell = ((p - candidates.front()) / spacing).array().round();
    return std::make_tuple(std::lround(cell.x()), std::lround(cell.y()), std::lround(cell.z()));
  };
  for (std::size_t i = 0; i < candidates.size(); ++i) by_cell.emplace(cellOf(candidates[i]), i);
  std::vector<std::vector<std::size_t>> neighbours(candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const auto [x, y, z] = cellOf(candidates[i]);
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = by_cell.find({x + dx, y + dy, z + dz});
          if (it != by_cell.end() && it->second != i) neighbours[i].push_back(it->second);
        }
      }
    }
    std::sort(neighbours[i].begin(), neighbours[i].end(), [&](std::size_t a, std::size_t b) {
      return (candidates[a] - candidates[i]).squaredNorm() < (candidates[b] - candidates[i]).squaredNorm();
    });
  }
  std::vector<std::optional<Eigen::VectorXd>> found(candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (progress && i % 100 == 0) progress(0.8 * static_cast<double>(i) / static_cast<double>(candidates.size()));
    const Eigen::Vector3d& p = candidates[i];
    const auto nearest_found = std::find_if(neighbours[i].begin(), neighbours[i].end(), [&](std::size_t j) { return found[j].has_value(); });
    Eigen::VectorXd q;
    if ((nearest_found != neighbours[i].end() &&
         accessibleWithoutCollision(model, parameters, world, p, *found[*nearest_found], 1, random, &q, nullptr, tolerance_m)) ||
        accessibleWithoutCollision(model, parameters, world, p, q_home, 24, random, &q, nullptr, tolerance_m)) {
      found[i] = q;
    }
  }
  std::vector<std::set<std::size_t>> tried(candidates.size());
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      if (found[i]) continue;
      for (const std::size_t j : neighbours[i]) {
        if (!found[j] || !tried[i].insert(j).second) continue;
        Eigen::VectorXd q;
        if (accessibleWithoutCollision(model, parameters, world, candidates[i], *found[j], 1, random, &q, nullptr, tolerance_m)) {
          found[i] = q;
          grew = true;
          break;
        }
      }
    }
  }
  if (progress) progress(1.0);
  std::vector<bool> accessible(candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) accessible[i] = found[i].has_value();
  return accessible;
}

}  // namespace

ReachableResult evaluateReachable(const robot::RobotModel& model, const robot::Scene& scene,
                                  const robot::ParameterSet& parameters, const learning::Learner& map,
                                  const Eigen::VectorXd& q_start, const robot::EvaluationGrid& grid,
                                  const learning::TrainingSet& training, const ProgressCallback& progress,
                                  ApproachFrom approach) {
  model.checkPosture(q_start);
  if (training.size() > 0 && training.X.rows() < 3) {
    throw InputError("reachability: the demonstration's inputs have " + std::to_string(training.X.rows()) +
                     " rows, not a tip position");
  }
  // The postures kNearestVisited starts from; a demonstration without postures has none.
  const bool start_from_samples = approach == ApproachFrom::kNearestVisited && training.Y.size() > 0;
  if (start_from_samples && (training.Y.cols() != training.X.cols() || training.Y.rows() != model.dof())) {
    throw InputError("reachability: the demonstration has " + std::to_string(training.Y.rows()) + " x " +
                     std::to_string(training.Y.cols()) + " postures for " + std::to_string(training.X.cols()) +
                     " positions of a robot with " + std::to_string(model.dof()) + " joints");
  }
  robot::CollisionWorld world(model, scene);
  const ArmReach arm_reach = armReach(model);
  const std::vector<Eigen::Vector3d> points = grid.points();
  // Grid cells holding a training sample (explored space, Tab. 3.3).
  std::set<std::tuple<long, long, long>> explored_cells;
  for (Eigen::Index l = 0; l < training.X.cols(); ++l) {
    const Eigen::Vector3d cell = ((training.X.col(l).head<3>() - grid.lower) / grid.spacing).array().round();
    explored_cells.insert({std::lround(cell.x()), std::lround(cell.y()), std::lround(cell.z())});
  }
  ReachableResult result;
  result.grid_points = static_cast<int>(points.size());
  // Progress: the IK searches that find T take about as long as driving to its targets.
  constexpr double kFindingShare = 0.3;
  std::vector<Eigen::Vector3d> candidates;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    if (arm_reach.fromShoulder(p) > arm_reach.reach - kReachEdgeMargin) {
      ++result.out_of_reach;
    } else if (robot::obstacleAt(scene, p, kOnObstacleFace) != nullptr) {
      // A point on an obstacle's face (x = -0.29999999999999993 for a face at -0.3 m) is no
      // more a free target than one inside.
      ++result.in_obstacles;
    } else if (grid.excludes(p)) {
      ++result.excluded;
    } else {
      candidates.push_back(p);
    }
  }
  const std::vector<bool> accessible = accessibleGridPoints(
      model, parameters, scene, world, candidates, grid.spacing, grid.tolerance,
      progress ? ProgressCallback([&](double done) { progress(kFindingShare * done); }) : ProgressCallback());
  std::vector<Eigen::Vector3d> targets;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (accessible[i]) {
      targets.push_back(candidates[i]);
    } else {
      ++result.inaccessible;
    }
  }
  result.targets = static_cast<int>(targets.size());
  const bool from_nearest = approach == ApproachFrom::kNearestReached || approach == ApproachFrom::kNearestVisited;
  const bool tour = approach == ApproachFrom::kPreviousTarget || from_nearest;
  if (tour && !targets.empty()) {
    // Nearest-neighbour tour from the start posture's tip: consecutive targets one grid step
    // apart wherever the grid allows, as a person would command them.
    Eigen::Vector3d from = robot::tipPose(model, q_start).translation();
    for (std::size_t i = 0; i < targets.size(); ++i) {
      std::size_t best = i;
      for (std::size_t j = i + 1; j < targets.size(); ++j) {
        if ((targets[j] - from).squaredNorm() < (targets[best] - from).squaredNorm()) best = j;
      }
      std::swap(targets[i], targets[best]);
      from = targets[i];
    }
  }
  Eigen::VectorXd q_previous = q_start;  // kPreviousTarget: last posture reached without contact
  // kNearestReached, kNearestVisited: tip positions with the postures the arm stood in there.
  std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>>& reached_postures = result.standing_postures;
  if (start_from_samples) reached_postures = demonstratedStandingPostures(model, training);
  const auto nearestReachedPosture = [&](const Eigen::Vector3d& p) -> const Eigen::VectorXd& {
    return nearestStandingPosture(reached_postures, p, q_start);
  };
  int explored = 0;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const Eigen::Vector3d& p = targets[i];
    const Eigen::Vector3d cell = ((p - grid.lower) / grid.spacing).array().round();
    if (explored_cells.count({std::lround(cell.x()), std::lround(cell.y()), std::lround(cell.z())}) != 0) ++explored;
    const Eigen::VectorXd q_from = approach == ApproachFrom::kLearnedPosture   ? learnedPosture(model, map, p)
                                   : approach == ApproachFrom::kPreviousTarget ? q_previous
                                   : from_nearest                              ? nearestReachedPosture(p)
                                                                               : q_start;
    const MotionOutcome outcome = approachTarget(model, parameters, map, q_from, p, &world);
    if (outcome.collided) {
      ++result.collided;
      ++result.contacts[outcome.contact];
    } else {
      q_previous = outcome.q;
    }
    const bool reached = !outcome.collided && outcome.final_error_m <= grid.tolerance;
    if (reached) ++result.reached;
    if (reached && from_nearest) reached_postures.emplace_back(p, outcome.q);
    // The resolved posture: the run above where it started at q_c(x) and met no contact (the
    // world only watches), otherwise the same run without stopping at contacts.
    bool resolved_free = false;
    if (approach == ApproachFrom::kLearnedPosture && !outcome.collided) {
      resolved_free = reached;
    } else {
      const MotionOutcome resolved = approachTarget(model, parameters, map, learnedPosture(model, map, p), p, nullptr);
      world.update(resolved.q);
      resolved_free = world.contacts().empty() && resolved.final_error_m <= grid.tolerance;
    }
    if (resolved_free) ++result.resolved_free;
    result.target_resolved_free.push_back(resolved_free);
    result.target_points.push_back(p);
    result.target_reached.push_back(reached);
    result.final_postures.push_back(outcome.q);
    result.target_contact.push_back(outcome.collided ? outcome.contact : std::string());
    if (progress && i % 20 == 0) {
      progress(kFindingShare + (1.0 - kFindingShare) * static_cast<double>(i) / static_cast<double>(targets.size()));
    }
  }
  if (progress) progress(1.0);
  if (result.targets > 0) {
    result.reachable_fraction = static_cast<double>(result.reached) / result.targets;
    result.resolved_fraction = static_cast<double>(result.resolved_free) / result.targets;
    result.explored_fraction = static_cast<double>(explored) / result.targets;
  }
  return result;
}

SceneModelResult evaluateSceneModel(const robot::RobotModel& model, const robot::Scene& scene,
                                    const robot::EvaluationGrid& grid, const std::vector<Eigen::VectorXd>& postures,
                                    double distance) {
  const ArmReach arm_reach = armReach(model);
  robot::Kinematics kinematics(model);
  std::vector<Eigen::Vector3d> maneuvering;  // M
  for (const auto& q : postures) {
    kinematics.update(q);
    armPoints(kinematics, model.dof(), maneuvering);
  }
  // d(x, M) by buckets of `distance` edge: only the 27 neighbouring buckets can be closer.
  std::map<std::tuple<long, long, long>, std::vector<Eigen::Vector3d>> buckets;
  const auto key = [&](const Eigen::Vector3d& p) {
    return std::make_tuple(std::lround(std::floor(p.x() / distance)), std::lround(std::floor(p.y() / distance)),
                           std::lround(std::floor(p.z() / distance)));
  };
  for (const auto& p : maneuvering) buckets[key(p)].push_back(p);
  SceneModelResult result;
  for (const auto& x : grid.points()) {
    if (arm_reach.fromShoulder(x) > arm_reach.reach - kReachEdgeMargin) continue;
    ++result.workspace_points;
    bool near = false;
    const auto [i, j, k] = key(x);
    for (long di = -1; di <= 1 && !near; ++di) {
      for (long dj = -1; dj <= 1 && !near; ++dj) {
        for (long dk = -1; dk <= 1 && !near; ++dk) {
          const auto it = buckets.find({i + di, j + dj, k + dk});
          if (it == buckets.end()) continue;
          for (const auto& m : it->second) {
            if ((m - x).norm() <= distance) {
              near = true;
              break;
            }
          }
        }
      }
    }
    const bool inside = robot::obstacleAt(scene, x, kOnObstacleFace) != nullptr;  // as T counts them
    if (inside) ++result.obstacle_points;
    if (near) continue;
    result.model.push_back(x);
    if (inside) {
      ++result.obstacle_points_enclosed;
    } else {
      ++result.free_points_in_model;
    }
  }
  result.model_points = static_cast<int>(result.model.size());
  if (result.obstacle_points > 0) {
    result.obstacle_enclosed_fraction = static_cast<double>(result.obstacle_points_enclosed) / result.obstacle_points;
  }
  return result;
}

namespace {

// The first point of a chain of straight segments (every 2 cm) that no posture can put the tip
// at: beyond the arm's reach or inside an obstacle; empty if there is none.
std::string impossiblePoint(const ArmReach& reach, const robot::Scene& scene, const std::vector<Eigen::Vector3d>& waypoints) {
  const auto describe = [](const Eigen::Vector3d& p) {
    std::ostringstream text;
    text << std::fixed << std::setprecision(2) << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") m";
    return text.str();
  };
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    const Eigen::Vector3d from = waypoints[i];
    const Eigen::Vector3d to = i + 1 < waypoints.size() ? waypoints[i + 1] : waypoints[i];
    const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.02)));
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector3d p = from + (to - from) * (static_cast<double>(k) / steps);
      if (reach.fromShoulder(p) > reach.reach) {
        std::ostringstream text;
        text << describe(p) << std::fixed << std::setprecision(2) << " is " << reach.fromShoulder(p)
             << " m from the shoulder, reach " << reach.reach << " m";
        return text.str();
      }
      if (const robot::Obstacle* obstacle = robot::obstacleAt(scene, p)) return describe(p) + " lies inside " + obstacle->name;
    }
  }
  return {};
}

}  // namespace

TrajectoryResult evaluateTrajectories(const robot::RobotModel& model, const robot::Scene& scene,
                                      const robot::ParameterSet& parameters, const learning::Learner& map,
                                      const std::vector<EvaluatedArea>& areas, int per_area, double speed,
                                      std::uint64_t seed, const ProgressCallback& progress, TrajectorySource source) {
  if (areas.empty()) throw InputError("trajectories: no taught area");
  if (source == TrajectorySource::kScene && scene.trajectories.empty()) {
    throw InputError("trajectories: the scene lists no trajectories (use the regions around the training data)");
  }
  if (!(speed > 0.0)) throw InputError("trajectories: speed must be positive");
  for (const auto& area : areas) {
    model.checkPosture(area.q_fixed);
    if (area.samples.rows() != 3 || area.samples.cols() < 1) throw InputError("trajectories: an area has no samples");
  }
  // The regions: name -> list of named point sequences (each a chain of straight segments; the
  // name is what a collided trajectory is reported as).
  struct NamedWaypoints {
    std::string name;
    std::vector<Eigen::Vector3d> waypoints;
  };
  std::vector<std::pair<std::string, std::vector<NamedWaypoints>>> regions;
  const auto region = [&](const std::string& name) -> std::vector<NamedWaypoints>& {
    for (auto& r : regions) {
      if (r.first == name) return r.second;
    }
    regions.push_back({name, {}});
    return regions.back().second;
  };
  // A drawn region's area: the arm starts there first, its tip on a straight way to the start.
  std::map<std::string, std::size_t> drawn_from;
  const ArmReach arm_reach = armReach(model);
  TrajectoryResult result;
  const bool from_scene = source == TrajectorySource::kScene ||
                          (source == TrajectorySource::kAuto && !scene.trajectories.empty());
  if (from_scene) {
    result.from_scene = true;
    for (const auto& trajectory : scene.trajectories) {
      region(trajectory.group.empty() ? "ungrouped" : trajectory.group).push_back({trajectory.name, trajectory.waypoints});
    }
  } else {
    if (areas.size() < 2) {
      throw InputError(source == TrajectorySource::kTrainingData
                           ? "trajectories: drawing them around the training data needs at least two taught areas"
                           : "trajectories: the scene lists none and fewer than two areas were taught");
    }
    if (per_area < 1) throw InputError("trajectories: expected at least one trajectory per area");
    learning::UniformRandom random(seed);
    // Points a trajectory may pass: within the arm's reach, off its base and the table, 5 cm
    // clear of every obstacle; a box around two areas can hold the robot itself or a wall.
    const auto passable = [&](const Eigen::Vector3d& p) {
      return arm_reach.roomFor(p, 0.05) && (!scene.table || p.z() >= 0.05) && robot::obstacleAt(scene, p, 0.05) == nullptr;
    };
    const auto segment_passable = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.02)));
      for (int i = 0; i <= steps; ++i) {
        if (!passable(a + (b - a) * (static_cast<double>(i) / steps))) return false;
      }
      return true;
    };
    struct Box {
      Eigen::Vector3d lower, upper;
    };
    const auto sampleBox = [](const EvaluatedArea& area) {
      return Box{area.samples.rowwise().minCoeff(), area.samples.rowwise().maxCoeff()};
    };
    // The interpolation area of two boxes: between them along the axis that separates their
    // centres most, spanning both along the other two (Fig. 3.7).
    const auto boxBetween = [](const Box& a, const Box& b) {
      Box between{a.lower.cwiseMin(b.lower), a.upper.cwiseMax(b.upper)};
      Eigen::Index axis = 0;
      (0.5 * (a.lower + a.upper) - 0.5 * (b.lower + b.upper)).cwiseAbs().maxCoeff(&axis);
      const bool a_low = a.lower[axis] + a.upper[axis] < b.lower[axis] + b.upper[axis];
      const Box& low = a_low ? a : b;
      const Box& high = a_low ? b : a;
      between.lower[axis] = std::min(low.upper[axis], high.lower[axis]);
      between.upper[axis] = std::max(low.upper[axis], high.lower[axis]);
      return between;
    };
    // A point of the box the way from `from` to it is passable along (any passable point when
    // there is no `from` yet).
    const auto draw = [&](const std::string& name, const Box& box, const Eigen::Vector3d* from) {
      for (int attempt = 0; attempt < 2000; ++attempt) {
        const Eigen::Vector3d p = random.uniform(box.lower, box.upper);
        if (from != nullptr ? segment_passable(*from, p) : passable(p)) return p;
      }
      throw InputError("trajectories: no straight way in the " + name +
                       " region stays within reach and clear of the base, the table and the obstacles");
    };
    // Each region: a chain of random points, every trajectory starting where the last ended,
    // the first on a passable straight way from the centre of area k's samples (where that
    // centre itself is passable): the arm is led there from k's posture, and a start behind
    // an obstacle would make every trajectory of the region collide on the way to it.
    const auto chain = [&](const std::string& name, const Box& box, int count, std::size_t k) {
      const Eigen::Vector3d centre = areas[k].samples.rowwise().mean();
      drawn_from[name] = k;
      Eigen::Vector3d from = draw(name, box, passable(centre) ? &centre : nullptr);
      for (int t = 0; t < count; ++t) {
        const Eigen::Vector3d to = draw(name, box, &from);
        region(name).push_back({name + "_" + std::to_string(t + 1), {from, to}});
        from = to;
      }
    };
    // Every area is a region of its own (Tab. 3.2's left and right). The interpolation regions
    // lie between areas taught one after the other: the tutor moves on to a neighbouring area,
    // and N areas give N - 1 such regions, with two areas the thesis' one between them.
    std::vector<std::string> names;
    for (std::size_t k = 0; k < areas.size(); ++k) {
      names.push_back(areas[k].name.empty() ? "area " + std::to_string(k + 1) : areas[k].name);
    }
    for (std::size_t k = 0; k < areas.size(); ++k) chain(names[k], sampleBox(areas[k]), per_area, k);
    for (std::size_t k = 0; k + 1 < areas.size(); ++k) {
      chain("between " + names[k] + " and " + names[k + 1], boxBetween(sampleBox(areas[k]), sampleBox(areas[k + 1])),
            2 * per_area, k);
    }
  }
  robot::CollisionWorld world(model, scene);
  robot::Kinematics kinematics(model);
  int total = 0;
  for (const auto& r : regions) total += static_cast<int>(r.second.size());
  int done = 0;
  for (const auto& [name, trajectories] : regions) {
    TrajectoryRegionResult out;
    out.name = name;
    // The arm starts in the taught posture of the area a drawn region was drawn from, else of
    // the area nearest the region's first point, is brought there kinematically, then follows
    // each straight segment at `speed`. Where that start touches something, the next nearest
    // area's is taken: otherwise every trajectory after a collision would restart in contact
    // and count as collided at once. Where every one does, the region starts in the first
    // area's taught posture itself, and each trajectory first leads the tip from there to its
    // start.
    const Eigen::Vector3d first = trajectories.front().waypoints.front();
    std::vector<std::size_t> by_distance(areas.size());
    for (std::size_t k = 0; k < areas.size(); ++k) by_distance[k] = k;
    std::stable_sort(by_distance.begin(), by_distance.end(), [&](std::size_t a, std::size_t b) {
      return (areas[a].samples.col(0) - first).norm() < (areas[b].samples.col(0) - first).norm();
    });
    if (const auto drawn = drawn_from.find(name); drawn != drawn_from.end()) {
      std::stable_partition(by_distance.begin(), by_distance.end(), [&](std::size_t k) { return k == drawn->second; });
    }
    Eigen::VectorXd q_area;
    for (const std::size_t k : by_distance) {
      const Eigen::VectorXd q_start =
          executeMotion(model, parameters, map, areas[k].q_fixed, [&](double) { return first; }, 0.0, 3.0, nullptr).q;
      world.update(q_start);
      if (world.contacts().empty()) {
        q_area = q_start;
        out.start_contact.clear();
        break;
      }
      if (out.start_contact.empty()) {
        out.start_contact = world.bodyName(world.contacts().front().body) + "/" + world.otherName(world.contacts().front());
      }
    }
    if (q_area.size() == 0) q_area = areas[by_distance.front()].q_fixed;
    // After a collision the arm is brought back, as on the real robot, to where the region
    // started.
    Eigen::VectorXd q = q_area;
    std::vector<double> errors;
    // Follows a chain of straight segments at `speed` from rest, then settles.
    const auto follow = [&](const Eigen::VectorXd& q_from, const std::vector<Eigen::Vector3d>& line) {
      std::vector<double> at{0.0};
      for (std::size_t i = 1; i < line.size(); ++i) at.push_back(at.back() + (line[i] - line[i - 1]).norm() / speed);
      const auto along = [&](double t) {
        for (std::size_t i = 1; i < line.size(); ++i) {
          if (t <= at[i]) return Eigen::Vector3d(line[i - 1] + (line[i] - line[i - 1]) * ((t - at[i - 1]) / std::max(1e-9, at[i] - at[i - 1])));
        }
        return line.back();
      };
      struct Followed {
        MotionOutcome outcome;
        Eigen::Vector3d contact_target;
      };
      MotionOutcome outcome = executeMotion(model, parameters, map, q_from, along, std::max(at.back(), 1e-3), 0.5, &world);
      const Eigen::Vector3d contact_target = along(std::min(outcome.contact_time, at.back()));
      return Followed{std::move(outcome), contact_target};
    };
    for (const auto& [trajectory_name, waypoints] : trajectories) {
      out.waypoints.push_back(waypoints);
      if (const std::string why = impossiblePoint(arm_reach, scene, waypoints); !why.empty()) {
        out.impossible.push_back(trajectory_name + ": " + why);
      }
      // The tip is first led on a straight way to the trajectory's start and comes to rest there;
      // E_task is measured along the trajectory alone. Chained into it, the lead-in's end
      // reversed the tip's direction at full speed wherever the trajectory started back
      // towards the arm, and the acceleration bound left the tip up to 18 mm behind there.
      // A contact on the lead-in counts: the arm has to get there. A trajectory of one point
      // (built in code; scene files need two) has no start of its own: it is the way there.
      kinematics.update(q);
      std::vector<Eigen::Vector3d> line = waypoints;
      if (line.size() == 1) {
        line.insert(line.begin(), kinematics.p_WT());
      } else if ((kinematics.p_WT() - line.front()).norm() > 1e-4 && crossesObstacle(scene, kinematics.p_WT(), line.front())) {
        // No arm follows the tip through an obstacle: brought there as the region's start is.
        ++out.starts_placed;
        q = executeMotion(model, parameters, map, q, [&](double) { return line.front(); }, 0.0, 3.0, nullptr).q;
        world.update(q);
        if (!world.contacts().empty()) {
          const robot::Contact& contact = world.contacts().front();
          const std::string touching = world.bodyName(contact.body) + "/" + world.otherName(contact);
          ++out.collisions;
          ++out.contacts[touching];
          out.collided.push_back({trajectory_name, touching, 0.0, line.front(), true});
          q = q_area;
          if (progress) progress(static_cast<double>(++done) / total);
          continue;
        }
      } else if ((kinematics.p_WT() - line.front()).norm() > 1e-4) {
        const auto lead_in = follow(q, {kinematics.p_WT(), waypoints.front()});
        if (lead_in.outcome.collided) {
          ++out.collisions;
          ++out.contacts[lead_in.outcome.contact];
          out.collided.push_back({trajectory_name, lead_in.outcome.contact, lead_in.outcome.contact_time, lead_in.contact_target, true});
          q = q_area;
          if (progress) progress(static_cast<double>(++done) / total);
          continue;
        }
        q = lead_in.outcome.q;
      }
      const auto [outcome, contact_target] = follow(q, line);
      errors.push_back(outcome.mean_error_m);
      if (1e3 * outcome.max_error_m > out.e_task_max_mm) {
        out.e_task_max_mm = 1e3 * outcome.max_error_m;
        out.e_task_max_trajectory = trajectory_name;
        out.e_task_max_time = outcome.max_error_time;
      }
      if (outcome.collided) {
        ++out.collisions;
        ++out.e_task_until_contact;
        ++out.contacts[outcome.contact];
        out.collided.push_back({trajectory_name, outcome.contact, outcome.contact_time, contact_target, false});
        q = q_area;
      } else {
        q = outcome.q;
      }
      if (progress) progress(static_cast<double>(++done) / total);
    }
    out.trajectories = static_cast<int>(trajectories.size());
    out.e_task_trajectories = static_cast<int>(errors.size());
    if (errors.empty()) {
      result.regions.push_back(out);
      continue;
    }
    double sum = 0.0;
    for (const double e : errors) sum += e;
    const double mean = sum / static_cast<double>(errors.size());
    double variance = 0.0;
    for (const double e : errors) variance += (e - mean) * (e - mean);
    out.e_task_mean_mm = 1e3 * mean;
    out.e_task_std_mm = 1e3 * std::sqrt(variance / static_cast<double>(errors.size()));
    result.regions.push_back(out);
  }
  return result;
}

PlanningResult evaluatePlanning(const robot::RobotModel& model, const robot::Scene& scene,
                                const robot::ParameterSet& parameters, const learning::Learner& map,
                                const planning::Itm& graph, const Eigen::VectorXd& q_start, int goals,
                                std::uint64_t seed, const ProgressCallback& progress, planning::PlanPostures postures) {
  if (goals < 1) throw InputError("goals: expected at least 1");
  const std::vector<int> all_nodes = graph.nodeIds();
  if (all_nodes.size() < 2) throw InputError("plan: the session's ITM has fewer than two nodes");
  model.checkPosture(q_start);
  // Goals are nodes the graph connects to where the arm starts: a node of another component
  // (an approach the map recorded away from every area) has no path by construction, which
  // says nothing about the planner; how many there are is reported.
  const int start_node = graph.nearestNode(robot::tipPose(model, q_start).translation(), true);
  std::vector<char> connected(static_cast<std::size_t>(graph.slotCount()), 0);
  std::vector<int> frontier{start_node};
  connected[static_cast<std::size_t>(start_node)] = 1;
  while (!frontier.empty()) {
    const int node = frontier.back();
    frontier.pop_back();
    for (const int next : graph.neighbors(node)) {
      if (connected[static_cast<std::size_t>(next)] == 0) {
        connected[static_cast<std::size_t>(next)] = 1;
        frontier.push_back(next);
      }
    }
  }
  std::vector<int> nodes;
  for (const int node : all_nodes) {
    if (connected[static_cast<std::size_t>(node)] != 0) nodes.push_back(node);
  }
  if (nodes.size() < 2) throw InputError("plan: the ITM connects no other node to where the arm starts");
  robot::CollisionWorld world(model, scene);
  learning::UniformRandom random(seed);
  PlanningResult result;
  result.goals = goals;
  result.disconnected_nodes = static_cast<int>(all_nodes.size() - nodes.size());
  Eigen::VectorXd q = q_start;
  double plan_ms = 0.0;
  for (int g = 0; g < goals; ++g) {
    const Eigen::Vector3d p_start = robot::tipPose(model, q).translation();
    // A goal where the tip already is (the last goal, or where a failed motion left it) would be
    // a move of no length, counted as a success. Nodes lie e_max apart: at most one is that near.
    int goal = nodes[random.index(nodes.size())];
    for (int redraw = 0; redraw < 1000 && (graph.prototype(goal).head<3>() - p_start).norm() < 0.01; ++redraw) {
      goal = nodes[random.index(nodes.size())];
    }
    const Eigen::Vector3d p_goal = graph.prototype(goal).head<3>();
    const auto t0 = std::chrono::steady_clock::now();
    const planning::PlannedPath path = planning::planPath(graph, p_start, p_goal);
    plan_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    PlannedMotion motion;
    motion.start_W = p_start;
    motion.goal_W = p_goal;
    motion.final_W = p_start;
    if (!path.found || !path.trajectory) {
      result.motions.push_back(motion);
      continue;
    }
    ++result.found;
    const planning::CubicSplineTrajectory& spline = *path.trajectory;
    motion.found = true;
    for (double t = 0.0; t < spline.duration(); t += 0.05) motion.planned_W.emplace_back(spline.position(t).head<3>());
    motion.planned_W.emplace_back(spline.position(spline.duration()).head<3>());
    // The collision world only counts contacts (Sect. A.4): a motion runs to its end through a
    // contact, so that each path is judged on its own and the next starts at this one's goal.
    const auto along = [&](double t) { return Eigen::Vector3d(spline.position(t).head<3>()); };
    const MotionOutcome outcome = [&] {
      if (postures == planning::PlanPostures::kLearned) {
        return executeMotion(model, parameters, map, q, along, spline.duration(), 2.0, &world, AtContact::kContinue);
      }
      const planning::PathPostures shown(graph, path, p_start, q);
      return executeMotion(
          model, parameters, [&shown](const Eigen::Vector3d& p_W, Eigen::VectorXd& q_c) { shown.at(p_W, q_c); }, q, along,
          spline.duration(), 2.0, &world, AtContact::kContinue);
    }();
    // Collision-free and within 1 cm are judged apart, as the thesis reports them (Sect. 8.3:
    // 100 collision-free, 99 within 1 cm): a motion through a contact may still end at its goal.
    if (!outcome.collided) ++result.collision_free;
    motion.final_W = robot::tipPose(model, outcome.q).translation();
    motion.final_error_m = (motion.final_W - p_goal).norm();
    motion.tracking_error_max_m = outcome.max_error_m;
    motion.reached_1cm = motion.final_error_m <= 0.01;
    if (motion.reached_1cm) ++result.reached_1cm;
    result.final_error_max_m = std::max(result.final_error_max_m, motion.final_error_m);
    result.tracking_error_max_m = std::max(result.tracking_error_max_m, motion.tracking_error_max_m);
    motion.collided = outcome.collided;
    motion.contact = outcome.contact;
    motion.contact_time = outcome.contact_time;
    motion.contact_path_error = outcome.contact_task_error;
    if (outcome.collided) ++result.contacts[outcome.contact];
    // Where the motion ended in contact, the next starts where the last one ended free (the
    // operator frees the arm): starting inside the obstacle would count it as collided as well.
    world.update(outcome.q);
    motion.ended_in_contact = !world.contacts().empty();
    if (!motion.ended_in_contact) q = outcome.q;
    result.motions.push_back(std::move(motion));
    if (progress) progress(static_cast<double>(g + 1) / goals);
  }
  result.mean_plan_ms = plan_ms / goals;
  return result;
}

}  // namespace flexirob::app
