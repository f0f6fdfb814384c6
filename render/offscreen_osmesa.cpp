// Offscreen rendering through OSMesa (Mesa's software rasterizer in a plain memory buffer).
//
// Debian's OpenSceneGraph calls OpenGL through libGL (glvnd), whose entry points dispatch to
// the current GLX context and do nothing without one. Two measures make OSMesa's own entry
// points win in the programs that link this library:
//  - libOSMesa is a direct dependency of the program, so it comes before libGL (a dependency of
//    the OSG libraries) in the dynamic linker's global search order: OSG's direct GL calls and
//    its dlsym() look-ups of extension functions resolve to OSMesa;
//  - glXGetProcAddress / glXGetProcAddressARB are defined here and forward to
//    OSMesaGetProcAddress, so code that asks GLX for extension functions gets OSMesa's too.
#include <GL/osmesa.h>
#include <osgViewer/Viewer>
#include <zlib.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "render/offscreen.hpp"
#include "robot/errors.hpp"

extern "C" {
// Same signature as GLX's (a function pointer returned for a GLubyte name); not declared in a
// header on purpose, so no GLX header is needed.
__attribute__((visibility("default"))) OSMESAproc glXGetProcAddressARB(const unsigned char* name) {
  return OSMesaGetProcAddress(reinterpret_cast<const char*>(name));
}
__attribute__((visibility("default"))) OSMESAproc glXGetProcAddress(const unsigned char* name) {
  return OSMesaGetProcAddress(reinterpret_cast<const char*>(name));
}
}

namespace flexirob::render {

namespace {
constexpr int kMaxRenderSize = 8192;
}  // namespace

std::array<std::uint8_t, 4> Image::pixel(int x, int y) const {
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4;
  return {rgba.at(i), rgba.at(i + 1), rgba.at(i + 2), rgba.at(i + 3)};
}

struct OffscreenRenderer::Impl {
  int width = 0;
  int height = 0;
  int factor = 1;
  int render_width = 0;
  int render_height = 0;
  OSMesaContext context = nullptr;
  std::vector<std::uint8_t> buffer;  // render_width x render_height RGBA, bottom row first
  osg::ref_ptr<osgViewer::Viewer> viewer;
  osg::Node* scene = nullptr;

  void makeCurrent() {
    if (OSMesaMakeCurrent(context, buffer.data(), GL_UNSIGNED_BYTE, render_width, render_height) == 0) {
      throw std::runtime_error("OSMesaMakeCurrent failed");
    }
  }
};

OffscreenRenderer::OffscreenRenderer(int width, int height, int supersampling) : impl_(new Impl) {
  if (width < 1 || height < 1 || width > kMaxRenderSize || height > kMaxRenderSize) {
    throw InputError("image size must lie in [1, " + std::to_string(kMaxRenderSize) + "] pixels per side, got " +
                     std::to_string(width) + " x " + std::to_string(height));
  }
  if (supersampling < 1 || supersampling > 4) {
    throw InputError("supersampling must lie in [1, 4], got " + std::to_string(supersampling));
  }
  Impl& d = *impl_;
  d.width = width;
  d.height = height;
  // Supersample only as far as the renderer's size limit allows.
  d.factor = supersampling;
  while (d.factor > 1 && (width * d.factor > kMaxRenderSize || height * d.factor > kMaxRenderSize)) --d.factor;
  d.render_width = width * d.factor;
  d.render_height = height * d.factor;
  d.buffer.assign(static_cast<std::size_t>(d.render_width) * static_cast<std::size_t>(d.render_height) * 4, 0);

  const int attributes[] = {OSMESA_FORMAT,  OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 8,
                            OSMESA_PROFILE, OSMESA_COMPAT_PROFILE, 0};
  d.context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (d.context == nullptr) throw std::runtime_error("OSMesa could not create an OpenGL context");
  d.makeCurrent();

  // A viewer drawing into the current context: OSG's embedded window does no context handling
  // of its own, which is exactly what an OSMesa buffer needs.
  d.viewer = new osgViewer::Viewer;
  d.viewer->setThreadingModel(osgViewer::Viewer::SingleThreaded);
  d.viewer->setUpViewerAsEmbeddedInWindow(0, 0, d.render_width, d.render_height);
  d.viewer->setLightingMode(osg::View::NO_LIGHT);  // the world brings its own lights
  d.viewer->setKeyEventSetsDone(0);
  d.viewer->realize();
}

OffscreenRenderer::~OffscreenRenderer() {
  Impl& d = *impl_;
  if (d.context == nullptr) return;
  // OSG releases its GL objects on destruction: keep our context current while it does.
  OSMesaMakeCurrent(d.context, d.buffer.data(), GL_UNSIGNED_BYTE, d.render_width, d.render_height);
  d.viewer = nullptr;
  OSMesaDestroyContext(d.context);
}

int OffscreenRenderer::width() const { return impl_->width; }
int OffscreenRenderer::height() const { return impl_->height; }

Image OffscreenRenderer::render(osg::Node* scene, const CameraPose& camera, const std::array<float, 4>& background) {
  Impl& d = *impl_;
  d.makeCurrent();
  if (scene != d.scene) {
    d.viewer->setSceneData(scene);
    d.scene = scene;
  }
  osg::Camera* osg_camera = d.viewer->getCamera();
  osg_camera->setClearColor(osg::Vec4(background[0], background[1], background[2], background[3]));
  osg_camera->setViewMatrixAsLookAt(osg::Vec3d(camera.eye_W.x(), camera.eye_W.y(), camera.eye_W.z()),
                                    osg::Vec3d(camera.center_W.x(), camera.center_W.y(), camera.center_W.z()),
                                    osg::Vec3d(camera.up_W.x(), camera.up_W.y(), camera.up_W.z()));
  // Near and far are recomputed by OSG from the scene's bounds; only the field of view and the
  // aspect ratio matter for where things land in the image.
  osg_camera->setProjectionMatrixAsPerspective(camera.fovy_deg,
                                               static_cast<double>(d.render_width) / d.render_height, 0.01, 100.0);
  d.viewer->frame();
  glFinish();

  // Flip to top-down rows and average factor x factor blocks.
  Image image;
  image.width = d.width;
  image.height = d.height;
  image.rgba.assign(static_cast<std::size_t>(d.width) * static_cast<std::size_t>(d.height) * 4, 0);
  const int f = d.factor;
  const int samples = f * f;
  for (int y = 0; y < d.height; ++y) {
    for (int x = 0; x < d.width; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (int sy = 0; sy < f; ++sy) {
        const int source_row = d.render_height - 1 - (y * f + sy);
        const std::uint8_t* row = d.buffer.data() + static_cast<std::size_t>(source_row) * static_cast<std::size_t>(d.render_width) * 4;
        for (int sx = 0; sx < f; ++sx) {
          const std::uint8_t* p = row + static_cast<std::size_t>(x * f + sx) * 4;
          for (int c = 0; c < 4; ++c) sum[c] += p[c];
        }
      }
      std::uint8_t* out = image.rgba.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(d.width) + static_cast<std::size_t>(x)) * 4;
      for (int c = 0; c < 4; ++c) out[c] = static_cast<std::uint8_t>((sum[c] + samples / 2) / samples);
    }
  }
  return image;
}

namespace {

void appendBigEndian(std::string& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((value >> shift) & 0xFFU));
}

void appendChunk(std::string& out, const char* type, const std::string& data) {
  appendBigEndian(out, static_cast<std::uint32_t>(data.size()));
  const std::string body = std::string(type, 4) + data;
  out += body;
  appendBigEndian(out, static_cast<std::uint32_t>(
                           crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
}

}  // namespace

Image printLabels(const Image& base, const std::vector<PlacedLabel>& labels) {
  if (labels.empty()) return base;
  OffscreenRenderer renderer(base.width, base.height);
  osg::ref_ptr<osg::Group> root = new osg::Group();
  root->addChild(makePlacedLabels(labels, base.width, base.height));
  const Image ink = renderer.render(root.get(), CameraPose{}, {1.0F, 1.0F, 1.0F, 1.0F});
  Image printed = base;
  for (std::size_t i = 0; i + 3 < printed.rgba.size(); i += 4) {
    for (std::size_t c = 0; c < 3; ++c) {
      printed.rgba[i + c] = static_cast<std::uint8_t>((static_cast<unsigned>(printed.rgba[i + c]) * ink.rgba[i + c] + 127U) / 255U);
    }
  }
  return printed;
}

std::string encodePng(const Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4) {
    throw std::invalid_argument("encodePng: image size does not match its pixel data");
  }
  // Raw scanlines, each preceded by filter type 0 (none), deflated into one IDAT chunk.
  const std::size_t stride = static_cast<std::size_t>(image.width) * 4;
  std::string raw;
  raw.reserve((stride + 1) * static_cast<std::size_t>(image.height));
  for (int y = 0; y < image.height; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(image.rgba.data()) + static_cast<std::size_t>(y) * stride, stride);
  }
  uLongf compressed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string compressed(compressed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), 6) != Z_OK) {
    throw std::runtime_error("encodePng: compression failed");
  }
  compressed.resize(compressed_size);

  std::string header;
  appendBigEndian(header, static_cast<std::uint32_t>(image.width));
  appendBigEndian(header, static_cast<std::uint32_t>(image.height));
  header += std::string("\x08\x06\x00\x00\x00", 5);  // 8 bits, RGBA, deflate, no filter, no interlace
  std::string png("\x89PNG\r\n\x1a\n", 8);
  appendChunk(png, "IHDR", header);
  appendChunk(png, "IDAT", compressed);
  appendChunk(png, "IEND", "");
  return png;
}

}  // namespace flexirob::render
