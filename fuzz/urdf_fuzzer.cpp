// Fuzz target: URDF text -> RobotModel (chain extraction, fixed-joint folding, limits, mesh URI
// resolution against the LWR IV resource directory). Malformed input must end in an
// InputError; an accepted model must be self-consistent.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_support.hpp"
#include "robot/errors.hpp"
#include "robot/robot_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path base_dir = flexirob::fuzz::resourceDir() / "robots" / "lwr4";
  const std::string xml(reinterpret_cast<const char*>(data), size);
  try {
    const auto model = flexirob::robot::RobotModel::fromUrdfString(xml, base_dir);
    if (model.bodies().size() != model.joints().size() + 1) flexirob::fuzz::invariantBroken("bodies != joints + 1");
    for (const auto& joint : model.joints()) {
      if (!joint.X_PJ.matrix().allFinite()) flexirob::fuzz::invariantBroken("non-finite joint pose");
      if (!joint.axis_J.allFinite() || std::abs(joint.axis_J.norm() - 1.0) > 1e-9) flexirob::fuzz::invariantBroken("axis not unit");
      if (std::isnan(joint.limits.lower) || std::isnan(joint.limits.upper) || joint.limits.lower > joint.limits.upper) {
        flexirob::fuzz::invariantBroken("joint limits out of order");
      }
      if (joint.limits.soft_lower < joint.limits.lower || joint.limits.soft_upper > joint.limits.upper ||
          joint.limits.soft_lower > joint.limits.soft_upper) {
        flexirob::fuzz::invariantBroken("software limits outside the hardware limits");
      }
    }
    for (const auto& body : model.bodies()) {
      if (!std::isfinite(body.mass) || body.mass < 0.0) flexirob::fuzz::invariantBroken("body mass");
      for (const auto* shapes : {&body.visuals, &body.collisions}) {
        for (const auto& shape : *shapes) {
          if (shape.kind == flexirob::robot::Geometry::Kind::kMesh && !std::filesystem::is_regular_file(shape.mesh_file)) {
            flexirob::fuzz::invariantBroken("resolved mesh file does not exist");
          }
        }
      }
    }
    // A posture at the centre of the limits must be accepted by the model's own check.
    model.checkPosture(model.midPosture());
  } catch (const flexirob::InputError&) {
  }
  return 0;
}
