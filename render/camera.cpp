#include "render/camera.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "robot/errors.hpp"

namespace flexirob::render {

namespace {
double degToRad(double degrees) { return degrees * std::numbers::pi / 180.0; }
}  // namespace

CameraPose frameSphere(const Eigen::Vector3d& center_W, double radius, double aspect) {
  CameraPose camera;
  const double safe_radius = std::isfinite(radius) && radius > 1e-3 ? radius : 1.0;
  const double safe_aspect = std::isfinite(aspect) && aspect > 1e-3 ? aspect : 1.0;
  // Front-left, slightly above: the robot works towards -x, its left is -y.
  const Eigen::Vector3d direction = Eigen::Vector3d(-1.0, -0.62, 0.42).normalized();
  // The sphere must fit both the vertical and the horizontal field of view.
  const double half_fovy = degToRad(camera.fovy_deg) / 2.0;
  const double half_fovx = std::atan(std::tan(half_fovy) * safe_aspect);
  const double distance = safe_radius / std::sin(std::min(half_fovy, half_fovx));
  camera.center_W = center_W;
  camera.eye_W = center_W + distance * direction;
  camera.up_W = Eigen::Vector3d::UnitZ();
  return camera;
}

CameraPose frameBox(const Eigen::Vector3d& lower_W, const Eigen::Vector3d& upper_W, double aspect, double margin) {
  return frameBoxFrom(lower_W, upper_W, aspect, Eigen::Vector3d(-1.0, -0.62, 0.42), Eigen::Vector3d::UnitZ(), margin);
}

CameraPose frameBoxFrom(const Eigen::Vector3d& lower_W, const Eigen::Vector3d& upper_W, double aspect,
                        const Eigen::Vector3d& direction_W, const Eigen::Vector3d& up_W, double margin) {
  const Eigen::Vector3d center_W = 0.5 * (lower_W + upper_W);
  const double radius = 0.5 * (upper_W - lower_W).norm();
  // The circumscribed sphere always fits; move closer while every corner still fits.
  CameraPose camera = frameSphere(center_W, radius, aspect);
  const Eigen::Vector3d direction =
      direction_W.norm() > 1e-9 ? Eigen::Vector3d(direction_W.normalized()) : Eigen::Vector3d(-1.0, -0.62, 0.42).normalized();
  camera.up_W = direction.cross(up_W).norm() > 1e-6 ? up_W : Eigen::Vector3d::UnitZ();
  camera.eye_W = center_W + (camera.eye_W - center_W).norm() * direction;
  const int height = 1000;
  const int width = std::max(1, static_cast<int>(std::lround(height * (aspect > 1e-3 ? aspect : 1.0))));
  const auto fits = [&](double distance) {
    CameraPose trial = camera;
    trial.eye_W = center_W + distance * direction;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p_W((corner & 1) ? upper_W.x() : lower_W.x(), (corner & 2) ? upper_W.y() : lower_W.y(),
                                (corner & 4) ? upper_W.z() : lower_W.z());
      const auto pixel = projectToPixel(trial, width, height, p_W);
      if (!pixel || pixel->x() < margin * width || pixel->x() > (1.0 - margin) * width ||
          pixel->y() < margin * height || pixel->y() > (1.0 - margin) * height) {
        return false;
      }
    }
    return true;
  };
  double far = (camera.eye_W - center_W).norm();
  while (!fits(far) && far < 1e4) far *= 1.5;
  double near = 0.0;
  for (int i = 0; i < 40; ++i) {
    const double middle = 0.5 * (near + far);
    (fits(middle) ? far : near) = middle;
  }
  camera.eye_W = center_W + far * direction;
  return camera;
}

void namedView(const std::string& name, Eigen::Vector3d& direction_W, Eigen::Vector3d& up_W) {
  up_W = Eigen::Vector3d::UnitZ();
  if (name == "front-left") {
    direction_W = Eigen::Vector3d(-1.0, -0.62, 0.42);
  } else if (name == "front-left-low") {
    // Low enough that the eye stays under a ceiling over the robot.
    direction_W = Eigen::Vector3d(-1.0, -0.62, 0.10);
  } else if (name == "back-left") {
    // From behind the robot: sees the arm when a wall stands between it and the front.
    direction_W = Eigen::Vector3d(1.0, -0.62, 0.42);
  } else if (name == "back-right") {
    direction_W = Eigen::Vector3d(1.0, 0.62, 0.42);
  } else if (name == "front-right") {
    // Lower than front-left: shows what stands behind obstacles on the robot's right (+y).
    direction_W = Eigen::Vector3d(-1.0, 0.62, 0.30);
  } else if (name == "front") {
    direction_W = Eigen::Vector3d(-1.0, -0.12, 0.45);
  } else if (name == "back") {
    direction_W = Eigen::Vector3d(1.0, 0.12, 0.45);
  } else if (name == "left") {
    // The robot's sides, as in every other name: it works towards -x, so its left is -y (a
    // tutor facing it has them mirrored).
    direction_W = Eigen::Vector3d(-0.25, -1.0, 0.45);
  } else if (name == "right") {
    direction_W = Eigen::Vector3d(-0.25, 1.0, 0.45);
  } else if (name == "top") {
    // Looking straight down with +x up in the image: the front (-x) at the bottom.
    direction_W = Eigen::Vector3d::UnitZ();
    up_W = Eigen::Vector3d::UnitX();
  } else {
    throw InputError("--view: unknown view '" + name +
                     "' (front-left, front-left-low, front-right, front, back, back-left, back-right, left, right, top)");
  }
}

std::optional<Eigen::Vector2d> projectToPixel(const CameraPose& camera, int width, int height,
                                              const Eigen::Vector3d& p_W) {
  // Camera frame C: x right, y up, looking along -z (the OpenGL convention).
  const Eigen::Vector3d forward = (camera.center_W - camera.eye_W).normalized();
  const Eigen::Vector3d right = forward.cross(camera.up_W).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  const Eigen::Vector3d d_W = p_W - camera.eye_W;
  const double depth = d_W.dot(forward);
  if (depth <= 1e-9) return std::nullopt;
  // Pinhole projection to normalized device coordinates in [-1, 1].
  const double f = 1.0 / std::tan(degToRad(camera.fovy_deg) / 2.0);
  const double aspect = static_cast<double>(width) / static_cast<double>(height);
  const double ndc_x = f / aspect * d_W.dot(right) / depth;
  const double ndc_y = f * d_W.dot(up) / depth;
  // Viewport: NDC -1..1 covers pixel edges 0..width; image rows count downwards.
  return Eigen::Vector2d((ndc_x + 1.0) * 0.5 * width, (1.0 - ndc_y) * 0.5 * height);
}

CameraPose parseCamera(const std::string& text) {
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string token = text.substr(start, end - start);
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (token.empty() || used != token.size() || !std::isfinite(value)) {
      throw InputError("--camera: '" + token + "' is not a finite number (expected ex,ey,ez,cx,cy,cz[,fovy_deg])");
    }
    values.push_back(value);
    if (end == text.size()) break;
    start = end + 1;
  }
  if (values.size() != 6 && values.size() != 7) {
    throw InputError("--camera: expected 6 or 7 numbers (ex,ey,ez,cx,cy,cz[,fovy_deg]), got " +
                     std::to_string(values.size()));
  }
  CameraPose camera;
  camera.eye_W = Eigen::Vector3d(values[0], values[1], values[2]);
  camera.center_W = Eigen::Vector3d(values[3], values[4], values[5]);
  if (values.size() == 7) camera.fovy_deg = values[6];
  if ((camera.eye_W - camera.center_W).norm() < 1e-6) {
    throw InputError("--camera: eye and centre coincide");
  }
  if (camera.fovy_deg <= 1.0 || camera.fovy_deg >= 170.0) {
    throw InputError("--camera: field of view must lie in (1, 170) degrees, got " + std::to_string(camera.fovy_deg));
  }
  // Looking straight up or down: any horizontal up vector will do.
  const Eigen::Vector3d forward = (camera.center_W - camera.eye_W).normalized();
  if (std::abs(forward.z()) > 0.999) camera.up_W = Eigen::Vector3d::UnitX();
  return camera;
}

}  // namespace flexirob::render
