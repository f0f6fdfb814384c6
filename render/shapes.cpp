#include "render/shapes.hpp"

#include <osg/BlendFunc>
#include <osg/Geometry>
#include <osg/Material>
#include <osg/MatrixTransform>
#include <osg/ShapeDrawable>

#include "robot/errors.hpp"
#include "robot/mesh.hpp"

namespace flexirob::render {

osg::Matrixd toOsgMatrix(const Eigen::Isometry3d& X) {
  // OSG multiplies row vectors from the left, so its matrix is the transpose of ours.
  osg::Matrixd m;
  const Eigen::Matrix4d& h = X.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(c, r) = h(r, c);
  }
  return m;
}

osg::Vec3d toOsg(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

osg::Vec4 toOsgColor(const Eigen::Vector4f& rgba) { return {rgba[0], rgba[1], rgba[2], rgba[3]}; }

void applyColor(osg::Node& node, const Eigen::Vector4f& rgba) {
  osg::StateSet* state = node.getOrCreateStateSet();
  osg::ref_ptr<osg::Material> material = new osg::Material();
  material->setColorMode(osg::Material::OFF);
  const osg::Vec4 diffuse = toOsgColor(rgba);
  // Ambient a bit darker than diffuse, a soft white highlight: rounded shells read as round.
  material->setAmbient(osg::Material::FRONT_AND_BACK,
                       osg::Vec4(diffuse.r() * 0.45F, diffuse.g() * 0.45F, diffuse.b() * 0.45F, diffuse.a()));
  material->setDiffuse(osg::Material::FRONT_AND_BACK, diffuse);
  material->setSpecular(osg::Material::FRONT_AND_BACK, osg::Vec4(0.3F, 0.3F, 0.3F, diffuse.a()));
  material->setShininess(osg::Material::FRONT_AND_BACK, 48.0F);
  state->setAttributeAndModes(material, osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
  if (rgba[3] < 0.999F) {
    // Blend colours, but keep the framebuffer opaque: a translucent pixel in a PNG or in Qt's
    // widget buffer would let the desktop or a checkerboard show through.
    state->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA));
    state->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
  } else {
    state->removeAttribute(osg::StateAttribute::BLENDFUNC);
    state->setRenderBinToInherit();
  }
}

osg::ref_ptr<osg::Geode> makePrimitive(PrimitiveShape shape, const Eigen::Vector3d& size,
                                       const Eigen::Vector4f& rgba) {
  osg::ref_ptr<osg::Shape> osg_shape;
  switch (shape) {
    case PrimitiveShape::kBox:
      osg_shape = new osg::Box(osg::Vec3(), static_cast<float>(size.x()), static_cast<float>(size.y()),
                               static_cast<float>(size.z()));
      break;
    case PrimitiveShape::kCylinder:
      osg_shape = new osg::Cylinder(osg::Vec3(), static_cast<float>(size.x()), static_cast<float>(size.y()));
      break;
    case PrimitiveShape::kSphere:
      osg_shape = new osg::Sphere(osg::Vec3(), static_cast<float>(size.x()));
      break;
  }
  osg::ref_ptr<osg::TessellationHints> hints = new osg::TessellationHints();
  // OSG's default tessellation (40 segments around) keeps silhouettes smooth at the view's sizes;
  // each doubling quadruples the triangles a software renderer has to set up every frame.
  hints->setDetailRatio(1.0F);
  osg::ref_ptr<osg::ShapeDrawable> drawable = new osg::ShapeDrawable(osg_shape.get(), hints.get());
  drawable->setColor(toOsgColor(rgba));
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  geode->addDrawable(drawable);
  applyColor(*geode, rgba);
  return geode;
}

osg::ref_ptr<osg::Geode> makeMesh(const std::filesystem::path& file, const Eigen::Vector3d& scale,
                                  const Eigen::Vector4f& rgba) {
  // Meshes are shared between views and with the simulation's collision shapes.
  const std::shared_ptr<const robot::TriangleMesh> loaded = robot::loadMeshCached(file);
  const robot::TriangleMesh mesh =
      scale.isOnes() ? *loaded : robot::transformedMesh(*loaded, Eigen::Isometry3d::Identity(), scale);
  if (mesh.empty()) throw InputError("mesh file '" + file.string() + "' holds no triangles");
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
  osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
  vertices->reserve(mesh.vertices.size());
  normals->reserve(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    const Eigen::Vector3f& n = mesh.normals[v];
    vertices->push_back(osg::Vec3(p.x(), p.y(), p.z()));
    normals->push_back(osg::Vec3(n.x(), n.y(), n.z()));
  }
  osg::ref_ptr<osg::DrawElementsUInt> indices =
      new osg::DrawElementsUInt(GL_TRIANGLES, mesh.indices.begin(), mesh.indices.end());
  osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
  geometry->setVertexArray(vertices);
  geometry->setNormalArray(normals, osg::Array::BIND_PER_VERTEX);
  geometry->addPrimitiveSet(indices);
  geometry->setUseVertexBufferObjects(true);
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  geode->addDrawable(geometry);
  applyColor(*geode, rgba);
  return geode;
}

osg::ref_ptr<osg::Node> makeVisual(const robot::Geometry& geometry) {
  osg::ref_ptr<osg::Geode> shape;
  switch (geometry.kind) {
    case robot::Geometry::Kind::kMesh:
      try {
        shape = makeMesh(geometry.mesh_file, geometry.mesh_scale, geometry.rgba);
      } catch (const InputError& error) {
        throw InputError("link '" + geometry.source_link + "': " + error.what());
      }
      break;
    case robot::Geometry::Kind::kBox:
      shape = makePrimitive(PrimitiveShape::kBox, geometry.size, geometry.rgba);
      break;
    case robot::Geometry::Kind::kCylinder:
      shape = makePrimitive(PrimitiveShape::kCylinder, geometry.size, geometry.rgba);
      break;
    case robot::Geometry::Kind::kSphere:
      shape = makePrimitive(PrimitiveShape::kSphere, geometry.size, geometry.rgba);
      break;
  }
  osg::ref_ptr<osg::MatrixTransform> transform = new osg::MatrixTransform(toOsgMatrix(geometry.X_BG));
  transform->addChild(shape);
  transform->setName(geometry.source_link);
  return transform;
}

}  // namespace flexirob::render
