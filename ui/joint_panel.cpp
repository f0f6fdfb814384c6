#include "ui/joint_panel.hpp"

#include "app/workflow.hpp"

#include <QGridLayout>
#include <QLabel>
#include <QPainter>
#include <QStyleOptionSlider>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace flexirob::ui {

namespace {

// Continuous joints have no limits; the slider then covers one turn each way.
double finiteOr(double value, double fallback) { return std::isfinite(value) ? value : fallback; }

int toSteps(double value) { return static_cast<int>(std::lround(value / LimitSlider::kStep)); }

QString formatValue(double value, bool prismatic) {
  if (prismatic) return QString::number(value, 'f', 3) + QStringLiteral(" m");
  return QString::number(value * 180.0 / std::numbers::pi, 'f', 1) + QStringLiteral("°");
}

}  // namespace

LimitSlider::LimitSlider(const robot::JointLimits& limits, QWidget* parent) : QSlider(Qt::Horizontal, parent) {
  const double lower = finiteOr(limits.lower, -2.0 * std::numbers::pi);
  const double upper = finiteOr(limits.upper, 2.0 * std::numbers::pi);
  setRange(toSteps(lower), toSteps(upper));
  soft_lower_ = toSteps(finiteOr(limits.soft_lower, lower));
  soft_upper_ = toSteps(finiteOr(limits.soft_upper, upper));
  setSingleStep(toSteps(std::numbers::pi / 180.0));
  setPageStep(toSteps(10.0 * std::numbers::pi / 180.0));
  setMinimumWidth(100);
}

void LimitSlider::setValueSi(double value) { setValue(toSteps(value)); }

void LimitSlider::paintEvent(QPaintEvent* event) {
  QSlider::paintEvent(event);
  if (soft_lower_ <= minimum() && soft_upper_ >= maximum()) return;
  // Shade the groove beyond the software limits: the controllers never go there.
  QStyleOptionSlider option;
  initStyleOption(&option);
  const QRect groove = style()->subControlRect(QStyle::CC_Slider, &option, QStyle::SC_SliderGroove, this);
  const QRect handle = style()->subControlRect(QStyle::CC_Slider, &option, QStyle::SC_SliderHandle, this);
  const int span = groove.width() - handle.width();
  const auto xOf = [&](int value) {
    return groove.left() + handle.width() / 2 +
           QStyle::sliderPositionFromValue(minimum(), maximum(), value, span, option.upsideDown);
  };
  QPainter painter(this);
  const QColor zone(210, 40, 30, 150);
  const int top = groove.center().y() - 3;
  if (soft_lower_ > minimum()) painter.fillRect(QRect(QPoint(xOf(minimum()), top), QPoint(xOf(soft_lower_), top + 6)), zone);
  if (soft_upper_ < maximum()) painter.fillRect(QRect(QPoint(xOf(soft_upper_), top), QPoint(xOf(maximum()), top + 6)), zone);
}

LimitDistanceBar::LimitDistanceBar(const robot::Joint& joint, QWidget* parent)
    : QWidget(parent),
      lower_(joint.limits.soft_lower),
      upper_(joint.limits.soft_upper),
      red_margin_(app::nearLimitMargin(joint, app::WorkflowOptions{})) {
  setMinimumWidth(50);
  setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Fixed);
}

void LimitDistanceBar::setValue(double q) {
  const double distance = std::min(q - lower_, upper_ - q);
  if (distance == distance_) return;
  distance_ = distance;
  setToolTip(tr("%1 to the nearest software limit").arg(QString::number(distance_, 'f', 3)));
  update();
}

LimitDistanceBar::Level LimitDistanceBar::level() const {
  if (!std::isfinite(distance_)) return Level::kOk;
  if (distance_ < red_margin_) return Level::kRed;
  if (distance_ < 2.0 * red_margin_) return Level::kAmber;
  return Level::kOk;
}

void LimitDistanceBar::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  const QRect frame = rect().adjusted(0, 2, -1, -3);
  painter.fillRect(frame, QColor(0xe4, 0xe4, 0xe4));
  const double half_range = 0.5 * (upper_ - lower_);
  const double fraction =
      std::isfinite(half_range) && half_range > 0.0 ? std::clamp(distance_ / half_range, 0.0, 1.0) : 1.0;
  QColor colour(0x3a, 0xa0, 0x50);
  if (level() == Level::kAmber) colour = QColor(0xf0, 0xa0, 0x20);
  if (level() == Level::kRed) colour = QColor(0xd0, 0x25, 0x25);
  QRect bar = frame;
  bar.setWidth(std::max(level() == Level::kOk ? 0 : 3, static_cast<int>(frame.width() * fraction)));
  painter.fillRect(bar, colour);
  painter.setPen(QColor(0x88, 0x88, 0x88));
  painter.drawRect(frame);
}

JointPanel::JointPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  auto* title = new QLabel(tr("<b>Joints</b> &nbsp; <small>slider red: beyond the software limits; bar: distance to the nearest software limit, red where a taught posture warns (0.17 rad, 2 cm for a slide, at most a tenth of the range), amber within twice that</small>"), this);
  title->setWordWrap(true);
  layout->addWidget(title);
  grid_ = new QGridLayout;
  layout->addLayout(grid_);
  layout->addStretch(1);
}

void JointPanel::setRobot(const robot::RobotModel& model, const Eigen::VectorXd& q) {
  // Remove the rows of the previous robot.
  while (QLayoutItem* item = grid_->takeAt(0)) {
    delete item->widget();
    delete item;
  }
  sliders_.clear();
  value_labels_.clear();
  bars_.clear();
  prismatic_.clear();
  for (int j = 0; j < model.dof(); ++j) {
    const robot::Joint& joint = model.joints()[static_cast<std::size_t>(j)];
    const bool prismatic = joint.type == robot::JointType::kPrismatic;
    // A long joint name is cut (whole in the tooltip): the row keeps room for its bar.
    const QString full_name = QString::fromStdString(joint.name);
    auto* name = new QLabel(this);
    name->setText(name->fontMetrics().elidedText(full_name, Qt::ElideRight, 110));
    name->setToolTip(full_name);
    auto* slider = new LimitSlider(joint.limits, this);
    // The panel mirrors the live arm, whose posture the backend owns: a slider that could be
    // dragged would move nothing and snap back.
    slider->setEnabled(false);
    auto* value = new QLabel(this);
    value->setMinimumWidth(62);
    value->setAlignment(Qt::AlignRight | Qt::AlignVCenter);
    const QString range = std::isfinite(joint.limits.lower)
                              ? QStringLiteral("[%1, %2]").arg(formatValue(joint.limits.lower, prismatic),
                                                                formatValue(joint.limits.upper, prismatic))
                              : tr("continuous");
    auto* limits = new QLabel(range, this);
    limits->setStyleSheet(QStringLiteral("color: #555"));
    const QString tip = tr("%1: hardware limits %2, software limits [%3, %4]")
                            .arg(QString::fromStdString(joint.name), range,
                                 formatValue(joint.limits.soft_lower, prismatic),
                                 formatValue(joint.limits.soft_upper, prismatic));
    slider->setToolTip(tip);
    limits->setToolTip(tip);
    grid_->addWidget(name, j, 0);
    grid_->addWidget(slider, j, 1);
    grid_->addWidget(value, j, 2);
    grid_->addWidget(limits, j, 3);
    auto* bar = new LimitDistanceBar(joint, this);
    grid_->addWidget(bar, j, 4);
    bars_.push_back(bar);
    sliders_.push_back(slider);
    value_labels_.push_back(value);
    prismatic_.push_back(prismatic);
    connect(slider, &QSlider::valueChanged, this, [this, j] { updateValueLabel(j); });
  }
  grid_->setColumnStretch(1, 1);
  setPosture(q);
}

void JointPanel::setPosture(const Eigen::VectorXd& q) {
  for (int j = 0; j < jointCount() && j < q.size(); ++j) {
    sliders_[static_cast<std::size_t>(j)]->setValueSi(q[j]);
    updateValueLabel(j);
  }
}

Eigen::VectorXd JointPanel::posture() const {
  Eigen::VectorXd q(jointCount());
  for (int j = 0; j < jointCount(); ++j) q[j] = sliders_[static_cast<std::size_t>(j)]->valueSi();
  return q;
}

void JointPanel::updateValueLabel(int joint) {
  const auto j = static_cast<std::size_t>(joint);
  value_labels_[j]->setText(formatValue(sliders_[j]->valueSi(), prismatic_[j]));
  if (j < bars_.size()) bars_[j]->setValue(sliders_[j]->valueSi());
}

}  // namespace flexirob::ui
