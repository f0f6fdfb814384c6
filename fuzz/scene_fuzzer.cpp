// Fuzz target: scene YAML -> Scene. Malformed input must end in an InputError. An accepted scene
// must hold finite numbers only and survive a write/read round trip (sceneToYaml promises that
// parseScene reads its output back).
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_support.hpp"
#include "robot/errors.hpp"
#include "robot/scene.hpp"

namespace {

void checkFinite(const flexirob::robot::Scene& scene) {
  for (const auto& target : scene.targets) {
    if (!target.allFinite()) flexirob::fuzz::invariantBroken("non-finite target");
  }
  for (const auto& trajectory : scene.trajectories) {
    for (const auto& p : trajectory.waypoints) {
      if (!p.allFinite()) flexirob::fuzz::invariantBroken("non-finite waypoint");
    }
  }
  if (scene.home_posture && !scene.home_posture->allFinite()) flexirob::fuzz::invariantBroken("non-finite home posture");
  for (const auto& [name, value] : scene.parameters) {
    if (!std::isfinite(value)) flexirob::fuzz::invariantBroken("non-finite parameter");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path base_dir = flexirob::fuzz::resourceDir() / "scenes";
  const std::string text(reinterpret_cast<const char*>(data), size);
  flexirob::robot::Scene scene;
  try {
    scene = flexirob::robot::parseScene(text, base_dir, "fuzz input");
  } catch (const flexirob::InputError&) {
    return 0;
  }
  checkFinite(scene);
  try {
    const auto again = flexirob::robot::parseScene(flexirob::robot::sceneToYaml(scene), base_dir, "round trip");
    if (again.obstacles.size() != scene.obstacles.size() || again.targets.size() != scene.targets.size() ||
        again.training_areas.size() != scene.training_areas.size() || again.table != scene.table) {
      flexirob::fuzz::invariantBroken("round trip changed the scene");
    }
  } catch (const flexirob::InputError& e) {
    std::fprintf(stderr, "round trip refused: %s\n", e.what());
    flexirob::fuzz::invariantBroken("an accepted scene does not read back");
  }
  return 0;
}
