#include "render/overlays.hpp"

#include <osg/BlendFunc>
#include <osg/Depth>
#include <osg/LineWidth>
#include <osg/MatrixTransform>
#include <osg/Point>
#include <osg/ShapeDrawable>
#include <osgDB/Options>
#include <osgText/Font>
#include <osgText/Text>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <stdexcept>

#include "render/shapes.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"

namespace flexirob::render {

namespace {

osg::Vec3 toVec3(const Eigen::Vector3d& p) {
  return {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
}

// Unlit, coloured by the geometry's colour array, blended when translucent.
void makeUnlit(osg::StateSet& state, bool translucent) {
  state.setMode(GL_LIGHTING, osg::StateAttribute::OFF | osg::StateAttribute::PROTECTED);
  if (translucent) {
    state.setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA));
    state.setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false));
    state.setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
  }
}

osg::ref_ptr<osg::Geometry> makeGeometry(osg::Vec3Array* vertices, const osg::Vec4& color, osg::PrimitiveSet* primitive) {
  osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry();
  osg::ref_ptr<osg::Vec4Array> colors = new osg::Vec4Array();
  colors->push_back(color);
  geometry->setVertexArray(vertices);
  geometry->setColorArray(colors, osg::Array::BIND_OVERALL);
  geometry->addPrimitiveSet(primitive);
  return geometry;
}

}  // namespace

Eigen::Vector4f OverlayPalette::area(int index) {
  // Eight colours chosen to stay apart in CIELAB (ΔE76 at least 36) from each other and from
  // every other overlay (reached green, unreached red, ITM orange and brown, path magenta, a
  // path with a contact wine, trajectories black, purple and blue, the scene model's grey, the
  // force's yellow) and from the light background, with a lightness L* of 35-70 so that small
  // points show on it. The first ones are the farthest apart: most sessions have few areas.
  static const std::array<Eigen::Vector4f, 8> kColors = {
      Eigen::Vector4f(0.30F, 0.00F, 1.00F, 1.0F),  // ultramarine
      Eigen::Vector4f(0.15F, 0.75F, 0.60F, 1.0F),  // turquoise
      Eigen::Vector4f(0.15F, 0.50F, 1.00F, 1.0F),  // azure
      Eigen::Vector4f(0.45F, 0.50F, 0.00F, 1.0F),  // olive
      Eigen::Vector4f(0.95F, 0.50F, 0.45F, 1.0F),  // salmon
      Eigen::Vector4f(0.75F, 0.60F, 0.90F, 1.0F),  // lilac
      Eigen::Vector4f(0.15F, 0.40F, 0.20F, 1.0F),  // forest green
      Eigen::Vector4f(0.55F, 0.25F, 0.00F, 1.0F),  // rust
  };
  const int n = static_cast<int>(kColors.size());
  return kColors[static_cast<std::size_t>(((index % n) + n) % n)];
}

Eigen::Vector4f confidenceColor(double value) {
  if (std::isnan(value)) return {0.5F, 0.5F, 0.5F, 0.0F};
  // Five control points of viridis, linearly interpolated.
  static const std::array<Eigen::Vector3f, 5> kStops = {
      Eigen::Vector3f(0.267F, 0.005F, 0.329F), Eigen::Vector3f(0.229F, 0.322F, 0.546F),
      Eigen::Vector3f(0.128F, 0.567F, 0.551F), Eigen::Vector3f(0.369F, 0.789F, 0.383F),
      Eigen::Vector3f(0.993F, 0.906F, 0.144F)};
  const double v = std::clamp(value, 0.0, 1.0) * static_cast<double>(kStops.size() - 1);
  const auto i = std::min(static_cast<std::size_t>(v), kStops.size() - 2);
  const auto s = static_cast<float>(v - static_cast<double>(i));
  const Eigen::Vector3f c = (1.0F - s) * kStops[i] + s * kStops[i + 1];
  return {c.x(), c.y(), c.z(), 1.0F};
}

osg::ref_ptr<osg::Geode> makePoints(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Vector4f& rgba,
                                    float size_px) {
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array();
  vertices->reserve(points_W.size());
  for (const Eigen::Vector3d& p : points_W) vertices->push_back(toVec3(p));
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  geode->addDrawable(makeGeometry(vertices.get(), toOsgColor(rgba),
                                  new osg::DrawArrays(GL_POINTS, 0, static_cast<int>(vertices->size()))));
  // A lone point has a bounding sphere of radius 0, which small-feature culling would drop.
  geode->setCullingActive(false);
  osg::StateSet* state = geode->getOrCreateStateSet();
  makeUnlit(*state, rgba[3] < 0.999F);
  state->setAttributeAndModes(new osg::Point(size_px));
  return geode;
}

osg::ref_ptr<osg::Geode> makePolyline(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Vector4f& rgba,
                                      float width_px) {
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  if (points_W.size() >= 2) {
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array();
    for (const Eigen::Vector3d& p : points_W) vertices->push_back(toVec3(p));
    geode->addDrawable(makeGeometry(vertices.get(), toOsgColor(rgba),
                                    new osg::DrawArrays(GL_LINE_STRIP, 0, static_cast<int>(vertices->size()))));
  }
  osg::StateSet* state = geode->getOrCreateStateSet();
  makeUnlit(*state, rgba[3] < 0.999F);
  state->setAttributeAndModes(new osg::LineWidth(width_px));
  return geode;
}

osg::ref_ptr<osg::Group> makeTrainingSamples(const std::vector<AreaSamples>& areas, float size_px) {
  osg::ref_ptr<osg::Group> group = new osg::Group();
  for (const AreaSamples& area : areas) {
    osg::ref_ptr<osg::Geode> points = makePoints(area.points_W, OverlayPalette::area(area.area), size_px);
    points->setName("samples:" + std::to_string(area.area));
    group->addChild(points);
  }
  return group;
}

osg::ref_ptr<osg::Node> makeGhostArm(const robot::RobotModel& model, const Eigen::VectorXd& q,
                                     const Eigen::Vector4f& rgba) {
  if (q.size() != model.dof()) {
    throw std::invalid_argument("makeGhostArm: expected " + std::to_string(model.dof()) + " joint values, got " +
                                std::to_string(q.size()));
  }
  RobotGraph graph(model);
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  graph.setPosture(kinematics);
  osg::ref_ptr<osg::Group> ghost = graph.root();
  ghost->setName("ghost:" + model.name());
  // The parent's OVERRIDE material wins over the visuals' own (they are not PROTECTED).
  applyColor(*ghost, rgba);
  osg::StateSet* state = ghost->getOrCreateStateSet();
  state->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false),
                              osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
  state->setRenderingHint(osg::StateSet::TRANSPARENT_BIN);
  return ghost;
}

ConfidenceGrid sampleConfidence(const std::function<double(const Eigen::Vector3d&)>& confidence,
                                const Eigen::Vector2d& lower_xy, const Eigen::Vector2d& upper_xy, double z,
                                int resolution) {
  if (resolution < 2) throw std::invalid_argument("sampleConfidence: resolution must be at least 2");
  ConfidenceGrid grid;
  grid.lower_xy = lower_xy;
  grid.upper_xy = upper_xy;
  grid.z = z;
  grid.values.resize(resolution, resolution);
  const Eigen::Vector2d step = (upper_xy - lower_xy) / (resolution - 1);
  for (int i = 0; i < resolution; ++i) {
    for (int j = 0; j < resolution; ++j) {
      grid.values(i, j) = confidence(Eigen::Vector3d(lower_xy.x() + i * step.x(), lower_xy.y() + j * step.y(), z));
    }
  }
  return grid;
}

osg::ref_ptr<osg::Geode> makeConfidenceSlice(const ConfidenceGrid& grid, float alpha) {
  const auto rows = static_cast<int>(grid.values.rows());
  const auto cols = static_cast<int>(grid.values.cols());
  if (rows < 2 || cols < 2) throw std::invalid_argument("makeConfidenceSlice: need at least 2 x 2 values");
  const Eigen::Vector2d extent = grid.upper_xy - grid.lower_xy;
  if (!(std::abs(extent.x()) > 0.0 && std::abs(extent.y()) > 0.0)) {
    throw std::invalid_argument("makeConfidenceSlice: the slice has no extent");
  }
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array();
  osg::ref_ptr<osg::Vec4Array> colors = new osg::Vec4Array();
  vertices->reserve(static_cast<std::size_t>(rows * cols));
  colors->reserve(static_cast<std::size_t>(rows * cols));
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const double x = grid.lower_xy.x() + extent.x() * i / (rows - 1);
      const double y = grid.lower_xy.y() + extent.y() * j / (cols - 1);
      vertices->push_back(toVec3(Eigen::Vector3d(x, y, grid.z)));
      Eigen::Vector4f c = confidenceColor(grid.values(i, j));
      c[3] *= alpha;
      colors->push_back(toOsgColor(c));
    }
  }
  osg::ref_ptr<osg::DrawElementsUInt> triangles = new osg::DrawElementsUInt(GL_TRIANGLES);
  triangles->reserve(static_cast<std::size_t>(6 * (rows - 1) * (cols - 1)));
  for (int i = 0; i + 1 < rows; ++i) {
    for (int j = 0; j + 1 < cols; ++j) {
      const auto a = static_cast<unsigned>(i * cols + j);
      const auto b = a + static_cast<unsigned>(cols);
      for (unsigned index : {a, b, b + 1, a, b + 1, a + 1}) triangles->push_back(index);
    }
  }
  osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry();
  geometry->setVertexArray(vertices);
  geometry->setColorArray(colors, osg::Array::BIND_PER_VERTEX);
  geometry->addPrimitiveSet(triangles);
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  geode->setName("confidence:z=" + std::to_string(grid.z));
  geode->addDrawable(geometry);
  osg::StateSet* state = geode->getOrCreateStateSet();
  makeUnlit(*state, alpha < 0.999F);
  state->setMode(GL_CULL_FACE, osg::StateAttribute::OFF);
  return geode;
}

osg::ref_ptr<osg::Group> makeReachability(const std::vector<Eigen::Vector3d>& points_W,
                                          const std::vector<bool>& reachable, float size_px) {
  if (points_W.size() != reachable.size()) {
    throw std::invalid_argument("makeReachability: " + std::to_string(points_W.size()) + " points but " +
                                std::to_string(reachable.size()) + " flags");
  }
  std::vector<Eigen::Vector3d> yes;
  std::vector<Eigen::Vector3d> no;
  for (std::size_t i = 0; i < points_W.size(); ++i) (reachable[i] ? yes : no).push_back(points_W[i]);
  osg::ref_ptr<osg::Group> group = new osg::Group();
  osg::ref_ptr<osg::Geode> reached = makePoints(yes, OverlayPalette::reachable(), size_px);
  reached->setName("reachable");
  osg::ref_ptr<osg::Geode> missed = makePoints(no, OverlayPalette::unreachable(), size_px);
  missed->setName("unreachable");
  group->addChild(reached);
  group->addChild(missed);
  return group;
}

osg::ref_ptr<osg::Node> makeGoalMarker(const Eigen::Vector3d& p_W, double radius, const Eigen::Vector4f& rgba) {
  osg::ref_ptr<osg::MatrixTransform> marker =
      new osg::MatrixTransform(osg::Matrixd::translate(p_W.x(), p_W.y(), p_W.z()));
  marker->setName("goal");
  marker->addChild(makePrimitive(PrimitiveShape::kSphere, Eigen::Vector3d(radius, 0, 0), rgba));
  // Three axis lines twice as long as the sphere: the goal stays visible inside an obstacle.
  const auto r = static_cast<float>(2.0 * radius);
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array();
  for (const osg::Vec3& axis : {osg::Vec3(r, 0, 0), osg::Vec3(0, r, 0), osg::Vec3(0, 0, r)}) {
    vertices->push_back(-axis);
    vertices->push_back(axis);
  }
  osg::ref_ptr<osg::Geode> cross = new osg::Geode();
  cross->addDrawable(makeGeometry(vertices.get(), toOsgColor(rgba), new osg::DrawArrays(GL_LINES, 0, 6)));
  makeUnlit(*cross->getOrCreateStateSet(), false);
  cross->getOrCreateStateSet()->setAttributeAndModes(new osg::LineWidth(2.0F));
  marker->addChild(cross);
  return marker;
}

osg::ref_ptr<osg::Node> makeForceArrow(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& force_W,
                                       double metres_per_newton, const Eigen::Vector4f& rgba) {
  osg::ref_ptr<osg::Group> group = new osg::Group();
  group->setName("force");
  const double magnitude = force_W.norm();
  if (magnitude < 1e-6) return group;
  const double length = magnitude * metres_per_newton;
  const double head = std::min(0.3 * length, 0.04);
  const double shaft = length - head;
  const double radius = std::clamp(0.04 * length, 0.003, 0.008);
  // The arrow is built along +z and rotated onto the force.
  const osg::Matrixd rotation = osg::Matrixd::rotate(osg::Vec3d(0, 0, 1), toOsg(force_W / magnitude));
  osg::ref_ptr<osg::MatrixTransform> frame =
      new osg::MatrixTransform(rotation * osg::Matrixd::translate(toOsg(origin_W)));
  osg::ref_ptr<osg::MatrixTransform> shaft_node =
      new osg::MatrixTransform(osg::Matrixd::translate(0, 0, 0.5 * shaft));
  shaft_node->addChild(makePrimitive(PrimitiveShape::kCylinder, Eigen::Vector3d(radius, shaft, 0), rgba));
  osg::ref_ptr<osg::Cone> cone = new osg::Cone(osg::Vec3(), static_cast<float>(2.5 * radius), static_cast<float>(head));
  // osg::Cone's origin is a quarter of the height above its base.
  osg::ref_ptr<osg::MatrixTransform> head_node =
      new osg::MatrixTransform(osg::Matrixd::translate(0, 0, shaft + 0.25 * head));
  osg::ref_ptr<osg::ShapeDrawable> cone_drawable = new osg::ShapeDrawable(cone);
  osg::ref_ptr<osg::Geode> cone_geode = new osg::Geode();
  cone_geode->addDrawable(cone_drawable);
  applyColor(*cone_geode, rgba);
  head_node->addChild(cone_geode);
  frame->addChild(shaft_node);
  frame->addChild(head_node);
  group->addChild(frame);
  return group;
}

int showCollisions(RobotGraph& robot, const std::vector<std::string>& touching) {
  robot.resetColors();
  int coloured = 0;
  for (const std::string& link : touching) coloured += robot.setLinkColor(link, OverlayPalette::collision());
  return coloured;
}

std::vector<char32_t> decodeUtf8(const std::string& text) {
  constexpr char32_t kReplacement = 0xFFFD;
  std::vector<char32_t> code_points;
  code_points.reserve(text.size());
  std::size_t i = 0;
  while (i < text.size()) {
    const auto lead = static_cast<unsigned char>(text[i]);
    int length = 0;
    char32_t value = 0;
    char32_t smallest = 0;  // below it the form is overlong
    if (lead < 0x80) {
      code_points.push_back(lead);
      ++i;
      continue;
    }
    if ((lead & 0xE0U) == 0xC0U) {
      length = 2, value = lead & 0x1FU, smallest = 0x80;
    } else if ((lead & 0xF0U) == 0xE0U) {
      length = 3, value = lead & 0x0FU, smallest = 0x800;
    } else if ((lead & 0xF8U) == 0xF0U) {
      length = 4, value = lead & 0x07U, smallest = 0x10000;
    }
    bool valid = length > 0 && i + static_cast<std::size_t>(length) <= text.size();
    for (int k = 1; valid && k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]);
      valid = (next & 0xC0U) == 0x80U;
      value = (value << 6U) | (next & 0x3FU);
    }
    valid = valid && value >= smallest && value <= 0x10FFFF && (value < 0xD800 || value > 0xDFFF);
    // An invalid lead byte is skipped alone, so that the characters after it still read.
    code_points.push_back(valid ? value : kReplacement);
    i += valid ? static_cast<std::size_t>(length) : 1;
  }
  return code_points;
}

namespace {

constexpr float kLegendMargin = 10.0F;
constexpr float kLegendLine = 20.0F;
constexpr float kLegendSwatch = 12.0F;
constexpr float kLegendCharHeight = 14.0F;

// A TrueType face read anew for each legend (OSG's cache would share its glyph textures across
// OpenGL contexts that come and go), from the first of `paths` the system has; null if none.
osg::ref_ptr<osgText::Font> readFirstFont(std::initializer_list<const char*> paths) {
  osg::ref_ptr<osgDB::Options> options = new osgDB::Options();
  options->setObjectCacheHint(osgDB::Options::CACHE_NONE);
  for (const char* path : paths) {
    if (!std::filesystem::is_regular_file(path)) continue;
    if (osg::ref_ptr<osgText::Font> font = osgText::readRefFontFile(path, options.get())) return font;
  }
  return {};
}

// The faces of the labels: DejaVu Sans (Latin, Greek, Cyrillic and more; fonts-dejavu-core),
// and for a label in Chinese, Japanese or Korean, which DejaVu does not cover, WenQuanYi Micro
// Hei (fonts-wqy-microhei; it has the Latin letters too, so one face draws the whole label).
// Where the system has neither, the labels fall back to OSG's built-in face, ASCII alone.
class LegendFonts {
 public:
  osgText::Font* faceFor(const std::vector<char32_t>& code_points) {
    if (!latin_read_) {
      latin_ = readFirstFont({"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf",
                              "/usr/share/fonts/dejavu/DejaVuSans.ttf"});
      latin_read_ = true;
    }
    if (std::any_of(code_points.begin(), code_points.end(), isEastAsian)) {
      if (!east_asian_read_) {
        east_asian_ = readFirstFont({"/usr/share/fonts/truetype/wqy/wqy-microhei.ttc", "/usr/share/fonts/wqy-microhei/wqy-microhei.ttc"});
        east_asian_read_ = true;
      }
      if (east_asian_ != nullptr) return east_asian_.get();
    }
    return latin_.get();
  }

 private:
  // Kana, CJK ideographs and their punctuation, Hangul, full-width forms.
  static bool isEastAsian(char32_t c) {
    return (c >= 0x2E80 && c <= 0x9FFF) || (c >= 0xAC00 && c <= 0xD7AF) || (c >= 0xF900 && c <= 0xFAFF) ||
           (c >= 0xFE30 && c <= 0xFE4F) || (c >= 0xFF00 && c <= 0xFFEF) || (c >= 0x20000 && c <= 0x3134F);
  }

  osg::ref_ptr<osgText::Font> latin_, east_asian_;
  bool latin_read_ = false;
  bool east_asian_read_ = false;
};

// `code_points` as the face can draw them: the built-in face shows '?' for what is not ASCII.
osgText::String drawableText(const std::vector<char32_t>& code_points, bool truetype) {
  osgText::String text;
  for (const char32_t c : code_points) {
    if (!truetype && c == U'\u2026') {
      text.insert(text.end(), 3, U'.');
      continue;
    }
    const bool printable = c >= 0x20 && c != 0x7F && !(c >= 0x80 && c < 0xA0);
    text.push_back(!printable ? U'?' : (truetype || c < 0x80 ? static_cast<unsigned int>(c) : U'?'));
  }
  return text;
}

osg::ref_ptr<osgText::Text> makeLabel(const osgText::String& label, osgText::Font* font) {
  osg::ref_ptr<osgText::Text> text = new osgText::Text();
  if (font != nullptr) text->setFont(font);
  text->setCharacterSize(kLegendCharHeight);
  text->setColor(osg::Vec4(0.08F, 0.08F, 0.1F, 1.0F));
  text->setAxisAlignment(osgText::Text::SCREEN);
  // On the base line, so that rows with and without descenders line up with their swatches.
  text->setAlignment(osgText::Text::LEFT_BASE_LINE);
  text->setText(label);
  return text;
}

float labelWidth(osgText::Text& text) {
  const osg::BoundingBox& box = text.getBoundingBox();
  return box.valid() ? box.xMax() - box.xMin() : 0.0F;
}

// The label, cut at a code point and ended with an ellipsis where it would be wider than
// `max_width` pixels.
osg::ref_ptr<osgText::Text> fittedLabel(const std::string& utf8, LegendFonts& fonts, float max_width) {
  std::vector<char32_t> code_points = decodeUtf8(utf8);
  osgText::Font* font = fonts.faceFor(code_points);
  const bool truetype = font != nullptr;
  osg::ref_ptr<osgText::Text> text = makeLabel(drawableText(code_points, truetype), font);
  const std::vector<char32_t> ellipsis =
      truetype ? std::vector<char32_t>{U'\u2026'} : std::vector<char32_t>{U'.', U'.', U'.'};
  for (int attempt = 0; attempt < 8 && labelWidth(*text) > max_width && !code_points.empty(); ++attempt) {
    // Glyph widths vary, so cut in proportion and measure again.
    const float ratio = max_width / labelWidth(*text);
    const auto keep = static_cast<std::size_t>(
        std::max(0.0F, std::floor(ratio * static_cast<float>(code_points.size())) - static_cast<float>(ellipsis.size())));
    code_points.resize(std::min(keep, code_points.size() - 1));
    std::vector<char32_t> shown = code_points;
    shown.insert(shown.end(), ellipsis.begin(), ellipsis.end());
    text->setText(drawableText(shown, truetype));
  }
  return text;
}

}  // namespace

std::vector<LegendEntry> legendRows(const std::vector<LegendEntry>& entries, int viewport_height) {
  const auto fitting = static_cast<std::size_t>(
      std::max(1.0F, std::floor((static_cast<float>(viewport_height) - 2.0F * kLegendMargin) / kLegendLine)));
  if (entries.size() <= fitting) return entries;
  std::vector<LegendEntry> rows(entries.begin(), entries.begin() + static_cast<std::ptrdiff_t>(fitting - 1));
  rows.push_back({"\u2026 and " + std::to_string(entries.size() - rows.size()) + " more", Eigen::Vector4f::Zero()});
  return rows;
}

namespace {

// A camera drawn after the scene in pixels of a viewport of width x height, y up.
osg::ref_ptr<osg::Camera> makeHud(const char* name, int viewport_width, int viewport_height) {
  osg::ref_ptr<osg::Camera> hud = new osg::Camera();
  hud->setName(name);
  hud->setReferenceFrame(osg::Transform::ABSOLUTE_RF);
  hud->setProjectionMatrixAsOrtho2D(0.0, std::max(1, viewport_width), 0.0, std::max(1, viewport_height));
  hud->setViewMatrix(osg::Matrixd::identity());
  hud->setClearMask(GL_DEPTH_BUFFER_BIT);
  hud->setRenderOrder(osg::Camera::POST_RENDER);
  hud->setAllowEventFocus(false);
  osg::StateSet* state = hud->getOrCreateStateSet();
  state->setMode(GL_LIGHTING, osg::StateAttribute::OFF | osg::StateAttribute::PROTECTED);
  state->setMode(GL_DEPTH_TEST, osg::StateAttribute::OFF);
  state->setAttributeAndModes(new osg::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA));
  return hud;
}

}  // namespace

osg::ref_ptr<osg::Camera> makeLegend(const std::vector<LegendEntry>& entries, int viewport_width,
                                     int viewport_height) {
  osg::ref_ptr<osg::Camera> hud = makeHud("legend", viewport_width, viewport_height);
  if (entries.empty()) return hud;

  const std::vector<LegendEntry> rows = legendRows(entries, viewport_height);
  const float top = static_cast<float>(viewport_height) - kLegendMargin;
  const float text_x = 2.0F * kLegendMargin + kLegendSwatch;
  const float max_label_width = std::max(kLegendCharHeight, static_cast<float>(viewport_width) - text_x - 2.0F * kLegendMargin);
  LegendFonts fonts;

  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  // A light panel behind the entries, then one swatch per entry (quads, drawn in order).
  osg::ref_ptr<osg::Vec3Array> quads = new osg::Vec3Array();
  osg::ref_ptr<osg::Vec4Array> colors = new osg::Vec4Array();
  const auto quad = [&](float x0, float y0, float x1, float y1, const osg::Vec4& color) {
    for (const osg::Vec3& v : {osg::Vec3(x0, y0, 0), osg::Vec3(x1, y0, 0), osg::Vec3(x1, y1, 0), osg::Vec3(x0, y1, 0)}) {
      quads->push_back(v);
      colors->push_back(color);
    }
  };
  // Labels first: the panel behind them is as wide as the widest.
  std::vector<osg::ref_ptr<osgText::Text>> labels;
  float widest = 0.0F;
  for (const LegendEntry& row : rows) {
    labels.push_back(fittedLabel(row.label, fonts, max_label_width));
    widest = std::max(widest, labelWidth(*labels.back()));
  }
  const float bottom = top - static_cast<float>(rows.size()) * kLegendLine - kLegendMargin * 0.5F;
  quad(kLegendMargin * 0.5F, bottom, text_x + widest + kLegendMargin, top + kLegendMargin * 0.5F,
       osg::Vec4(1.0F, 1.0F, 1.0F, 0.78F));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const float y = top - static_cast<float>(i + 1) * kLegendLine + 0.5F * (kLegendLine - kLegendSwatch);
    if (!rows[i].rgba.isZero()) {
      Eigen::Vector4f rgba = rows[i].rgba;
      rgba[3] = 1.0F;
      quad(kLegendMargin, y, kLegendMargin + kLegendSwatch, y + kLegendSwatch, toOsgColor(rgba));
    }
    labels[i]->setPosition(osg::Vec3(text_x, y + 1.0F, 0.0F));
    geode->addDrawable(labels[i]);
  }
  osg::ref_ptr<osg::Geometry> panel = new osg::Geometry();
  panel->setVertexArray(quads);
  panel->setColorArray(colors, osg::Array::BIND_PER_VERTEX);
  panel->addPrimitiveSet(new osg::DrawArrays(GL_QUADS, 0, static_cast<int>(quads->size())));
  geode->insertChild(0, panel);  // behind the swatches and labels
  hud->addChild(geode);
  return hud;
}

osg::ref_ptr<osg::Camera> makePlacedLabels(const std::vector<PlacedLabel>& labels, int viewport_width, int viewport_height) {
  osg::ref_ptr<osg::Camera> hud = makeHud("labels", viewport_width, viewport_height);
  LegendFonts fonts;
  osg::ref_ptr<osg::Geode> geode = new osg::Geode();
  for (const PlacedLabel& label : labels) {
    osg::ref_ptr<osgText::Text> text = fittedLabel(label.text, fonts, std::max(kLegendCharHeight, label.max_width));
    text->setPosition(osg::Vec3(label.x, static_cast<float>(viewport_height) - label.baseline, 0.0F));
    geode->addDrawable(text);
  }
  hud->addChild(geode);
  return hud;
}

// --- ItmGraphOverlay ------------------------------------------------------------------------

ItmGraphOverlay::ItmGraphOverlay(float node_size_px, float edge_width_px)
    : geode_(new osg::Geode),
      vertices_(new osg::Vec3Array),
      live_nodes_(new osg::DrawElementsUInt(GL_POINTS)),
      edge_indices_(new osg::DrawElementsUInt(GL_LINES)) {
  geode_->setName("itm_graph");
  // Vertex arrays change as the graph grows: display lists would be rebuilt every frame.
  lines_ = makeGeometry(vertices_.get(), toOsgColor(OverlayPalette::itmEdge()), edge_indices_.get());
  points_ = makeGeometry(vertices_.get(), toOsgColor(OverlayPalette::itmNode()), live_nodes_.get());
  for (osg::Geometry* geometry : {lines_.get(), points_.get()}) {
    geometry->setUseDisplayList(false);
    geometry->setUseVertexBufferObjects(true);
    geometry->setDataVariance(osg::Object::DYNAMIC);
  }
  lines_->getOrCreateStateSet()->setAttributeAndModes(new osg::LineWidth(edge_width_px));
  points_->getOrCreateStateSet()->setAttributeAndModes(new osg::Point(node_size_px));
  // Nodes lie at the ends of their edges, at the same depth: the edges test depth without
  // writing it, so a node wins over its edges in whichever order the two are drawn.
  lines_->getOrCreateStateSet()->setAttributeAndModes(new osg::Depth(osg::Depth::LESS, 0.0, 1.0, false));
  points_->setCullingActive(false);  // a lone node has a bound of radius 0
  geode_->addDrawable(lines_);
  geode_->addDrawable(points_);  // after the edges: nodes on top of the lines meeting them
  makeUnlit(*geode_->getOrCreateStateSet(), false);
}

bool ItmGraphOverlay::hasNode(int id) const {
  return id >= 0 && static_cast<std::size_t>(id) < slot_of_node_.size() && slot_of_node_[static_cast<std::size_t>(id)] >= 0;
}

void ItmGraphOverlay::touch() {
  vertices_->dirty();
  live_nodes_->dirty();
  edge_indices_->dirty();
  points_->dirtyBound();
  lines_->dirtyBound();
}

void ItmGraphOverlay::setNode(int id, const Eigen::Vector3d& p_W) {
  if (id < 0) throw std::invalid_argument("ItmGraphOverlay::setNode: negative node id");
  const auto index = static_cast<std::size_t>(id);
  if (index >= vertices_->size()) {
    vertices_->resize(index + 1);
    slot_of_node_.resize(index + 1, -1);
  }
  (*vertices_)[index] = toVec3(p_W);
  if (slot_of_node_[index] < 0) {
    slot_of_node_[index] = static_cast<int>(live_nodes_->size());
    live_nodes_->push_back(static_cast<unsigned>(id));
  }
  touch();
}

void ItmGraphOverlay::removeNode(int id) {
  if (!hasNode(id)) return;
  const auto index = static_cast<std::size_t>(id);
  // Swap-remove from the list of live nodes.
  const auto slot = static_cast<std::size_t>(slot_of_node_[index]);
  const unsigned last = live_nodes_->back();
  (*live_nodes_)[slot] = last;
  slot_of_node_[last] = static_cast<int>(slot);
  live_nodes_->pop_back();
  slot_of_node_[index] = -1;
  // Its edges (a node has a handful: a linear scan of the edges is cheap next to a redraw).
  osg::DrawElementsUInt& edges = *edge_indices_;
  for (std::size_t e = 0; e + 1 < edges.size();) {
    if (edges[e] == static_cast<unsigned>(id) || edges[e + 1] == static_cast<unsigned>(id)) {
      edges[e] = edges[edges.size() - 2];
      edges[e + 1] = edges[edges.size() - 1];
      edges.resize(edges.size() - 2);
    } else {
      e += 2;
    }
  }
  touch();
}

void ItmGraphOverlay::addEdge(int a, int b) {
  if (!hasNode(a) || !hasNode(b) || a == b) {
    throw std::invalid_argument("ItmGraphOverlay::addEdge: no nodes " + std::to_string(a) + " and " + std::to_string(b));
  }
  const osg::DrawElementsUInt& edges = *edge_indices_;
  const auto ua = static_cast<unsigned>(a);
  const auto ub = static_cast<unsigned>(b);
  for (std::size_t e = 0; e + 1 < edges.size(); e += 2) {
    if ((edges[e] == ua && edges[e + 1] == ub) || (edges[e] == ub && edges[e + 1] == ua)) return;
  }
  edge_indices_->push_back(ua);
  edge_indices_->push_back(ub);
  touch();
}

void ItmGraphOverlay::removeEdge(int a, int b) {
  osg::DrawElementsUInt& edges = *edge_indices_;
  const auto ua = static_cast<unsigned>(a);
  const auto ub = static_cast<unsigned>(b);
  for (std::size_t e = 0; e + 1 < edges.size(); e += 2) {
    if ((edges[e] == ua && edges[e + 1] == ub) || (edges[e] == ub && edges[e + 1] == ua)) {
      edges[e] = edges[edges.size() - 2];
      edges[e + 1] = edges[edges.size() - 1];
      edges.resize(edges.size() - 2);
      touch();
      return;
    }
  }
}

void ItmGraphOverlay::clear() {
  vertices_->clear();
  live_nodes_->clear();
  edge_indices_->clear();
  slot_of_node_.clear();
  touch();
}

void ItmGraphOverlay::setGraph(const std::vector<std::pair<int, Eigen::Vector3d>>& nodes,
                               const std::vector<std::pair<int, int>>& edges) {
  clear();
  int largest = -1;
  for (const auto& [id, p] : nodes) {
    if (id < 0) throw std::invalid_argument("ItmGraphOverlay::setGraph: negative node id");
    largest = std::max(largest, id);
  }
  vertices_->resize(static_cast<std::size_t>(largest + 1));
  slot_of_node_.assign(static_cast<std::size_t>(largest + 1), -1);
  live_nodes_->reserve(nodes.size());
  for (const auto& [id, p] : nodes) {
    (*vertices_)[static_cast<std::size_t>(id)] = toVec3(p);
    if (slot_of_node_[static_cast<std::size_t>(id)] >= 0) continue;
    slot_of_node_[static_cast<std::size_t>(id)] = static_cast<int>(live_nodes_->size());
    live_nodes_->push_back(static_cast<unsigned>(id));
  }
  // Edges are taken as given (an ITM holds each once); no per-edge duplicate search.
  edge_indices_->reserve(2 * edges.size());
  for (const auto& [a, b] : edges) {
    if (!hasNode(a) || !hasNode(b)) {
      clear();
      throw std::invalid_argument("ItmGraphOverlay::setGraph: edge " + std::to_string(a) + "-" + std::to_string(b) +
                                  " joins a node not given");
    }
    edge_indices_->push_back(static_cast<unsigned>(a));
    edge_indices_->push_back(static_cast<unsigned>(b));
  }
  touch();
}

// --- Overlays -------------------------------------------------------------------------------

const char* overlayLayerName(OverlayLayer layer) {
  switch (layer) {
    case OverlayLayer::kTrainingSamples: return "samples";
    case OverlayLayer::kGhostArms: return "ghosts";
    case OverlayLayer::kConfidence: return "confidence";
    case OverlayLayer::kItmGraph: return "itm";
    case OverlayLayer::kGoalAndPath: return "path";
    case OverlayLayer::kTrajectories: return "trajectories";
    case OverlayLayer::kReachability: return "reachability";
    case OverlayLayer::kForce: return "force";
    case OverlayLayer::kLegend: return "legend";
  }
  return "?";
}

const char* overlayLayerTitle(OverlayLayer layer) {
  switch (layer) {
    case OverlayLayer::kTrainingSamples: return "Training samples";
    case OverlayLayer::kGhostArms: return "q_fixed ghost arms";
    case OverlayLayer::kConfidence: return "Confidence slices";
    case OverlayLayer::kItmGraph: return "ITM graph";
    case OverlayLayer::kGoalAndPath: return "Goal and planned path";
    case OverlayLayer::kTrajectories: return "Target and teach-in trajectories";
    case OverlayLayer::kReachability: return "Reachable targets";
    case OverlayLayer::kForce: return "Hand force";
    case OverlayLayer::kLegend: return "Legend";
  }
  return "?";
}

OverlayLayer parseOverlayLayer(const std::string& name) {
  std::string valid;
  for (OverlayLayer layer : kAllOverlayLayers) {
    if (name == overlayLayerName(layer)) return layer;
    valid += (valid.empty() ? "" : ", ") + std::string(overlayLayerName(layer));
  }
  throw InputError("unknown overlay '" + name + "' (expected one of: " + valid + ")");
}

Overlays::Overlays() : root_(new osg::Group), itm_(std::make_unique<ItmGraphOverlay>()) {
  root_->setName("overlays");
  for (OverlayLayer layer : kAllOverlayLayers) {
    osg::ref_ptr<osg::Group> group = new osg::Group();
    group->setName(std::string("overlay:") + overlayLayerName(layer));
    layers_[static_cast<std::size_t>(layer)] = group;
    root_->addChild(group);
  }
  layer(OverlayLayer::kItmGraph)->addChild(itm_->node());
}

Overlays::~Overlays() = default;

osg::Group* Overlays::layer(OverlayLayer layer) const { return layers_[static_cast<std::size_t>(layer)].get(); }

void Overlays::setContent(OverlayLayer which, osg::ref_ptr<osg::Node> content) {
  osg::Group* group = layer(which);
  group->removeChildren(0, group->getNumChildren());
  if (which == OverlayLayer::kItmGraph) group->addChild(itm_->node());  // the incremental graph stays
  if (content) group->addChild(content);
}

void Overlays::addContent(OverlayLayer which, osg::ref_ptr<osg::Node> content) {
  if (content) layer(which)->addChild(content);
}

void Overlays::setVisible(OverlayLayer which, bool visible) { layer(which)->setNodeMask(visible ? ~0U : 0U); }

bool Overlays::visible(OverlayLayer which) const { return layer(which)->getNodeMask() != 0U; }

}  // namespace flexirob::render
