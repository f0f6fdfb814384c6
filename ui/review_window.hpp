#pragma once
// The review window (issue #8 item 3): a session recording (app/session_reader.hpp) replayed.
// A timeline with the stage bands and the trigger and button markers, play/pause, a speed
// (reverse included) and frame stepping; the arm replayed in a 3D view with the overlays of that
// moment (training samples recorded so far, the areas' q_fixed ghosts, teach-in and target
// trajectories, colliding links in red, the ITM graph of the last snapshot recorded before the
// moment, and slices of the confidence field C(x) of the areas completed by then, Fig. 6.5);
// the plots (ui/plot_panel.hpp) share the time cursor.
//
// Opening reads only the recording's ends, its events and ~2000 states picked through the time
// index (SessionReader::stateAt), so a 30-minute recording opens in well under 2 s and
// scrubbing reads one state per displayed frame.
//
// Started by `flexirob --review FILE` (ui/main.cpp) or from the main window's File menu.
#include <QKeyEvent>
#include <QMainWindow>
#include <QThread>
#include <QWidget>

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "render/world.hpp"
#include "robot/collision.hpp"
#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"

namespace flexirob::app {
class SessionReader;
}

class QComboBox;
class QLabel;
class QPushButton;
class QTimer;

namespace flexirob::ui {

class OsgView;
class PlotPanel;
class ConfidencePanel;

/// A stretch of session time spent in one stage (and sub-stage).
struct StageBand {
  double t0 = 0.0;
  double t1 = 0.0;
  std::string label;  ///< "STAGE" or "STAGE / SUB_STAGE"
};

/// A trigger (drawn as a tick above the bands) or a button press (a triangle below).
struct TimelineMarker {
  double time = 0.0;
  bool trigger = true;
  std::string name;
};

/// Colour of a stage band: fixed for the workflow's stages, a stable hue for any other name.
QColor stageColor(const std::string& label);

/// The time strip: stage bands, markers (triggers above, buttons below) and the cursor; clicking
/// and dragging scrubs (timeRequested).
class Timeline : public QWidget {
  Q_OBJECT

 public:
  explicit Timeline(QWidget* parent = nullptr);

  void setRange(double t0, double t1);
  void setBands(std::vector<StageBand> bands);
  void setMarkers(std::vector<TimelineMarker> markers);
  void setTime(double time);
  double time() const { return time_; }
  double t0() const { return t0_; }
  double t1() const { return t1_; }
  /// The widget x coordinate of a time, and back.
  double xOf(double time) const;
  double timeAt(double x) const;
  /// What lies under widget x, as the tooltip says it: the stage band with its start, end and
  /// length, and the triggers and buttons within a few pixels. A band too short for its label
  /// is read this way.
  QString describeAt(double x) const;
  QSize sizeHint() const override { return {600, 56}; }

 Q_SIGNALS:
  void timeRequested(double time);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;

 private:
  double t0_ = 0.0;
  double t1_ = 1.0;
  double time_ = 0.0;
  std::vector<StageBand> bands_;
  std::vector<TimelineMarker> markers_;
};

/// The stage's name beside the playback controls, cut to the room they leave (review_window.cpp).
class StageLabel;

class ReviewWindow : public QMainWindow {
  Q_OBJECT

 public:
  /// One displayed frame of the recording when stepping [s] (30 frames per second).
  static constexpr double kFrameSeconds = 1.0 / 30.0;

  explicit ReviewWindow(QWidget* parent = nullptr);
  ~ReviewWindow() override;

  /// Opens a recording. On failure returns false, keeps what was open and leaves the one-line
  /// reason in errorString() (and the status bar).
  bool open(const std::filesystem::path& file);
  const QString& errorString() const { return error_; }
  /// Why the open file is damaged (SQLite's quick check), empty when it is not; a damaged file
  /// is still shown as far as it can be read.
  const QString& damage() const { return damage_; }
  /// Whether a damage check of an opened file is still reading it.
  bool checkingForDamage() const { return !damage_checks_.empty(); }
  bool isOpen() const { return reader_ != nullptr; }

  /// Shows the recording at `time` (clamped to the recording).
  void setTime(double time);
  double time() const { return time_; }
  void play();
  void pause();
  bool playing() const;
  /// Playback speed, a multiple of real time; negative plays backwards (not 0).
  void setSpeed(double speed);
  double speed() const { return speed_; }
  /// Moves by `frames` frames of kFrameSeconds (negative: back); pauses playback.
  void stepFrames(int frames);

  /// The posture shown now (empty before a recording is open).
  const Eigen::VectorXd& shownPosture() const { return shown_q_; }
  /// The links drawn red: in a contact recorded lately, or touching something in the posture shown.
  const std::vector<std::string>& linksShownInContact() const { return shown_collisions_; }
  /// The stage band at the current time (empty label if none).
  std::string stageAt(double time) const;

  Timeline* timeline() const { return timeline_; }
  PlotPanel* plots() const { return plots_; }
  OsgView* view() const { return view_; }
  render::World& world() { return *world_; }
  const app::SessionReader* reader() const { return reader_.get(); }
  const robot::RobotModel* robotModel() const { return model_.get(); }
  ConfidencePanel* confidencePanel() const { return confidence_panel_; }
  /// ITM snapshots kept from the recording (thinned to at most kMaxItmSnapshots), and nodes drawn now.
  int itmSnapshots() const;
  int itmNodesShown() const;
  /// Confidence slices drawn now (0 before the first area is complete).
  int confidenceSlicesShown() const { return confidence_slices_; }

  static constexpr int kMaxItmSnapshots = 240;

 protected:
  /// Space plays and pauses, Left / Right step a frame (with Shift a second), Home / End go to
  /// the recording's start and end.
  void keyPressEvent(QKeyEvent* event) override;

 private:
  void advance();
  void updateOverlays();
  void updateItm();
  void checkForDamage(const std::filesystem::path& file);
  void updateConfidence(bool force);
  void updateLabels();

  std::unique_ptr<render::World> world_;
  std::unique_ptr<app::SessionReader> reader_;
  std::pair<double, double> span_{0.0, 0.0};  ///< [s] first and last time the recording holds (SessionReader::recordedTimeSpan)
  std::unique_ptr<robot::RobotModel> model_;
  std::unique_ptr<robot::Kinematics> kinematics_;
  /// The recorded scene with the recorded arm: which links touch something in the posture shown
  /// (the recording holds a contact's start, not how long the arm stayed in it).
  std::unique_ptr<robot::CollisionWorld> collision_world_;
  struct Events;  // the recording's events, read once when opened
  std::unique_ptr<Events> events_;
  std::vector<StageBand> bands_;

  OsgView* view_ = nullptr;
  Timeline* timeline_ = nullptr;
  PlotPanel* plots_ = nullptr;
  QPushButton* play_button_ = nullptr;
  QComboBox* speed_box_ = nullptr;
  QLabel* time_label_ = nullptr;
  StageLabel* stage_label_ = nullptr;
  QTimer* timer_ = nullptr;
  QString error_;
  QString damage_;
  std::vector<QThread*> damage_checks_;  ///< quick checks still running (checkForDamage)

  double time_ = 0.0;
  double speed_ = 1.0;
  qint64 last_tick_ms_ = -1;
  Eigen::VectorXd shown_q_;
  // What the overlays show now, to rebuild them only when the moment's content changes.
  std::size_t shown_samples_ = static_cast<std::size_t>(-1);
  std::size_t shown_areas_ = static_cast<std::size_t>(-1);
  std::size_t shown_trajectories_ = static_cast<std::size_t>(-1);
  std::vector<std::string> shown_collisions_;
  std::ptrdiff_t shown_itm_ = -2;
  std::size_t shown_confidence_areas_ = static_cast<std::size_t>(-1);
  ConfidencePanel* confidence_panel_ = nullptr;
  int confidence_slices_ = 0;
  bool operator_heights_ = false;
};

}  // namespace flexirob::ui
