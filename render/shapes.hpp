#pragma once
// Turning the project's geometry descriptions (URDF visuals, scene obstacles, triangle meshes)
// into OpenSceneGraph nodes, and the pose conversion at the render boundary.
#include <osg/Geode>
#include <osg/Matrixd>
#include <osg/ref_ptr>

#include <Eigen/Geometry>
#include <filesystem>

#include "robot/robot_model.hpp"

namespace flexirob::render {

osg::Matrixd toOsgMatrix(const Eigen::Isometry3d& X);
osg::Vec3d toOsg(const Eigen::Vector3d& v);
osg::Vec4 toOsgColor(const Eigen::Vector4f& rgba);

enum class PrimitiveShape { kBox, kCylinder, kSphere };

/// A lit, coloured primitive centred at its frame's origin. size: box edge lengths;
/// cylinder (radius, length, -) along z; sphere (radius, -, -). Metres.
osg::ref_ptr<osg::Geode> makePrimitive(PrimitiveShape shape, const Eigen::Vector3d& size,
                                       const Eigen::Vector4f& rgba);

/// A lit, coloured triangle mesh read from a file (STL, DAE, OBJ, ... through assimp, by
/// robot/mesh.hpp), scaled per axis. Throws InputError if the file cannot be read.
osg::ref_ptr<osg::Geode> makeMesh(const std::filesystem::path& file, const Eigen::Vector3d& scale,
                                  const Eigen::Vector4f& rgba);

/// The node of one URDF visual, in its body's frame (X_BG applied).
osg::ref_ptr<osg::Node> makeVisual(const robot::Geometry& geometry);

/// Colours a node through its material (lit), with blending when rgba's alpha is below 1.
void applyColor(osg::Node& node, const Eigen::Vector4f& rgba);

}  // namespace flexirob::render
