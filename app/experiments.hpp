#pragma once
// The thesis' experiments run headless: a simulated tutor teaches a scene (CONFIGURATION with
// the workflow on the Bullet simulation), then the evaluations of app/evaluation.hpp run on
// what was taught. Used by `flexirob-cli sweep` (Tab. 3.2, 3.3, 3.4, 7.1, Sect. 8.3) and by the
// tests on small versions. Frames: W = robot base; metres, radians.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "app/evaluation.hpp"
#include "app/simulated_tutor.hpp"
#include "app/workflow.hpp"
#include "learning/learner.hpp"
#include "planning/itm.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {

struct TeachSpec {
  int areas = 1;                  ///< training areas the tutor teaches (the scene's first, then automatic)
  std::uint64_t seed = 1;         ///< tutor and learner seed
  WorkflowOptions workflow;       ///< learner and ITM parameters (check_scene is set to the scene)
  TutorOptions tutor;             ///< seed is overwritten by `seed`
};

/// What a simulated teaching session left behind.
struct TaughtSystem {
  std::vector<TrainingArea> areas;
  learning::TrainingSet data;      ///< all samples, area indices set
  std::unique_ptr<planning::Itm> itm;
  TutorReport tutor;
  Eigen::VectorXd home;            ///< the posture evaluations start from [rad]
  double wall_seconds = 0.0;
  int areas_given_up = 0;
};

/// The parameters a scene sets (robot::sceneTunableParameters()) with its overrides applied.
robot::ParameterSet sceneParameters(const robot::Scene& scene);

/// Runs the tutor on a fresh simulation of `model` in `scene`.
TaughtSystem teachInSimulation(const robot::RobotModel& model, const robot::Scene& scene, const TeachSpec& spec);

/// Every s-th sample of each area (Tab. 3.4's sub-sampling; s = 1 keeps all, the first sample
/// of an area is always kept).
learning::TrainingSet subsample(const learning::TrainingSet& data, int s);

/// A learner of `kind` fitted to `data` (ELM ε and LLM η from the options, seeded).
std::unique_ptr<learning::Learner> fitMap(const learning::TrainingSet& data, int dof, LearnerKind kind,
                                          const learning::ElmParams& elm, const learning::LlmParams& llm);

/// The evaluation grid of a scene (its own, else G of Sect. 3.3.2), spacing overridden if > 0.
/// Throws InputError when the grid has more than robot::kMaxGridPoints points at that spacing.
robot::EvaluationGrid sceneGrid(const robot::Scene& scene, double spacing);

/// The taught areas as the trajectory evaluation needs them.
std::vector<EvaluatedArea> evaluatedAreas(const TaughtSystem& taught);

}  // namespace flexirob::app
