#include "ui/parameter_panel.hpp"

#include <QDoubleSpinBox>
#include <QEvent>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>

namespace flexirob::ui {
namespace {

// Enough decimals to show the value with three significant digits.
int decimalsFor(double value) {
  if (value == 0.0) return 3;
  const int digits = static_cast<int>(std::ceil(-std::log10(std::abs(value)))) + 3;
  return std::clamp(digits, 2, 8);
}

}  // namespace

ParameterPanel::ParameterPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  auto* note = new QLabel(tr("Applying restarts the robot with the new values (the taught data of the running session "
                             "stays in its recording)."));
  note->setWordWrap(true);
  layout->addWidget(note);
  form_ = new QFormLayout;
  layout->addLayout(form_);
  auto* apply = new QPushButton(tr("Apply and restart"));
  apply->setObjectName(QStringLiteral("apply_parameters"));
  connect(apply, &QPushButton::clicked, this, [this] { Q_EMIT applyRequested(values()); });
  layout->addWidget(apply);
  layout->addStretch(1);
}

void ParameterPanel::setParameters(const robot::ParameterSet& parameters) {
  while (form_->rowCount() > 0) form_->removeRow(0);
  boxes_.clear();
  for (const robot::ParameterDeclaration& declaration : parameters.declarations()) {
    auto* box = new QDoubleSpinBox;
    const double value = parameters.get(declaration.name);
    box->setDecimals(decimalsFor(value));
    box->setRange(declaration.min_value, declaration.max_value);
    box->setValue(value);
    box->setSingleStep(value != 0.0 ? std::abs(value) * 0.1 : 0.1);
    box->setSuffix(declaration.unit[0] != '\0' ? QStringLiteral(" ") + QString::fromUtf8(declaration.unit) : QString());
    box->setToolTip(QStringLiteral("%1\n[%2, %3], default %4")
                        .arg(QString::fromUtf8(declaration.description))
                        .arg(declaration.min_value)
                        .arg(declaration.max_value)
                        .arg(declaration.default_value));
    box->setObjectName(QString::fromUtf8(declaration.name));
    box->setFocusPolicy(Qt::StrongFocus);  // not focused by the wheel
    box->installEventFilter(this);
    form_->addRow(QString::fromUtf8(declaration.name), box);
    boxes_.emplace_back(declaration.name, box);
  }
}

bool ParameterPanel::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::Wheel) {
    auto* box = qobject_cast<QAbstractSpinBox*>(watched);
    if (box != nullptr && !box->hasFocus()) {
      event->ignore();  // on to the scroll area around the panel
      return true;
    }
  }
  return QWidget::eventFilter(watched, event);
}

std::map<std::string, double> ParameterPanel::values() const {
  std::map<std::string, double> values;
  for (const auto& [name, box] : boxes_) values[name] = box->value();
  return values;
}

QDoubleSpinBox* ParameterPanel::spinBox(const std::string& name) const {
  for (const auto& [box_name, box] : boxes_) {
    if (box_name == name) return box;
  }
  return nullptr;
}

}  // namespace flexirob::ui
