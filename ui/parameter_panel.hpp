#pragma once
// The declared parameters (DESIGN §2: every tunable value has a name, a range and a unit) as
// one spin box each, with the description as tooltip. Values are checked against the declared
// range by the spin boxes; "Apply" hands them to the main window, which restarts the live robot
// with them (the simulation and the workflow read their parameters when they are built).
#include <QWidget>
#include <map>
#include <string>
#include <vector>

#include "robot/parameters.hpp"

class QDoubleSpinBox;
class QFormLayout;

namespace flexirob::ui {

class ParameterPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ParameterPanel(QWidget* parent = nullptr);

  /// Rebuilds the rows for the declarations of `parameters` and shows its values.
  void setParameters(const robot::ParameterSet& parameters);
  /// The values shown now, by name.
  std::map<std::string, double> values() const;
  QDoubleSpinBox* spinBox(const std::string& name) const;

 Q_SIGNALS:
  void applyRequested(const std::map<std::string, double>& values);

 protected:
  /// A wheel turned over a box the operator has not clicked into scrolls the panel instead of
  /// changing the value (a scroll over the list changed sim.gravity unnoticed).
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  QFormLayout* form_ = nullptr;
  std::vector<std::pair<std::string, QDoubleSpinBox*>> boxes_;
};

}  // namespace flexirob::ui
