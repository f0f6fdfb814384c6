#pragma once
// The confidence field overlay (thesis Fig. 6.5, issue #7 item 4): horizontal slices of the
// areas' confidence C(x) (Eq. 6.9) at heights the operator chooses, coloured by
// render::confidenceColor, with a colour bar as the legend.
//
// confidenceSlices() samples the slices from a learned ConfidenceModel (the workflow's, from the
// live snapshot, or one rebuilt from a recording's samples); ConfidencePanel holds the heights
// (lowest slice, count, spacing) and the colour bar; ConfidenceColourBar is the legend, also
// drawn over the 3D view while slices are shown.
#include <QWidget>

#include <Eigen/Core>
#include <vector>

#include "render/overlays.hpp"

class QDoubleSpinBox;
class QSpinBox;
class QSlider;
class QLabel;

namespace flexirob::learning {
class ConfidenceModel;
}

namespace flexirob::ui {

/// Where the slices are: `count` horizontal planes from `lowest_z` upwards, `spacing` apart.
struct ConfidenceSliceSettings {
  double lowest_z = 0.3;  ///< [m]
  double spacing = 0.1;  ///< [m]
  int count = 3;
  int resolution = 48;  ///< grid points along each side of a slice
  /// Heights of the slices [m], lowest first.
  std::vector<double> heights() const;
};

/// The x-y extent of the slices: the areas' means (Eq. 6.7) with 3 standard deviations of their
/// Gaussians (Eq. 6.8) and `margin` [m] around them, so every area's bump shows whole.
void confidenceExtent(const learning::ConfidenceModel& model, double margin, Eigen::Vector2d& lower_xy,
                      Eigen::Vector2d& upper_xy);

/// The slices of C(x) (Eq. 6.9) of `model` (3-D input) at the settings' heights over its extent.
/// Empty for a model without areas.
std::vector<render::ConfidenceGrid> confidenceSlices(const learning::ConfidenceModel& model,
                                                     const ConfidenceSliceSettings& settings);

/// `settings` with the slices moved so that the middle one passes through the mean height of
/// the areas' centres (rounded to centimetres); unchanged for a model without areas.
ConfidenceSliceSettings centredSlices(const learning::ConfidenceModel& model, ConfidenceSliceSettings settings);

/// Builds the overlay content of the slices (a group of render::makeConfidenceSlice); null if none.
osg::ref_ptr<osg::Group> makeConfidenceOverlay(const std::vector<render::ConfidenceGrid>& slices);

/// The legend of the colour map: a vertical bar from C = 0 (bottom) to 1 (top) with ticks.
class ConfidenceColourBar : public QWidget {
  Q_OBJECT

 public:
  explicit ConfidenceColourBar(QWidget* parent = nullptr);
  /// The title's width and a bar of five labels; the main window lowers it on a short view.
  QSize sizeHint() const override;

 protected:
  void paintEvent(QPaintEvent* event) override;
};

/// The heights of the slices and the legend, in a dock.
class ConfidencePanel : public QWidget {
  Q_OBJECT

 public:
  explicit ConfidencePanel(QWidget* parent = nullptr);

  ConfidenceSliceSettings settings() const;
  void setSettings(const ConfidenceSliceSettings& settings);
  /// A line under the controls: what is shown ("3 areas, C max 0.97 at z = 0.45 m", or why not).
  void setStatus(const QString& text);

  QSlider* heightSlider() const { return height_slider_; }
  QDoubleSpinBox* heightBox() const { return height_box_; }
  QSpinBox* countBox() const { return count_box_; }
  QDoubleSpinBox* spacingBox() const { return spacing_box_; }
  QLabel* statusLabel() const { return status_label_; }

 Q_SIGNALS:
  void settingsChanged();

 private:
  QSlider* height_slider_ = nullptr;  // centimetres, mirrors height_box_
  QDoubleSpinBox* height_box_ = nullptr;
  QSpinBox* count_box_ = nullptr;
  QDoubleSpinBox* spacing_box_ = nullptr;
  QLabel* status_label_ = nullptr;
};

}  // namespace flexirob::ui
