// Pieces of the thesis' experiments: sub-sampling (Tab. 3.4), the accessible targets of
// Sect. 3.3.2, the implicit scene model (Eq. 4.1) and the trajectory evaluation (Tab. 3.2).
#include <gtest/gtest.h>

#include "tests/common/scene_objects.hpp"
#include "app/evaluation.hpp"
#include "app/experiments.hpp"
#include "learning/elm.hpp"
#include "robot/kinematics.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"

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

// An area taught in q_fixed whose samples span a cube of half-edge `half` about `centre`.
EvaluatedArea cubeArea(const Eigen::VectorXd& q_fixed, const Eigen::Vector3d& centre, double half) {
  EvaluatedArea area;
  area.q_fixed = q_fixed;
  area.samples.resize(3, 2);
  area.samples.col(0) = centre - Eigen::Vector3d::Constant(half);
  area.samples.col(1) = centre + Eigen::Vector3d::Constant(half);
  return area;
}

using testing::boxObstacle;

// The scene's trajectories at 0.1 m/s with the constant map, one area taught in ready() at its
// tip; the one region they form.
TrajectoryRegionResult onlyRegion(const robot::Scene& scene) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  const auto map = constantMap();
  const TrajectoryResult result =
      evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, {cubeArea(ready(), tip, 0.0)}, 1, 0.1, 1);
  EXPECT_EQ(result.regions.size(), 1u);
  return result.regions.at(0);
}

TEST(Experiments, SubsamplingKeepsEverySthSampleOfEachAreaStartingWithItsFirst) {
  learning::TrainingSet data;
  data.X.resize(3, 12);
  data.Y.resize(1, 12);
  for (int l = 0; l < 12; ++l) {
    data.X.col(l) = Eigen::Vector3d::Constant(l);
    data.Y(0, l) = l;
    data.area.push_back(l < 7 ? 0 : 1);  // area 0: samples 0..6, area 1: samples 7..11
  }
  const learning::TrainingSet out = subsample(data, 3);
  // Area 0 keeps 0, 3, 6; area 1 keeps 7, 10.
  ASSERT_EQ(out.size(), 5);
  const std::vector<double> expected{0, 3, 6, 7, 10};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(out.Y(0, i), expected[static_cast<std::size_t>(i)]);
  EXPECT_EQ(out.area, (std::vector<int>{0, 0, 0, 1, 1}));
  EXPECT_EQ(subsample(data, 1).size(), 12);
  EXPECT_THROW(subsample(data, 0), InputError);
}

TEST(Experiments, ASpacingThatMakesTheScenesGridTooLargeIsRefusedBeforeAnyWork) {
  robot::Scene scene;
  scene.grid = robot::EvaluationGrid{};
  scene.grid->lower = Eigen::Vector3d(-2, -2, 0);
  scene.grid->upper = Eigen::Vector3d(2, 2, 2);
  scene.grid->spacing = 0.1;
  EXPECT_DOUBLE_EQ(sceneGrid(scene, 0.0).spacing, 0.1);
  EXPECT_DOUBLE_EQ(sceneGrid(scene, 0.05).spacing, 0.05);
  try {
    sceneGrid(scene, 0.01);
    FAIL() << "a grid of 3.2e7 points was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("spacing of 0.01 m: the grid would have 3.23e+07 points"), std::string::npos)
        << error.what();
  }
}

TEST(Experiments, TargetsAboveTheBoardOfSetupIAreNotAccessibleButTargetsInFrontAre) {
  const robot::Scene scene = robot::loadScene("setup_I");
  const robot::ParameterSet parameters = sceneParameters(scene);
  robot::CollisionWorld world(lwr4(), scene);
  learning::UniformRandom random(7);
  // In front of the robot, in free space.
  EXPECT_TRUE(accessibleWithoutCollision(lwr4(), parameters, world, Eigen::Vector3d(-0.5, -0.1, 0.3), ready(), 8, random));
  // Just above the far end of the board (z = 0.56 m top face): the arm would have to pass
  // through the board or the box to put its tip there (Sect. 3.3.2 removes these from T_I).
  EXPECT_FALSE(accessibleWithoutCollision(lwr4(), parameters, world, Eigen::Vector3d(-0.6, 0.4, 0.6), ready(), 8, random));
}

TEST(Experiments, SaysWhetherAnInaccessibleTargetIsBlockedOrBeyondEveryPosture) {
  const robot::Scene scene = robot::loadScene("setup_I");
  const robot::ParameterSet parameters = sceneParameters(scene);
  robot::CollisionWorld world(lwr4(), scene);
  learning::UniformRandom random(7);
  int reaching = -1;
  // Above the board: postures reach it, every one through the board or the box.
  EXPECT_FALSE(accessibleWithoutCollision(lwr4(), parameters, world, Eigen::Vector3d(-0.6, 0.4, 0.6), ready(), 8, random,
                                          nullptr, &reaching));
  EXPECT_GT(reaching, 0);
  // About 2 m from the shoulder, twice the arm's reach: no posture puts the tip there.
  EXPECT_FALSE(accessibleWithoutCollision(lwr4(), parameters, world, Eigen::Vector3d(-2.0, 0.0, 0.3), ready(), 8, random,
                                          nullptr, &reaching));
  EXPECT_EQ(reaching, 0);
  // Reached clear of contact: at least the posture returned reaches it.
  EXPECT_TRUE(accessibleWithoutCollision(lwr4(), parameters, world, Eigen::Vector3d(-0.5, -0.1, 0.3), ready(), 8, random,
                                         nullptr, &reaching));
  EXPECT_GE(reaching, 1);
}

TEST(Experiments, SceneModelEnclosesAnObstacleTheArmNeverComesNear) {
  // The arm rests in the ready posture (tip about 0.5 m in front); a box far to the side and
  // one around the tip. Eq. 4.1: S holds the grid points farther than 0.1 m from the arm.
  robot::Scene scene;
  robot::Obstacle far;
  far.name = "far";
  far.shape = robot::Obstacle::Shape::kBox;
  far.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  far.X_WO = Eigen::Isometry3d(Eigen::Translation3d(-0.3, -0.5, 0.2));
  scene.obstacles.push_back(far);
  // 0.1 m edges: every point of it lies within 0.1 m (half the diagonal, 0.087 m) of the tip.
  robot::Obstacle at_tip = far;
  at_tip.name = "at_tip";
  at_tip.size = Eigen::Vector3d(0.1, 0.1, 0.1);
  at_tip.X_WO = Eigen::Isometry3d(Eigen::Translation3d(robot::tipPose(lwr4(), ready()).translation()));
  scene.obstacles.push_back(at_tip);
  robot::EvaluationGrid grid;
  grid.spacing = 0.05;
  const SceneModelResult result = evaluateSceneModel(lwr4(), scene, grid, {ready()});
  ASSERT_GT(result.obstacle_points, 0);
  // Every point of the far box is in S; no point of the box at the tip is.
  int far_points = 0;
  // The points on its faces too (a micrometre: the grid's rounding), as T counts them.
  for (const auto& p : grid.points()) far_points += robot::obstacleContains(far, p, 1e-6) ? 1 : 0;
  EXPECT_EQ(result.obstacle_points_enclosed, far_points);
  for (const auto& p : result.model) EXPECT_FALSE(robot::obstacleContains(at_tip, p));
  EXPECT_GT(result.free_points_in_model, 0);
  // With no posture at all, S is the whole workspace.
  EXPECT_EQ(evaluateSceneModel(lwr4(), scene, grid, {}).model_points, result.workspace_points);
}

TEST(Experiments, AScenesOverridesReachTheRecordingControllersAsWellAsTheSimulation) {
  robot::Scene scene;
  scene.parameters = {{"interaction.cartesian_damping", 80.0}, {"sim.gravity", 9.0}, {"hierarchical.kappa_q", 3.0}};
  const robot::ParameterSet parameters = sceneParameters(scene);
  EXPECT_DOUBLE_EQ(parameters.get("interaction.cartesian_damping"), 80.0);
  EXPECT_DOUBLE_EQ(parameters.get("sim.gravity"), 9.0);
  EXPECT_DOUBLE_EQ(parameters.get("hierarchical.kappa_q"), 3.0);
  EXPECT_DOUBLE_EQ(sceneParameters(robot::Scene{}).get("interaction.cartesian_damping"), 60.0);
}

TEST(Experiments, TrajectoriesBetweenTwoAreasAreAccurateAndCountedPerRegion) {
  robot::Scene empty;
  const robot::ParameterSet parameters = sceneParameters(empty);
  const auto map = constantMap();
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  // Two areas of samples 0.3 m apart along y, the ready posture taught in both.
  std::vector<EvaluatedArea> areas(2);
  for (int k = 0; k < 2; ++k) {
    areas[static_cast<std::size_t>(k)].q_fixed = ready();
    Eigen::MatrixXd& samples = areas[static_cast<std::size_t>(k)].samples;
    samples.resize(3, 8);
    for (int l = 0; l < 8; ++l) {
      samples.col(l) = tip + Eigen::Vector3d(0.05 * ((l & 1) - 0.5), (k == 0 ? 0.15 : -0.15) + 0.05 * (((l >> 1) & 1) - 0.5),
                                             0.05 * (((l >> 2) & 1) - 0.5));
    }
  }
  constexpr double kSpeed = 0.1;  // [m/s], as in Tab. 3.2
  const TrajectoryResult result = evaluateTrajectories(lwr4(), empty, parameters, *map, areas, 2, kSpeed, 1);
  ASSERT_EQ(result.regions.size(), 3u);
  EXPECT_FALSE(result.from_scene);
  EXPECT_EQ(result.regions[0].trajectories, 2);
  EXPECT_EQ(result.regions[1].trajectories, 2);
  EXPECT_EQ(result.regions[2].trajectories, 4);
  for (const auto& region : result.regions) {
    EXPECT_EQ(region.collisions, 0);
    // Eq. 2.11's feedback alone would trail the target by v/κ_x = 0.1 m/s / 10 s⁻¹ = 10 mm;
    // with the path's velocity fed forward the error is mostly the start from rest, where the
    // limiter's acceleration limit holds the arm back.
    const double lag_mm = 1e3 * kSpeed / parameters.get("hierarchical.kappa_x");
    EXPECT_GT(region.e_task_max_mm, 0.0) << region.name;
    EXPECT_LE(region.e_task_mean_mm, region.e_task_max_mm) << region.name;
    EXPECT_LT(region.e_task_mean_mm, 0.2 * lag_mm) << region.name;
    EXPECT_LT(region.e_task_max_mm, 0.5 * lag_mm) << region.name;
  }
}

TEST(Experiments, DrawnTrajectoriesRunInEveryAreaNamedAfterItAndBetweenAreasTaughtOneAfterTheOther) {
  // Three 5 cm areas 0.15 m apart along y, taught from +y to -y: each is a region under its own
  // name, and the two regions between them lie between the first and second, second and third.
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  const std::vector<std::string> names = {"I1", "auto_2", "I3"};
  std::vector<EvaluatedArea> areas;
  for (std::size_t k = 0; k < 3; ++k) {
    areas.push_back(cubeArea(ready(), tip + Eigen::Vector3d(0.0, 0.15 - 0.15 * static_cast<double>(k), 0.0), 0.025));
    areas.back().name = names[k];
  }
  robot::Scene empty;
  const auto map = constantMap();
  const TrajectoryResult result = evaluateTrajectories(lwr4(), empty, sceneParameters(empty), *map, areas, 2, 0.1, 1);
  EXPECT_FALSE(result.from_scene);
  // Each region with the box its points must lie in: an area's samples' box, or between two
  // areas' boxes along y (the axis separating them) and spanning them along x and z.
  struct Expected {
    std::string name;
    int trajectories;
    Eigen::Vector3d lower, upper;
  };
  std::vector<Expected> expected;
  for (std::size_t k = 0; k < 3; ++k) {
    expected.push_back({names[k], 2, areas[k].samples.col(0), areas[k].samples.col(1)});
  }
  expected.push_back({"between I1 and auto_2", 4, tip + Eigen::Vector3d(-0.025, 0.025, -0.025), tip + Eigen::Vector3d(0.025, 0.125, 0.025)});
  expected.push_back({"between auto_2 and I3", 4, tip + Eigen::Vector3d(-0.025, -0.125, -0.025), tip + Eigen::Vector3d(0.025, -0.025, 0.025)});
  ASSERT_EQ(result.regions.size(), expected.size());
  for (std::size_t r = 0; r < expected.size(); ++r) {
    const TrajectoryRegionResult& region = result.regions[r];
    EXPECT_EQ(region.name, expected[r].name);
    EXPECT_EQ(region.trajectories, expected[r].trajectories) << region.name;
    ASSERT_EQ(static_cast<int>(region.waypoints.size()), region.trajectories) << region.name;
    for (const auto& waypoints : region.waypoints) {
      ASSERT_EQ(waypoints.size(), 2u) << region.name;
      for (const Eigen::Vector3d& p : waypoints) {
        EXPECT_TRUE((p.array() >= expected[r].lower.array() - 1e-9).all() && (p.array() <= expected[r].upper.array() + 1e-9).all())
            << region.name << ": " << p.transpose();
      }
    }
  }
}

TEST(Experiments, TrajectoriesCanBeDrawnAroundTheTrainingDataWhereTheSceneListsItsOwn) {
  // The thesis' regions are the boxes around the samples (Sect. 3.3.1); the scene's one
  // trajectory runs 0.3 m away from both areas. Drawn, every point lies in an area's box or
  // between them; from the scene, the one trajectory runs; a scene without any has none to run.
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  std::vector<EvaluatedArea> areas{cubeArea(ready(), tip + Eigen::Vector3d(0.0, 0.05, 0.0), 0.02),
                                   cubeArea(ready(), tip - Eigen::Vector3d(0.0, 0.05, 0.0), 0.02)};
  areas[0].name = "left";
  areas[1].name = "right";
  robot::Scene scene;
  scene.trajectories.push_back({"far", "left", {tip + Eigen::Vector3d(0.3, 0.0, 0.0), tip + Eigen::Vector3d(0.3, 0.1, 0.0)}});
  const auto map = constantMap();
  const auto run = [&](const robot::Scene& s, TrajectorySource source) {
    return evaluateTrajectories(lwr4(), s, sceneParameters(s), *map, areas, 2, 0.1, 1, {}, source);
  };
  const TrajectoryResult drawn = run(scene, TrajectorySource::kTrainingData);
  EXPECT_FALSE(drawn.from_scene);
  ASSERT_EQ(drawn.regions.size(), 3u);
  EXPECT_EQ(drawn.regions[2].name, "between left and right");
  const Eigen::Vector3d lower = tip - Eigen::Vector3d(0.02, 0.07, 0.02), upper = tip + Eigen::Vector3d(0.02, 0.07, 0.02);
  for (const auto& region : drawn.regions) {
    EXPECT_EQ(region.trajectories, region.name == "between left and right" ? 4 : 2);
    for (const auto& waypoints : region.waypoints) {
      for (const Eigen::Vector3d& p : waypoints) {
        EXPECT_TRUE((p.array() >= lower.array() - 1e-9).all() && (p.array() <= upper.array() + 1e-9).all())
            << region.name << ": " << p.transpose();
      }
    }
  }
  for (const TrajectorySource source : {TrajectorySource::kScene, TrajectorySource::kAuto}) {
    const TrajectoryResult listed = run(scene, source);
    EXPECT_TRUE(listed.from_scene);
    ASSERT_EQ(listed.regions.size(), 1u);
    EXPECT_EQ(listed.regions[0].trajectories, 1);
  }
  EXPECT_THROW(run(robot::Scene{}, TrajectorySource::kScene), InputError);
  EXPECT_EQ(parseTrajectorySource("training-data"), TrajectorySource::kTrainingData);
  EXPECT_THROW(parseTrajectorySource("samples"), InputError);
}

TEST(Experiments, SaysWhichScenesTrajectoriesLeaveTheArmsReachOrPassInsideAnObstacle) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  robot::Scene scene;
  scene.obstacles.push_back(boxObstacle("crate", Eigen::Vector3d(0.1, 0.1, 0.1), tip + Eigen::Vector3d(0.0, 0.2, 0.0)));
  scene.trajectories.push_back({"free", "g", {tip, tip + Eigen::Vector3d(0.0, -0.1, 0.0)}});
  scene.trajectories.push_back({"through", "g", {tip, tip + Eigen::Vector3d(0.0, 0.3, 0.0)}});
  scene.trajectories.push_back({"far", "g", {tip, Eigen::Vector3d(-2.0, 0.0, 0.4)}});
  const TrajectoryRegionResult region = onlyRegion(scene);
  ASSERT_EQ(region.impossible.size(), 2U);
  EXPECT_EQ(region.impossible[0].rfind("through: (", 0), 0U) << region.impossible[0];
  EXPECT_NE(region.impossible[0].find(" lies inside crate"), std::string::npos) << region.impossible[0];
  EXPECT_EQ(region.impossible[1].rfind("far: (", 0), 0U) << region.impossible[1];
  EXPECT_NE(region.impossible[1].find(" m from the shoulder, reach "), std::string::npos) << region.impossible[1];
  EXPECT_EQ(region.trajectories, 3);
}

TEST(Experiments, TrajectoriesThatMeetAnObstacleAreNamedWithTheirContactAndWhereTheTipWasHeaded) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  robot::Scene scene;
  // A thin wall across +y, 0.13-0.17 m beside the tip; only the second trajectory crosses it.
  robot::Obstacle wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.6, 0.04, 0.6);
  wall.X_WO = Eigen::Isometry3d(Eigen::Translation3d(tip + Eigen::Vector3d(0.0, 0.15, 0.0)));
  scene.obstacles.push_back(wall);
  scene.trajectories.push_back({"short_of_it", "left", {tip + Eigen::Vector3d(0.0, 0.05, 0.0)}});
  scene.trajectories.push_back({"through_it", "left", {tip + Eigen::Vector3d(0.0, 0.3, 0.0)}});
  scene.trajectories.push_back({"away_from_it", "left", {tip + Eigen::Vector3d(0.0, -0.05, 0.0)}});
  const auto map = constantMap();
  std::vector<EvaluatedArea> areas(1);
  areas[0].q_fixed = ready();
  areas[0].samples = tip;
  constexpr double kSpeed = 0.1;  // [m/s]
  const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 1, kSpeed, 1);
  ASSERT_TRUE(result.from_scene);
  ASSERT_EQ(result.regions.size(), 1u);
  const TrajectoryRegionResult& left = result.regions[0];
  EXPECT_EQ(left.trajectories, 3);
  EXPECT_EQ(left.collisions, 1);
  ASSERT_EQ(left.collided.size(), 1u);
  const CollidedTrajectory& collided = left.collided[0];
  EXPECT_EQ(collided.name, "through_it");
  EXPECT_TRUE(collided.contact.ends_with("/wall")) << collided.contact;
  // It starts 0.05 m along, where the first ended; the tip was headed for a point before the
  // wall's far face when some link met the wall, and the time matches that point at 0.1 m/s.
  const double along = collided.target.y() - tip.y();
  EXPECT_GT(along, 0.05);
  EXPECT_LT(along, 0.17);
  EXPECT_NEAR(collided.target.x(), tip.x(), 1e-6);
  EXPECT_NEAR(collided.target.z(), tip.z(), 1e-6);
  EXPECT_NEAR(collided.contact_time, (along - 0.05) / kSpeed, 0.02);
  EXPECT_EQ(left.contacts.at(collided.contact), 1);
  // Its E_task counts up to the contact, and the region says so.
  EXPECT_EQ(left.e_task_trajectories, 3);
  EXPECT_EQ(left.e_task_until_contact, 1);
}

TEST(Experiments, ETaskIsMeasuredAlongTheTrajectoryFromRestAtItsStartNotOnTheWayThere) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  robot::Scene scene;
  // The second trajectory starts 0.1 m beyond where the first ended and runs back: the way to
  // its start and the trajectory point in opposite directions. Reversing at 0.1 m/s within the
  // limiter's acceleration bound leaves the tip millimetres behind a target that turns at once;
  // at rest at the start, only the start from rest to 0.1 m/s remains, a fraction of that.
  scene.trajectories.push_back({"out", "left", {tip, tip + Eigen::Vector3d(0.0, 0.1, 0.0)}});
  scene.trajectories.push_back({"back", "left", {tip + Eigen::Vector3d(0.0, 0.2, 0.0), tip + Eigen::Vector3d(0.0, 0.05, 0.0)}});
  const TrajectoryRegionResult left = onlyRegion(scene);
  EXPECT_EQ(left.collisions, 0);
  EXPECT_EQ(left.e_task_trajectories, 2);
  EXPECT_LT(left.e_task_max_mm, 2.5) << "on " << left.e_task_max_trajectory << " at " << left.e_task_max_time << " s";
  // The largest error, where there is one, is in the first tenths of a second of a trajectory.
  EXPECT_LT(left.e_task_max_time, 0.3);
}

TEST(Experiments, AContactOnTheWayToATrajectorysStartCountsAndIsReportedAsSuch) {
  {
    // A plate above the straight way, where the wrist (7.8 cm above the tip) passes and the tip
    // does not: the arm is led along the way and meets it.
    const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
    robot::Scene scene;
    scene.obstacles.push_back(boxObstacle("plate", Eigen::Vector3d(0.06, 0.12, 0.02), tip + Eigen::Vector3d(0.0, 0.2, 0.08)));
    scene.trajectories.push_back({"near", "left", {tip, tip + Eigen::Vector3d(0.0, 0.05, 0.0)}});
    scene.trajectories.push_back({"beyond", "left", {tip + Eigen::Vector3d(0.0, 0.3, 0.0), tip + Eigen::Vector3d(0.0, 0.35, 0.0)}});
    const TrajectoryRegionResult left = onlyRegion(scene);
    EXPECT_EQ(left.starts_placed, 0);
    ASSERT_EQ(left.collided.size(), 1u);
    EXPECT_EQ(left.collided[0].name, "beyond");
    EXPECT_TRUE(left.collided[0].on_way_to_start);
    EXPECT_TRUE(left.collided[0].contact.ends_with("/plate")) << left.collided[0].contact;
    // The tip was headed for a point between the first's end and the plate's far edge.
    EXPECT_GT(left.collided[0].target.y() - tip.y(), 0.05);
    EXPECT_LT(left.collided[0].target.y() - tip.y(), 0.3);
  }
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  robot::Scene scene;
  // A thin wall across +y, 0.13-0.17 m beside the tip; "beyond" lies behind it, and only the
  // way to its start crosses it.
  scene.obstacles.push_back(boxObstacle("wall", Eigen::Vector3d(0.6, 0.04, 0.6), tip + Eigen::Vector3d(0.0, 0.15, 0.0)));
  scene.trajectories.push_back({"near", "left", {tip, tip + Eigen::Vector3d(0.0, 0.05, 0.0)}});
  scene.trajectories.push_back({"beyond", "left", {tip + Eigen::Vector3d(0.0, 0.3, 0.0), tip + Eigen::Vector3d(0.0, 0.35, 0.0)}});
  scene.trajectories.push_back({"near_again", "left", {tip, tip + Eigen::Vector3d(0.0, -0.05, 0.0)}});
  const TrajectoryRegionResult left = onlyRegion(scene);
  EXPECT_EQ(left.collisions, 1);
  ASSERT_EQ(left.collided.size(), 1u);
  EXPECT_EQ(left.collided[0].name, "beyond");
  EXPECT_TRUE(left.collided[0].on_way_to_start);
  EXPECT_TRUE(left.collided[0].contact.ends_with("/wall")) << left.collided[0].contact;
  // The tip's straight way crosses the wall: the arm is brought to the start instead, and the
  // arm reaching from this side of the wall to beyond it lies in it there.
  EXPECT_EQ(left.starts_placed, 1);
  EXPECT_NEAR(left.collided[0].target.y() - tip.y(), 0.3, 1e-9);
  // E_task is over the two trajectories that ran; the third started again in the area.
  EXPECT_EQ(left.e_task_trajectories, 2);
  EXPECT_EQ(left.e_task_until_contact, 0);
  EXPECT_LT(left.e_task_mean_mm, 2.0);
}

TEST(Experiments, DrawnTrajectoriesThatMeetAnObstacleAreNamedAfterTheirRegion) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  // Two 5 cm areas 0.3 m apart along y and a 10 cm plate across y half way, above the tip's way
  // (the trajectories keep 5 cm from obstacles) but where the wrist, 7.8 cm above the tip,
  // passes: only trajectories between the areas meet it.
  const std::vector<EvaluatedArea> areas{cubeArea(ready(), tip + Eigen::Vector3d(0.0, 0.15, 0.0), 0.025),
                                         cubeArea(ready(), tip + Eigen::Vector3d(0.0, -0.15, 0.0), 0.025)};
  robot::Scene scene;
  scene.obstacles.push_back(boxObstacle("plate", Eigen::Vector3d(0.1, 0.02, 0.1), tip + Eigen::Vector3d(0.0, 0.0, 0.13)));
  const auto map = constantMap();
  const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 3, 0.1, 1);
  ASSERT_EQ(result.regions.size(), 3u);
  for (const auto& region : result.regions) EXPECT_EQ(region.start_contact, "") << region.name;
  EXPECT_TRUE(result.regions[0].collided.empty());
  EXPECT_TRUE(result.regions[1].collided.empty());
  const TrajectoryRegionResult& between = result.regions[2];
  ASSERT_EQ(between.name, "between area 1 and area 2");
  ASSERT_FALSE(between.collided.empty());
  EXPECT_EQ(static_cast<int>(between.collided.size()), between.collisions);
  for (const CollidedTrajectory& trajectory : between.collided) {
    ASSERT_TRUE(trajectory.name.starts_with("between area 1 and area 2_")) << trajectory.name;
    const int k = std::stoi(trajectory.name.substr(std::string("between area 1 and area 2_").size()));
    EXPECT_GE(k, 1);
    EXPECT_LE(k, 6);
    EXPECT_TRUE(trajectory.contact.ends_with("/plate")) << trajectory.contact;
  }
}

TEST(Experiments, DrawnTrajectoriesBetweenAreasOnEitherSideOfTheRobotKeepOffItsBase) {
  // Areas to the left and to the right of the robot, 0.54 m out: the box between them holds the
  // robot's own column. Every drawn way must be one the tip can follow.
  Eigen::VectorXd left = ready();
  left[0] = std::numbers::pi / 2;
  Eigen::VectorXd right = ready();
  right[0] = -std::numbers::pi / 2;
  const std::vector<EvaluatedArea> areas{cubeArea(left, robot::tipPose(lwr4(), left).translation(), 0.05),
                                         cubeArea(right, robot::tipPose(lwr4(), right).translation(), 0.05)};
  // A map that keeps the taught posture's side of the robot: q1 follows the target's azimuth.
  learning::TrainingSet data;
  data.X.resize(3, 16);
  data.Y.resize(7, 16);
  for (int l = 0; l < 16; ++l) {
    const double azimuth = std::numbers::pi * l / 15.0 - std::numbers::pi / 2;
    Eigen::VectorXd q = ready();
    q[0] = azimuth;
    data.X.col(l) = robot::tipPose(lwr4(), q).translation();
    data.Y.col(l) = q;
  }
  learning::Elm map(3, 7);
  map.fit(data);
  robot::Scene scene;
  const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), map, areas, 3, 0.1, 1);
  ASSERT_EQ(result.regions.size(), 3u);
  const TrajectoryRegionResult& between = result.regions[2];
  ASSERT_EQ(between.name, "between area 1 and area 2");
  // Through the base, the tip would trail its target by decimetres.
  EXPECT_LT(between.e_task_max_mm, 50.0);
}

TEST(Experiments, ARegionWhoseStartTouchesSomethingStartsInTheAreaInstead) {
  // Two areas 0.15 m left and right of the ready posture's tip, and a plate above the way
  // between them where the wrist (7.8 cm above the tip) passes: moved to any point between
  // the areas, the map's posture puts the wrist into the plate.
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  std::vector<EvaluatedArea> areas;
  for (const double q1 : {0.27, -0.27}) {
    Eigen::VectorXd q_fixed = ready();
    q_fixed[0] = q1;
    areas.push_back(cubeArea(q_fixed, robot::tipPose(lwr4(), q_fixed).translation(), 0.025));
  }
  robot::Scene scene;
  scene.obstacles.push_back(boxObstacle("plate", Eigen::Vector3d(0.1, 0.12, 0.1), tip + Eigen::Vector3d(0.0, 0.0, 0.13)));
  robot::CollisionWorld world(lwr4(), scene);
  for (const EvaluatedArea& area : areas) {
    world.update(area.q_fixed);
    ASSERT_TRUE(world.contacts().empty()) << "the taught postures are free";
  }
  const auto map = constantMap();
  const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 3, 0.1, 1);
  const TrajectoryRegionResult& between = result.regions[2];
  ASSERT_EQ(between.name, "between area 1 and area 2");
  EXPECT_TRUE(between.start_contact.ends_with("/plate")) << between.start_contact;
  // Every trajectory starts in the area's free posture and meets the plate on its way, never
  // at its first check as one started in contact would.
  ASSERT_FALSE(between.collided.empty());
  for (const CollidedTrajectory& trajectory : between.collided) EXPECT_GT(trajectory.contact_time, 0.05) << trajectory.name;
}

// Two trajectories of a region with a small block between them, on the straight way from the
// first one's end to the second one's start: no arm follows the tip through it. The lead-in had
// counted the second trajectory as collided on its way; the arm is brought to that start as a
// region's start is, and the trajectory runs from there.
TEST(Experiments, ATrajectoryWhoseStraightWayToItsStartCrossesAnObstacleStartsThereInstead) {
  const Eigen::Vector3d tip = robot::tipPose(lwr4(), ready()).translation();
  robot::Scene scene;
  scene.obstacles.push_back(boxObstacle("block", Eigen::Vector3d(0.03, 0.03, 0.03), tip));
  const Eigen::Vector3d left(0.0, 0.12, 0.0), right(0.0, -0.12, 0.0), step(0.0, 0.04, 0.0);
  scene.trajectories.push_back({"left", "region", {tip + left + step, tip + left}});
  scene.trajectories.push_back({"right", "region", {tip + right, tip + right - step}});
  const std::vector<EvaluatedArea> areas{cubeArea(ready(), tip, 0.02)};
  const auto map = constantMap();
  const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 1, 0.1, 1);
  ASSERT_EQ(result.regions.size(), 1U);
  const TrajectoryRegionResult& region = result.regions[0];
  EXPECT_EQ(region.starts_placed, 1);
  EXPECT_EQ(region.collisions, 0) << (region.collided.empty() ? "" : region.collided.front().contact);
  EXPECT_EQ(region.e_task_trajectories, 2);
  EXPECT_LT(region.e_task_max_mm, 5.0);
  // Without the block the straight way is taken.
  scene.obstacles.clear();
  const TrajectoryResult free = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 1, 0.1, 1);
  EXPECT_EQ(free.regions[0].starts_placed, 0);
  EXPECT_EQ(free.regions[0].collisions, 0);
}

// Two areas on either side of a board, as on the shelves of a cupboard: the region between them
// holds free points on both sides, and no straight way crosses the board. The arm is led to a
// region's start from the area it was drawn from, so the start lies on that area's side;
// drawn anywhere, half the regions began behind the board and every trajectory of them
// collided on the way to its start.
TEST(Experiments, ARegionDrawnBetweenAreasOnEitherSideOfABoardStartsOnTheSideOfTheAreaItIsDrawnFrom) {
  const Eigen::Vector3d board_centre = robot::tipPose(lwr4(), ready()).translation();
  const std::vector<EvaluatedArea> areas{cubeArea(ready(), board_centre + Eigen::Vector3d(0.0, 0.0, 0.12), 0.025),
                                         cubeArea(ready(), board_centre - Eigen::Vector3d(0.0, 0.0, 0.12), 0.025)};
  robot::Scene scene;
  scene.obstacles.push_back(boxObstacle("board", Eigen::Vector3d(0.3, 0.3, 0.02), board_centre));
  const auto map = constantMap();
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const TrajectoryResult result = evaluateTrajectories(lwr4(), scene, sceneParameters(scene), *map, areas, 1, 0.1, seed);
    ASSERT_EQ(result.regions.size(), 3u);
    const TrajectoryRegionResult& between = result.regions[2];
    ASSERT_EQ(between.name, "between area 1 and area 2");
    ASSERT_FALSE(between.waypoints.empty());
    for (const auto& trajectory : between.waypoints) {
      for (const Eigen::Vector3d& point : trajectory) {
        EXPECT_GT(point.z(), board_centre.z() + 0.05) << "seed " << seed << ": a point below the board, away from area 1";
      }
    }
  }
}

}  // namespace
}  // namespace flexirob::app
