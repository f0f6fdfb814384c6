#pragma once
// A perspective camera described by what a person would say: where the eye is, what it looks
// at, which way is up and how wide the view is. Both the offscreen renderer and the GUI turn it
// into OpenSceneGraph matrices; projectToPixel() computes the same projection with Eigen alone,
// so tests and tools can find where a world point lands in an image without asking OSG.
#include <Eigen/Core>
#include <optional>
#include <string>

namespace flexirob::render {

struct CameraPose {
  Eigen::Vector3d eye_W{-2.0, -1.5, 1.2};     ///< eye position in the world frame W [m]
  Eigen::Vector3d center_W{0.0, 0.0, 0.5};    ///< point looked at, in W [m]
  Eigen::Vector3d up_W{0.0, 0.0, 1.0};        ///< approximate up direction in W (z up)
  double fovy_deg = 35.0;                     ///< vertical field of view [degrees]
};

/// Frames a sphere (centre in W, radius in metres) from the front-left of the robot, slightly
/// above: the robot faces -x (its workspace, Sect. 3.3.2), so the eye sits at -x, -y, +z of
/// the centre, far enough that the whole sphere fits the narrower of the two fields of view.
CameraPose frameSphere(const Eigen::Vector3d& center_W, double radius, double aspect);

/// Frames an axis-aligned box (corners in W, metres) from the same direction as frameSphere,
/// looking at its centre from the nearest distance at which every corner lies inside the image
/// with `margin` (a fraction of the image size) to spare.
CameraPose frameBox(const Eigen::Vector3d& lower_W, const Eigen::Vector3d& upper_W, double aspect,
                    double margin = 0.05);

/// Frames the box as frameBox does, but with the eye on the side `direction_W` (from the box's
/// centre towards the eye, need not be normalized) and `up_W` as the image's up direction
/// (must not be parallel to direction_W).
CameraPose frameBoxFrom(const Eigen::Vector3d& lower_W, const Eigen::Vector3d& upper_W, double aspect,
                        const Eigen::Vector3d& direction_W, const Eigen::Vector3d& up_W, double margin = 0.05);

/// A named viewing direction for figures, named by the robot's sides (it works towards -x, so
/// its left is -y): "front-left" (from -x, -y; frameSphere's, the default), "front-left-low"
/// (the same side, about 5 degrees above the horizon), "front-right" (from -x, +y, lower),
/// "front" (from -x, the tutor's side, slightly above), "back", "back-left" and "back-right"
/// (from +x, mirroring the front views), "left" (-y), "right" (+y), "top" (straight down, the
/// front at the bottom of the image). Sets direction_W (centre to eye) and
/// up_W. Throws InputError naming the valid names otherwise.
void namedView(const std::string& name, Eigen::Vector3d& direction_W, Eigen::Vector3d& up_W);

/// Pixel coordinates (x right, y down, origin at the top-left corner of the image, pixel
/// centres at +0.5) of the world point p_W for an image of width x height pixels. Returns
/// nothing for points behind the eye.
std::optional<Eigen::Vector2d> projectToPixel(const CameraPose& camera, int width, int height,
                                              const Eigen::Vector3d& p_W);

/// Parses "ex,ey,ez,cx,cy,cz[,fovy_deg]" (eye and centre in W, metres). Throws InputError.
CameraPose parseCamera(const std::string& text);

}  // namespace flexirob::render
