#pragma once
// Click a point to set a goal (issue #7 item 4, thesis Sect. 7.4): in EXECUTION the operator
// Ctrl+clicks the 3D view; the goal is the explored position the click points at — the ITM
// node drawn nearest the click in the picture, if one lies within a few pixels — else the point
// where the click's ray meets the horizontal plane through the current tip. The workflow then
// plans through the ITM graph to it and executes (WorkflowThread's planTo).
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "render/camera.hpp"

namespace flexirob::ui {

struct GoalPick {
  Eigen::Vector3d goal_W = Eigen::Vector3d::Zero();  ///< [m]
  int node = -1;  ///< index into the nodes given, or -1 for the plane's point
};

/// The goal under pixel `click` (x right, y down) of a width x height view seen from `camera`:
/// the node (positions in W) whose projection is nearest the click within `max_pixels`, else
/// the point where the ray (origin, unit direction, in W) meets the plane z = plane_z in front
/// of the eye; nullopt when the ray runs parallel to the plane or away from it.
std::optional<GoalPick> pickGoal(const render::CameraPose& camera, int width, int height, const Eigen::Vector2d& click,
                                 const std::vector<Eigen::Vector3d>& nodes_W, const Eigen::Vector3d& ray_origin_W,
                                 const Eigen::Vector3d& ray_direction_W, double plane_z, double max_pixels = 18.0);

}  // namespace flexirob::ui
