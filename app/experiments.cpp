#include "app/experiments.hpp"

#include <chrono>
#include <sstream>
#include <string>

#include "robot/errors.hpp"
#include "robot/sim/reach.hpp"
#include "robot/sim/simulation.hpp"

namespace flexirob::app {

robot::ParameterSet sceneParameters(const robot::Scene& scene) {
  const std::vector<robot::ParameterDeclaration> declarations = robot::sceneTunableParameters();
  robot::ParameterSet parameters(declarations);
  parameters.applyOverrides(scene.parameters, robot::sceneOrigin(scene));
  return parameters;
}

TaughtSystem teachInSimulation(const robot::RobotModel& model, const robot::Scene& scene, const TeachSpec& spec) {
  const robot::ParameterSet parameters = sceneParameters(scene);
  robot::Simulation sim(model, &scene, parameters);
  TaughtSystem taught;
  taught.home = homePosture(model, scene);
  sim.reset(taught.home);
  WorkflowOptions workflow_options = spec.workflow;
  workflow_options.check_scene = &scene;
  workflow_options.elm.seed = spec.seed;
  workflow_options.llm.seed = spec.seed;
  Workflow workflow(sim, parameters, workflow_options);
  TutorOptions tutor_options = spec.tutor;
  tutor_options.seed = spec.seed;
  tutor_options.home = taught.home;
  SimulatedTutor tutor(sim, workflow, scene, parameters, tutor_options);
  const auto start = std::chrono::steady_clock::now();
  taught.tutor = tutor.configure(spec.areas);
  taught.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const auto& area : taught.tutor.areas) taught.areas_given_up += area.taught ? 0 : 1;
  taught.areas = workflow.areas();
  Eigen::Index samples = 0;
  for (const auto& area : taught.areas) samples += area.X.cols();
  taught.data.X.resize(3, samples);
  taught.data.Y.resize(model.dof(), samples);
  Eigen::Index l = 0;
  for (std::size_t k = 0; k < taught.areas.size(); ++k) {
    const TrainingArea& area = taught.areas[k];
    taught.data.X.middleCols(l, area.X.cols()) = area.X;
    taught.data.Y.middleCols(l, area.Q.cols()) = area.Q;
    for (Eigen::Index i = 0; i < area.X.cols(); ++i) taught.data.area.push_back(static_cast<int>(k));
    l += area.X.cols();
  }
  taught.itm = std::make_unique<planning::Itm>(workflow.itm());
  return taught;
}

learning::TrainingSet subsample(const learning::TrainingSet& data, int s) {
  if (s < 1) throw InputError("subsampling: expected s >= 1, got " + std::to_string(s));
  std::vector<Eigen::Index> keep;
  int previous_area = -1;
  int in_area = 0;
  for (Eigen::Index l = 0; l < data.size(); ++l) {
    const int area = data.area.empty() ? 0 : data.area[static_cast<std::size_t>(l)];
    if (area != previous_area) {
      previous_area = area;
      in_area = 0;
    }
    if (in_area++ % s == 0) keep.push_back(l);
  }
  learning::TrainingSet out;
  out.X.resize(data.X.rows(), static_cast<Eigen::Index>(keep.size()));
  out.Y.resize(data.Y.rows(), static_cast<Eigen::Index>(keep.size()));
  for (std::size_t i = 0; i < keep.size(); ++i) {
    out.X.col(static_cast<Eigen::Index>(i)) = data.X.col(keep[i]);
    out.Y.col(static_cast<Eigen::Index>(i)) = data.Y.col(keep[i]);
    if (!data.area.empty()) out.area.push_back(data.area[static_cast<std::size_t>(keep[i])]);
  }
  return out;
}

std::unique_ptr<learning::Learner> fitMap(const learning::TrainingSet& data, int dof, LearnerKind kind,
                                          const learning::ElmParams& elm, const learning::LlmParams& llm) {
  WorkflowOptions options;
  options.learner = kind;
  options.elm = elm;
  options.llm = llm;
  std::unique_ptr<learning::Learner> learner = makeLearner(options, dof);
  learner->fit(data);
  return learner;
}

robot::EvaluationGrid sceneGrid(const robot::Scene& scene, double spacing) {
  robot::EvaluationGrid grid = scene.grid.value_or(robot::EvaluationGrid{});
  if (spacing > 0.0) grid.spacing = spacing;
  if (const std::string problem = grid.sizeProblem(); !problem.empty()) {
    std::ostringstream spacing_text;
    spacing_text << grid.spacing;
    throw InputError("evaluation grid at a spacing of " + spacing_text.str() + " m: " + problem + "; increase the spacing");
  }
  return grid;
}

std::vector<EvaluatedArea> evaluatedAreas(const TaughtSystem& taught) {
  std::vector<EvaluatedArea> out;
  for (const auto& area : taught.areas) out.push_back({area.X, area.q_fixed, area.name});
  return out;
}

}  // namespace flexirob::app
