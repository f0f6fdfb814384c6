#pragma once
// Offscreen rendering through OSMesa: no X server, no GPU. Lives in the library
// flexirob_render_offscreen, which only headless programs (flexirob-cli, tests) link; the GUI
// renders through Qt's OpenGL context instead and must never link it.
#include <osg/Node>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/camera.hpp"
#include "render/overlays.hpp"

namespace flexirob::render {

/// An RGBA8 image, rows from top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  ///< width * height * 4 bytes

  std::array<std::uint8_t, 4> pixel(int x, int y) const;
};

class OffscreenRenderer {
 public:
  /// An OSMesa context of width x height pixels [1, 8192]. supersampling (1..4) renders at that
  /// multiple of the size and averages blocks of pixels (anti-aliasing). Throws InputError for
  /// bad sizes, std::runtime_error if OSMesa cannot create a context.
  OffscreenRenderer(int width, int height, int supersampling = 1);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Renders `scene` (world frame, z up) as seen by `camera` on a background colour (RGBA 0..1).
  Image render(osg::Node* scene, const CameraPose& camera, const std::array<float, 4>& background);

  int width() const;
  int height() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// `base` with `labels` printed on it in dark ink: the text is drawn offscreen on white and
/// multiplied in, so that what lies under a letter's gaps stays as it was.
Image printLabels(const Image& base, const std::vector<PlacedLabel>& labels);

/// The image as the bytes of an 8-bit RGBA PNG file. The caller writes them (the CLI through
/// app::writeFileReplacing, so that a picture is replaced whole or not at all).
std::string encodePng(const Image& image);

}  // namespace flexirob::render
