#pragma once
// Arms far from the LWR IV's size and weight, for tests of what is sized for it (gains, the
// tutor's hands, the GUI's mouse spring, the ITM's distances).
#include <array>
#include <sstream>
#include <string>

namespace flexirob::testing {

// Seven joints about z, y, z, y, z, y, z, each link a solid cylinder (link j's radius `radius` −
// j `radius_step`) standing on the joint before it; the base a cylinder `base_radius` wide and
// `base_height` high. Joints of ±2.8 rad, the given effort, 3 rad/s (1.5 rad/s above 1 kNm).
inline std::string cylinderArmUrdf(const std::string& name, const std::array<double, 7>& lengths,
                                   const std::array<double, 7>& masses, double radius, double radius_step,
                                   double base_radius, double base_height, double effort) {
  const char* axes[] = {"0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1"};
  std::ostringstream urdf;
  urdf << "<robot name=\"" << name << "\"><link name=\"base\"><collision><origin xyz=\"0 0 " << base_height / 2
       << "\"/><geometry><cylinder radius=\"" << base_radius << "\" length=\"" << base_height
       << "\"/></geometry></collision></link>\n";
  std::string parent = "base";
  double offset = base_height;
  for (int j = 0; j < 7; ++j) {
    const std::string child = "l" + std::to_string(j + 1);
    const double l = lengths[static_cast<std::size_t>(j)], m = masses[static_cast<std::size_t>(j)], r = radius - radius_step * j;
    urdf << "<joint name=\"j" << j + 1 << "\" type=\"revolute\"><parent link=\"" << parent << "\"/><child link=\"" << child
         << "\"/><origin xyz=\"0 0 " << offset << "\"/><axis xyz=\"" << axes[j] << "\"/>"
         << "<limit lower=\"-2.8\" upper=\"2.8\" velocity=\"" << (effort > 1000 ? 1.5 : 3.0) << "\" effort=\"" << effort
         << "\"/></joint>\n"
         << "<link name=\"" << child << "\"><inertial><origin xyz=\"0 0 " << l / 2 << "\"/><mass value=\"" << m << "\"/><inertia ixx=\""
         << m * (3 * r * r + l * l) / 12 << "\" ixy=\"0\" ixz=\"0\" iyy=\"" << m * (3 * r * r + l * l) / 12 << "\" iyz=\"0\" izz=\""
         << m * r * r / 2 << "\"/></inertial><collision><origin xyz=\"0 0 " << l / 2 << "\"/><geometry><cylinder radius=\"" << r
         << "\" length=\"" << l << "\"/></geometry></collision></link>\n";
    parent = child;
    offset = l;
  }
  urdf << "</robot>\n";
  return urdf.str();
}

// Links of 0.06 to 0.03 m and 0.3 to 0.05 kg, 1.1 kg in all: about a quarter metre from the
// shoulder to the tip.
inline std::string smallLightArmUrdf() {
  return cylinderArmUrdf("small", {0.06, 0.06, 0.05, 0.05, 0.04, 0.04, 0.03}, {0.3, 0.25, 0.2, 0.15, 0.1, 0.07, 0.05}, 0.018,
                         0.001, 0.025, 0.03, 20.0);
}

// Links of 0.4 to 0.2 m and 60 to 20 kg, 260 kg in all: 1.85 m from the shoulder to the tip, 86
// times the LWR IV's largest joint inertia, with joints of 6 kNm that hold it anywhere.
inline std::string heavyLongArmUrdf() {
  return cylinderArmUrdf("heavy", {0.4, 0.4, 0.4, 0.4, 0.35, 0.3, 0.2}, {60, 50, 40, 35, 30, 25, 20}, 0.12, 0.0072, 0.168,
                         0.12, 6000.0);
}

}  // namespace flexirob::testing
