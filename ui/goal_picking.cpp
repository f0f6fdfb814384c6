#include "ui/goal_picking.hpp"

#include <cmath>
#include <limits>

namespace flexirob::ui {

std::optional<GoalPick> pickGoal(const render::CameraPose& camera, int width, int height, const Eigen::Vector2d& click,
                                 const std::vector<Eigen::Vector3d>& nodes_W, const Eigen::Vector3d& ray_origin_W,
                                 const Eigen::Vector3d& ray_direction_W, double plane_z, double max_pixels) {
  double best = max_pixels;
  std::optional<GoalPick> pick;
  for (std::size_t i = 0; i < nodes_W.size(); ++i) {
    const std::optional<Eigen::Vector2d> pixel = render::projectToPixel(camera, width, height, nodes_W[i]);
    if (!pixel) continue;  // behind the eye
    const double distance = (*pixel - click).norm();
    if (distance <= best) {
      best = distance;
      pick = GoalPick{nodes_W[i], static_cast<int>(i)};
    }
  }
  if (pick) return pick;
  // The ray o + s d meets z = plane_z at s = (plane_z − o_z) / d_z; only in front of the eye.
  if (std::abs(ray_direction_W.z()) < 1e-9) return std::nullopt;
  const double s = (plane_z - ray_origin_W.z()) / ray_direction_W.z();
  if (!(s > 0.0) || !std::isfinite(s)) return std::nullopt;
  return GoalPick{ray_origin_W + s * ray_direction_W, -1};
}

}  // namespace flexirob::ui
