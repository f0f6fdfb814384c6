#include "ui/confidence_panel.hpp"

#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLinearGradient>
#include <QPainter>
#include <QSlider>
#include <QSpinBox>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <limits>

#include "learning/confidence.hpp"

namespace flexirob::ui {
namespace {

// The extent is cut to this half-size [m] so a degenerate, huge Gaussian cannot blow the grid
// up to where the areas shrink to a pixel.
constexpr double kMaxHalfExtent = 1.5;
// Standard deviations of an area's Gaussian inside the extent: C = exp(-1/2 · 2.5²) ≈ 0.04 there.
constexpr double kExtentSigmas = 2.5;

QColor toQColor(const Eigen::Vector4f& rgba) { return QColor::fromRgbF(rgba[0], rgba[1], rgba[2], rgba[3]); }

}  // namespace

std::vector<double> ConfidenceSliceSettings::heights() const {
  std::vector<double> z;
  for (int i = 0; i < count; ++i) z.push_back(lowest_z + spacing * i);
  return z;
}

void confidenceExtent(const learning::ConfidenceModel& model, double margin, Eigen::Vector2d& lower_xy,
                      Eigen::Vector2d& upper_xy) {
  lower_xy = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  upper_xy = -lower_xy;
  for (int k = 0; k < model.areas(); ++k) {
    const Eigen::Vector2d mean = model.mean(k).head<2>();
    const Eigen::Vector2d sigma = model.covariance(k).diagonal().head<2>().cwiseSqrt();
    lower_xy = lower_xy.cwiseMin(mean - kExtentSigmas * sigma);
    upper_xy = upper_xy.cwiseMax(mean + kExtentSigmas * sigma);
  }
  if (model.areas() == 0) {
    lower_xy.setConstant(-0.5);
    upper_xy.setConstant(0.5);
  }
  lower_xy.array() -= margin;
  upper_xy.array() += margin;
  const Eigen::Vector2d centre = 0.5 * (lower_xy + upper_xy);
  lower_xy = lower_xy.cwiseMax((centre.array() - kMaxHalfExtent).matrix());
  upper_xy = upper_xy.cwiseMin((centre.array() + kMaxHalfExtent).matrix());
}

std::vector<render::ConfidenceGrid> confidenceSlices(const learning::ConfidenceModel& model,
                                                     const ConfidenceSliceSettings& settings) {
  std::vector<render::ConfidenceGrid> slices;
  if (model.areas() == 0 || model.inputDim() != 3 || settings.count < 1) return slices;
  Eigen::Vector2d lower;
  Eigen::Vector2d upper;
  confidenceExtent(model, 0.05, lower, upper);
  const int n = std::max(2, settings.resolution);
  for (const double z : settings.heights()) {
    // All grid points at once: C(x) of Eq. 6.9, vectorized per area.
    Eigen::MatrixXd points(3, n * n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        points.col(i * n + j) << lower.x() + (upper.x() - lower.x()) * i / (n - 1),
            lower.y() + (upper.y() - lower.y()) * j / (n - 1), z;
      }
    }
    const Eigen::VectorXd values = model.evaluateColumns(points);
    render::ConfidenceGrid grid;
    grid.lower_xy = lower;
    grid.upper_xy = upper;
    grid.z = z;
    grid.values.resize(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) grid.values(i, j) = values[i * n + j];
    }
    slices.push_back(std::move(grid));
  }
  return slices;
}

ConfidenceSliceSettings centredSlices(const learning::ConfidenceModel& model, ConfidenceSliceSettings settings) {
  if (model.areas() == 0) return settings;
  double z = 0.0;
  for (int k = 0; k < model.areas(); ++k) z += model.mean(k)[model.inputDim() >= 3 ? 2 : 0];
  z /= model.areas();
  settings.lowest_z = std::round((z - settings.spacing * (settings.count - 1) / 2.0) * 100.0) / 100.0;
  return settings;
}

osg::ref_ptr<osg::Group> makeConfidenceOverlay(const std::vector<render::ConfidenceGrid>& slices) {
  if (slices.empty()) return nullptr;
  osg::ref_ptr<osg::Group> group = new osg::Group();
  group->setName("confidence_slices");
  for (const render::ConfidenceGrid& grid : slices) group->addChild(render::makeConfidenceSlice(grid, 0.6F));
  return group;
}

// --- ConfidenceColourBar --------------------------------------------------------------------

ConfidenceColourBar::ConfidenceColourBar(QWidget* parent) : QWidget(parent) {
  setObjectName(QStringLiteral("confidence_legend"));
  setMinimumSize(120, 120);
  setAttribute(Qt::WA_TransparentForMouseEvents);
}

QSize ConfidenceColourBar::sizeHint() const {
  const QFontMetrics metrics(font());
  return {std::max(90, metrics.horizontalAdvance(tr("Confidence C(x)")) + 20), 170};
}

void ConfidenceColourBar::paintEvent(QPaintEvent* /*event*/) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), QColor(255, 255, 255, 215));
  painter.setPen(QColor(136, 136, 136));
  painter.drawRect(rect().adjusted(0, 0, -1, -1));
  const QFontMetrics metrics(font());
  // Room under the title for half the "1" label, which is centred on the bar's top.
  const int top = 10 + metrics.height() + metrics.ascent() / 2;
  const int bottom = height() - 10;
  const QRect bar(10, top, 22, std::max(10, bottom - top));
  QLinearGradient gradient(bar.bottomLeft(), bar.topLeft());
  for (int i = 0; i <= 10; ++i) gradient.setColorAt(i / 10.0, toQColor(render::confidenceColor(i / 10.0)));
  painter.fillRect(bar, gradient);
  painter.setPen(QColor(40, 40, 40));
  painter.drawRect(bar);
  painter.drawText(QPoint(8, 4 + metrics.ascent()), tr("Confidence C(x)"));
  // Five labels where the bar has room for them, else three.
  const bool roomy = bar.height() >= 4 * (metrics.height() + 2);
  for (const double value : {0.0, 0.25, 0.5, 0.75, 1.0}) {
    if (!roomy && (value == 0.25 || value == 0.75)) continue;
    const int y = bar.bottom() - static_cast<int>(std::lround(value * bar.height()));
    painter.drawLine(bar.right(), y, bar.right() + 5, y);
    painter.drawText(QPoint(bar.right() + 9, y + metrics.ascent() / 2 - 1), QString::number(value, 'g', 2));
  }
}

// --- ConfidencePanel ------------------------------------------------------------------------

ConfidencePanel::ConfidencePanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  auto* form = new QFormLayout();
  height_box_ = new QDoubleSpinBox(this);
  height_box_->setObjectName(QStringLiteral("confidence_height"));
  height_box_->setRange(-0.5, 2.0);
  height_box_->setSingleStep(0.01);
  height_box_->setDecimals(2);
  height_box_->setSuffix(QStringLiteral(" m"));
  height_box_->setToolTip(tr("Height z of the lowest slice in the world frame"));
  height_slider_ = new QSlider(Qt::Horizontal, this);
  height_slider_->setObjectName(QStringLiteral("confidence_height_slider"));
  height_slider_->setRange(-50, 200);  // centimetres
  count_box_ = new QSpinBox(this);
  count_box_->setObjectName(QStringLiteral("confidence_count"));
  count_box_->setRange(1, 6);
  spacing_box_ = new QDoubleSpinBox(this);
  spacing_box_->setObjectName(QStringLiteral("confidence_spacing"));
  spacing_box_->setRange(0.02, 0.5);
  spacing_box_->setSingleStep(0.01);
  spacing_box_->setDecimals(2);
  spacing_box_->setSuffix(QStringLiteral(" m"));
  form->addRow(tr("Lowest slice"), height_box_);
  form->addRow(QString(), height_slider_);
  form->addRow(tr("Slices"), count_box_);
  form->addRow(tr("Spacing"), spacing_box_);
  layout->addLayout(form);
  status_label_ = new QLabel(this);
  status_label_->setObjectName(QStringLiteral("confidence_status"));
  status_label_->setWordWrap(true);
  // The panel is as wide as its controls: a status that asked for its own width would widen
  // the dock, and shift the 3D view beside it, each time the text changes while a review plays.
  status_label_->setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Preferred);
  layout->addWidget(status_label_);
  auto* legend_row = new QHBoxLayout();
  legend_row->addWidget(new ConfidenceColourBar(this));
  legend_row->addStretch(1);
  layout->addLayout(legend_row);
  layout->addStretch(1);
  setSettings(ConfidenceSliceSettings{});

  connect(height_slider_, &QSlider::valueChanged, this, [this](int centimetres) {
    if (std::lround(height_box_->value() * 100.0) != centimetres) height_box_->setValue(centimetres / 100.0);
  });
  connect(height_box_, &QDoubleSpinBox::valueChanged, this, [this](double metres) {
    const QSignalBlocker block(height_slider_);
    height_slider_->setValue(static_cast<int>(std::lround(metres * 100.0)));
    Q_EMIT settingsChanged();
  });
  connect(count_box_, &QSpinBox::valueChanged, this, [this] { Q_EMIT settingsChanged(); });
  connect(spacing_box_, &QDoubleSpinBox::valueChanged, this, [this] { Q_EMIT settingsChanged(); });
}

ConfidenceSliceSettings ConfidencePanel::settings() const {
  ConfidenceSliceSettings settings;
  settings.lowest_z = height_box_->value();
  settings.count = count_box_->value();
  settings.spacing = spacing_box_->value();
  return settings;
}

void ConfidencePanel::setSettings(const ConfidenceSliceSettings& settings) {
  {
    const QSignalBlocker a(height_box_);
    const QSignalBlocker b(height_slider_);
    const QSignalBlocker c(count_box_);
    const QSignalBlocker d(spacing_box_);
    height_box_->setValue(settings.lowest_z);
    height_slider_->setValue(static_cast<int>(std::lround(settings.lowest_z * 100.0)));
    count_box_->setValue(settings.count);
    spacing_box_->setValue(settings.spacing);
  }
  Q_EMIT settingsChanged();
}

void ConfidencePanel::setStatus(const QString& text) { status_label_->setText(text); }

}  // namespace flexirob::ui
