#include "ui/joint_panel.hpp"

#include <QGridLayout>
#include <QLabel>
#include <QPainter>
#include <QPushButton>
#include <QStyleOptionSlider>
#include <QVBoxLayout>
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
  setMinimumWidth(160);
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

JointPanel::JointPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  auto* title = new QLabel(tr("<b>Joints</b> &nbsp; <small>red: beyond the software limits</small>"), this);
  layout->addWidget(title);
  grid_ = new QGridLayout;
  layout->addLayout(grid_);
  auto* home = new QPushButton(tr("Home posture"), this);
  home->setToolTip(tr("Back to the start posture of robot and scene"));
  connect(home, &QPushButton::clicked, this, [this] {
    setPosture(home_);
    emit postureChanged(posture());
  });
  layout->addWidget(home);
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
  prismatic_.clear();
  home_ = q;
  for (int j = 0; j < model.dof(); ++j) {
    const robot::Joint& joint = model.joints()[static_cast<std::size_t>(j)];
    const bool prismatic = joint.type == robot::JointType::kPrismatic;
    auto* name = new QLabel(QString::fromStdString(joint.name), this);
    auto* slider = new LimitSlider(joint.limits, this);
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
    sliders_.push_back(slider);
    value_labels_.push_back(value);
    prismatic_.push_back(prismatic);
    connect(slider, &QSlider::valueChanged, this, [this, j] {
      updateValueLabel(j);
      if (!updating_) emit postureChanged(posture());
    });
  }
  grid_->setColumnStretch(1, 1);
  setPosture(q);
}

void JointPanel::setPosture(const Eigen::VectorXd& q) {
  updating_ = true;
  for (int j = 0; j < jointCount() && j < q.size(); ++j) {
    sliders_[static_cast<std::size_t>(j)]->setValueSi(q[j]);
    updateValueLabel(j);
  }
  updating_ = false;
}

Eigen::VectorXd JointPanel::posture() const {
  Eigen::VectorXd q(jointCount());
  for (int j = 0; j < jointCount(); ++j) q[j] = sliders_[static_cast<std::size_t>(j)]->valueSi();
  return q;
}

void JointPanel::updateValueLabel(int joint) {
  const auto j = static_cast<std::size_t>(joint);
  value_labels_[j]->setText(formatValue(sliders_[j]->valueSi(), prismatic_[j]));
}

}  // namespace flexirob::ui
