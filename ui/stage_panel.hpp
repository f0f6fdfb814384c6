#pragma once
// The stage panel (thesis Sect. 2.3, Fig. 2.5 and 2.8): the four buttons of the teaching
// procedure, enabled only when the workflow would accept them; the current stage and sub-stage
// in large, colour-coded letters (APPROACHING amber, RECORDING red, TEACH-IN magenta, EXECUTION
// blue, ...); a progress bar while the redundancy resolution is learned; the latest tutor
// warning; counts of areas, teach-ins and triggers; what to do next, in words; the replay of a
// teach-in in EXECUTION; an area chosen by name removed or recorded again (Sect. 4.4: a tutor
// undoes an area that made the map worse). The panel only shows a LiveSnapshot and
// emits the button the operator pressed; it owns no workflow.
#include <QWidget>

#include <cstdint>

#include "app/workflow.hpp"
#include "ui/live_teaching.hpp"

class QComboBox;
class QLabel;
class QScrollArea;
class QProgressBar;
class QPushButton;
class QSpinBox;

namespace flexirob::ui {

/// A workflow message as the operator reads it: a leading request name ("finished_configuration:",
/// "plan:") becomes what the operator pressed ("Finish configuration:", "Goal:"); the rest stays.
QString operatorWording(const QString& message);

/// A button signal as a session records it ("remove_area 0", "start_programming") in the
/// operator's words ("Remove area: area 1", "Start programming"): areas counted from 1, as the
/// Teaching panel counts them.
QString operatorSignalName(const std::string& recorded);

/// The Teaching panel's warning box: every warning about an area or the map that still stands
/// (app::standingWarnings over `events`, with the pose being recorded), then `last`, the newest warning or refusal, unless it
/// is one of them; one per line, bulleted when there are several. Empty when none stands.
QString standingWarningText(const std::vector<app::WorkflowEvent>& events, const QString& last);

class StagePanel : public QWidget {
  Q_OBJECT

 public:
  explicit StagePanel(QWidget* parent = nullptr);

  /// Shows the state of `snapshot` (cheap when nothing changed; called at display rate).
  /// Without a measurement of the robot yet (`robot_measured` false: an FRI link waiting for
  /// the arm) every button is disabled: the workflow would teach on a posture never measured.
  /// `hand_can_pull`: the mouse can pull the arm (a simulation), which the next-step hint says.
  void showSnapshot(const LiveSnapshot& snapshot, bool robot_measured = true, bool hand_can_pull = true);
  /// No robot runs (it could not be loaded or started): every button disabled, and why.
  void showNoRobot(const QString& reason);
  /// A tutor warning or a refused request, shown until the next one or until cleared.
  void showWarning(const QString& text);
  void clearWarning();
  /// What the last learning said (learner, areas, samples, time), shown under the counts while
  /// the map is learned: the status bar's message of it is soon replaced (by the transition
  /// check's warning). Empty: none yet (a new robot or scene).
  void setModelSummary(const QString& text);
  QLabel* countsLabel() const { return counts_label_; }

  QPushButton* button(app::Button button) const;
  QLabel* stageLabel() const { return stage_label_; }
  QLabel* warningLabel() const { return warning_label_; }
  /// The warning box's own scroll area: at most kWarningLines lines tall, scrolled to the end.
  QScrollArea* warningScroll() const { return warning_scroll_; }
  static constexpr int kWarningLines = 10;
  QProgressBar* learningBar() const { return learning_bar_; }
  QLabel* hintLabel() const { return hint_label_; }
  QPushButton* replayButton() const { return replay_button_; }
  QSpinBox* replayChoice() const { return replay_choice_; }
  QComboBox* areaChoice() const { return area_choice_; }
  QPushButton* removeAreaButton() const { return remove_area_button_; }
  QPushButton* reteachAreaButton() const { return reteach_area_button_; }
  /// The area the area controls name, 0-based (-1: none taught).
  int chosenArea() const;
  /// The teach-in the replay control names, 0-based (the newest unless the operator chose).
  int chosenTeachIn() const;

  /// Background and text colour of a stage / sub-stage (also used by the view's banner).
  static QColor stageColor(app::Stage stage, app::SubStage sub_stage);
  static QString stageText(app::Stage stage, app::SubStage sub_stage);
  /// What the operator does next, in one or two sentences: a novice in WAITING is told to
  /// touch the arm, and how (the mouse when `hand_can_pull`, the keys in keyboard mode).
  static QString nextStepHint(const LiveSnapshot& snapshot, bool hand_can_pull);

 Q_SIGNALS:
  void buttonPressed(app::Button button);
  /// The operator asked to replay teach-in `teach_in` (0-based) in EXECUTION.
  void replayRequested(int teach_in);
  /// The operator asked to remove area `area` (0-based), or to record it again.
  void removeAreaRequested(int area);
  void reteachAreaRequested(int area);

 protected:
  void resizeEvent(QResizeEvent* event) override;

 private:
  /// Keeps the hint as tall as the longest hint needs at the panel's width, so that the buttons
  /// under it stay where the operator's hand is as the hint changes.
  void reserveHintHeight();

  int hint_reserved_for_width_ = -1;
  QPushButton* buttons_[4] = {};
  QLabel* stage_label_ = nullptr;
  QLabel* controller_label_ = nullptr;
  QLabel* counts_label_ = nullptr;
  QString model_summary_;
  QLabel* warning_label_ = nullptr;
  QScrollArea* warning_scroll_ = nullptr;
  /// The warning box as tall as its text, up to kWarningLines lines, its end in view.
  void fitWarningBox();
  QProgressBar* learning_bar_ = nullptr;
  QLabel* hint_label_ = nullptr;
  QSpinBox* replay_choice_ = nullptr;
  QPushButton* replay_button_ = nullptr;
  int shown_teach_ins_ = 0;
  QComboBox* area_choice_ = nullptr;
  QPushButton* remove_area_button_ = nullptr;
  QPushButton* reteach_area_button_ = nullptr;
  std::uint64_t shown_areas_version_ = ~0ULL;
  QString shown_stage_;
};

}  // namespace flexirob::ui
