#pragma once
// Obstacles for scenes built in test code.
#include <Eigen/Geometry>
#include <string>

#include "robot/scene.hpp"

namespace flexirob::testing {

// An axis-aligned box of `size` [m] centred at `centre` [m, W].
inline robot::Obstacle boxObstacle(const std::string& name, const Eigen::Vector3d& size, const Eigen::Vector3d& centre) {
  robot::Obstacle box;
  box.name = name;
  box.size = size;
  box.X_WO = Eigen::Isometry3d(Eigen::Translation3d(centre));
  return box;
}

}  // namespace flexirob::testing
