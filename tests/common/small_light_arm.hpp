#pragma once
// A small, light arm for tests of what is sized for the LWR IV (gains, the tutor's hands, the
// GUI's mouse spring).
#include <sstream>
#include <string>

namespace flexirob::testing {

// Seven joints, links of 0.06 to 0.03 m and 0.3 to 0.05 kg (solid cylinders), 1.1 kg in all:
// about a quarter metre from the shoulder to the tip.
inline std::string smallLightArmUrdf() {
  const double lengths[] = {0.06, 0.06, 0.05, 0.05, 0.04, 0.04, 0.03};
  const double masses[] = {0.3, 0.25, 0.2, 0.15, 0.1, 0.07, 0.05};
  const char* axes[] = {"0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1"};
  std::ostringstream urdf;
  urdf << "<robot name=\"small\"><link name=\"base\"><collision><origin xyz=\"0 0 0.015\"/><geometry><cylinder radius=\"0.025\" "
          "length=\"0.03\"/></geometry></collision></link>\n";
  std::string parent = "base";
  double offset = 0.03;
  for (int j = 0; j < 7; ++j) {
    const std::string child = "l" + std::to_string(j + 1);
    const double l = lengths[j], m = masses[j], r = 0.018 - 0.001 * j;
    urdf << "<joint name=\"j" << j + 1 << "\" type=\"revolute\"><parent link=\"" << parent << "\"/><child link=\"" << child
         << "\"/><origin xyz=\"0 0 " << offset << "\"/><axis xyz=\"" << axes[j] << "\"/>"
         << "<limit lower=\"-2.8\" upper=\"2.8\" velocity=\"3\" effort=\"20\"/></joint>\n"
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

}  // namespace flexirob::testing
