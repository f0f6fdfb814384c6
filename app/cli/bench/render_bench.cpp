#include <benchmark/benchmark.h>

#include "app/cli/bench/benchmarks.hpp"
#include "render/offscreen.hpp"
#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"

namespace flexirob::bench {
namespace {

// One offscreen frame (OSMesa, llvmpipe) of the LWR IV in a thesis scene, posture changing
// every frame, including the read-back of the pixels. Wall-clock time.
void offscreenFrame(benchmark::State& state, int width, int height) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  render::World world;
  world.setRobot(model);
  world.setScene(robot::loadScene("setup_I"));
  robot::Kinematics kinematics(model);
  Eigen::VectorXd q = model.midPosture();
  kinematics.update(q);
  world.robot()->setPosture(kinematics);
  const render::CameraPose camera = world.defaultCamera(static_cast<double>(width) / height);
  render::OffscreenRenderer renderer(width, height, 1);
  for (auto _ : state) {
    q[0] += 1e-3;
    kinematics.update(q);
    world.robot()->setPosture(kinematics);
    const render::Image image = renderer.render(world.root(), camera, {0.86F, 0.89F, 0.93F, 1.0F});
    benchmark::DoNotOptimize(image.rgba.data());
  }
}

}  // namespace

void registerRenderBenchmarks() {
  benchmark::RegisterBenchmark("render/offscreen_frame/lwr4_setup_I_640x480", offscreenFrame, 640, 480)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();  // llvmpipe rasterizes on worker threads: CPU time of this thread says little
}

}  // namespace flexirob::bench
