// flexirob-meshgen: generates the KUKA LWR IV meshes (resources/robots/lwr4/meshes/*.stl) from
// the link dimensions of resources/robots/lwr4/lwr4.urdf. The 9-DoF arm reuses them.
//
// Regenerate (the STL files are committed data; rerun after changing a dimension below):
//   ninja -C build-meshes flexirob-meshgen
//   build-meshes/tools/flexirob-meshgen resources/robots/lwr4/meshes
//
// Every shape is a surface of revolution (a closed profile in the (rho, h) half-plane turned
// about an axis), so each component is a closed, consistently wound surface with outward
// normals. Each mesh is written in its own URDF link frame, derived from the DH table of the
// URDF (URDF link i = DH frame i-1 turned by q_i; every joint axis is the link frame's z):
//   link1: A1 axis = z, from the base top up to the shoulder (A2) at z = 0.3105.
//   link2: origin on the A2 axis (= z); the upper arm continues along +y.
//   link3: A3 axis = z (the upper arm), elbow (A4) at z = 0.4; A4 axis along +y.
//   link4: origin on the A4 axis (= z); the forearm continues along -y.
//   link5: A5 axis = z (the forearm), wrist (A6) at z = 0.39; A6 axis along -y.
//   link6: origin on the A6 axis (= z); the hand continues along +y.
//   link7: A7 axis = z, the flange frame at z = 0.078.
// Transverse joints (A2, A4, A6) sit in a rounded housing owned by the child link (its axis is
// the child's z, so turning the joint maps the housing onto itself); the parent's tube ends in
// a hemisphere hidden inside that housing. Axial joints (A1, A3, A5, A7) split a tube by a plane
// across the axis, covered by a grey ring.
#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Eigen::Isometry3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

// ---- Dimensions [m] ------------------------------------------------------------------------
// Kinematics (DH offsets of the URDF): shoulder, elbow, wrist, flange.
constexpr double kShoulderZ = 0.3105;  // A2 in link1
constexpr double kUpperArm = 0.4;      // A4 in link3
constexpr double kForearm = 0.39;      // A6 in link5
constexpr double kFlangeZ = 0.078;     // flange frame in link7
// Appearance: radii and where the axial joints split the segments (the LWR IV's A3 and A5
// interfaces sit about half-way along the upper arm and forearm). A3 and A5 split at the same
// distance so that the 9-DoF arm's duplicated link3 meets the link4 before it without a gap.
constexpr double kBaseRadius = 0.08;
constexpr double kBaseHeight = 0.11;
constexpr double kLink1Radius = 0.07;
constexpr double kUpperArmRadius = 0.065;
constexpr double kForearmRadius = 0.056;
constexpr double kHandRadius = 0.045;
constexpr double kA3Split = 0.20;   // along link3's z (from the shoulder)
constexpr double kA5Split = 0.20;   // along link5's z (from the elbow)
constexpr double kA7Split = 0.060;  // along link7's z (from the wrist)
constexpr double kLink7Top = 0.070;
constexpr double kFlangeRadius = 0.0315;  // ISO 9409-1-A50 flange, 63 mm
constexpr double kFlangeThickness = kFlangeZ - kLink7Top;

struct Resolution {
  int around;  // segments around the axis
  int arc;     // segments per quarter arc (fillets, hemispheres)
};
constexpr Resolution kVisual{64, 8};
constexpr Resolution kCollision{16, 3};

struct Triangle {
  std::array<Vector3d, 3> v;
};
using Mesh = std::vector<Triangle>;

// A profile point in the half-plane of the axis: rho >= 0 the distance from the axis, h the
// height along it.
struct ProfilePoint {
  double rho;
  double h;
};

// Turns a profile about the z axis of frame X_LA (given in the link frame L) and appends the
// triangles. The profile either runs from a pole on the axis (rho = 0) to another pole, or is a
// closed loop (last point joined to the first) that stays off the axis. interior_rho_h is a
// point inside the profile's region: each segment's outward normal points away from it, and
// each triangle is wound to face that way, whatever the profile's direction.
void revolve(Mesh& mesh, const Isometry3d& X_LA, const std::vector<ProfilePoint>& profile, bool closed_loop,
             int around, const Vector2d& interior_rho_h) {
  const auto point = [&](const ProfilePoint& p, int j) {
    const double phi = 2.0 * std::numbers::pi * j / around;
    return Vector3d(X_LA * Vector3d(p.rho * std::cos(phi), p.rho * std::sin(phi), p.h));
  };
  const std::size_t segments = closed_loop ? profile.size() : profile.size() - 1;
  for (std::size_t k = 0; k < segments; ++k) {
    const ProfilePoint& a = profile[k];
    const ProfilePoint& b = profile[(k + 1) % profile.size()];
    // Outward normal of the segment in (rho, h): perpendicular to it, pointing away from a
    // point known to be inside the solid.
    Vector2d tangent(b.rho - a.rho, b.h - a.h);
    Vector2d normal(tangent.y(), -tangent.x());
    const Vector2d mid(0.5 * (a.rho + b.rho), 0.5 * (a.h + b.h));
    if (normal.dot(mid - interior_rho_h) < 0) normal = -normal;
    for (int j = 0; j < around; ++j) {
      const double phi = 2.0 * std::numbers::pi * (j + 0.5) / around;
      const Vector3d n_L = X_LA.linear() * Vector3d(normal.x() * std::cos(phi), normal.x() * std::sin(phi), normal.y());
      const Vector3d p00 = point(a, j), p01 = point(a, j + 1), p10 = point(b, j), p11 = point(b, j + 1);
      auto emit = [&](const Vector3d& x, const Vector3d& y, const Vector3d& z) {
        const Vector3d face = (y - x).cross(z - x);
        if (face.norm() < 1e-14) return;  // degenerate (at a pole)
        if (face.dot(n_L) >= 0) {
          mesh.push_back({{x, y, z}});
        } else {
          mesh.push_back({{x, z, y}});
        }
      };
      emit(p00, p01, p11);
      emit(p00, p11, p10);
    }
  }
}

// Adds a quarter arc from angle a0 to a1 (radians, in the (rho, h) plane) around centre c.
void addArc(std::vector<ProfilePoint>& profile, Vector2d c, double radius, double a0, double a1, int steps) {
  for (int i = 0; i <= steps; ++i) {
    const double a = a0 + (a1 - a0) * i / steps;
    profile.push_back({c.x() + radius * std::cos(a), c.y() + radius * std::sin(a)});
  }
}

// A cylinder of radius r from h0 to h1 about the z axis of X_LA; each end either flat with an
// edge fillet (fillet > 0), flat and sharp (fillet = 0) or a hemisphere (fillet < 0).
void roundedCylinder(Mesh& mesh, const Isometry3d& X_LA, double r, double h0, double h1, double fillet0,
                     double fillet1, const Resolution& res) {
  constexpr double kHalfPi = std::numbers::pi / 2;
  std::vector<ProfilePoint> profile;
  // Bottom end, from the pole outwards.
  if (fillet0 < 0) {
    addArc(profile, {0.0, h0}, r, -kHalfPi, 0.0, 2 * res.arc);
    profile.front().rho = 0.0;
  } else {
    profile.push_back({0.0, h0});
    if (fillet0 > 0) {
      addArc(profile, {r - fillet0, h0 + fillet0}, fillet0, -kHalfPi, 0.0, res.arc);
    } else {
      profile.push_back({r, h0});
    }
  }
  // Top end, from the side up to the pole.
  if (fillet1 < 0) {
    addArc(profile, {0.0, h1}, r, 0.0, kHalfPi, 2 * res.arc);
    profile.back().rho = 0.0;
  } else {
    if (fillet1 > 0) {
      addArc(profile, {r - fillet1, h1 - fillet1}, fillet1, 0.0, kHalfPi, res.arc);
    } else {
      profile.push_back({r, h1});
    }
    profile.push_back({0.0, h1});
  }
  revolve(mesh, X_LA, profile, false, res.around, Vector2d(0.0, 0.5 * (h0 + h1)));
}

// A ring (annulus of rectangular section, closed) about the z axis of X_LA.
void ring(Mesh& mesh, const Isometry3d& X_LA, double r_in, double r_out, double h0, double h1, const Resolution& res) {
  const std::vector<ProfilePoint> profile{{r_in, h0}, {r_out, h0}, {r_out, h1}, {r_in, h1}};
  revolve(mesh, X_LA, profile, true, res.around, Vector2d(0.5 * (r_in + r_out), 0.5 * (h0 + h1)));
}

// Frames of revolution axes in the link frame.
Isometry3d alongZ() { return Isometry3d::Identity(); }
// Axis along +y (rotation taking z to +y) or -y.
Isometry3d alongY(double sign) {
  Isometry3d X = Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(-sign * std::numbers::pi / 2, Vector3d::UnitX()).toRotationMatrix();
  return X;
}

// The housing of a transverse joint: a cylinder about the joint axis (the link's z) with
// rounded rims. Half-width = radius, rim fillet 0.25 radius: the parent's hemisphere of the
// same radius lies inside it in every joint position.
void transverseHousing(Mesh& mesh, double radius, const Resolution& res) {
  roundedCylinder(mesh, alongZ(), radius, -radius, radius, 0.25 * radius, 0.25 * radius, res);
}
// The grey rings on both faces of a transverse housing.
void transverseRings(Mesh& mesh, double radius, const Resolution& res) {
  for (const double side : {-1.0, 1.0}) {
    const double h_in = side * (radius - 0.002);
    const double h_out = side * (radius + 0.003);
    ring(mesh, alongZ(), 0.45 * radius, 0.72 * radius, std::min(h_in, h_out), std::max(h_in, h_out), res);
  }
}
// The grey band over the split of an axial joint at height h along the link's z.
void axialRing(Mesh& mesh, double radius, double h, const Resolution& res) {
  ring(mesh, alongZ(), radius - 0.006, radius + 0.003, h - 0.008, h + 0.008, res);
}

struct LinkMeshes {
  Mesh shell, ring, collision;
};

// shell(res): the orange body; rings: the grey joint rings of the link's own joint.
LinkMeshes makeLink(int link) {
  LinkMeshes out;
  auto shell = [&](Mesh& m, const Resolution& res) {
    switch (link) {
      case 1:  // base top to the shoulder, ending in a hemisphere inside link2's housing
        roundedCylinder(m, alongZ(), kLink1Radius, kBaseHeight, kShoulderZ, 0.0, -1.0, res);
        break;
      case 2:  // A2 housing, then the upper arm along +y up to the A3 split
        transverseHousing(m, kLink1Radius, res);
        roundedCylinder(m, alongY(+1), kUpperArmRadius, 0.0, kA3Split, 0.0, 0.0, res);
        break;
      case 3:  // A3 split to the elbow, hemisphere inside link4's housing
        roundedCylinder(m, alongZ(), kUpperArmRadius, kA3Split, kUpperArm, 0.0, -1.0, res);
        break;
      case 4:  // A4 housing, forearm along -y to the A5 split
        transverseHousing(m, kUpperArmRadius, res);
        roundedCylinder(m, alongY(-1), kForearmRadius, 0.0, kA5Split, 0.0, 0.0, res);
        break;
      case 5:  // A5 split to the wrist
        roundedCylinder(m, alongZ(), kForearmRadius, kA5Split, kForearm, 0.0, -1.0, res);
        break;
      case 6:  // A6 housing, hand along +y to the A7 split
        transverseHousing(m, kForearmRadius, res);
        roundedCylinder(m, alongY(+1), kHandRadius, 0.0, kA7Split, 0.0, 0.0, res);
        break;
      case 7:  // A7 split to the flange seat
        roundedCylinder(m, alongZ(), kHandRadius, kA7Split, kLink7Top, 0.0, 0.006, res);
        break;
      default: throw std::logic_error("no such link");
    }
  };
  shell(out.shell, kVisual);
  shell(out.collision, kCollision);
  switch (link) {
    case 1: axialRing(out.ring, kLink1Radius, kBaseHeight, kVisual); break;
    case 2: transverseRings(out.ring, kLink1Radius, kVisual); break;
    case 3: axialRing(out.ring, kUpperArmRadius, kA3Split, kVisual); break;
    case 4: transverseRings(out.ring, kUpperArmRadius, kVisual); break;
    case 5: axialRing(out.ring, kForearmRadius, kA5Split, kVisual); break;
    case 6: transverseRings(out.ring, kForearmRadius, kVisual); break;
    case 7: axialRing(out.ring, kHandRadius, kA7Split, kVisual); break;
    default: break;
  }
  return out;
}

// Binary STL: 80-byte header, triangle count, then per triangle the facet normal, three
// vertices (little-endian float32) and a 16-bit attribute word.
void writeStl(const fs::path& file, const Mesh& mesh) {
  std::ofstream out(file, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  std::array<char, 80> header{};
  const std::string title = "FlexIRob LWR IV mesh " + file.filename().string() + ", metres";
  std::copy_n(title.begin(), std::min<std::size_t>(title.size(), header.size()), header.begin());
  out.write(header.data(), header.size());
  const auto count = static_cast<std::uint32_t>(mesh.size());
  out.write(reinterpret_cast<const char*>(&count), sizeof count);
  for (const Triangle& t : mesh) {
    const Vector3d n = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalized();
    std::array<float, 12> values{};
    for (int i = 0; i < 3; ++i) values[static_cast<std::size_t>(i)] = static_cast<float>(n[i]);
    for (std::size_t k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) values[3 + 3 * k + static_cast<std::size_t>(i)] = static_cast<float>(t.v[k][i]);
    }
    out.write(reinterpret_cast<const char*>(values.data()), sizeof values);
    const std::uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), sizeof attribute);
  }
  if (!out) throw std::runtime_error("error writing " + file.string());
  std::cout << file.string() << ": " << mesh.size() << " triangles\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: flexirob-meshgen OUTPUT_DIR  (e.g. resources/robots/lwr4/meshes)\n";
    return 2;
  }
  try {
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    // Base: a cylinder with a rounded top rim on the mounting plane (base frame z = 0).
    Mesh base, base_collision;
    roundedCylinder(base, alongZ(), kBaseRadius, 0.0, kBaseHeight, 0.0, 0.012, kVisual);
    ring(base, alongZ(), kBaseRadius - 0.004, kBaseRadius + 0.006, 0.0, 0.012, kVisual);  // mounting foot
    roundedCylinder(base_collision, alongZ(), kBaseRadius + 0.006, 0.0, kBaseHeight, 0.0, 0.012, kCollision);
    writeStl(dir / "base_shell.stl", base);
    writeStl(dir / "base_collision.stl", base_collision);
    for (int link = 1; link <= 7; ++link) {
      const LinkMeshes meshes = makeLink(link);
      const std::string stem = "link" + std::to_string(link);
      writeStl(dir / (stem + "_shell.stl"), meshes.shell);
      writeStl(dir / (stem + "_ring.stl"), meshes.ring);
      writeStl(dir / (stem + "_collision.stl"), meshes.collision);
    }
    // Flange (in the flange frame, link7 z = 0.078): a disc whose top face is the mounting plane.
    Mesh flange;
    roundedCylinder(flange, alongZ(), kFlangeRadius, -kFlangeThickness, 0.0, 0.0, 0.0015, kVisual);
    writeStl(dir / "flange.stl", flange);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
