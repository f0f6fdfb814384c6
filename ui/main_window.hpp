#pragma once
// The operator's main window (issue #7): the 3D view in the centre mirroring the live robot at
// display rate; docks with the stage panel (four buttons, stage, learning, warnings), the joints
// (posture and distance to the limits) and the declared parameters; menus for robot, scene,
// backend and sessions; keyboard tele-operation and mouse perturbation of the arm in the view.
//
// The live robot (LiveTeaching: backend + workflow in a 1 kHz worker) is rebuilt when the robot,
// the scene, the backend or the parameters change. Every run is recorded into a session file
// (File ▸ Save session as… keeps a copy); the window's layout is remembered (QSettings).
#include <QMainWindow>
#include <QElapsedTimer>
#include <QPointer>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "app/backend_factory.hpp"
#include "render/overlays.hpp"
#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "robot/parameters.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"
#include "ui/live_teaching.hpp"
#include "ui/teleop_keys.hpp"

class QColor;
class QLabel;
class QMenu;
class QTimer;
class QAction;
class QDockWidget;

namespace flexirob::app {
class SessionRecorder;
}

namespace flexirob::ui {

class JointPanel;
class OsgView;
class StagePanel;
class ParameterPanel;
class MousePerturbation;
class ForceArrow;
class ConvergedChime;
class PlotPanel;
class ConfidencePanel;
class ConfidenceColourBar;
class ReviewWindow;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  struct Options {
    std::string backend = "sim";  ///< "sim" or "fri://HOST:PORT"
    bool record_sessions = true;  ///< record every run into a session file
    bool restore_layout = true;   ///< restore the window layout of the last run (QSettings)
    /// The robot and scene named in the constructor, already read by the caller (the command
    /// line checks them before a window opens): shown without reading their files again.
    std::optional<robot::RobotModel> robot_read;
    std::optional<robot::Scene> scene_read;
  };

  /// robot: built-in name or URDF path; scene: built-in name or scene file ("" = empty).
  /// Failures are reported in the status bar (the window then starts without robot or with the
  /// empty scene) rather than thrown.
  MainWindow(const std::string& robot, const std::string& scene, QWidget* parent = nullptr);
  MainWindow(const std::string& robot, const std::string& scene, const Options& options, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Loads a robot (built-in name or URDF path). Returns false and shows why on failure; the
  /// previous robot stays.
  bool loadRobot(const std::string& name_or_path);
  /// Shows a robot readRobot() has read from `name_or_path`.
  bool loadRobot(const std::string& name_or_path, robot::RobotModel read);
  /// Loads a scene (built-in name or file). Returns false and shows why on failure (the arm
  /// before runs on). Without `start_live` the arm is left stopped after a scene that loaded,
  /// for a robot to follow (chooseScene).
  bool loadScene(const std::string& name_or_path, bool start_live = true);
  /// Shows a scene readScene() has read from `name_or_path`.
  bool loadScene(const std::string& name_or_path, robot::Scene read, bool start_live = true);
  /// The Scene menu's choice: the scene, and its own robot where the loaded one cannot take its
  /// postures.
  void chooseScene(const std::string& name);
  /// Whether loading `what` (a robot or scene, named for the question) may discard what was
  /// taught in this window: true at once where nothing was, else the person's answer.
  bool mayDiscardTeaching(const QString& what);
  /// What loadRobot() and loadScene() read, without a window: throws with the reason the robot
  /// or scene cannot be shown (the command line refuses such an argument before a window opens).
  static robot::RobotModel readRobot(const std::string& name_or_path);
  static robot::Scene readScene(const std::string& name_or_path);
  /// Switches the backend ("sim" or "fri://HOST:PORT"); false and the reason shown on failure.
  bool setBackend(const std::string& choice);

  /// Takes the newest snapshot of the live robot into the view and the panels (the display
  /// timer calls it; tests call it to avoid waiting).
  void mirror();

  OsgView* view() const { return view_; }
  JointPanel* jointPanel() const { return joint_panel_; }
  StagePanel* stagePanel() const { return stage_panel_; }
  ParameterPanel* parameterPanel() const { return parameter_panel_; }
  LiveTeaching* live() const { return live_.get(); }
  MousePerturbation* perturbation() const { return perturbation_.get(); }
  ForceArrow* forceArrow() const { return force_arrow_.get(); }
  QLabel* keyMapLabel() const { return key_map_label_; }
  QLabel* bannerLabel() const { return banner_label_; }
  /// Where runs are recorded: $XDG_DATA_HOME/flexirob/sessions (~/.local/share/flexirob/sessions).
  static QString sessionDirectory();
  /// The problems the view shows (a robot, scene or backend that could not be used); hidden if none.
  QLabel* problemLabel() const { return problem_label_; }
  render::World& world() { return world_; }
  render::Overlays& overlays() { return *overlays_; }
  const robot::RobotModel* robotModel() const { return model_.get(); }
  const robot::Kinematics* kinematics() const { return kinematics_.get(); }
  const robot::Scene& scene() const { return scene_; }
  const robot::ParameterSet& parameters() const { return *parameters_; }
  QMenu* teachingMenu() const { return teaching_menu_; }
  QMenu* robotMenu() const { return robot_menu_; }
  QMenu* sceneMenu() const { return scene_menu_; }
  QMenu* backendMenu() const { return backend_menu_; }
  /// The status bar's link line (backend, FRI state and quality; red on a fault).
  QLabel* linkLabel() const { return link_label_; }
  /// "Confirm reconnect after a fault": enabled only while the watchdog holds the robot.
  QAction* reconnectAction() const { return reconnect_action_; }
  /// The session file the current run records into (empty when not recording).
  QString sessionFile() const { return session_file_; }
  /// on_converged acknowledgements played so far.
  int chimes() const { return chimes_; }
  /// Frames per second of the 3D view over the last seconds (0 before the first second).
  double framesPerSecond() const { return fps_; }
  /// Frames of the 3D view per second since the window started mirroring the robot.
  double meanFramesPerSecond() const;

  /// Shows (or hides) the key map over the view.
  void toggleKeyMap(bool visible);

  /// Writes everything the run recorded so far to `file` (".flexirob" added to a name without
  /// a suffix) and goes on recording the whole run into sessionFile(); File ▸ Save session
  /// writes it there again, and closing the window asks first when the teaching changed since.
  /// The recording holds the states at display rate, the stages, triggers, buttons, areas with
  /// their samples and ITM snapshots.
  bool saveSession(const QString& file);
  /// The file the last saveSession() wrote (empty: none yet).
  QString savedSessionFile() const { return saved_session_file_; }
  /// Whether areas or teach-ins changed since the last saveSession() (false before one).
  bool teachingChangedSinceSave() const;

  /// Opens a session recording in a review window of its own (File ▸ Open recording…). Null
  /// and the reason in the status bar if the file is no readable recording.
  ReviewWindow* openRecording(const QString& file);
  /// The review windows opened and still open.
  std::vector<ReviewWindow*> reviewWindows() const;

  /// EXECUTION: sets `goal_W` [m] as the goal, draws it and asks the workflow to plan through
  /// the ITM graph and execute (Sect. 7.4). Outside EXECUTION the workflow refuses and the
  /// reason shows as a warning. False if the request could not be posted.
  bool setGoal(const Eigen::Vector3d& goal_W);
  /// [m] of the goal's marker: 2.5 cm on the LWR IV, less on a smaller robot.
  double goalMarkerRadius() const;
  /// A Ctrl+click at widget position `position` of the view: the goal under it (ui/goal_picking).
  void clickGoal(const QPointF& position);
  /// The goal set last (none before the first).
  const std::optional<Eigen::Vector3d>& goal() const { return goal_; }

  PlotPanel* plotPanel() const { return plot_panel_; }
  ConfidencePanel* confidencePanel() const { return confidence_panel_; }
  /// The colour-map legend drawn over the view while confidence slices are shown.
  QWidget* confidenceLegend() const;
  /// Slices of the confidence field drawn now (0 without a confidence model or when hidden).
  int confidenceSlicesShown() const { return confidence_slices_; }

 protected:
  void keyPressEvent(QKeyEvent* event) override;
  void keyReleaseEvent(QKeyEvent* event) override;
  void closeEvent(QCloseEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;
  void focusOutEvent(QFocusEvent* event) override;

 private:
  void buildMenus();
  /// The Teaching menu from the Teaching panel's controls as they are now (run as it opens).
  void fillTeachingMenu();
  bool saveSessionAs();  // File ▸ Save session as…: the dialog, then saveSession()
  // File ▸ Save session: saveSession() into the file saved last, or the dialog where there is
  // none, or where that file holds a recording that ended (the rest would replace it).
  bool saveSessionAgain();
  void buildDocks();
  void updateStatus();
  void reportError(const QString& what, const std::exception& error);
  /// What keeps the window from doing what was asked: a robot, a scene or a backend that could
  /// not be used. Shown whole in the view until that kind of thing is next loaded.
  enum class Problem { kRobot, kRobotNotes, kScene, kSceneNotes, kPostures, kStartContact, kBackend, kDeadlines, kRecording };
  void reportProblem(Problem kind, const QString& message);
  void clearProblem(Problem kind);
  /// The notes the CLI prints on stderr, shown in the view under `kind` (cleared when none).
  void showNotes(Problem kind, const std::vector<std::string>& notes);
  void showProblems();
  void refuseScene(const std::string& name_or_path, const std::exception& error);
  void refuseRobot(const std::string& name_or_path, const std::exception& error);
  /// Checks the Robot and Scene menus' entries of what is loaded (after a choice taken back).
  void markLoadedChoices();
  /// Points the home camera at the robot from a side obstacles do not hide it from, or draws
  /// those that hide it from every side see-through.
  void frameView();
  /// Says in the view when most control cycles of the last seconds were late.
  void watchDeadlines(const app::CycleStatistics& stats);
  /// Says in the view when the run's file failed and the recording goes on in memory only.
  void watchRecording();
  /// Ends the run's recording (stop, save, close); one no file holds joins unsaved_recordings_.
  void endRecording();
  /// Whether some of what this run recorded is held in memory only, and why (one line).
  bool recordingAtRisk() const;
  QString recordingAtRiskReason() const;
  /// Stops the live robot and closes its session (before model or scene change).
  void stopLive();
  /// Builds and starts the live robot for the current model, scene, backend and parameters.
  void startLive();
  void startRecording();
  void handleEvents();
  /// Rebuilds the overlays whose data changed (areas, ghosts, teach-ins, ITM graph).
  void updateOverlays(const LiveSnapshot& snapshot);
  void driveKeyboard();
  void showBanner(const QString& warning);
  void showNoRobotBanner();
  /// The banner's text and colour; `key` tells showBanner's callers what it shows.
  void setBanner(const QString& text, const QColor& colour, const QString& key);
  /// Whether the live robot has sent a state (always for the simulation; an FRI link may wait).
  bool robotMeasured() const;
  void applyParameters(const std::map<std::string, double>& values);
  void resetParameters();
  void updatePlots(const LiveSnapshot& snapshot);
  /// Rebuilds the confidence slices when the model or the heights changed (or `force`).
  void updateConfidence(const LiveSnapshot& snapshot, bool force);
  void updateGoalAndPath(const LiveSnapshot& snapshot);
  /// Takes the goal and its path out of the view (left EXECUTION, or the plan was refused).
  void clearGoal();
  void placeViewLabels();
  /// Records the ITM graph into the session when it changed (at most once per second, and at the end).
  void recordItm(const LiveSnapshot& snapshot, bool final);
  /// The learned model, once per version, as teach records it (the control thread records the
  /// rest; serializing a model is no work for its cycle).
  void recordModel(const LiveSnapshot& snapshot);
  /// The graph and the model as they stand, before the file is closed, copied or opened.
  void recordSnapshotData(const LiveSnapshot& snapshot);

  Options options_;
  render::World world_;
  std::unique_ptr<robot::RobotModel> model_;
  std::unique_ptr<robot::Kinematics> kinematics_;
  robot::Scene scene_;
  std::string loaded_robot_, loaded_scene_;  ///< as named when loaded (menu entries' data)
  robot::Scene live_scene_;  ///< scene_ as the live robot runs in it (sceneFitFor); outlives live_
  std::vector<robot::ParameterDeclaration> declarations_;
  std::unique_ptr<robot::ParameterSet> parameters_;
  std::map<std::string, double> parameter_edits_;  // operator's values, applied after scene overrides
  app::BackendChoice backend_;
  std::unique_ptr<app::SessionRecorder> recorder_;
  std::unique_ptr<LiveTeaching> live_;
  QString session_file_;
  QString saved_session_file_;
  bool saved_session_ended_a_recording_ = false;  // the file holds a recording the run left
  // Recordings of this run that ended held in memory only (their file failed or was removed),
  // oldest first: Save session copies them one by one, and closing the window asks for them.
  std::vector<std::unique_ptr<app::SessionRecorder>> unsaved_recordings_;
  std::uint64_t saved_areas_version_ = 0, saved_teach_ins_version_ = 0;
  std::uint64_t shown_cycle_ = ~0ULL;
  int chimes_ = 0;

  OsgView* view_ = nullptr;
  JointPanel* joint_panel_ = nullptr;
  StagePanel* stage_panel_ = nullptr;
  ParameterPanel* parameter_panel_ = nullptr;
  QLabel* key_map_label_ = nullptr;
  QLabel* banner_label_ = nullptr;
  QLabel* problem_label_ = nullptr;
  std::map<Problem, QString> problems_;
  QLabel* status_label_ = nullptr;
  QLabel* link_label_ = nullptr;
  QMenu* teaching_menu_ = nullptr;
  QMenu* robot_menu_ = nullptr;
  QMenu* scene_menu_ = nullptr;
  QMenu* backend_menu_ = nullptr;
  QAction* reconnect_action_ = nullptr;
  QTimer* display_timer_ = nullptr;
  std::unique_ptr<MousePerturbation> perturbation_;
  std::unique_ptr<ForceArrow> force_arrow_;
  std::unique_ptr<ConvergedChime> chime_;
  TeleopKeys teleop_;
  bool keyboard_mode_ = false;
  QElapsedTimer key_clock_;
  void rememberForStandingWarnings(const LiveEvent& event);
  void showWarnings();
  /// The newest warning, or a request's refusal (the workflow's, or one the window refuses
  /// itself): in the warning box, the banner and the status bar, named by its button
  /// (`text` as "replay: ..." is worded, operatorWording).
  void showLastWarning(const QString& text, bool refused);
  std::vector<app::WorkflowEvent> standing_warning_events_;  ///< read by app::standingWarnings()
  QPointer<QWidget> focus_before_menu_;  ///< where the keys go back to when a menu closes
  bool replay_moving_ = false;  ///< a replay accepted and not yet ended
  double replay_time_ = 0.0;     ///< [s] robot time it was accepted at
  QString replay_name_;          ///< "teach-in k", as the workflow names it
  QString last_warning_;
  bool last_warning_refused_ = false;  ///< last_warning_ is a refused request's reason
  QElapsedTimer deadline_clock_;
  std::uint64_t deadline_cycles_ = 0, deadline_misses_ = 0;
  bool start_checked_ = false;  ///< whether the live arm's first state was checked for contacts
  QElapsedTimer fps_clock_;
  long fps_frames_ = 0;
  QElapsedTimer run_clock_;  // since the first mirrored frame
  long run_first_frame_ = 0;
  double fps_ = 0.0;
  std::vector<std::string> coloured_links_;
  std::unique_ptr<render::Overlays> overlays_;
  std::uint64_t shown_areas_version_ = ~0ULL, shown_teach_ins_version_ = ~0ULL, shown_itm_version_ = ~0ULL;
  int shown_chosen_area_ = -1;
  QString status_fields_owner_;  // the robot and scene the status fields' width was grown for
  std::uint64_t shown_model_version_ = ~0ULL, shown_path_version_ = ~0ULL, recorded_itm_version_ = ~0ULL;
  // The model last recorded: a new area raises the model version (its confidence changed)
  // without a new model, so the object, not the version, says whether it was recorded.
  std::shared_ptr<const flexirob::learning::Learner> recorded_model_;
  PlotPanel* plot_panel_ = nullptr;
  QElapsedTimer plot_clock_;
  ConfidencePanel* confidence_panel_ = nullptr;
  ConfidenceColourBar* confidence_legend_ = nullptr;
  int confidence_slices_ = 0;
  bool operator_heights_ = false;  // the operator chose the slice heights: no automatic centring
  std::optional<Eigen::Vector3d> goal_;
  bool goal_moving_ = false;  // a plan to goal_ was accepted and its motion has not ended
  double goal_plan_time_ = 0.0;  // [s] robot time the plan to goal_ was accepted
  QElapsedTimer itm_record_clock_;
  std::size_t recorded_itm_bytes_ = 0;  ///< size of the last ITM snapshot recorded
  std::vector<QPointer<ReviewWindow>> reviews_;
};

}  // namespace flexirob::ui
