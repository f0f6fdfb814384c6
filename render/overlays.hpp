#pragma once
// Overlays: what the 3D view draws on top of the robot and the scene to show what the system
// has learned and plans (thesis Chap. 6 and 7): training samples per area, q_fixed ghost arms,
// confidence slices (Fig. 6.5), the ITM graph, goal and planned path, target and teach-in
// trajectories, reachable and unreachable targets (Fig. 3.10), a force arrow, collisions and a
// legend.
//
// Every builder takes plain data (Eigen types, the robot model) and returns an OSG node in the
// world frame W; none knows of the workflow, the learners or Qt, so the GUI, the review window
// and offscreen figures share them. `Overlays` keeps one group per layer under one root so that
// each layer can be replaced and toggled on its own; World owns one (World::overlays()).
//
// Points and lines are unlit and keep their colour from every side; markers and arrows are lit
// shapes like the robot's. Sizes of points and lines are in pixels, everything else in metres.
#include <osg/Camera>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/ref_ptr>

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "render/robot_graph.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::render {

/// The fixed colours of the overlays (RGBA, 0..1).
struct OverlayPalette {
  /// Colour of training area `index` (0-based): eight well separated hues, then repeating.
  static Eigen::Vector4f area(int index);
  static Eigen::Vector4f ghost() { return {0.55F, 0.60F, 0.70F, 0.30F}; }
  static Eigen::Vector4f itmNode() { return {0.95F, 0.55F, 0.05F, 1.0F}; }
  static Eigen::Vector4f itmEdge() { return {0.45F, 0.35F, 0.25F, 1.0F}; }
  static Eigen::Vector4f goal() { return {0.95F, 0.10F, 0.60F, 1.0F}; }
  static Eigen::Vector4f plannedPath() { return {0.95F, 0.10F, 0.60F, 1.0F}; }
  static Eigen::Vector4f targetTrajectory() { return {0.10F, 0.10F, 0.12F, 1.0F}; }
  static Eigen::Vector4f teachInTrajectory() { return {0.55F, 0.15F, 0.65F, 1.0F}; }
  static Eigen::Vector4f executedTrajectory() { return {0.05F, 0.55F, 0.75F, 1.0F}; }
  static Eigen::Vector4f reachable() { return {0.10F, 0.70F, 0.15F, 1.0F}; }
  static Eigen::Vector4f unreachable() { return {0.90F, 0.10F, 0.10F, 1.0F}; }
  /// A planned path whose execution touched something: wine, apart from the unreached targets'
  /// red it is often drawn with (ΔE76 68) and from the planned paths' magenta.
  static Eigen::Vector4f collidedPath() { return {0.40F, 0.00F, 0.20F, 1.0F}; }
  static Eigen::Vector4f collision() { return {1.0F, 0.0F, 0.0F, 1.0F}; }
  /// The points of the implicit scene model S (Eq. 4.1, Fig. 4.6).
  static Eigen::Vector4f sceneModel() { return {0.22F, 0.22F, 0.28F, 1.0F}; }
  static Eigen::Vector4f force() { return {1.0F, 0.80F, 0.0F, 1.0F}; }
};

/// The colour map of confidence slices: value 0 (no confidence) dark blue, through teal and
/// green, to 1 (full confidence) yellow (viridis-like, ordered in lightness). Clamped to [0, 1];
/// NaN maps to transparent grey.
Eigen::Vector4f confidenceColor(double value);

// --- Primitive overlay geometry -------------------------------------------------------------

/// Unlit square points of `size_px` pixels, one colour.
osg::ref_ptr<osg::Geode> makePoints(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Vector4f& rgba,
                                    float size_px = 6.0F);
/// An unlit polyline through the points (nothing for fewer than two), `width_px` wide.
osg::ref_ptr<osg::Geode> makePolyline(const std::vector<Eigen::Vector3d>& points_W, const Eigen::Vector4f& rgba,
                                      float width_px = 2.5F);

// --- Layers' content ------------------------------------------------------------------------

/// The training samples of one area: their task-space (tip) positions.
struct AreaSamples {
  int area = 0;  ///< area index (0-based), selects the colour
  std::vector<Eigen::Vector3d> points_W;
};
/// One point cloud per area, each in OverlayPalette::area(area); children named "samples:<area>".
osg::ref_ptr<osg::Group> makeTrainingSamples(const std::vector<AreaSamples>& areas, float size_px = 5.0F);

/// The robot at posture q as a translucent ghost (the q_fixed of a training area), drawn without
/// writing depth so that the real arm and the scene stay visible through it. Throws
/// std::invalid_argument if q does not fit the model, InputError if a mesh cannot be read.
osg::ref_ptr<osg::Node> makeGhostArm(const robot::RobotModel& model, const Eigen::VectorXd& q,
                                     const Eigen::Vector4f& rgba = OverlayPalette::ghost());

/// A horizontal slice of the confidence field: values on a regular grid at height z.
struct ConfidenceGrid {
  Eigen::Vector2d lower_xy = Eigen::Vector2d(-1.0, -1.0);  ///< [m] corner of the slice
  Eigen::Vector2d upper_xy = Eigen::Vector2d(1.0, 1.0);    ///< [m] opposite corner
  double z = 0.5;                                          ///< [m] height of the slice
  /// values(i, j) at x = lower.x + i (upper.x - lower.x) / (rows - 1), y likewise along cols;
  /// in [0, 1] (clamped), at least 2 x 2.
  Eigen::MatrixXd values;
};
/// Samples `confidence(p_W)` on a resolution x resolution grid (resolution >= 2) of a slice.
ConfidenceGrid sampleConfidence(const std::function<double(const Eigen::Vector3d&)>& confidence,
                                const Eigen::Vector2d& lower_xy, const Eigen::Vector2d& upper_xy, double z,
                                int resolution);
/// The slice as a translucent, unlit, two-sided quad mesh coloured by confidenceColor, the
/// colours interpolated between grid points. Throws std::invalid_argument for fewer than 2 x 2
/// values or an empty extent.
osg::ref_ptr<osg::Geode> makeConfidenceSlice(const ConfidenceGrid& grid, float alpha = 0.65F);

/// Target points coloured by whether the robot reaches them (Fig. 3.10): reachable in
/// OverlayPalette::reachable(), the others in unreachable(). Sizes must match.
osg::ref_ptr<osg::Group> makeReachability(const std::vector<Eigen::Vector3d>& points_W,
                                          const std::vector<bool>& reachable, float size_px = 9.0F);

/// A goal marker: a lit sphere of `radius` [m] at p_W with a ring of three axis lines.
osg::ref_ptr<osg::Node> makeGoalMarker(const Eigen::Vector3d& p_W, double radius = 0.025,
                                       const Eigen::Vector4f& rgba = OverlayPalette::goal());

/// A force arrow from `origin_W` along `force_W` [N], `metres_per_newton` long per newton
/// (shaft plus cone head, lit). An empty group for forces below 1e-6 N.
osg::ref_ptr<osg::Node> makeForceArrow(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& force_W,
                                       double metres_per_newton = 0.01,
                                       const Eigen::Vector4f& rgba = OverlayPalette::force());

/// Colours the links in `touching` (URDF link names) red, every other link in its URDF colour.
/// Returns how many visuals were coloured red.
int showCollisions(RobotGraph& robot, const std::vector<std::string>& touching);

/// One line of the legend.
struct LegendEntry {
  std::string label;
  Eigen::Vector4f rgba;
};
/// The legend as a head-up display: a camera drawn after the scene, in pixels of a viewport of
/// width x height, with one coloured swatch and label per entry in the top-left corner. Labels
/// are UTF-8 (area names are the tutor's); each is cut with an ellipsis where it would leave the
/// viewport, and entries beyond the viewport's height end in one "… and N more" line.
osg::ref_ptr<osg::Camera> makeLegend(const std::vector<LegendEntry>& entries, int viewport_width,
                                     int viewport_height);

/// A line of text at a place of a viewport, in pixels counted as images count them (y down).
struct PlacedLabel {
  std::string text;  ///< UTF-8
  float x = 0.0F;          ///< left end
  float baseline = 0.0F;   ///< base line, from the top
  float max_width = 0.0F;  ///< cut with an ellipsis beyond this
};
/// The labels as a head-up display of a viewport of width x height pixels, in the legend's face,
/// size and ink.
osg::ref_ptr<osg::Camera> makePlacedLabels(const std::vector<PlacedLabel>& labels, int viewport_width, int viewport_height);

/// The code points of UTF-8 `text`; a byte that starts no valid sequence (stray continuation,
/// overlong form, surrogate, beyond U+10FFFF, cut short) reads as U+FFFD.
std::vector<char32_t> decodeUtf8(const std::string& text);

/// The legend's rows for a viewport `viewport_height` pixels high: all entries when they fit,
/// else as many as fit but one and a last row "… and N more" (rgba all zero: no swatch).
std::vector<LegendEntry> legendRows(const std::vector<LegendEntry>& entries, int viewport_height);

// --- The ITM graph, updated incrementally ---------------------------------------------------

/// The ITM graph drawn as points (nodes) and lines (edges) from two shared vertex arrays, so
/// that adding a node or an edge appends to an array instead of rebuilding the geometry: cheap
/// while the graph grows to 10 000 nodes and more. Node ids are the ITM's (sparse after
/// deletions); positions are in W (the task-space part of each node's weight, or its tip).
class ItmGraphOverlay {
 public:
  explicit ItmGraphOverlay(float node_size_px = 5.0F, float edge_width_px = 1.5F);

  osg::Geode* node() const { return geode_.get(); }

  /// Replaces the whole graph: nodes as (id, position), edges as pairs of ids. Throws
  /// std::invalid_argument for a negative id or an edge to a node not given.
  void setGraph(const std::vector<std::pair<int, Eigen::Vector3d>>& nodes,
                const std::vector<std::pair<int, int>>& edges);
  /// Adds node `id` at p_W, or moves it if it exists (an adapted weight).
  void setNode(int id, const Eigen::Vector3d& p_W);
  /// Removes a node and its edges; nothing if it does not exist.
  void removeNode(int id);
  /// Adds an edge between two existing nodes (once). Throws std::invalid_argument otherwise.
  void addEdge(int a, int b);
  void removeEdge(int a, int b);
  void clear();

  int nodeCount() const { return static_cast<int>(live_nodes_->size()); }
  int edgeCount() const { return static_cast<int>(edge_indices_->size() / 2); }
  bool hasNode(int id) const;

 private:
  void touch();
  osg::ref_ptr<osg::Geode> geode_;
  osg::ref_ptr<osg::Geometry> points_;
  osg::ref_ptr<osg::Geometry> lines_;
  osg::ref_ptr<osg::Vec3Array> vertices_;          // indexed by node id
  osg::ref_ptr<osg::DrawElementsUInt> live_nodes_; // ids of live nodes
  osg::ref_ptr<osg::DrawElementsUInt> edge_indices_;
  std::vector<int> slot_of_node_;                  // position in live_nodes_, -1 if absent
};

// --- All layers -----------------------------------------------------------------------------

enum class OverlayLayer {
  kTrainingSamples,
  kGhostArms,
  kConfidence,
  kItmGraph,
  kGoalAndPath,
  kTrajectories,
  kReachability,
  kForce,
  kLegend,
};
inline constexpr int kOverlayLayerCount = 9;
inline constexpr std::array<OverlayLayer, kOverlayLayerCount> kAllOverlayLayers = {
    OverlayLayer::kTrainingSamples, OverlayLayer::kGhostArms,   OverlayLayer::kConfidence,
    OverlayLayer::kItmGraph,        OverlayLayer::kGoalAndPath, OverlayLayer::kTrajectories,
    OverlayLayer::kReachability,    OverlayLayer::kForce,       OverlayLayer::kLegend};

/// Short, stable name of a layer ("samples", "ghosts", "confidence", "itm", "path",
/// "trajectories", "reachability", "force", "legend"), used by menus and --overlay options.
const char* overlayLayerName(OverlayLayer layer);
/// A human title ("Training samples", ...), for menus and the legend.
const char* overlayLayerTitle(OverlayLayer layer);
/// The layer of a short name; throws InputError naming the valid names otherwise.
OverlayLayer parseOverlayLayer(const std::string& name);

class Overlays {
 public:
  Overlays();
  ~Overlays();
  Overlays(const Overlays&) = delete;
  Overlays& operator=(const Overlays&) = delete;

  /// The root of every layer (add it once to a scene graph).
  osg::Group* root() const { return root_.get(); }
  /// The group of one layer (named "overlay:<name>").
  osg::Group* layer(OverlayLayer layer) const;
  /// Replaces the content of a layer (nullptr: empties it). The ITM layer always keeps the
  /// ItmGraphOverlay's node besides what is set here.
  void setContent(OverlayLayer layer, osg::ref_ptr<osg::Node> content);
  /// Adds to a layer's content (several trajectories, several ghosts).
  void addContent(OverlayLayer layer, osg::ref_ptr<osg::Node> content);

  void setVisible(OverlayLayer layer, bool visible);
  bool visible(OverlayLayer layer) const;

  ItmGraphOverlay& itm() { return *itm_; }

 private:
  osg::ref_ptr<osg::Group> root_;
  std::array<osg::ref_ptr<osg::Group>, kOverlayLayerCount> layers_;
  std::unique_ptr<ItmGraphOverlay> itm_;
};

}  // namespace flexirob::render
