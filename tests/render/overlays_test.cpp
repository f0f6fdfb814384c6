// Overlays: the geometry holds what the input says, and an offscreen render with a layer on
// shows that layer's colour where the camera projection puts its points.
#include <gtest/gtest.h>
#include <osg/ComputeBoundsVisitor>
#include <osg/Geometry>

#include <cmath>
#include <filesystem>
#include <utility>
#include <vector>

#include "render/camera.hpp"
#include "render/offscreen.hpp"
#include "render/overlays.hpp"
#include "render/shapes.hpp"
#include "render/world.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::render {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;

std::array<float, 4> background() {
  const Eigen::Vector4f c = Palette::background();
  return {c[0], c[1], c[2], c[3]};
}

const osg::Geometry& onlyGeometry(const osg::Geode& geode) {
  EXPECT_EQ(geode.getNumDrawables(), 1U);
  const osg::Drawable* drawable = geode.getNumDrawables() > 0 ? geode.getDrawable(0) : nullptr;
  const osg::Geometry* geometry = drawable != nullptr ? drawable->asGeometry() : nullptr;
  if (geometry == nullptr) throw std::runtime_error("expected a geode holding one geometry");
  return *geometry;
}

Eigen::Vector3d vertex(const osg::Geometry& geometry, std::size_t i) {
  const auto& vertices = *static_cast<const osg::Vec3Array*>(geometry.getVertexArray());
  return {vertices[i].x(), vertices[i].y(), vertices[i].z()};
}

// Colour distance (sum over RGB, 0..765) between a pixel and an RGBA colour in 0..1.
int colorDistance(const std::array<std::uint8_t, 4>& pixel, const Eigen::Vector4f& rgba) {
  int distance = 0;
  for (int c = 0; c < 3; ++c) distance += std::abs(int{pixel[static_cast<std::size_t>(c)]} - static_cast<int>(std::lround(rgba[c] * 255.0F)));
  return distance;
}

std::array<std::uint8_t, 4> pixelAt(const Image& image, const CameraPose& camera, const Eigen::Vector3d& p_W) {
  const auto pixel = projectToPixel(camera, image.width, image.height, p_W);
  EXPECT_TRUE(pixel.has_value());
  return image.pixel(static_cast<int>(pixel->x()), static_cast<int>(pixel->y()));
}

int changedPixels(const Image& a, const Image& b) {
  int count = 0;
  for (std::size_t i = 0; i < a.rgba.size(); i += 4) {
    if (a.rgba[i] != b.rgba[i] || a.rgba[i + 1] != b.rgba[i + 1] || a.rgba[i + 2] != b.rgba[i + 2]) ++count;
  }
  return count;
}

const CameraPose& testCamera() {
  static const CameraPose camera = parseCamera("-1.8,-1.2,1.3,-0.3,0,0.4");
  return camera;
}

// CIE L*a*b* (D65) of an sRGB colour, for distances that follow what the eye tells apart.
Eigen::Vector3d cieLab(const Eigen::Vector4f& rgba) {
  const auto linear = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  const double r = linear(rgba[0]), g = linear(rgba[1]), b = linear(rgba[2]);
  const double x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
  const double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
  const double z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
  const auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
  return {116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))};
}

double deltaE(const Eigen::Vector4f& a, const Eigen::Vector4f& b) { return (cieLab(a) - cieLab(b)).norm(); }

TEST(OverlayPalette, AreaColoursDifferFromEachOtherAndFromTheOtherOverlaysAndRepeatAfterEight) {
  // ΔE76 of about 2 is the smallest difference seen side by side; the palette keeps 36 (the
  // ghost arm, translucent grey over the arm, is no colour of its own).
  constexpr double kApart = 36.0;
  EXPECT_NEAR(cieLab(Eigen::Vector4f(1.0F, 1.0F, 1.0F, 1.0F))[0], 100.0, 1e-3);  // white
  EXPECT_NEAR(deltaE(Eigen::Vector4f(1.0F, 0.0F, 0.0F, 1.0F), Eigen::Vector4f(0.0F, 0.0F, 1.0F, 1.0F)), 176.3, 0.2);
  for (int a = 0; a < 8; ++a) {
    for (int b = a + 1; b < 8; ++b) {
      EXPECT_GT(deltaE(OverlayPalette::area(a), OverlayPalette::area(b)), kApart) << a << " vs " << b;
    }
  }
  // Samples are drawn together with targets, the ITM graph, paths, trajectories, the scene
  // model and the force arrow, on the light background: no area may look like one of them,
  // and every area must stand out from the background.
  const std::vector<std::pair<const char*, Eigen::Vector4f>> others = {
      {"reachable", OverlayPalette::reachable()},
      {"unreachable", OverlayPalette::unreachable()},
      {"ITM node", OverlayPalette::itmNode()},
      {"ITM edge", OverlayPalette::itmEdge()},
      {"planned path", OverlayPalette::plannedPath()},
      {"path with a contact", OverlayPalette::collidedPath()},
      {"target trajectory", OverlayPalette::targetTrajectory()},
      {"scene's trajectory", Palette::trajectory()},
      {"teach-in", OverlayPalette::teachInTrajectory()},
      {"executed motion", OverlayPalette::executedTrajectory()},
      {"scene model", OverlayPalette::sceneModel()},
      {"force", OverlayPalette::force()},
      {"background", Palette::background()}};
  for (int a = 0; a < 8; ++a) {
    for (const auto& [name, colour] : others) {
      EXPECT_GT(deltaE(OverlayPalette::area(a), colour), kApart) << "area " << a << " vs " << name;
    }
    const double lightness = cieLab(OverlayPalette::area(a))[0];
    EXPECT_GT(lightness, 35.0) << "area " << a << " is too dark to tell from the black target trajectory";
    EXPECT_LT(lightness, 70.0) << "area " << a << " is too light for the background";
  }
  // A path with a contact is drawn with the targets of a reachability run and the graph: it
  // had been the unreached targets' red.
  for (const auto& [name, colour] : others) {
    if (std::string(name) != "path with a contact" && std::string(name) != "background") {
      EXPECT_GT(deltaE(OverlayPalette::collidedPath(), colour), kApart) << "path with a contact vs " << name;
    }
  }
  EXPECT_EQ(OverlayPalette::area(9), OverlayPalette::area(1));
  EXPECT_EQ(OverlayPalette::area(-1), OverlayPalette::area(7));
}

TEST(ConfidenceColor, GetsLighterWithConfidenceAndClamps) {
  // Relative luminance (Rec. 709) grows monotonically along the map.
  const auto luminance = [](const Eigen::Vector4f& c) { return 0.2126F * c[0] + 0.7152F * c[1] + 0.0722F * c[2]; };
  float previous = -1.0F;
  for (int i = 0; i <= 20; ++i) {
    const float l = luminance(confidenceColor(i / 20.0));
    EXPECT_GT(l, previous) << "at " << i / 20.0;
    previous = l;
  }
  EXPECT_EQ(confidenceColor(-3.0), confidenceColor(0.0));
  EXPECT_EQ(confidenceColor(7.0), confidenceColor(1.0));
  EXPECT_EQ(confidenceColor(std::nan(""))[3], 0.0F);
}

TEST(TrainingSamples, OneCloudPerAreaHoldingItsPointsInItsColour) {
  std::vector<AreaSamples> areas(3);
  for (int a = 0; a < 3; ++a) {
    areas[static_cast<std::size_t>(a)].area = a;
    for (int k = 0; k <= a * 4; ++k) areas[static_cast<std::size_t>(a)].points_W.emplace_back(0.1 * a, 0.01 * k, 0.5);
  }
  const osg::ref_ptr<osg::Group> group = makeTrainingSamples(areas);
  ASSERT_EQ(group->getNumChildren(), 3U);
  for (unsigned a = 0; a < 3; ++a) {
    const auto* geode = group->getChild(a)->asGeode();
    ASSERT_NE(geode, nullptr);
    EXPECT_EQ(geode->getName(), "samples:" + std::to_string(a));
    const osg::Geometry& geometry = onlyGeometry(*geode);
    ASSERT_EQ(geometry.getVertexArray()->getNumElements(), areas[a].points_W.size());
    for (std::size_t k = 0; k < areas[a].points_W.size(); ++k) {
      EXPECT_LT((vertex(geometry, k) - areas[a].points_W[k]).norm(), 1e-6);
    }
    const auto& color = (*static_cast<const osg::Vec4Array*>(geometry.getColorArray()))[0];
    EXPECT_EQ(color, toOsgColor(OverlayPalette::area(static_cast<int>(a))));
  }
}

TEST(ConfidenceSlice, SamplesTheCallbackOnTheGridAndColoursEachVertex) {
  // Confidence rising linearly in x across the slice, constant in y.
  const auto confidence = [](const Eigen::Vector3d& p) { return (p.x() + 1.0) / 2.0; };
  const ConfidenceGrid grid = sampleConfidence(confidence, {-1.0, -0.5}, {1.0, 0.5}, 0.4, 5);
  ASSERT_EQ(grid.values.rows(), 5);
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) EXPECT_NEAR(grid.values(i, j), i / 4.0, 1e-12);
  }
  const osg::ref_ptr<osg::Geode> slice = makeConfidenceSlice(grid, 1.0F);
  const osg::Geometry& geometry = onlyGeometry(*slice);
  ASSERT_EQ(geometry.getVertexArray()->getNumElements(), 25U);
  EXPECT_EQ(geometry.getPrimitiveSet(0)->getNumIndices(), 6U * 4U * 4U);
  const auto& colors = *static_cast<const osg::Vec4Array*>(geometry.getColorArray());
  for (std::size_t v = 0; v < 25; ++v) {
    const Eigen::Vector3d p = vertex(geometry, v);
    EXPECT_NEAR(p.z(), 0.4, 1e-6);
    EXPECT_EQ(colors[v], toOsgColor(confidenceColor(confidence(p))));
  }
  EXPECT_THROW(sampleConfidence(confidence, {0, 0}, {1, 1}, 0.0, 1), std::invalid_argument);
  ConfidenceGrid flat = grid;
  flat.upper_xy.x() = flat.lower_xy.x();
  EXPECT_THROW(makeConfidenceSlice(flat), std::invalid_argument);
}

TEST(ItmGraphOverlay, FollowsInsertionsAndDeletionsOfNodesAndEdges) {
  ItmGraphOverlay graph;
  graph.setGraph({{0, {0, 0, 0}}, {1, {1, 0, 0}}, {4, {0, 1, 0}}}, {{0, 1}, {1, 4}});
  EXPECT_EQ(graph.nodeCount(), 3);
  EXPECT_EQ(graph.edgeCount(), 2);
  EXPECT_FALSE(graph.hasNode(2));
  graph.setNode(2, {0.5, 0.5, 0});
  graph.addEdge(2, 0);
  graph.addEdge(0, 2);  // already there
  EXPECT_EQ(graph.edgeCount(), 3);
  graph.removeNode(1);  // takes both its edges
  EXPECT_EQ(graph.nodeCount(), 3);
  EXPECT_EQ(graph.edgeCount(), 1);
  EXPECT_THROW(graph.addEdge(1, 0), std::invalid_argument);
  graph.removeEdge(0, 2);
  EXPECT_EQ(graph.edgeCount(), 0);
  EXPECT_THROW(graph.setGraph({{0, {0, 0, 0}}}, {{0, 3}}), std::invalid_argument);
  EXPECT_EQ(graph.nodeCount(), 0) << "a refused graph leaves nothing half-built";

  // The drawn primitives are exactly the live nodes and the edges.
  ItmGraphOverlay grown;
  for (int id = 0; id < 10000; ++id) {
    grown.setNode(id, Eigen::Vector3d(0.001 * id, 0.0, 0.5));
    if (id > 0) grown.addEdge(id - 1, id);
  }
  for (int id = 0; id < 10000; id += 2) grown.removeNode(id);
  EXPECT_EQ(grown.nodeCount(), 5000);
  EXPECT_EQ(grown.edgeCount(), 0) << "a chain with every other node removed keeps no edge";
  const osg::Geode& geode = *grown.node();
  ASSERT_EQ(geode.getNumDrawables(), 2U);
  EXPECT_EQ(geode.getDrawable(1)->asGeometry()->getPrimitiveSet(0)->getNumIndices(), 5000U);
}

TEST(Reachability, SplitsPointsByFlagAndRefusesMismatchedSizes) {
  const osg::ref_ptr<osg::Group> group =
      makeReachability({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {true, false, true});
  ASSERT_EQ(group->getNumChildren(), 2U);
  EXPECT_EQ(onlyGeometry(*group->getChild(0)->asGeode()).getVertexArray()->getNumElements(), 2U);
  EXPECT_EQ(onlyGeometry(*group->getChild(1)->asGeode()).getVertexArray()->getNumElements(), 1U);
  EXPECT_THROW(makeReachability({{0, 0, 0}}, {}), std::invalid_argument);
}

TEST(ForceArrow, SpansFromTheOriginAlongTheScaledForce) {
  const Eigen::Vector3d origin(0.2, -0.1, 0.6);
  const Eigen::Vector3d force(0.0, 30.0, -40.0);  // 50 N
  const osg::ref_ptr<osg::Node> arrow = makeForceArrow(origin, force, 0.01);
  osg::ComputeBoundsVisitor visitor;
  arrow->accept(visitor);
  const osg::BoundingBox& box = visitor.getBoundingBox();
  ASSERT_TRUE(box.valid());
  const Eigen::Vector3d tip = origin + 0.01 * force;  // 0.5 m away
  const Eigen::Vector3d lower(box.xMin(), box.yMin(), box.zMin());
  const Eigen::Vector3d upper(box.xMax(), box.yMax(), box.zMax());
  // The arrow is at most a head radius (2.5 x 8 mm) thick around the segment origin-tip.
  const double thickness = 0.021;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(lower[k], std::min(origin[k], tip[k]), thickness) << "axis " << k;
    EXPECT_NEAR(upper[k], std::max(origin[k], tip[k]), thickness) << "axis " << k;
  }
  osg::ComputeBoundsVisitor none;
  makeForceArrow(origin, Eigen::Vector3d::Zero())->accept(none);
  EXPECT_FALSE(none.getBoundingBox().valid()) << "no arrow without a force";
}

TEST(OverlayLayers, NamesRoundTripAndUnknownNamesAreRefused) {
  for (OverlayLayer layer : kAllOverlayLayers) EXPECT_EQ(parseOverlayLayer(overlayLayerName(layer)), layer);
  EXPECT_THROW(parseOverlayLayer("nonsense"), InputError);
}

// --- Offscreen: each layer shows its colour where its points project -------------------------

class OverlayRender : public ::testing::Test {
 protected:
  OverlayRender() : renderer_(kWidth, kHeight) { world_.setGridVisible(false); }
  Image render() { return renderer_.render(world_.root(), testCamera(), background()); }

  World world_;
  OffscreenRenderer renderer_;
};

TEST_F(OverlayRender, SamplesShowInTheirAreaColourWhereProjected) {
  const Image empty = render();
  const std::vector<Eigen::Vector3d> area0 = {{-0.5, -0.2, 0.3}, {-0.4, 0.3, 0.7}};
  const std::vector<Eigen::Vector3d> area2 = {{-0.2, 0.1, 0.5}};
  world_.overlays().setContent(OverlayLayer::kTrainingSamples, makeTrainingSamples({{0, area0}, {2, area2}}, 9.0F));
  const Image shown = render();
  for (const Eigen::Vector3d& p : area0) EXPECT_LT(colorDistance(pixelAt(shown, testCamera(), p), OverlayPalette::area(0)), 30);
  EXPECT_LT(colorDistance(pixelAt(shown, testCamera(), area2[0]), OverlayPalette::area(2)), 30);
  // Toggled off, the layer leaves no trace.
  world_.overlays().setVisible(OverlayLayer::kTrainingSamples, false);
  EXPECT_FALSE(world_.overlays().visible(OverlayLayer::kTrainingSamples));
  EXPECT_EQ(changedPixels(render(), empty), 0);
}

TEST_F(OverlayRender, ReachableGreenUnreachableRedAndItmNodesInTheirColour) {
  const Eigen::Vector3d reached(-0.5, -0.3, 0.5);
  const Eigen::Vector3d missed(-0.2, 0.4, 0.9);
  world_.overlays().setContent(OverlayLayer::kReachability, makeReachability({reached, missed}, {true, false}));
  const Eigen::Vector3d node_a(-0.6, 0.3, 0.2);
  const Eigen::Vector3d node_b(0.1, -0.4, 0.3);
  world_.overlays().itm().setGraph({{3, node_a}, {8, node_b}}, {{3, 8}});
  const Image image = render();
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), reached), OverlayPalette::reachable()), 30);
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), missed), OverlayPalette::unreachable()), 30);
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), node_a), OverlayPalette::itmNode()), 30)
      << "a node is drawn over the ends of its edges";
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), node_b), OverlayPalette::itmNode()), 30);
  // The middle of the edge is drawn in the edge colour.
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), 0.5 * (node_a + node_b)), OverlayPalette::itmEdge()), 40);
}

TEST_F(OverlayRender, ConfidenceSliceShowsItsColourMapWhereProjected) {
  const auto confidence = [](const Eigen::Vector3d& p) { return p.x() < -0.3 ? 0.0 : 1.0; };
  world_.overlays().setContent(OverlayLayer::kConfidence,
                               makeConfidenceSlice(sampleConfidence(confidence, {-0.8, -0.4}, {0.2, 0.4}, 0.3, 41), 1.0F));
  const Image image = render();
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), {-0.6, 0.0, 0.3}), confidenceColor(0.0)), 30);
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), {0.0, 0.0, 0.3}), confidenceColor(1.0)), 30);
}

TEST_F(OverlayRender, GoalMarkerPathAndForceArrowShowInTheirColours) {
  const Eigen::Vector3d goal(-0.4, 0.2, 0.6);
  world_.overlays().setContent(OverlayLayer::kGoalAndPath, makeGoalMarker(goal, 0.04));
  const Eigen::Vector3d from(-0.7, -0.4, 0.2);
  world_.overlays().addContent(OverlayLayer::kGoalAndPath,
                               makePolyline({from, Eigen::Vector3d(-0.7, -0.4, 0.5)}, OverlayPalette::plannedPath(), 4.0F));
  const Eigen::Vector3d origin(0.0, -0.3, 0.3);
  world_.overlays().setContent(OverlayLayer::kForce, makeForceArrow(origin, Eigen::Vector3d(0, 0, 40.0), 0.01));
  const Image image = render();
  // The lit sphere's centre faces the camera: its hue is the goal's (red and blue above green).
  const auto goal_pixel = pixelAt(image, testCamera(), goal);
  EXPECT_GT(goal_pixel[0], goal_pixel[1] + 60);
  EXPECT_GT(goal_pixel[2], goal_pixel[1] + 20);
  EXPECT_LT(colorDistance(pixelAt(image, testCamera(), Eigen::Vector3d(-0.7, -0.4, 0.35)), OverlayPalette::plannedPath()), 30);
  // The arrow's shaft, 40 N x 0.01 m/N = 0.4 m up: yellow (red and green far above blue).
  const auto shaft = pixelAt(image, testCamera(), origin + Eigen::Vector3d(0, 0, 0.15));
  EXPECT_GT(shaft[0], shaft[2] + 80);
  EXPECT_GT(shaft[1], shaft[2] + 50);
}

TEST_F(OverlayRender, LegendDrawsItsSwatchesInTheTopLeftCorner) {
  const Image empty = render();
  world_.overlays().setContent(OverlayLayer::kLegend,
                               makeLegend({{"area 0", OverlayPalette::area(0)}, {"area 1", OverlayPalette::area(1)}}, kWidth, kHeight));
  const Image image = render();
  // Swatch i spans x in [10, 22], y (from the top) in [10 + 20 i + 4, 10 + 20 i + 16].
  EXPECT_LT(colorDistance(image.pixel(16, 10 + 10), OverlayPalette::area(0)), 12);
  EXPECT_LT(colorDistance(image.pixel(16, 10 + 20 + 10), OverlayPalette::area(1)), 12);
  EXPECT_GT(changedPixels(empty, image), 200) << "the labels and the panel are drawn too";
  // Nothing far from the corner changes.
  EXPECT_EQ(image.pixel(kWidth - 5, kHeight - 5), empty.pixel(kWidth - 5, kHeight - 5));
}

// Pixels in [x0, x1) x [y0, y1) (rows from the top) as dark as the labels' ink.
int inkPixels(const Image& image, int x0, int y0, int x1, int y1) {
  int count = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const auto p = image.pixel(x, y);
      if (p[0] < 110 && p[1] < 110 && p[2] < 110) ++count;
    }
  }
  return count;
}

TEST_F(OverlayRender, LegendDrawsLabelsOutsideAscii) {
  // The first row's label spans x >= 32, y (from the top) in [10, 30].
  world_.overlays().setContent(OverlayLayer::kLegend, makeLegend({{"", OverlayPalette::area(0)}}, kWidth, kHeight));
  const int blank = inkPixels(render(), 32, 10, 160, 30);
  world_.overlays().setContent(OverlayLayer::kLegend,
                               makeLegend({{"\u00c4\u00d6\u00dc \u0416\u0414 \u03a9", OverlayPalette::area(0)}}, kWidth, kHeight));
  const Image glyphs = render();
  EXPECT_GT(inkPixels(glyphs, 32, 10, 160, 30), blank + 20) << "umlauts, Cyrillic and Greek leave ink";
  // Drawn as their own glyphs (the TrueType face fonts-dejavu-core installs), not as the '?' of
  // OSG's ASCII face.
  world_.overlays().setContent(OverlayLayer::kLegend, makeLegend({{"??? ?? ?", OverlayPalette::area(0)}}, kWidth, kHeight));
  EXPECT_GT(changedPixels(glyphs, render()), 20);
}

TEST_F(OverlayRender, LegendDrawsChineseJapaneseAndKoreanLabelsInTheirOwnGlyphs) {
  // DejaVu has no CJK glyphs: every character would be the same empty box, and two labels of
  // as many characters would look alike. In WenQuanYi Micro Hei (fonts-wqy-microhei) they differ.
  const auto legendOf = [this](const char* label) {
    world_.overlays().setContent(OverlayLayer::kLegend, makeLegend({{label, OverlayPalette::area(0)}}, kWidth, kHeight));
    return render();
  };
  const Image japanese = legendOf("日本語");  // 日本語
  const Image chinese = legendOf("中文区");   // 中文区
  const Image korean = legendOf("한국어");    // 한국어
  EXPECT_GT(changedPixels(japanese, chinese), 20);
  EXPECT_GT(changedPixels(japanese, korean), 20);
  EXPECT_GT(changedPixels(chinese, korean), 20);
  // A label mixing Latin letters and CJK is drawn in one face, the Latin part included.
  const Image mixed = legendOf("area 日本");
  EXPECT_GT(changedPixels(mixed, legendOf("area 中文")), 20);
  EXPECT_GT(inkPixels(mixed, 32, 10, 160, 30), inkPixels(legendOf("日本"), 32, 10, 160, 30) + 20);
}

TEST_F(OverlayRender, LegendCutsALabelTooLongForThePicture) {
  const Image empty = render();
  world_.overlays().setContent(OverlayLayer::kLegend,
                               makeLegend({{std::string(300, 'W'), OverlayPalette::area(0)}}, kWidth, kHeight));
  const Image image = render();
  EXPECT_GT(inkPixels(image, kWidth / 2, 10, kWidth - 20, 30), 20) << "the label runs across the picture";
  for (int y = 0; y < 40; ++y) {
    EXPECT_EQ(image.pixel(kWidth - 2, y), empty.pixel(kWidth - 2, y)) << "panel or label at the right edge, row " << y;
  }
}

// Text printed onto a finished picture (the study's scatter plot): dark letters where the label
// stands, cut at its width, and every other pixel exactly as it was.
TEST(PrintedLabels, DarkenTheirOwnPlaceAndLeaveTheRestOfThePictureAsItWas) {
  Image base;
  base.width = 240;
  base.height = 60;
  base.rgba.resize(static_cast<std::size_t>(4 * base.width * base.height));
  for (std::size_t i = 0; i < base.rgba.size(); i += 4) {
    base.rgba[i] = 90;
    base.rgba[i + 1] = 200;
    base.rgba[i + 2] = 250;
    base.rgba[i + 3] = 255;
  }
  const Image printed = printLabels(base, {{std::string(60, 'W'), 20.0F, 30.0F, 100.0F}});
  ASSERT_EQ(printed.width, base.width);
  ASSERT_EQ(printed.height, base.height);
  int dark = 0;
  for (int y = 0; y < base.height; ++y) {
    for (int x = 0; x < base.width; ++x) {
      const auto before = base.pixel(x, y);
      const auto after = printed.pixel(x, y);
      for (int c = 0; c < 3; ++c) ASSERT_LE(after[c], before[c]) << x << ", " << y;
      const bool inside = x >= 18 && x <= 20 + 100 + 2 && y >= 30 - 16 && y <= 30 + 5;
      if (!inside) {
        ASSERT_EQ(after, before) << "ink outside the label's place at " << x << ", " << y;
      }
      dark += after[1] < before[1] / 2 ? 1 : 0;
    }
  }
  EXPECT_GT(dark, 150) << "the letters of a 100 px label";
  EXPECT_EQ(printLabels(base, {}).rgba, base.rgba);
}

TEST(OverlayLegend, RowsBeyondThePicturesHeightEndInOneCountingRow) {
  std::vector<LegendEntry> entries;
  for (int i = 0; i < 100; ++i) entries.push_back({"area " + std::to_string(i), OverlayPalette::area(i)});
  // 240 px less two 10 px margins hold eleven 20 px rows.
  const std::vector<LegendEntry> rows = legendRows(entries, 240);
  ASSERT_EQ(rows.size(), 11U);
  EXPECT_EQ(rows[9].label, "area 9");
  EXPECT_EQ(rows[10].label, "\u2026 and 90 more");
  EXPECT_TRUE(rows[10].rgba.isZero()) << "no swatch";
  entries.resize(11);
  EXPECT_EQ(legendRows(entries, 240).size(), 11U) << "all that fit are shown as they are";
  EXPECT_EQ(legendRows(entries, 240).back().label, "area 10");
  EXPECT_EQ(legendRows(entries, 1).size(), 1U) << "at least one row";
}

TEST(OverlayLegend, DecodesUtf8AndReadsBrokenBytesAsReplacementCharacters) {
  EXPECT_EQ(decodeUtf8("a\u00e9\u20ac\U0001F600"), (std::vector<char32_t>{U'a', 0xE9, 0x20AC, 0x1F600}));
  constexpr char32_t kBad = 0xFFFD;
  EXPECT_EQ(decodeUtf8("\x80z"), (std::vector<char32_t>{kBad, U'z'})) << "stray continuation byte";
  EXPECT_EQ(decodeUtf8("\xC0\xAF"), (std::vector<char32_t>{kBad, kBad})) << "overlong '/'";
  EXPECT_EQ(decodeUtf8("\xED\xA0\x80"), (std::vector<char32_t>{kBad, kBad, kBad})) << "a surrogate";
  EXPECT_EQ(decodeUtf8("\xF4\x90\x80\x80"), (std::vector<char32_t>(4, kBad))) << "beyond U+10FFFF";
  EXPECT_EQ(decodeUtf8("ab\xE2\x82"), (std::vector<char32_t>{U'a', U'b', kBad, kBad})) << "cut short";
  EXPECT_EQ(decodeUtf8("\xFF"), (std::vector<char32_t>{kBad}));
  EXPECT_TRUE(decodeUtf8("").empty());
}

TEST_F(OverlayRender, GhostArmTintsThePictureWithoutHidingTheArm) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  world_.setRobot(model);
  const Image arm_only = render();
  Eigen::VectorXd q = model.midPosture();
  q[0] += 1.2;
  q[1] += 0.7;
  world_.overlays().setContent(OverlayLayer::kGhostArms, makeGhostArm(model, q));
  const Image with_ghost = render();
  robot::Kinematics kinematics(model);
  kinematics.update(q);
  // Where the ghost's elbow is (nothing else there), the background turns towards its grey.
  const Eigen::Vector3d elbow = kinematics.X_WB(4).translation();
  const auto before = pixelAt(arm_only, testCamera(), elbow);
  const auto after = pixelAt(with_ghost, testCamera(), elbow);
  EXPECT_LT(colorDistance(after, OverlayPalette::ghost()), colorDistance(before, OverlayPalette::ghost()));
  EXPECT_GT(changedPixels(arm_only, with_ghost), 500);
  EXPECT_THROW(makeGhostArm(model, Eigen::VectorXd::Zero(3)), std::invalid_argument);
}

TEST_F(OverlayRender, CollidingLinkTurnsRed) {
  const auto model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  world_.setRobot(model);
  robot::Kinematics kinematics(model);
  kinematics.update(model.midPosture());
  const std::string link = model.bodies().at(3).name;
  ASSERT_GT(showCollisions(*world_.robot(), {link}), 0);
  const Image red = render();
  // Somewhere along the body, towards the next one, the shell is red.
  const Eigen::Vector3d a = kinematics.X_WB(3).translation();
  const Eigen::Vector3d b = kinematics.X_WB(4).translation();
  bool found = false;
  for (double s = 0.1; s < 0.95 && !found; s += 0.1) {
    const auto pixel = pixelAt(red, testCamera(), a + s * (b - a));
    found = pixel[0] > 120 && pixel[1] < pixel[0] / 4 && pixel[2] < pixel[0] / 4;
  }
  EXPECT_TRUE(found) << "expected the colliding link " << link << " in red";
  EXPECT_EQ(showCollisions(*world_.robot(), {}), 0);
  const Image restored = render();
  bool still_red = false;
  for (double s = 0.1; s < 0.95; s += 0.1) {
    const auto pixel = pixelAt(restored, testCamera(), a + s * (b - a));
    still_red = still_red || (pixel[0] > 120 && pixel[1] < pixel[0] / 4 && pixel[2] < pixel[0] / 4);
  }
  EXPECT_FALSE(still_red) << "the URDF colours come back once nothing touches";
}

}  // namespace
}  // namespace flexirob::render
