// The simulated tutor teaching the simulated LWR IV in setup A through the workflow.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>

#include "app/evaluation.hpp"
#include "app/simulated_tutor.hpp"
#include "app/workflow.hpp"
#include "robot/collision.hpp"
#include "robot/controllers.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"
#include "tests/common/cylinder_arms.hpp"

namespace flexirob::app {
namespace {

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

struct TeachRun {
  TutorReport report;
  std::vector<TrainingArea> areas;
  std::shared_ptr<const learning::Learner> model;
  std::vector<TransitionCheck> checks;
  int itm_nodes = 0;
  int warnings = 0;
};

TeachRun teachSetupA(std::uint64_t seed) {
  const robot::Scene scene = robot::loadScene("setup_A");
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  robot::Simulation sim(lwr4(), &scene, parameters);
  sim.reset(*scene.home_posture);
  WorkflowOptions options;
  options.check_scene = &scene;
  options.elm.seed = seed;
  Workflow workflow(sim, parameters, options);
  TutorOptions tutor_options;
  tutor_options.seed = seed;
  tutor_options.circles = 1;
  tutor_options.posture_candidates = 8;
  SimulatedTutor tutor(sim, workflow, scene, parameters, tutor_options);
  TeachRun run;
  run.report = tutor.configure(2);
  run.areas = workflow.areas();
  run.model = workflow.model();
  run.checks = workflow.transitionChecks();
  run.itm_nodes = workflow.itm().nodeCount();
  for (const auto& event : workflow.events()) run.warnings += event.kind == WorkflowEvent::Kind::kWarning ? 1 : 0;
  return run;
}

TEST(SimulatedTutor, TeachesTwoAreasInSetupAWithoutCollisions) {
  const TeachRun run = teachSetupA(3);
  for (const auto& area : run.report.areas) {
    EXPECT_TRUE(area.taught) << area.name << ": " << area.failure << " (clearance " << area.clearance << " m)";
  }
  ASSERT_EQ(run.areas.size(), 2U);
  EXPECT_EQ(run.report.collisions, 0U);
  // The areas are where the scene puts them (within the approach accuracy and the circles).
  const robot::Scene scene = robot::loadScene("setup_A");
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_LT((run.areas[k].centre - scene.training_areas[k].p_WA).norm(), 0.05) << k;
    EXPECT_GE(run.areas[k].X.cols(), 20);
  }
  // The learned map reproduces each q_fixed at the area centre, and tells the areas apart.
  ASSERT_NE(run.model, nullptr);
  const double apart = (run.areas[0].q_fixed - run.areas[1].q_fixed).norm();
  for (const auto& area : run.areas) {
    const double error = (run.model->predict(area.centre) - area.q_fixed).norm();
    EXPECT_LT(error, 0.1);
    EXPECT_LT(error, 0.2 * apart);
  }
  EXPECT_GT(run.itm_nodes, 2);
  ASSERT_EQ(run.checks.size(), 1U);
}

TEST(SimulatedTutor, GuidesATeachInTrajectoryInProgramming) {
  const robot::Scene scene = robot::loadScene("setup_A");
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  robot::Simulation sim(lwr4(), &scene, parameters);
  sim.reset(*scene.home_posture);
  WorkflowOptions options;
  Workflow workflow(sim, parameters, options);
  TutorOptions tutor_options;
  tutor_options.circles = 1;
  tutor_options.posture_candidates = 8;
  SimulatedTutor tutor(sim, workflow, scene, parameters, tutor_options);
  tutor.configure(2);
  ASSERT_NE(workflow.model(), nullptr);
  // From the right area's centre over the interpolation area towards the left one.
  const std::vector<Eigen::Vector3d> waypoints{Eigen::Vector3d(-0.55, -0.3, 0.3), Eigen::Vector3d(-0.55, 0.0, 0.3),
                                               Eigen::Vector3d(-0.55, 0.2, 0.3)};
  ASSERT_TRUE(tutor.program(waypoints));
  EXPECT_EQ(workflow.stage(), Stage::kExecution);
  ASSERT_EQ(workflow.teachIns().size(), 1U);
  const Eigen::MatrixXd& path = workflow.teachIns()[0];
  ASSERT_GE(path.cols(), 10);
  // The recorded path ends near the last waypoint (the hand's reference tracks it).
  EXPECT_LT((path.col(path.cols() - 1) - waypoints.back()).norm(), 0.05);
  // EXECUTION: the hierarchical controller with the learned map drives the tip back.
  const Eigen::Vector3d goal(-0.55, -0.3, 0.3);
  ASSERT_TRUE(workflow.execute({goal}));
  for (int k = 0; k < 8000; ++k) workflow.step();
  EXPECT_TRUE(workflow.executionDone());
  robot::RobotState state;
  state.resize(lwr4().dof());
  sim.readState(state);
  EXPECT_LT((state.p_WT() - goal).norm(), 0.01);
  EXPECT_EQ(sim.collisions().events(), 0U);
}

// The areas are explored like the participants' helices (Sect. 3.3.1): wider than the old 4 cm
// circles and at several heights, never closer to an obstacle than the tutor allows (no contact).
TEST(SimulatedTutor, ExploresEachAreaWithAHelixAtSeveralHeights) {
  const TeachRun run = teachSetupA(3);
  ASSERT_EQ(run.areas.size(), 2U);
  EXPECT_EQ(run.report.collisions, 0U);
  double widest = 0.0;
  for (const auto& area : run.areas) {
    const Eigen::Vector3d extent = area.X.rowwise().maxCoeff() - area.X.rowwise().minCoeff();
    widest = std::max(widest, extent.head<2>().maxCoeff());
    EXPECT_GE(extent.head<2>().maxCoeff(), 0.015) << "an area hardly deflected";
    EXPECT_GE(extent.z(), 0.01) << "the samples lie at one height only";
  }
  EXPECT_GE(widest, 0.06);  // at least one area wider than the former 4 cm circles
}

// Sect. 3.3.1 (setup A, Tab. 3.2): with the map learned from two taught areas, the straight
// motion from one area's centre to the other's stays collision-free (checked every 10 ms in the
// collision world) and accurate up to the controller's lag v/κ_x.
TEST(SimulatedTutor, LearnedMapMovesStraightBetweenTwoTaughtAreasWithoutCollision) {
  const TeachRun run = teachSetupA(3);
  ASSERT_EQ(run.areas.size(), 2U);
  ASSERT_NE(run.model, nullptr);
  const robot::Scene scene = robot::loadScene("setup_A");
  const std::vector<robot::ParameterDeclaration> declarations = robot::reachParameters();
  robot::ParameterSet parameters(declarations);
  parameters.applyOverrides(scene.parameters);
  robot::CollisionWorld world(lwr4(), scene);
  const Eigen::Vector3d from = run.areas[0].centre;
  const Eigen::Vector3d to = run.areas[1].centre;
  const MotionOutcome settled = executeMotion(lwr4(), parameters, *run.model, run.areas[0].q_fixed,
                                              [&](double) { return from; }, 0.0, 3.0, &world);
  ASSERT_FALSE(settled.collided) << settled.contact;
  const double speed = 0.05;
  const double duration = (to - from).norm() / speed;
  const MotionOutcome moved = executeMotion(
      lwr4(), parameters, *run.model, settled.q, [&](double t) { return Eigen::Vector3d(from + (to - from) * (t / duration)); },
      duration, 2.0, &world);
  EXPECT_FALSE(moved.collided) << moved.contact << " at " << moved.contact_time << " s";
  EXPECT_LT(moved.final_error_m, 0.01);
  EXPECT_LT(moved.max_error_m, speed / parameters.get("hierarchical.kappa_x") + 0.005);
}

TEST(SimulatedTutor, IsDeterministicForAFixedSeed) {
  const TeachRun a = teachSetupA(5);
  const TeachRun b = teachSetupA(5);
  ASSERT_EQ(a.areas.size(), b.areas.size());
  for (std::size_t k = 0; k < a.areas.size(); ++k) {
    EXPECT_EQ(a.areas[k].X, b.areas[k].X);
    EXPECT_EQ(a.areas[k].Q, b.areas[k].Q);
  }
  EXPECT_EQ(a.itm_nodes, b.itm_nodes);
}

}  // namespace
}  // namespace flexirob::app

namespace flexirob::app {
namespace {

// A short teaching run of `model` (which must outlive it) on `scene`: learning in the caller's
// thread, one helix turn per area, eight posture candidates. As `teach` runs it (`as_the_cli`):
// learning in the background, the transitions checked, the tutor's defaults.
struct ShortTeaching {
  explicit ShortTeaching(robot::Scene scene_in, const robot::RobotModel& model = lwr4(), LearnerKind learner = LearnerKind::kElm,
                         bool as_the_cli = false)
      : scene(std::move(scene_in)), declarations(robot::reachParameters()), parameters(declarations), sim(model, &scene, parameters) {
    sim.reset(*scene.home_posture);
    WorkflowOptions options;
    options.learner = learner;
    options.background_learning = as_the_cli;
    if (as_the_cli) options.check_scene = &scene;
    workflow = std::make_unique<Workflow>(sim, parameters, options);
    if (!as_the_cli) {
      tutor_options.circles = 1;
      tutor_options.posture_candidates = 8;
    }
  }
  TutorReport configure(int areas) {
    SimulatedTutor tutor(sim, *workflow, scene, parameters, tutor_options);
    return tutor.configure(areas);
  }

  robot::Scene scene;
  std::vector<robot::ParameterDeclaration> declarations;
  robot::ParameterSet parameters;
  robot::Simulation sim;
  std::unique_ptr<Workflow> workflow;
  TutorOptions tutor_options;
};

// With OS-ELM the second approach runs under assistance blending (Sect. 6.1), and where the
// first area's confidence is high the robot holds the null space at what it learned: pushing the
// links along the way to setup C's right posture stalled at its start, and the tutor's push then
// swung the arm into the table and the right marker (before: the right area was not taught and
// the tutor went on to places of its own). The tutor now leads the tip out of the confident
// region first.
TEST(SimulatedTutor, UnderAssistanceBlendingLeadsTheTipOutOfTheConfidentRegionFirst) {
  ShortTeaching teaching(robot::loadScene("setup_C"), lwr4(), LearnerKind::kOsElm);
  teaching.tutor_options = TutorOptions{};  // as `teach --scene setup_C --areas 2 --learner oselm`
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(2);
  ASSERT_GE(report.areas.size(), 2U);
  for (std::size_t k = 0; k < 2; ++k) EXPECT_TRUE(report.areas[k].taught) << report.areas[k].name << ": " << report.areas[k].failure;
  EXPECT_EQ(report.areas.size(), 2U);  // no place of its own taken instead
  EXPECT_EQ(report.collisions, 0U);
  EXPECT_GT(report.areas[1].assistance_lead, 0.05);
  EXPECT_EQ(teaching.workflow->areas().size(), 2U);
}

// An approach let go of because the arm ran off leaves it in APPROACHING, and under assistance
// blending the robot moves it on by itself. Grabbed again while it still moved, every later
// approach ran off at once (setup_A: 3 areas of 4 taught, 10 contact events). The tutor waits
// for the arm to come to rest first. As `teach --scene setup_A --areas 4 --learner oselm`.
TEST(SimulatedTutor, WaitsForAnArmLetGoUnderAssistanceToComeToRestBeforeTheNextArea) {
  ShortTeaching teaching(robot::loadScene("setup_A"), lwr4(), LearnerKind::kOsElm, /*as_the_cli=*/true);
  const TutorReport report = teaching.configure(4);
  const auto ran_off = std::count_if(report.areas.begin(), report.areas.end(), [](const TutorAreaReport& area) {
    return area.failure.find("the arm ran off the way") != std::string::npos;
  });
  ASSERT_GE(ran_off, 1) << "the run no longer lets an arm go; it cannot show the wait";
  EXPECT_EQ(teaching.workflow->areas().size(), 4U);
  EXPECT_EQ(report.collisions, 0U);
}

// The scene's workspace box may reach beyond the arm: places the tutor picks itself lie within
// reach (a person does not ask the arm for a place it cannot get to).
TEST(SimulatedTutor, PicksItsOwnAreasWithinTheArmsReach) {
  robot::Scene scene = robot::loadScene("setup_A");  // its home posture, without its pillar and areas
  scene.obstacles.clear();
  scene.training_areas.clear();
  robot::EvaluationGrid box;
  box.lower = Eigen::Vector3d(-2.0, -2.0, 0.0);
  box.upper = Eigen::Vector3d(2.0, 2.0, 2.0);
  scene.grid = box;
  ShortTeaching teaching(scene);
  teaching.tutor_options.check_points = 0;  // random places, all kept
  const TutorReport report = teaching.configure(2);
  const ArmReach arm_reach = armReach(lwr4());
  ASSERT_GE(report.areas.size(), 2U);
  for (const TutorAreaReport& area : report.areas) {
    EXPECT_TRUE(area.automatic);
    EXPECT_TRUE(arm_reach.roomFor(area.target, 0.05)) << area.name;
    EXPECT_EQ(area.failure.find("out of the arm's reach"), std::string::npos) << area.name << ": " << area.failure;
  }
  EXPECT_EQ(teaching.workflow->areas().size(), 2U);
}

// A start posture inside an obstacle leaves no way to any area: the tutor says so before it
// starts, naming the obstacle, instead of failing area after area.
TEST(SimulatedTutor, RefusesToStartFromAPostureInsideAnObstacle) {
  robot::Scene scene = robot::loadScene("setup_A");
  robot::Obstacle block;
  block.name = "block_at_the_wrist";
  block.shape = robot::Obstacle::Shape::kSphere;
  block.size = Eigen::Vector3d(0.1, 0.0, 0.0);
  block.X_WO.translation() = robot::tipPose(lwr4(), *scene.home_posture).translation();
  scene.obstacles.push_back(block);
  ShortTeaching teaching(scene);
  try {
    teaching.configure(2);
    FAIL() << "configured from inside an obstacle";
  } catch (const flexirob::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("block_at_the_wrist; give the scene a collision-free home_posture"), std::string::npos)
        << error.what();
  }
  EXPECT_TRUE(teaching.workflow->areas().empty());
  EXPECT_EQ(teaching.workflow->stage(), Stage::kIdle) << "nothing was started";

  // A clamp around the base holds the first link in every posture: no home_posture helps.
  robot::Scene clamped = robot::loadScene("setup_A");
  robot::Obstacle clamp;
  clamp.name = "clamp";
  clamp.size = Eigen::Vector3d(0.3, 0.3, 0.3);
  clamp.X_WO.translation() = Eigen::Vector3d(0.0, 0.0, 0.2);
  clamped.obstacles.push_back(clamp);
  ShortTeaching clamped_teaching(clamped);
  try {
    clamped_teaching.configure(2);
    FAIL() << "configured inside a clamp";
  } catch (const flexirob::InputError& error) {
    EXPECT_NE(std::string(error.what()).find("into clamp, as every posture tried does; move clamp off the robot"), std::string::npos)
        << error.what();
  }
}

// The library takes the range the CLI offers: a helix under 1 cm cannot be told from standing
// still, and a NaN must not slip through a comparison.
TEST(SimulatedTutor, RefusesAHelixDiameterOutsideTheRangeTeachOffers) {
  const robot::Scene scene = robot::loadScene("setup_A");
  robot::ParameterSet parameters(robot::reachParameters());
  robot::Simulation sim(lwr4(), &scene, parameters);
  Workflow workflow(sim, parameters, WorkflowOptions{});
  for (const double diameter : {0.0, 0.005, 0.51, std::numeric_limits<double>::quiet_NaN()}) {
    TutorOptions options;
    options.circle_diameter = diameter;
    try {
      SimulatedTutor tutor(sim, workflow, scene, parameters, options);
      FAIL() << "accepted a helix diameter of " << diameter << " m";
    } catch (const flexirob::InputError& error) {
      EXPECT_NE(std::string(error.what()).find("circle diameter must be in [0.01, 0.5] m"), std::string::npos) << error.what();
    }
  }
  for (const double diameter : {kSmallestCircleDiameter, kLargestCircleDiameter}) {
    TutorOptions options;
    options.circle_diameter = diameter;
    EXPECT_NO_THROW(SimulatedTutor(sim, workflow, scene, parameters, options)) << diameter;
  }
}

// An approach given up can leave the arm resting in an obstacle (a let-go under assistance
// blending, setup_B): every way planned from inside the contact failed, and so did every later
// area. The tutor first pulls the arm out, the penetration shrinking at every step, and never
// enters an obstacle again on the way on.
TEST(SimulatedTutor, LeadsAnArmRestingInAnObstacleOutBeforeLeadingItOn) {
  robot::Scene scene = robot::loadScene("setup_A");
  const Eigen::VectorXd q_resting = *scene.home_posture;
  robot::Kinematics kinematics(lwr4());
  kinematics.update(q_resting);
  robot::Obstacle post;
  post.name = "post_at_the_elbow";
  post.shape = robot::Obstacle::Shape::kSphere;
  post.size = Eigen::Vector3d(0.04, 0.0, 0.0);
  post.X_WO.translation() = kinematics.X_WB(4).translation() + Eigen::Vector3d(0.0, 0.05, 0.0);
  scene.obstacles.push_back(post);
  ShortTeaching teaching(scene);
  robot::CollisionWorld world(lwr4(), teaching.scene);
  // How deep the arm is in, all touching pairs together (two links can be in the post at once).
  const auto deepest = [&world](const Eigen::VectorXd& q) {
    world.update(q);
    double depth = 0.0;
    for (const robot::Contact& contact : world.contacts()) depth += contact.depth;
    return depth;
  };
  ASSERT_GT(deepest(q_resting), 0.02) << "the arm must start well inside the post";
  const Eigen::VectorXd q_goal = *teaching.scene.training_areas.front().posture;
  ASSERT_EQ(deepest(q_goal), 0.0);

  SimulatedTutor tutor(teaching.sim, *teaching.workflow, teaching.scene, teaching.parameters, teaching.tutor_options);
  const std::vector<Eigen::VectorXd> way = tutor.planWay(q_resting, q_goal);
  ASSERT_GE(way.size(), 2U) << "no way out of the post";
  EXPECT_LT((way.front() - q_resting).norm(), 1e-12);
  EXPECT_LT((way.back() - q_goal).norm(), 1e-12);
  EXPECT_GT(deepest(way[1]), 0.0) << "the way out starts with small steps, still in the post";
  // Each step out ends shallower than it began and on the way goes no deeper than half a
  // millimetre; once out, the arm stays out.
  bool out = false;
  for (std::size_t i = 0; i + 1 < way.size(); ++i) {
    const double depth = deepest(way[i]);
    for (int s = 1; s <= 20; ++s) {
      const double d = deepest(way[i] + (way[i + 1] - way[i]) * (s / 20.0));
      if (out) {
        ASSERT_EQ(d, 0.0) << "back into " << world.otherName(world.contacts().front()) << " after way point " << i;
      } else {
        ASSERT_LE(d, depth + 5e-4) << "deeper in after way point " << i;
      }
    }
    if (!out) {
      ASSERT_LT(deepest(way[i + 1]), depth + (depth == 0.0 ? 1e-12 : 0.0)) << "no step out at way point " << i;
    }
    out = out || deepest(way[i + 1]) == 0.0;
  }
  EXPECT_TRUE(out);
}

// Areas a person would see at once cannot be taught are reported as such, and the next one is
// taught as usual.
TEST(SimulatedTutor, SaysWhyAnAreaInsideAnObstacleOrOutOfReachIsNotTaught) {
  robot::Scene scene = robot::loadScene("setup_A");
  robot::Obstacle block;
  block.name = "crate";
  block.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  block.X_WO.translation() = Eigen::Vector3d(-0.5, 0.5, 0.1);
  scene.obstacles.push_back(block);
  robot::Area inside{"in_the_crate", block.X_WO.translation(), 0.05, std::nullopt, std::nullopt};
  robot::Area far{"far_away", Eigen::Vector3d(-2.0, 0.0, 0.4), 0.05, std::nullopt, std::nullopt};
  scene.training_areas.insert(scene.training_areas.begin(), {inside, far});
  ShortTeaching teaching(scene);
  const TutorReport report = teaching.configure(1);
  ASSERT_EQ(report.areas.size(), 3U);
  EXPECT_FALSE(report.areas[0].taught);
  EXPECT_EQ(report.areas[0].failure, "the area's centre lies inside crate");
  EXPECT_FALSE(report.areas[1].taught);
  EXPECT_NE(report.areas[1].failure.find("out of the arm's reach"), std::string::npos) << report.areas[1].failure;
  EXPECT_TRUE(report.areas[2].taught) << report.areas[2].failure;
  EXPECT_EQ(teaching.workflow->areas().size(), 1U);
}

// The LWR IV with a shoulder joint (A2) of 3 Nm: it cannot hold the arm in any posture that
// reaches setup A's first area (a person sees the arm sink), and the area's failure says so
// instead of naming the contacts of the sunken arm.
TEST(SimulatedTutor, SaysWhenTheJointsCannotHoldTheArmInAnyPostureReachingTheArea) {
  const std::filesystem::path urdf_file = resolveRobotPath("lwr4");
  std::ostringstream text;
  text << std::ifstream(urdf_file).rdbuf();
  std::string urdf = text.str();
  const std::size_t a2 = urdf.find("<joint name=\"A2\"");
  ASSERT_NE(a2, std::string::npos);
  const std::size_t effort = urdf.find("effort=\"176.0\"", a2);
  ASSERT_NE(effort, std::string::npos);
  urdf.replace(effort, std::string("effort=\"176.0\"").size(), "effort=\"3.0\"");
  const robot::RobotModel weak = robot::RobotModel::fromUrdfString(urdf, urdf_file.parent_path());

  robot::Scene scene = robot::loadScene("setup_A");
  scene.training_areas.resize(1);
  ShortTeaching teaching(scene, weak);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(1);
  ASSERT_GE(report.areas.size(), 1U);
  EXPECT_FALSE(report.areas[0].taught);
  EXPECT_NE(report.areas[0].failure.find("the joints cannot hold the arm up there"), std::string::npos) << report.areas[0].failure;
  EXPECT_NE(report.areas[0].failure.find("joint 'A2'"), std::string::npos) << report.areas[0].failure;
  EXPECT_NE(report.areas[0].failure.find("% of its effort limit of 3.0 Nm"), std::string::npos) << report.areas[0].failure;
  EXPECT_NE(report.areas[0].failure.find("at most 90 % of an effort limit"), std::string::npos) << report.areas[0].failure;
}

// The LWR IV standing straight up, an area beside it at x = 0: the tip pushed towards it (in the
// plane x = 0, through every joint axis) turns no joint, and on_affected never fired at any force
// (the area was given up). The tutor pushes where the arm gives instead.
TEST(SimulatedTutor, NoticesThatAnArmStandingStraightUpCannotFeelAPushThroughItsAxesAndPushesWhereItGives) {
  robot::Scene scene;
  scene.home_posture = Eigen::VectorXd::Zero(7);
  scene.training_areas.push_back({"beside", Eigen::Vector3d(0.0, 0.6, 0.2), 0.05, std::nullopt, std::nullopt});
  ShortTeaching teaching(scene);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(1);
  ASSERT_GE(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  EXPECT_LT((teaching.workflow->areas()[0].centre - Eigen::Vector3d(0.0, 0.6, 0.2)).norm(), 0.05);
}

// Setup I's area I3 lies under the board, on the far side of it from the home posture: the
// straight joint-space way there runs into the board, so the tutor has to lead the arm around
// it (the approach planner) and does so without a contact.
TEST(SimulatedTutor, LeadsTheArmAroundTheBoardToAnAreaUnderIt) {
  robot::Scene scene = robot::loadScene("setup_I");
  const robot::Area under_board = scene.training_areas.at(2);
  ASSERT_EQ(under_board.name, "I3");
  scene.training_areas = {under_board};
  ShortTeaching teaching(scene);
  const TutorReport report = teaching.configure(1);
  ASSERT_EQ(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  EXPECT_EQ(report.collisions, 0U);
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  EXPECT_LT((teaching.workflow->areas()[0].centre - under_board.p_WA).norm(), 0.05);
}

// Where no way to the best posture is found, a person tries another one. The postures the
// choice offers reach the target, keep the clearance asked for and differ from each other.
TEST(SimulatedTutor, OffersDistinctAlternativePosturesWithEnoughClearance) {
  robot::Scene scene = robot::loadScene("setup_I");
  const robot::Area under_board = scene.training_areas.at(2);
  ShortTeaching teaching(scene);
  teaching.tutor_options.posture_candidates = 24;
  teaching.tutor_options.posture_attempts = 4;
  SimulatedTutor tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  const std::vector<PostureChoice> choices = tutor.choosePostures(under_board.p_WA, std::nullopt);
  ASSERT_GE(choices.size(), 2U);
  EXPECT_LE(choices.size(), 4U);
  ASSERT_TRUE(choices.front().found);
  robot::CollisionWorld world(lwr4(), scene);
  std::vector<Eigen::VectorXd> postures{choices.front().q};
  for (std::size_t i = 1; i < choices.size(); ++i) {
    const PostureChoice& alternative = choices[i];
    EXPECT_TRUE(alternative.found);
    EXPECT_GE(alternative.clearance, teaching.tutor_options.min_clearance);
    EXPECT_LT((robot::tipPose(lwr4(), alternative.q).translation() - under_board.p_WA).norm(), 1e-3);
    world.update(alternative.q);
    EXPECT_TRUE(world.contacts().empty());
    for (const Eigen::VectorXd& taken : postures) EXPECT_GT((alternative.q - taken).norm(), 0.05);
    postures.push_back(alternative.q);
  }
}

// A listed place between two shelf boards: IK from random null-space targets puts a link within
// a few centimetres of a board every time, and the area used to be given up. A person takes
// the best posture found and moves the links away from the boards while holding the tip.
TEST(SimulatedTutor, PushesTheLinksClearWhereNoPostureFoundKeepsTheClearanceAtAListedPlace) {
  robot::Scene scene = robot::parseScene(R"(name: shelf
obstacles:
  - {name: board_low, shape: box, size: [0.3, 0.8, 0.02], position: [-0.55, 0, 0.3]}
  - {name: board_high, shape: box, size: [0.3, 0.8, 0.02], position: [-0.55, 0, 0.6]}
training_areas:
  - {name: between_boards, centre: [-0.5, 0.1, 0.45], radius: 0.05}
)",
                                         ".", "shelf");
  scene.home_posture = homePosture(lwr4(), scene);
  const Eigen::Vector3d p_between = scene.training_areas.at(0).p_WA;
  ShortTeaching teaching(scene);
  // Two tutors of the same seed draw the same IK candidates; only the second pushes them.
  SimulatedTutor random_only_tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  const std::vector<PostureChoice> random_only = random_only_tutor.choosePostures(p_between, std::nullopt, nullptr, false);
  ASSERT_FALSE(!random_only.empty() && random_only.front().found) << "the random IK alone keeps the clearance here";
  SimulatedTutor tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  const std::vector<PostureChoice> pushed = tutor.choosePostures(p_between, std::nullopt, nullptr, true);
  ASSERT_FALSE(pushed.empty());
  const PostureChoice& best = pushed.front();
  EXPECT_TRUE(best.found);
  EXPECT_GE(best.clearance, teaching.tutor_options.min_clearance);
  EXPECT_LT((robot::tipPose(lwr4(), best.q).translation() - p_between).norm(), 1e-3);
  robot::CollisionWorld world(lwr4(), scene);
  world.update(best.q);
  EXPECT_TRUE(world.contacts().empty());
  EXPECT_NEAR(world.clearance(0.5).distance, best.clearance, 1e-9);
  const TutorReport report = teaching.configure(1);
  ASSERT_GE(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  EXPECT_EQ(report.collisions, 0U);
}

// With no way around obstacles searched (0 RRT iterations) only a straight joint-space way
// counts: one posture tried is given up where several tried find one reachable.
TEST(SimulatedTutor, TriesTheNextPostureWhenNoWayToTheBestOneIsFound) {
  robot::Scene scene = robot::loadScene("setup_I");
  const robot::Area under_board = scene.training_areas.at(2);
  scene.training_areas = {under_board};
  int taught_with[2] = {0, 0};
  for (const int attempts : {1, 24}) {
    ShortTeaching teaching(scene);
    teaching.tutor_options.posture_candidates = 24;
    teaching.tutor_options.approach_iterations = 0;
    teaching.tutor_options.posture_attempts = attempts;
    const TutorReport report = teaching.configure(1);
    ASSERT_GE(report.areas.size(), 1U);  // an automatic area follows one given up
    ASSERT_EQ(report.areas[0].name, "I3");
    taught_with[attempts == 1 ? 0 : 1] = report.areas[0].taught ? 1 : 0;
  }
  EXPECT_EQ(taught_with[0], 0);
  EXPECT_EQ(taught_with[1], 1);
}

// Many arms turn a joint without end (URDF "continuous"): its limits are ±inf, which the
// tutor's random IK targets and its way around obstacles cannot be drawn from. Before, both
// came out NaN for such a joint and the teaching never ended.
// The hands push one link per cycle; on the 9-DoF arm's light links that leaves a vibration of
// a few hundredths rad/s at the posture, which the tutor must not take for an arm still moving
// (A1_left, the freely accessible front area, used to be given up with 0.001 rad to go).
TEST(SimulatedTutor, TeachesTheFrontAreaOfTheNineJointArm) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("arm9"));
  robot::Scene scene = robot::loadScene("arm9_areas");
  const robot::Area front = scene.training_areas.at(0);
  ASSERT_EQ(front.name, "A1_left");
  scene.training_areas = {front};
  ShortTeaching teaching(scene, model);
  const TutorReport report = teaching.configure(1);
  ASSERT_GE(report.areas.size(), 1U);
  EXPECT_EQ(report.areas[0].name, "A1_left");
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  EXPECT_EQ(report.collisions, 0U);
  // The hands keep the arm on the planned way: the reference waits for the lagging light links
  // (unbounded, it ran 0.11 rad ahead on this approach).
  EXPECT_GT(report.max_approach_lead, 0.0);
  EXPECT_LE(report.max_approach_lead, 0.06);
}

TEST(SimulatedTutor, TeachesAnArmWithAnUnboundedJointAroundTheBoard) {
  const std::filesystem::path urdf_file = resolveRobotPath("lwr4");
  std::ostringstream text;
  text << std::ifstream(urdf_file).rdbuf();
  std::string urdf = text.str();
  const std::string bounded_a1 = "<joint name=\"A1\" type=\"revolute\">";
  ASSERT_NE(urdf.find(bounded_a1), std::string::npos);
  urdf.replace(urdf.find(bounded_a1), bounded_a1.size(), "<joint name=\"A1\" type=\"continuous\">");
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(urdf, urdf_file.parent_path());
  ASSERT_TRUE(std::isinf(model.softUpperLimits()[0]));

  robot::Scene scene = robot::loadScene("setup_I");
  const robot::Area under_board = scene.training_areas.at(2);
  ASSERT_EQ(under_board.name, "I3");
  scene.training_areas = {under_board};
  ShortTeaching teaching(scene, model);
  teaching.tutor_options.approach_iterations = 1000;
  const TutorReport report = teaching.configure(1);
  ASSERT_EQ(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  EXPECT_EQ(report.collisions, 0U);
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  EXPECT_TRUE(teaching.workflow->areas()[0].q_fixed.allFinite());
}

// A 3-DoF arm whose second and third joints turn about parallel y axes: the hands must push
// each link off its own joint axis (a push on body 3's y axis cannot turn joint 3, and the
// approach stalled 0.05 rad short of every posture).
constexpr const char* kParallelAxesArm = R"(<robot name="parallel_axes">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
  <link name="l1"><inertial><origin xyz="0 0 0.15"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
  <link name="l2"><inertial><origin xyz="0 0 0.2"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/><limit lower="-2.9" upper="2.9" velocity="2" effort="100"/></joint>
  <link name="l3"><inertial><origin xyz="0 0 0.2"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
  <joint name="tip_joint" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0 0 0.4"/></joint>
  <link name="tip"><inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
</robot>)";

robot::Scene parallelAxesScene() {
  robot::Scene scene;
  scene.name = "parallel_axes";
  scene.home_posture = Eigen::Vector3d(0.3, 0.6, 0.8);
  robot::Area area;
  area.name = "front";
  area.p_WA = Eigen::Vector3d(0.3, 0.1, 0.6);
  area.radius = 0.05;
  scene.training_areas = {area};
  return scene;
}

TEST(SimulatedTutor, PushesEveryJointOfAnArmWithParallelJointAxes) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(kParallelAxesArm, ".");
  ShortTeaching teaching(parallelAxesScene(), model);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(1);
  ASSERT_FALSE(report.areas.empty());
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  robot::Kinematics kinematics(model);
  kinematics.update(teaching.workflow->areas()[0].q_fixed);
  EXPECT_LT((kinematics.p_WT() - teaching.scene.training_areas[0].p_WA).norm(), 0.02);
}

// A 6-DoF arm of cylinders whose tool and cable hang off the last link through fixed joints.
// In front of a wall its approach ends creeping: within 0.01 rad of the posture, slower than
// the triggers' still speed for 2 s, so on_converged posed the arm under the hands, their next
// push started a recording there, and the one area was taught as two (100 samples and the
// helix's 943).
constexpr double kDegree = std::numbers::pi / 180.0;

// limits: per joint (lower, upper) [rad]; ±2.9 rad each where empty.
std::string creepingArm(const std::vector<std::pair<double, double>>& limits = {}) {
  struct Segment {
    const char* axis;
    double length;
  };
  const Segment segments[] = {{"0 0 1", 0.3}, {"0 1 0", 0.4}, {"0 1 0", 0.35}, {"0 0 1", 0.1}, {"0 1 0", 0.1}, {"0 0 1", 0.08}};
  const auto link = [](const std::string& name, double length, double radius) {
    std::ostringstream text;
    text << "<link name=\"" << name << "\"><inertial><origin xyz=\"0 0 " << length / 2 << "\"/><mass value=\"1\"/>"
         << "<inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.002\"/></inertial>"
         << "<collision><origin xyz=\"0 0 " << length / 2 << "\"/><geometry><cylinder radius=\"" << radius << "\" length=\"" << length
         << "\"/></geometry></collision></link>\n";
    return text.str();
  };
  const auto joint = [](const std::string& name, const std::string& type, const std::string& parent, const std::string& child,
                        double z, const char* axis, std::pair<double, double> limit = {-2.9, 2.9}) {
    std::ostringstream text;
    text << "<joint name=\"" << name << "\" type=\"" << type << "\"><parent link=\"" << parent << "\"/><child link=\"" << child
         << "\"/><origin xyz=\"0 0 " << z << "\"/><axis xyz=\"" << axis << "\"/>";
    if (type != "fixed") text << "<limit lower=\"" << limit.first << "\" upper=\"" << limit.second << "\" velocity=\"2\" effort=\"100\"/>";
    text << "</joint>\n";
    return text.str();
  };
  std::string urdf = "<robot name=\"creeping\">\n" + link("l0", 0.1, 0.08);
  double previous_length = 0.1;
  for (int i = 0; i < 6; ++i) {
    const std::string parent = "l" + std::to_string(i);
    const std::string child = "l" + std::to_string(i + 1);
    const std::pair<double, double> limit = limits.empty() ? std::pair(-2.9, 2.9) : limits[static_cast<std::size_t>(i)];
    urdf += joint("j" + std::to_string(i + 1), "revolute", parent, child, previous_length, segments[i].axis, limit) +
            link(child, segments[i].length, 0.04);
    previous_length = segments[i].length;
  }
  urdf += joint("tool_joint", "fixed", "l6", "tool", 0.08, "0 0 1") + link("tool", 0.1, 0.02);
  urdf += joint("cable_joint", "fixed", "tool", "cable", 0.1, "0 0 1") + link("cable", 0.05, 0.01);
  return urdf + "</robot>\n";
}

TEST(SimulatedTutor, AnArmPosedUnderTheHandsAtTheEndOfItsWayIsTaughtOneArea) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(creepingArm(), ".");
  ASSERT_EQ(model.tipLink(), "cable");
  robot::Scene scene;
  scene.name = "wall";
  scene.home_posture = Eigen::VectorXd(6);
  *scene.home_posture << 0.0, 30 * kDegree, 60 * kDegree, 0.0, 60 * kDegree, 0.0;
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.05, 0.8, 0.3);
  wall.X_WO = Eigen::Translation3d(0.45, 0.0, 0.15) * Eigen::AngleAxisd(30 * kDegree, Eigen::Vector3d::UnitZ());
  scene.obstacles = {wall};
  robot::Area area;
  area.name = "front";
  area.p_WA = Eigen::Vector3d(0.5, 0.0, 0.5);
  area.radius = 0.08;
  scene.training_areas = {area};
  ShortTeaching teaching(scene, model);
  teaching.tutor_options.check_points = 0;
  teaching.tutor_options.circles = 4;
  teaching.tutor_options.posture_candidates = 24;
  const TutorReport report = teaching.configure(1);
  ASSERT_EQ(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  // The whole helix (4 turns of 4 s) went into the one area, and spans about its diameter.
  EXPECT_GT(teaching.workflow->areas()[0].X.cols(), 600);
  EXPECT_EQ(report.areas[0].samples, teaching.workflow->areas()[0].X.cols());
  EXPECT_GT(report.areas[0].span, 0.8 * report.areas[0].helix_diameter);
  EXPECT_LT(report.areas[0].span, 1.1 * report.areas[0].helix_diameter);
}

// An arm whose joints can hardly move (limits 0.01 rad wide about its posture) does not follow
// the helix: the recording is a spot of a few millimetres. Before, `teach` reported it as a taught
// area, and the learner read it as a posture to keep there.
TEST(SimulatedTutor, TakesBackARecordingTheArmDidNotSpread) {
  Eigen::VectorXd home(6);
  home << 0.0, 30 * kDegree, 60 * kDegree, 0.0, 60 * kDegree, 0.0;
  std::vector<std::pair<double, double>> limits;
  for (Eigen::Index i = 0; i < home.size(); ++i) limits.emplace_back(home[i] - 0.005, home[i] + 0.005);
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(creepingArm(limits), ".");
  robot::Scene scene;
  scene.name = "free";
  scene.home_posture = home;
  robot::Area area;
  area.name = "here";
  area.p_WA = robot::tipPose(model, home).translation();
  area.radius = 0.08;
  scene.training_areas = {area};
  ShortTeaching teaching(scene, model);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(1);
  // The listed area first; the places the tutor then tries on its own are out of the arm's reach.
  ASSERT_GE(report.areas.size(), 1U);
  const TutorAreaReport& here = report.areas[0];
  EXPECT_EQ(here.name, "here");
  EXPECT_FALSE(here.taught);
  EXPECT_NE(here.failure.find("taken back: the recording spans"), std::string::npos) << here.failure;
  EXPECT_GT(here.helix_diameter, 0.1);
  EXPECT_LT(here.span, 0.25 * here.helix_diameter);
  EXPECT_GT(here.samples, 0);
  EXPECT_TRUE(teaching.workflow->areas().empty());
}

// A small helix (setup_II's II10 lies so close to the boxes that it shrinks to a few centimetres;
// here the tutor is asked for a 2 cm one) drawn at the usual pace moved the tip so slowly that no
// joint reached the workflow's still speed: on_converged ended the recording after 2 s (114
// samples of 16 s in II10), and the rest of the helix went into the next area. The small helix is
// drawn faster, and the whole of it is recorded into its own area.
TEST(SimulatedTutor, RecordsTheWholeOfASmallHelix) {
  robot::Scene scene = robot::loadScene("setup_A");
  scene.training_areas.resize(1);
  ShortTeaching teaching(scene);
  teaching.tutor_options = TutorOptions{};
  teaching.tutor_options.check_points = 0;
  teaching.tutor_options.circle_diameter = 0.02;
  const TutorReport report = teaching.configure(1);
  ASSERT_EQ(report.areas.size(), 1U);
  EXPECT_TRUE(report.areas[0].taught) << report.areas[0].failure;
  ASSERT_EQ(teaching.workflow->areas().size(), 1U);
  // 4 turns of 4 s at 0.02 s per sample.
  EXPECT_GT(teaching.workflow->areas()[0].X.cols(), 750);
}

// Kinematic IK for the tip position p_W with the hierarchical controller (Eq. 2.11), its
// null-space target q_null, started at q_null.
Eigen::VectorXd solveIk(const robot::ParameterSet& parameters, const Eigen::Vector3d& p_W, const Eigen::VectorXd& q_null) {
  robot::HierarchicalController controller(lwr4(), parameters);
  Eigen::VectorXd q = q_null;
  Eigen::VectorXd q_target(q.size());
  for (int it = 0; it < 400; ++it) {
    controller.target(q, p_W, q_null, 0.02, q_target);
    q = q_target.cwiseMax(lwr4().softLowerLimits()).cwiseMin(lwr4().softUpperLimits());
  }
  return q;
}

// A posture with the clearance the tutor asks for wins over one nearer its reference (here the
// current posture) without it; before, the nearer one won, and the area was given up although
// a usable posture had been found.
TEST(SimulatedTutor, PrefersAPostureWithEnoughClearanceOverANearerOneWithout) {
  robot::Scene scene = robot::loadScene("setup_A");
  scene.obstacles.clear();
  scene.training_areas.clear();
  const Eigen::VectorXd home = *scene.home_posture;
  robot::Kinematics kinematics(lwr4());
  kinematics.update(home);
  const Eigen::Vector3d p_target = kinematics.p_WT();
  const Eigen::Vector3d elbow = kinematics.X_WB(4).translation();
  // A block beside the elbow, moved out until the home posture keeps 2.7-3 cm from it.
  robot::Obstacle block;
  block.name = "block";
  block.size = Eigen::Vector3d(0.1, 0.1, 0.1);
  for (double offset = 0.05; offset < 0.3; offset += 0.002) {
    block.X_WO = Eigen::Isometry3d(Eigen::Translation3d(elbow + Eigen::Vector3d(0.0, offset, 0.0)));
    scene.obstacles = {block};
    robot::CollisionWorld world(lwr4(), scene);
    world.update(home);
    if (world.contacts().empty() && world.clearance(0.5).distance > 0.027) break;
  }
  ShortTeaching teaching(scene);
  teaching.sim.reset(home);
  teaching.tutor_options.posture_candidates = 3;  // the suggestion, the reference, the current posture
  const double min_clearance = teaching.tutor_options.min_clearance;
  // The suggestion: the same tip position with the elbow swung away from the block (q3) and the
  // flange turned (q7, which does not move the tip), far from the home posture in joint space.
  Eigen::VectorXd swung = home;
  swung[2] = -2.4;
  swung[6] = 2.8;
  const Eigen::VectorXd suggested = solveIk(teaching.parameters, p_target, swung);
  robot::CollisionWorld world(lwr4(), scene);
  world.update(home);
  const double home_clearance = world.clearance(0.5).distance;
  world.update(suggested);
  const double suggested_clearance = world.clearance(0.5).distance;
  kinematics.update(suggested);
  ASSERT_LT((kinematics.p_WT() - p_target).norm(), 1e-3);
  ASSERT_GT(home_clearance, 0.0);
  ASSERT_LT(home_clearance, min_clearance);
  ASSERT_GE(suggested_clearance, min_clearance + 0.005);
  // The home posture scores higher by the tutor's rule (clearance up to 8 cm, 0.2 per rad from
  // the reference), so only the clearance requirement can make the suggestion win.
  ASSERT_GT(home_clearance / 0.08, std::min(suggested_clearance, 0.08) / 0.08 - 0.2 * (suggested - home).norm());

  SimulatedTutor tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  const std::vector<PostureChoice> choices = tutor.choosePostures(p_target, suggested);
  ASSERT_FALSE(choices.empty());
  const PostureChoice& choice = choices.front();
  EXPECT_TRUE(choice.found);
  EXPECT_GE(choice.clearance, min_clearance);
  EXPECT_LT((choice.q - suggested).norm(), 0.05);
}

// A seven-joint arm with a short slide (12.6 cm of travel) in the middle of its chain. IK
// moves the slide first (a metre of slide moves the tip a metre, a radian of a joint less), so
// it tends to end at a stop; the tutor penalized postures within 0.2 of a limit, which for a
// slide of 12.6 cm was every posture, and it chose postures with the slide at its stop: the
// area warned, and the hands' deflections under π_rec ran the slide into it.
std::string armWithAShortSlide() {
  std::ostringstream urdf;
  urdf << "<robot name=\"slide7\"><link name=\"base\"/>\n";
  const char* axes[] = {"0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1"};
  std::string parent = "base";
  double offset = 0.055;
  for (int j = 0; j < 7; ++j) {
    const std::string child = "l" + std::to_string(j + 1);
    const bool slide = j == 2;
    urdf << "<joint name=\"j" << j + 1 << "\" type=\"" << (slide ? "prismatic" : "revolute") << "\"><parent link=\"" << parent
         << "\"/><child link=\"" << child << "\"/><origin xyz=\"0 0 " << offset << "\"/><axis xyz=\"" << axes[j] << "\"/>"
         << "<limit lower=\"" << (slide ? 0.0 : -2.9) << "\" upper=\"" << (slide ? 0.126 : 2.9) << "\" velocity=\"1.5\" effort=\"150\"/></joint>\n"
         << "<link name=\"" << child << "\"><inertial><origin xyz=\"0 0 0.0786\"/><mass value=\"1.83\"/>"
         << "<inertia ixx=\"0.0047\" ixy=\"0\" ixz=\"0\" iyy=\"0.0047\" iyz=\"0\" izz=\"0.0019\"/></inertial>"
         << "<collision><origin xyz=\"0 0 0.0786\"/><geometry><cylinder radius=\"0.046\" length=\"0.157\"/></geometry></collision></link>\n";
    parent = child;
    offset = 0.157;
  }
  urdf << "</robot>\n";
  return urdf.str();
}

TEST(SimulatedTutor, ChoosesPosturesThatKeepAShortSlideAwayFromItsStops) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(armWithAShortSlide(), ".");
  ASSERT_EQ(model.joints()[2].type, robot::JointType::kPrismatic);
  robot::Scene scene;
  scene.name = "open";
  scene.home_posture = model.midPosture();
  ShortTeaching teaching(scene, model);
  teaching.tutor_options.posture_candidates = 24;
  const double near = nearLimitMargin(model.joints()[2], teaching.workflow->options());
  SimulatedTutor tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  const std::vector<Eigen::Vector3d> places{{-0.48, -0.47, 0.48}, {0.45, 0.2, 0.55}, {0.1, 0.5, 0.35}};
  for (const Eigen::Vector3d& place : places) {
    const std::vector<PostureChoice> choices = tutor.choosePostures(place, std::nullopt);
    ASSERT_FALSE(choices.empty()) << place.transpose();
    const Eigen::VectorXd& q = choices.front().q;
    EXPECT_LT((robot::tipPose(model, q).translation() - place).norm(), 1e-3) << place.transpose();
    const double slide = q[2];
    EXPECT_GE(std::min(slide - model.softLowerLimits()[2], model.softUpperLimits()[2] - slide), near)
        << "slide at " << slide << " m, at " << place.transpose();
  }
}


// A scene with nothing but the table, a 7-joint arm straight up at the start, and two listed
// places without postures.
robot::Scene openSceneWithTwoPlaces(const Eigen::Vector3d& first, const Eigen::Vector3d& second, double radius) {
  robot::Scene scene;
  scene.name = "open";
  scene.home_posture = Eigen::VectorXd::Zero(7);
  for (const Eigen::Vector3d& centre : {first, second}) {
    robot::Area area;
    area.name = "place";
    area.p_WA = centre;
    area.radius = radius;
    scene.training_areas.push_back(area);
  }
  return scene;
}

// Tab. A.1's gains, the admittance's damping, the simulation's drift damping and the tutor's
// hands are the LWR IV's. On a 25 cm arm of a few hundred grams the hands' pushes made it ring
// at up to 100 rad/s, and the drift damping held it like honey: no area could be taught, in an
// open scene. Scaled to the arm, both areas are taught, and the recording follows the helix.
// The places the tutor chooses itself are found reachable from IK starts over the joints' whole
// range; its own posture searches start in the middle of the ranges. A place only an unusual
// posture reaches (A3 and A6 near their stops) was given up as having "no posture within the
// joint limits" although the posture that showed it reachable was at hand.
TEST(SimulatedTutor, FindsAPostureForAPlaceFromThePostureThatShowedItReachable) {
  robot::Scene scene;
  scene.name = "open";
  scene.home_posture = Eigen::VectorXd::Zero(7);
  ShortTeaching teaching(scene);
  teaching.tutor_options.posture_candidates = 3;  // no random starts before the second round
  SimulatedTutor tutor(teaching.sim, *teaching.workflow, scene, teaching.parameters, teaching.tutor_options);
  Eigen::VectorXd shown(7);
  shown << -1.72, 0.22, -2.85, 1.99, 0.34, -1.95, 1.91;
  const Eigen::Vector3d place = robot::tipPose(lwr4(), shown).translation();
  const std::vector<PostureChoice> choices = tutor.choosePostures(place, std::nullopt, nullptr, false, shown);
  ASSERT_FALSE(choices.empty());
  EXPECT_LT((robot::tipPose(lwr4(), choices.front().q).translation() - place).norm(), 1e-3);
}

TEST(SimulatedTutor, TeachesASmallLightArmAsItTeachesTheLwrIv) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(testing::smallLightArmUrdf(), ".");
  const ArmScale scale = armScale(model);
  ASSERT_LT(scale.inertia, 0.01);
  ASSERT_LT(scale.length, 0.35);
  ShortTeaching teaching(openSceneWithTwoPlaces(Eigen::Vector3d(-0.15, 0.0, 0.15), Eigen::Vector3d(-0.1, -0.12, 0.12), 0.03), model);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(2);
  ASSERT_EQ(report.areas.size(), 2U);
  for (const TutorAreaReport& area : report.areas) {
    EXPECT_TRUE(area.taught) << area.failure;
    // The helix is the LWR IV's, times the arm's size (0.3 m → under 10 cm), and drawn.
    EXPECT_NEAR(area.helix_diameter, 0.3 * scale.length, 1e-9);
    EXPECT_GT(area.span, 0.5 * area.helix_diameter);
  }
  EXPECT_EQ(report.collisions, 0U);
  // At rest after teaching: the arm does not ring.
  robot::RobotState state;
  state.resize(7);
  teaching.sim.readState(state);
  EXPECT_LT(state.qd.cwiseAbs().maxCoeff(), 0.05);
}

// An arm of 260 kg and 1.85 m, 86 times the LWR IV's largest joint inertia, with the tutor's
// hands of an LWR IV's strength: its joints crept at 0.04 rad/s under the approach, and 2 of 20
// places were taught. The hands grow with it beyond four times the LWR IV's inertia
// (robot::inertiaScaleToLwr) and its joint gains stay the LWR IV's (grown as well, the joints
// held against the hands and the approaches touched the table): both listed areas are taught
// without a contact.
TEST(SimulatedTutor, TeachesAHeavyLongArmWithHandsOfItsStrength) {
  const robot::RobotModel model = robot::RobotModel::fromUrdfString(testing::heavyLongArmUrdf(), ".");
  const ArmScale scale = armScale(model);
  ASSERT_GT(scale.inertia, 10.0);
  ASSERT_EQ(scale.length, 1.0);
  ShortTeaching teaching(openSceneWithTwoPlaces(Eigen::Vector3d(-0.8, -0.4, 0.4), Eigen::Vector3d(-0.4, -0.2, 0.15), 0.1), model);
  teaching.tutor_options.check_points = 0;
  const TutorReport report = teaching.configure(2);
  ASSERT_EQ(report.areas.size(), 2U);
  for (const TutorAreaReport& area : report.areas) {
    EXPECT_TRUE(area.taught) << area.failure;
    EXPECT_GT(area.span, 0.5 * area.helix_diameter);
  }
  EXPECT_EQ(report.collisions, 0U);
}

// `teach` says why areas failed by kind: the first reason alone had named a cramped listed place
// where eight of ten attempts failed because the arm was not led to its posture.
TEST(SimulatedTutor, CountsTheReasonsAreasWereNotTaughtByKindMostFrequentFirst) {
  std::vector<TutorAreaReport> areas(5);
  areas[0].failure = "no posture with 3.0 cm clearance (the best found keeps 2.7 cm, l6 to table)";
  areas[1].failure = "the posture was not reached (timed out in CONFIGURATION/APPROACHING, at path point 2/2)";
  areas[2].failure = "the posture was not reached (on_converged fired 0.03 rad short of the posture)";
  areas[3].taught = true;
  areas[4].failure = "no place of its own found: 200 random points of the evaluation grid were all within 10 cm";
  EXPECT_EQ(failureKinds(areas),
            "2 × the posture was not reached, 1 × no posture with 3.0 cm clearance, 1 × no place of its own found");
  areas.resize(4);
  areas[0].taught = areas[1].taught = areas[2].taught = true;
  EXPECT_EQ(failureKinds(areas), "");
}

// Beyond the scene's list the tutor chooses where to teach: where the learned map fails, and an
// area that makes the map miss more of its check points than before is taken back (removed from
// the workflow), so no area it keeps made the map worse on them.
TEST(SimulatedTutor, KeepsAnAutomaticAreaOnlyWhenTheLearnedMapGetsNoWorseWithIt) {
  robot::Scene scene = robot::loadScene("setup_A");
  scene.training_areas.resize(1);
  ShortTeaching teaching(scene);
  teaching.tutor_options.check_points = 40;
  const TutorReport report = teaching.configure(2);
  const Workflow& workflow = *teaching.workflow;

  int taught = 0, checked = 0, taken_back = 0;
  int failures = -1;
  for (const TutorAreaReport& area : report.areas) {
    taught += area.taught ? 1 : 0;
    if (!area.automatic) {
      EXPECT_EQ(area.map_failures_before, -1) << area.name;
      continue;
    }
    // Every place chosen has room for an area: 0.1 m to the obstacles, off the base and the table.
    for (const auto& obstacle : scene.obstacles) EXPECT_FALSE(robot::obstacleContains(obstacle, area.target, 0.1)) << area.name;
    EXPECT_GE(area.target.z(), 0.08) << area.name;
    EXPECT_GE(area.target.head<2>().norm(), 0.2) << area.name;
    if (area.map_failures_with < 0) continue;  // not taught at all: nothing to check
    ++checked;
    EXPECT_GE(area.map_failures_before, 0) << area.name;
    EXPECT_LE(area.map_failures_before, 40) << area.name;
    if (failures >= 0) {
      EXPECT_EQ(area.map_failures_before, failures) << area.name << ": counted against the map kept last";
    }
    if (area.taught) {
      EXPECT_LE(area.map_failures_with, area.map_failures_before) << area.name;
      failures = area.map_failures_with;
    } else {
      EXPECT_GT(area.map_failures_with, area.map_failures_before) << area.name;
      EXPECT_NE(area.failure.find("taken back"), std::string::npos) << area.failure;
      ++taken_back;
      failures = area.map_failures_before;
    }
  }
  EXPECT_GE(checked, 1);
  EXPECT_EQ(static_cast<int>(workflow.areas().size()), taught);
  int removed = 0;
  for (const auto& event : workflow.events()) removed += event.kind == WorkflowEvent::Kind::kAreaRemoved ? 1 : 0;
  EXPECT_EQ(removed, taken_back);
  EXPECT_EQ(report.collisions, 0U);
}

}  // namespace
}  // namespace flexirob::app
