#include "ui/main_window.hpp"

#include <set>

#include <QAction>
#include <QPushButton>
#include <QActionGroup>
#include <QApplication>
#include <QCloseEvent>
#include <QDateTime>
#include <QDir>
#include <QComboBox>
#include <QDockWidget>
#include <QResizeEvent>
#include <QFile>
#include <QFileDialog>
#include <QFileInfo>
#include <QFontMetrics>
#include <QInputDialog>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QScreen>
#include <QProxyStyle>
#include <QStyle>
#include <QScrollArea>
#include <QSpinBox>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QThread>
#include <QTimer>
#include <QVBoxLayout>
#include <osg/Version>
#include <algorithm>
#include <functional>
#include <cmath>
#include <fstream>
#include <sstream>

#include "app/evaluation.hpp"
#include "app/mesh_digest.hpp"
#include "app/session_recorder.hpp"
#include "app/workflow_session.hpp"
#include "learning/confidence.hpp"
#include "planning/itm_file.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/sim/reach.hpp"
#include "ui/confidence_panel.hpp"
#include "ui/converged_chime.hpp"
#include "ui/goal_picking.hpp"
#include "ui/joint_panel.hpp"
#include "ui/live_teaching.hpp"
#include "ui/mouse_perturbation.hpp"
#include "ui/osg_view.hpp"
#include "ui/overlay_menu.hpp"
#include "ui/parameter_panel.hpp"
#include "ui/plot_panel.hpp"
#include "ui/review_window.hpp"
#include "ui/stage_panel.hpp"
#include "ui/status_message.hpp"

#ifndef FLEXIROB_VERSION_STRING
#define FLEXIROB_VERSION_STRING "unknown"
#endif

namespace flexirob::ui {
namespace {

constexpr int kDisplayPeriodMs = 16;  // ~60 Hz mirror
constexpr int kPlotPeriodMs = 200;    // plots take a sample every 200 ms (5 Hz: smooth, cheap to redraw)
constexpr qint64 kItmRecordPeriodMs = 1000;  // ITM snapshots at most once a second, rarer as it grows (app::itmSnapshotPeriod)
// The chosen area's ghost is more opaque than the others' (0.30) yet lets the arm show through;
// its samples are drawn larger than the default 5 px.
constexpr float kChosenGhostAlpha = 0.45F;
constexpr float kChosenSampleSizePx = 9.0F;

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Eigen::Vector4f collisionColour() { return {0.90F, 0.10F, 0.10F, 1.0F}; }

// The posture shown before the live robot reports: where teaching starts, or the middle of the
// limits where no collision world can be built for the robot and scene (starting the live robot
// then reports why, in the GUI).
// The scene as the robot can run in it (app::fitSceneToRobot), and what was left out of it.
robot::Scene sceneFitFor(const robot::Scene& scene, const robot::RobotModel& model, QString* problem) {
  app::FittedScene fitted = app::fitSceneToRobot(scene, model);
  QStringList lines;
  for (const std::string& reason : fitted.left_out) {
    if (lines.isEmpty() && fitted.other_joint_count > 0) {
      // A scene made for another arm: the scenes made for this one are the way out.
      QStringList made_for_this;
      for (const std::string& name : robot::builtinSceneNames()) {
        try {
          if (robot::loadScene(name).robot == model.name()) made_for_this << QString::fromStdString(name);
        } catch (const std::exception&) {
          // A built-in scene that does not read is no suggestion.
        }
      }
      lines << QCoreApplication::translate("MainWindow", "%1; %2 not used, the arm starts free%3")
                   .arg(QString::fromStdString(reason),
                        fitted.other_joint_count == 1 ? QCoreApplication::translate("MainWindow", "that posture is")
                                                      : QCoreApplication::translate("MainWindow", "those postures are"),
                        made_for_this.isEmpty() ? QString()
                                                : QCoreApplication::translate("MainWindow", " (made for it: Scene ▸ %1)")
                                                      .arg(made_for_this.join(QStringLiteral(", "))));
      continue;
    }
    lines << QCoreApplication::translate("MainWindow", "%1; that posture is not used").arg(QString::fromStdString(reason));
  }
  *problem = lines.join(QLatin1Char('\n'));
  return std::move(fitted.scene);
}

Eigen::VectorXd shownHomePosture(const robot::RobotModel& model, const robot::Scene& scene) {
  QString problem;
  try {
    return app::homePosture(model, sceneFitFor(scene, model, &problem));
  } catch (const std::exception&) {
    return model.midPosture();
  }
}

}  // namespace

MainWindow::MainWindow(const std::string& robot, const std::string& scene, QWidget* parent)
    : MainWindow(robot, scene, Options{}, parent) {}

MainWindow::MainWindow(const std::string& robot, const std::string& scene, const Options& options, QWidget* parent)
    : QMainWindow(parent), options_(options), declarations_(robot::sceneTunableParameters()) {
  setWindowTitle(tr("FlexIRob"));
  view_ = new OsgView(this);
  setCentralWidget(view_);
  view_->setSceneRoot(world_.root());

  overlays_ = std::make_unique<render::Overlays>();
  world_.root()->addChild(overlays_->root());
  force_arrow_ = std::make_unique<ForceArrow>();
  world_.root()->addChild(force_arrow_->node());
  perturbation_ = std::make_unique<MousePerturbation>(
      *view_, world_, [this] { return live_ && live_->simulated() ? live_.get() : nullptr; },
      [this]() -> const robot::Kinematics* { return kinematics_.get(); });
  view_->setMouseGrabber(perturbation_.get());
  chime_ = std::make_unique<ConvergedChime>();

  // Where the eye is: the stage and the latest tutor warning on top of the 3D view, the key map
  // on demand at its lower left.
  banner_label_ = new QLabel(view_);
  banner_label_->setObjectName(QStringLiteral("banner"));
  banner_label_->setAttribute(Qt::WA_TransparentForMouseEvents);
  // Two lines at most, each cut to the view's width (showBanner): a wrapped banner would grow
  // over the robot.
  banner_label_->setWordWrap(false);
  banner_label_->setAlignment(Qt::AlignCenter);
  QFont banner_font = banner_label_->font();
  banner_font.setPointSize(banner_font.pointSize() + 5);
  banner_font.setBold(true);
  banner_label_->setFont(banner_font);
  banner_label_->move(12, 10);
  problem_label_ = new QLabel(view_);
  problem_label_->setObjectName(QStringLiteral("problem"));
  problem_label_->setAttribute(Qt::WA_TransparentForMouseEvents);
  problem_label_->setWordWrap(true);
  problem_label_->setStyleSheet(QStringLiteral("QLabel { background: rgba(255,236,236,235); color: #7a0000;"
                                               " border: 1px solid #c00000; border-radius: 4px; padding: 6px; }"));
  problem_label_->setVisible(false);
  key_map_label_ = new QLabel(view_);
  key_map_label_->setObjectName(QStringLiteral("key_map"));
  key_map_label_->setAttribute(Qt::WA_TransparentForMouseEvents);
  key_map_label_->setStyleSheet(QStringLiteral("QLabel { background: rgba(255,255,255,215); color: #202020;"
                                               " border: 1px solid #888; padding: 6px; }"));
  key_map_label_->setVisible(false);
  confidence_legend_ = new ConfidenceColourBar(view_);
  confidence_legend_->resize(confidence_legend_->sizeHint());
  confidence_legend_->setVisible(false);
  view_->setControlClickHandler([this](const QPointF& position) { clickGoal(position); });

  parameters_ = std::make_unique<robot::ParameterSet>(declarations_);
  try {
    backend_ = app::parseBackendChoice(options_.backend);
  } catch (const std::exception& error) {
    reportProblem(Problem::kBackend, tr("%1; the simulation runs instead").arg(QString::fromUtf8(error.what())));
  }

  status_label_ = new QLabel;
  status_label_->setObjectName(QStringLiteral("status_fields"));
  link_label_ = new QLabel;
  statusBar()->addPermanentWidget(link_label_);
  statusBar()->addPermanentWidget(status_label_);
  buildDocks();
  buildMenus();

  if (options_.scene_read) {
    robot::Scene read = std::move(*options_.scene_read);
    options_.scene_read.reset();
    loadScene(scene, std::move(read));
  } else {
    loadScene(scene);
  }
  // Without an explicit robot, the robot the scene was made for.
  if (options_.robot_read && !robot.empty()) {
    robot::RobotModel read = std::move(*options_.robot_read);
    options_.robot_read.reset();
    loadRobot(robot, std::move(read));
  } else {
    loadRobot(robot.empty() ? (scene_.robot.empty() ? std::string("lwr4") : scene_.robot) : robot);
  }
  // 1280 x 800, or what the screen has room for (a small screen keeps the window whole).
  const QRect room = screen() != nullptr ? screen()->availableGeometry() : QRect(0, 0, 1280, 800);
  resize(std::min(1280, room.width()), std::min(800, room.height()));
  if (options_.restore_layout) {
    QSettings settings;
    restoreGeometry(settings.value(QStringLiteral("window/geometry")).toByteArray());
    restoreState(settings.value(QStringLiteral("window/state")).toByteArray());
    // A size remembered on a larger screen is cut to this one, and the window moved onto it:
    // a status bar below the screen's edge is no status bar.
    // The screen the window was remembered on, where that screen is still attached.
    const QScreen* remembered = QGuiApplication::screenAt(geometry().center());
    const QRect room_there = remembered != nullptr ? remembered->availableGeometry() : room;
    QRect kept = geometry();
    kept.setSize(kept.size().boundedTo(room_there.size()));
    if (kept.right() > room_there.right()) kept.moveRight(room_there.right());
    if (kept.bottom() > room_there.bottom()) kept.moveBottom(room_there.bottom());
    if (kept.left() < room_there.left()) kept.moveLeft(room_there.left());
    if (kept.top() < room_there.top()) kept.moveTop(room_there.top());
    if (kept != geometry()) setGeometry(kept);
  }

  display_timer_ = new QTimer(this);
  display_timer_->setTimerType(Qt::PreciseTimer);
  connect(display_timer_, &QTimer::timeout, this, &MainWindow::mirror);
  display_timer_->start(kDisplayPeriodMs);
  fps_clock_.start();
  view_->setFocus();
}

MainWindow::~MainWindow() {
  display_timer_->stop();
  stopLive();
}

void MainWindow::reportError(const QString& what, const std::exception& error) {
  const QString message = what + QStringLiteral(": ") + QString::fromUtf8(error.what());
  showStatusMessage(statusBar(), message, 15000);
  qWarning("%s", qPrintable(message));
}

void MainWindow::reportProblem(Problem kind, const QString& message) {
  const bool fresh = problems_.count(kind) == 0;
  problems_[kind] = message;
  // The late control loop is re-judged every two seconds; the log says when it starts.
  if (fresh || kind != Problem::kDeadlines) qWarning("%s", qPrintable(message));
  showProblems();
}

void MainWindow::clearProblem(Problem kind) {
  if (problems_.erase(kind) > 0) showProblems();
}

void MainWindow::showNotes(Problem kind, const std::vector<std::string>& notes) {
  QStringList lines;
  for (const std::string& note : notes) lines << tr("note: %1").arg(QString::fromStdString(note));
  if (lines.isEmpty()) {
    clearProblem(kind);
  } else {
    reportProblem(kind, lines.join(QLatin1Char('\n')));
  }
}

void MainWindow::showProblems() {
  QStringList lines;
  for (const auto& [which, text] : problems_) lines << text;
  problem_label_->setText(lines.join(QStringLiteral("\n")));
  problem_label_->setVisible(!problems_.empty());
  placeViewLabels();
}

void MainWindow::buildDocks() {
  stage_panel_ = new StagePanel;
  auto* stage_dock = new QDockWidget(tr("Teaching"), this);
  stage_dock->setObjectName(QStringLiteral("stage_dock"));
  // Scrolled, not squeezed: on a short screen the hint and a long warning keep their lines
  // (squeezed, the labels were drawn over each other and cut).
  auto* stage_scroll = new QScrollArea;
  stage_scroll->setObjectName(QStringLiteral("stage_scroll"));
  stage_scroll->setWidget(stage_panel_);
  stage_scroll->setWidgetResizable(true);
  stage_scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  stage_scroll->setFrameShape(QFrame::NoFrame);
  // As wide as the panel needs with the vertical bar beside it: the bar must not take the
  // buttons' right edge, with no horizontal bar to reach it.
  stage_scroll->setMinimumWidth(stage_panel_->minimumSizeHint().width() +
                                stage_scroll->style()->pixelMetric(QStyle::PM_ScrollBarExtent));
  stage_dock->setWidget(stage_scroll);
  stage_dock->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
  addDockWidget(Qt::LeftDockWidgetArea, stage_dock);
  connect(stage_panel_, &StagePanel::buttonPressed, this, [this](app::Button button) {
    if (live_) live_->press(button);
    view_->setFocus();
  });
  connect(stage_panel_, &StagePanel::replayRequested, this, [this](int teach_in) {
    if (live_) live_->replayTeachIn(teach_in);
    view_->setFocus();
  });
  connect(stage_panel_, &StagePanel::removeAreaRequested, this, [this](int area) {
    // One click beside Re-teach forgot an area for good: asked first, Cancel the default.
    if (!live_) return;
    const LiveSnapshot& now = live_->snapshot();
    if (now.area_data && area >= 0 && area < static_cast<int>(now.area_data->size())) {
      const app::TrainingArea& chosen = (*now.area_data)[static_cast<std::size_t>(area)];
      QMessageBox question(QMessageBox::Question, tr("Remove area"),
                           tr("Remove the area '%1'? Its %2 samples are forgotten%3.")
                               .arg(QString::fromStdString(chosen.name))
                               .arg(chosen.X.cols())
                               .arg(now.model_ready ? tr(" and the map is learned again from the other areas") : QString()),
                           QMessageBox::Cancel, this);
      QPushButton* remove = question.addButton(tr("Remove the area"), QMessageBox::DestructiveRole);
      question.setDefaultButton(QMessageBox::Cancel);
      const std::string name = chosen.name;  // the areas may change while the question is open
      question.exec();
      if (question.clickedButton() == remove && live_) {
        const LiveSnapshot& after = live_->snapshot();
        if (after.area_data && area < static_cast<int>(after.area_data->size()) &&
            (*after.area_data)[static_cast<std::size_t>(area)].name == name) {
          live_->removeArea(area);
        } else {
          showStatusMessage(statusBar(), tr("The areas changed while the question was open: nothing removed"), 10000);
        }
      }
    }
    view_->setFocus();
  });
  connect(stage_panel_, &StagePanel::reteachAreaRequested, this, [this](int area) {
    if (live_) live_->reteachArea(area);
    view_->setFocus();
  });

  joint_panel_ = new JointPanel;
  auto* scroll = new QScrollArea;
  scroll->setWidget(joint_panel_);
  scroll->setWidgetResizable(true);
  auto* joints_dock = new QDockWidget(tr("Joints"), this);
  joints_dock->setObjectName(QStringLiteral("joints_dock"));
  joints_dock->setWidget(scroll);
  joints_dock->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
  addDockWidget(Qt::RightDockWidgetArea, joints_dock);

  parameter_panel_ = new ParameterPanel;
  auto* parameter_scroll = new QScrollArea;
  parameter_scroll->setWidget(parameter_panel_);
  parameter_scroll->setWidgetResizable(true);
  auto* parameter_dock = new QDockWidget(tr("Parameters"), this);
  parameter_dock->setObjectName(QStringLiteral("parameters_dock"));
  parameter_dock->setWidget(parameter_scroll);
  addDockWidget(Qt::RightDockWidgetArea, parameter_dock);
  tabifyDockWidget(joints_dock, parameter_dock);
  joints_dock->raise();
  connect(parameter_panel_, &ParameterPanel::applyRequested, this,
          [this](const std::map<std::string, double>& values) {
            if (mayDiscardTeaching(tr("parameter change"))) applyParameters(values);
          });

  // The confidence field's slices (Fig. 6.5): heights and the colour map's legend.
  confidence_panel_ = new ConfidencePanel;
  auto* confidence_dock = new QDockWidget(tr("Confidence"), this);
  confidence_dock->setObjectName(QStringLiteral("confidence_dock"));
  confidence_dock->setWidget(confidence_panel_);
  addDockWidget(Qt::RightDockWidgetArea, confidence_dock);
  tabifyDockWidget(joints_dock, confidence_dock);
  joints_dock->raise();
  connect(confidence_panel_, &ConfidencePanel::settingsChanged, this, [this] {
    operator_heights_ = true;
    if (live_) updateConfidence(live_->snapshot(), true);
    view_->requestFrame();
  });

  // Live plots (issue #7 item 7): task error, joints against their limits, the control cycle.
  plot_panel_ = new PlotPanel;
  plot_panel_->setOrientation(Qt::Horizontal);
  plot_panel_->setMinimumHeight(150);
  auto* plot_dock = new QDockWidget(tr("Plots"), this);
  plot_dock->setObjectName(QStringLiteral("plots_dock"));
  plot_dock->setWidget(plot_panel_);
  // The Teaching panel runs down to the window's bottom, beside the plots: its warnings are
  // what the tutor must read, and under the plots they needed scrolling at 1280 x 800.
  setCorner(Qt::BottomLeftCorner, Qt::LeftDockWidgetArea);
  addDockWidget(Qt::BottomDockWidgetArea, plot_dock);
  resizeDocks({plot_dock}, {240}, Qt::Vertical);
}

void MainWindow::resetParameters() {
  parameters_ = std::make_unique<robot::ParameterSet>(declarations_);
  parameters_->applyOverrides(scene_.parameters, robot::sceneOrigin(scene_));
  parameters_->applyOverrides(parameter_edits_);
  parameter_panel_->setParameters(*parameters_);
}

void MainWindow::applyParameters(const std::map<std::string, double>& values) {
  // Keep only what differs from the scene's values, so that a later scene keeps its own.
  robot::ParameterSet scene_values(declarations_);
  scene_values.applyOverrides(scene_.parameters, robot::sceneOrigin(scene_));
  parameter_edits_.clear();
  for (const auto& [name, value] : values) {
    if (scene_values.has(name) && scene_values.get(name) != value) parameter_edits_[name] = value;
  }
  stopLive();
  resetParameters();
  startLive();
  showStatusMessage(statusBar(), tr("Parameters applied (%1 changed); the robot restarted").arg(parameter_edits_.size()), 8000);
}

void MainWindow::stopLive() {
  if (live_) {
    live_->stop();
    live_->setRecorder(nullptr);
    handleEvents();
  }
  if (live_ && recorder_) recordSnapshotData(live_->snapshot());
  live_.reset();
  stage_panel_->setModelSummary(QString());  // the next run learns its own map
  endRecording();
  keyboard_mode_ = false;
  teleop_.clear();
  if (force_arrow_) force_arrow_->hide();
  shown_cycle_ = ~0ULL;
  shown_areas_version_ = shown_teach_ins_version_ = shown_itm_version_ = ~0ULL;
  shown_model_version_ = shown_path_version_ = recorded_itm_version_ = ~0ULL;
  goal_.reset();
  confidence_slices_ = 0;
  if (confidence_legend_ != nullptr) confidence_legend_->setVisible(false);
  if (overlays_) {
    for (const render::OverlayLayer layer : {render::OverlayLayer::kTrainingSamples, render::OverlayLayer::kGhostArms,
                                             render::OverlayLayer::kTrajectories, render::OverlayLayer::kConfidence,
                                             render::OverlayLayer::kGoalAndPath}) {
      overlays_->setContent(layer, nullptr);
    }
    overlays_->itm().setGraph({}, {});
  }
}

QString MainWindow::sessionDirectory() {
  // ~/.local/share/flexirob/sessions: AppDataLocation would name the organization and the
  // application, both "flexirob", one folder inside the other.
  return QStandardPaths::writableLocation(QStandardPaths::GenericDataLocation) + QStringLiteral("/flexirob/sessions");
}

void MainWindow::startRecording() {
  recorded_itm_version_ = ~0ULL;  // a new file holds the graph and the model again
  recorded_model_.reset();
  session_file_.clear();
  if (!options_.record_sessions || !model_ || !live_) return;
  const QString directory = sessionDirectory();
  if (!QDir().mkpath(directory)) {
    showStatusMessage(statusBar(), tr("Cannot create %1: this run is not recorded").arg(directory), 15000);
    return;
  }
  const QString file = directory + QStringLiteral("/session-") +
                       QDateTime::currentDateTimeUtc().toString(QStringLiteral("yyyyMMdd-HHmmss-zzz")) +
                       QStringLiteral(".flexirob");
  try {
    app::SessionMetadata metadata;
    metadata.robot_name = model_->name();
    metadata.robot_urdf = readText(model_->urdfPath());
    metadata.tip_link = model_->tipLink();
    metadata.scene_name = scene_.name.empty() ? std::string("empty") : scene_.name;
    metadata.scene_text = robot::sceneToYaml(scene_);
    metadata.mesh_digests = app::meshDigestsText(app::meshDigests(*model_, scene_));
    std::ostringstream parameters;
    parameters << "{\"backend\": \"" << backend_.text << "\"";
    for (const auto& declaration : parameters_->declarations()) {
      parameters << ", \"" << declaration.name << "\": " << parameters_->get(declaration.name);
    }
    parameters << "}";
    metadata.parameters = parameters.str();
    metadata.software_version = FLEXIROB_VERSION_STRING;
    recorder_ = std::make_unique<app::SessionRecorder>(file.toStdString(), metadata);
    session_file_ = file;
    // The stage the workflow is in when the file starts (IDLE at a start, any stage after a
    // save), so that the review's bands begin with the recording, not at the first change.
    const LiveSnapshot& now = live_->snapshot();
    recorder_->recordStage({now.time, app::toString(now.stage), app::toString(now.sub_stage)});
    // The control thread records the robot state of every cycle, the training samples and the
    // areas; this window adds stages, signals, models and graphs.
    live_->setRecorder(recorder_.get());
  } catch (const std::exception& error) {
    reportError(tr("Cannot record the session"), error);
    recorder_.reset();
  }
}

void MainWindow::startLive() {
  if (!model_) return;
  QString postures_problem;
  live_scene_ = sceneFitFor(scene_, *model_, &postures_problem);
  if (postures_problem.isEmpty()) {
    clearProblem(Problem::kPostures);
  } else {
    reportProblem(Problem::kPostures, postures_problem);
  }
  try {
    app::WorkflowOptions workflow_options;
    live_ = std::make_unique<LiveTeaching>(*model_, live_scene_, *parameters_, workflow_options, backend_,
                                           LiveTeaching::Options{});
  } catch (const std::exception& error) {
    reportProblem(Problem::kRobot, tr("Cannot start the robot on backend '%1': %2")
                                       .arg(QString::fromStdString(backend_.text), QString::fromUtf8(error.what())));
    live_.reset();
    return;
  }
  clearProblem(Problem::kRobot);
  clearProblem(Problem::kDeadlines);
  clearProblem(Problem::kStartContact);
  force_arrow_->setArmScale(live_->armScale());
  start_checked_ = false;
  deadline_clock_.invalidate();
  startRecording();
  live_->start();
  last_warning_.clear();
  standing_warning_events_.clear();
  stage_panel_->clearWarning();
  mirror();
}

void MainWindow::endRecording() {
  if (!recorder_) return;
  if (live_) live_->setRecorder(nullptr);
  const bool on_disk = recorder_->fileHoldsTheRecording();
  recorder_->close();
  // Held in memory only (its file failed or was removed): kept for Save session, and closing
  // the window asks for it.
  if (!on_disk) unsaved_recordings_.push_back(std::move(recorder_));
  recorder_.reset();
}

bool MainWindow::recordingAtRisk() const {
  return !unsaved_recordings_.empty() || (recorder_ && !recorder_->fileHoldsTheRecording());
}

bool MainWindow::saveSession(const QString& chosen) {
  if (!recorder_ && unsaved_recordings_.empty()) {
    showStatusMessage(statusBar(), tr("No session is being recorded"), 10000);
    return false;
  }
  // Open recording lists *.flexirob: a typed name without a suffix gets it.
  const QString file = QFileInfo(chosen).suffix().isEmpty() ? chosen + QStringLiteral(".flexirob") : chosen;
  // Everything shown so far goes in.
  handleEvents();
  std::uint64_t areas_version = saved_areas_version_, teach_ins_version = saved_teach_ins_version_;
  if (live_) {
    const LiveSnapshot& now = live_->snapshot();
    recordSnapshotData(now);
    areas_version = now.areas_version;
    teach_ins_version = now.teach_ins_version;
  }
  bool ok = true;
  try {
    bool saved = false;
    if (unsaved_recordings_.empty() && recorder_ && recorder_->fileHoldsTheRecording()) {
      try {
        recorder_->saveSnapshot(file.toStdString());  // the run's file goes on holding the whole run
        saved_session_ended_a_recording_ = false;
        saved = true;
      } catch (const std::exception&) {
        if (recorder_->fileHoldsTheRecording()) throw;  // the target failed, not the recording
      }
    }
    if (!saved) {
      // A recording no file holds: the one the run's file failed under ends (the run records
      // on into a new file at once), and the oldest held in memory is copied. A copy that
      // fails keeps it for another try.
      if (recorder_ && !recorder_->fileHoldsTheRecording()) {
        endRecording();
        startRecording();
      }
      unsaved_recordings_.front()->saveCopy(file.toStdString());
      unsaved_recordings_.erase(unsaved_recordings_.begin());
      saved_session_ended_a_recording_ = true;
    }
    saved_session_file_ = file;
    saved_areas_version_ = areas_version;
    saved_teach_ins_version_ = teach_ins_version;
    showStatusMessage(statusBar(), unsaved_recordings_.empty()
                                       ? tr("Session saved to %1").arg(file)
                                       : tr("Session saved to %1; %n more recording(s) of this run held in memory: save again",
                                            nullptr, static_cast<int>(unsaved_recordings_.size()))
                                             .arg(file),
                      10000);
  } catch (const std::exception& error) {
    reportError(tr("Cannot save the session to %1").arg(file), error);
    ok = false;
  }
  return ok;
}

bool MainWindow::teachingChangedSinceSave() const {
  if (saved_session_file_.isEmpty() || !live_) return false;
  const LiveSnapshot& now = live_->snapshot();
  return now.areas_version != saved_areas_version_ || now.teach_ins_version != saved_teach_ins_version_;
}

bool MainWindow::saveSessionAgain() {
  if (saved_session_file_.isEmpty()) return saveSessionAs();
  if (saved_session_ended_a_recording_) {
    // That file holds the run up to the recording's failure; the new recording holds only what
    // came after, and would replace it.
    showStatusMessage(statusBar(), tr("%1 holds the run up to the recording's failure: save the rest under another name")
                                       .arg(saved_session_file_), 15000);
    return saveSessionAs();
  }
  return saveSession(saved_session_file_);
}

bool MainWindow::saveSessionAs() {
  // After a copy of an ended recording, the name offered is another one: the rest of the run
  // saved over it would replace what it holds.
  QString offered = saved_session_file_.isEmpty() ? QStringLiteral("session.flexirob") : saved_session_file_;
  if (saved_session_ended_a_recording_ && !saved_session_file_.isEmpty()) {
    const QFileInfo saved(saved_session_file_);
    offered = saved.dir().filePath(saved.completeBaseName() + QStringLiteral("-continued.flexirob"));
  }
  QFileDialog dialog(this, tr("Save session"), offered, tr("FlexIRob sessions (*.flexirob);;All files (*)"));
  dialog.setAcceptMode(QFileDialog::AcceptSave);
  dialog.setDefaultSuffix(QStringLiteral("flexirob"));
  if (dialog.exec() != QDialog::Accepted || dialog.selectedFiles().isEmpty()) return false;
  return saveSession(dialog.selectedFiles().front());
}

void MainWindow::refuseRobot(const std::string& name_or_path, const std::exception& error) {
  reportProblem(Problem::kRobot, tr("Cannot load robot '%1': %2%3")
                                     .arg(QString::fromStdString(name_or_path), QString::fromUtf8(error.what()),
                                          model_ ? tr("; the robot stays '%1'").arg(QString::fromStdString(model_->name()))
                                                 : tr("; no robot runs (choose one in the Robot menu)")));
}

bool MainWindow::loadRobot(const std::string& name_or_path) {
  try {
    return loadRobot(name_or_path, readRobot(name_or_path));
  } catch (const std::exception& error) {
    refuseRobot(name_or_path, error);
    return false;
  }
}

bool MainWindow::loadRobot(const std::string& name_or_path, robot::RobotModel read) {
  auto model = std::make_unique<robot::RobotModel>(std::move(read));
  stopLive();
  try {
    auto kinematics = std::make_unique<robot::Kinematics>(*model);
    world_.setRobot(*model);
    model_ = std::move(model);
    kinematics_ = std::move(kinematics);
  } catch (const std::exception& error) {
    startLive();  // the robot before runs on; its start clears the robot's problems, so say it after
    refuseRobot(name_or_path, error);
    return false;
  }
  coloured_links_.clear();
  // What the CLI notes about a robot description (a default tip past a gripper's slide, a drawn
  // link without a collision element).
  showNotes(Problem::kRobotNotes, model_->notes());
  // Start posture: the scene's, if it was made for a robot with this many joints, else a free one.
  const Eigen::VectorXd q = shownHomePosture(*model_, scene_);
  joint_panel_->setRobot(*model_, q);
  kinematics_->update(q);
  world_.robot()->setPosture(*kinematics_);
  frameView();
  loaded_robot_ = name_or_path;
  markLoadedChoices();
  key_map_label_->setText(TeleopKeys::keyMapText(model_->dof()));
  {
    std::vector<std::string> names;
    Eigen::VectorXd lower(model_->dof());
    Eigen::VectorXd upper(model_->dof());
    for (int j = 0; j < model_->dof(); ++j) {
      const robot::Joint& joint = model_->joints()[static_cast<std::size_t>(j)];
      names.push_back(joint.name);
      lower[j] = joint.limits.lower;
      upper[j] = joint.limits.upper;
    }
    plot_panel_->setJoints(names, lower, upper);
  }
  key_map_label_->adjustSize();
  resetParameters();
  startLive();
  updateStatus();
  return true;
}

robot::RobotModel MainWindow::readRobot(const std::string& name_or_path) {
  robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath(name_or_path));
  const robot::Kinematics chain_check(model);  // a chain the kinematics refuse is refused here too
  static_cast<void>(chain_check);
  return model;
}

robot::Scene MainWindow::readScene(const std::string& name_or_path) {
  robot::Scene scene = robot::loadScene(name_or_path);
  // A parameter out of its range refuses the scene, with the scene shown kept as it was.
  robot::ParameterSet(robot::sceneTunableParameters()).applyOverrides(scene.parameters, robot::sceneOrigin(scene));
  return scene;
}

bool MainWindow::loadScene(const std::string& name_or_path, bool start_live) {
  robot::Scene scene;
  try {
    scene = readScene(name_or_path);
  } catch (const std::exception& error) {
    refuseScene(name_or_path, error);
    return false;
  }
  return loadScene(name_or_path, std::move(scene), start_live);
}

bool MainWindow::loadScene(const std::string& name_or_path, robot::Scene scene, bool start_live) {
  stopLive();
  try {
    world_.setScene(scene);
    scene_ = std::move(scene);
  } catch (const std::exception& error) {
    refuseScene(name_or_path, error);
    startLive();
    return false;
  }
  clearProblem(Problem::kScene);
  // What the CLI notes about a scene (places tens of metres away: a scene in millimetres?).
  showNotes(Problem::kSceneNotes, robot::sceneNotes(scene_));
  if (model_) {
    const Eigen::VectorXd home = shownHomePosture(*model_, scene_);
    joint_panel_->setPosture(home);
    kinematics_->update(home);
    world_.robot()->setPosture(*kinematics_);
  }
  frameView();
  loaded_scene_ = name_or_path.empty() ? std::string("empty") : name_or_path;
  markLoadedChoices();
  resetParameters();
  if (start_live) startLive();
  updateStatus();
  return true;
}

bool MainWindow::mayDiscardTeaching(const QString& what) {
  if (!live_) return true;
  const LiveSnapshot& now = live_->snapshot();
  const bool recording = now.sub_stage == app::SubStage::kRecording || now.sub_stage == app::SubStage::kTeachIn;
  if (now.areas == 0 && now.teach_ins == 0 && !recording) return true;
  // A new robot or scene restarts the workflow: what was taught in this window is gone from it
  // (the session file keeps it). One click in a menu must not cost a person's teaching.
  const auto count = [](int n, const QString& one, const QString& many) { return n == 1 ? one : many.arg(n); };
  QStringList taught;
  if (now.areas > 0) taught << count(now.areas, tr("its 1 training area"), tr("its %1 training areas"));
  if (now.teach_ins > 0) taught << count(now.teach_ins, tr("its 1 teach-in"), tr("its %1 teach-ins"));
  if (recording) taught << (now.sub_stage == app::SubStage::kRecording ? tr("the area being recorded") : tr("the teach-in being taught"));
  const QString kept = recorder_ ? tr("the session file keeps what was finished") : tr("this run is not recorded: they are lost");
  if (now.model_ready) taught << tr("its learned map");
  QMessageBox question(QMessageBox::Question, tr("Discard the teaching?"),
                       tr("The %1 starts the teaching afresh and clears this run from the window: %2 (%3). Go on?")
                           .arg(what, taught.join(tr(", ")), kept),
                       QMessageBox::Cancel, this);
  // The button says what it does, not a bare "Yes".
  QPushButton* discard = question.addButton(tr("Discard the teaching"), QMessageBox::DestructiveRole);
  question.setDefaultButton(QMessageBox::Cancel);
  question.exec();
  return question.clickedButton() == discard;
}

void MainWindow::chooseScene(const std::string& name) {
  // As the command line starts a scene without --robot: a scene made for another arm, whose
  // postures the loaded one cannot take (another joint count), brings its own robot. A robot
  // that fits stays, the operator's own URDF included. The arm restarts once, with both.
  robot::Scene chosen;
  try {
    chosen = readScene(name);
  } catch (const std::exception& error) {
    refuseScene(name, error);
    return;
  }
  std::string own_robot;
  if (model_ && !chosen.robot.empty() && chosen.robot != loaded_robot_) {
    try {
      robot::checkPosturesFit(chosen, model_->dof(), model_->name());
    } catch (const InputError&) {
      own_robot = chosen.robot;
    }
  }
  if (own_robot.empty()) {
    loadScene(name, std::move(chosen));
    return;
  }
  if (!chosen.robot_unreadable.empty()) {  // its own robot is needed and this machine lacks it
    refuseScene(name, InputError(chosen.robot_unreadable));
    return;
  }
  const QString before = QString::fromStdString(model_->name());
  if (!loadScene(name, std::move(chosen), false)) return;  // refused: the arm before runs on
  if (!loadRobot(own_robot)) {
    startLive();  // the robot before, in the new scene (its postures left out, said by the notes)
    return;
  }
  showStatusMessage(statusBar(),
                    tr("Scene '%1' is made for the robot '%2', loaded with it ('%3' has another number of joints)")
                        .arg(QString::fromStdString(scene_.name), QString::fromStdString(scene_.robot), before),
                    15000);
}

void MainWindow::markLoadedChoices() {
  for (QAction* action : robot_menu_->actions()) action->setChecked(action->data().toString().toStdString() == loaded_robot_);
  for (QAction* action : scene_menu_->actions()) action->setChecked(action->data().toString().toStdString() == loaded_scene_);
}

void MainWindow::refuseScene(const std::string& name_or_path, const std::exception& error) {
  const QString shown = scene_.name.empty() ? QStringLiteral("empty") : QString::fromStdString(scene_.name);
  reportProblem(Problem::kScene, tr("Cannot load scene '%1': %2; the scene stays '%3'")
                                     .arg(QString::fromStdString(name_or_path), QString::fromUtf8(error.what()), shown));
}

void MainWindow::frameView() {
  const render::CameraPose camera = world_.defaultCamera(static_cast<double>(view_->width()) / std::max(1, view_->height()));
  view_->setFloor(scene_.table ? std::optional<double>(0.0) : std::nullopt);
  view_->setHomeCamera(camera);
  // Walls all round and a roof: no side shows the arm, so what hides it is drawn see-through.
  const std::vector<std::string> revealed = world_.revealRobot(camera);
  if (!revealed.empty()) {
    QStringList names;
    for (const std::string& name : revealed) names << QString::fromStdString(name);
    showStatusMessage(statusBar(), tr("Drawn see-through, as they hide the robot from every side: %1").arg(names.join(QStringLiteral(", "))),
                             15000);
  }
}

bool MainWindow::setBackend(const std::string& choice) {
  app::BackendChoice parsed;
  try {
    parsed = app::parseBackendChoice(choice);
  } catch (const std::exception& error) {
    reportProblem(Problem::kBackend, tr("%1; the backend stays '%2'")
                                         .arg(QString::fromUtf8(error.what()), QString::fromStdString(backend_.text)));
    return false;
  }
  clearProblem(Problem::kBackend);
  const app::BackendChoice previous = backend_;
  stopLive();
  backend_ = parsed;
  startLive();
  if (!live_) {  // e.g. the FRI port is taken or the robot is not an LWR IV: back to the previous
    const auto why = problems_.find(Problem::kRobot);
    const QString reason = why != problems_.end() ? why->second : tr("Cannot start the backend '%1'").arg(QString::fromStdString(choice));
    backend_ = previous;
    startLive();
    reportProblem(Problem::kBackend, tr("%1; the backend stays '%2'").arg(reason, QString::fromStdString(backend_.text)));
    return false;
  }
  for (QAction* action : backend_menu_->actions()) {
    if (action->isCheckable()) action->setChecked(action->data().toString().toStdString() == (parsed.kind == app::BackendKind::kSimulation ? "sim" : "fri"));
  }
  updateStatus();
  return true;
}

double MainWindow::meanFramesPerSecond() const {
  if (!run_clock_.isValid() || run_clock_.elapsed() <= 0) return 0.0;
  return 1000.0 * static_cast<double>(view_->framesDrawn() - run_first_frame_) / static_cast<double>(run_clock_.elapsed());
}

void MainWindow::mirror() {
  if (!run_clock_.isValid()) {
    run_clock_.start();
    run_first_frame_ = view_->framesDrawn();
  }
  // Frame rate of the 3D view, over windows of at least one second.
  const qint64 elapsed_ms = fps_clock_.elapsed();
  if (elapsed_ms >= 1000) {
    fps_ = 1000.0 * static_cast<double>(view_->framesDrawn() - fps_frames_) / static_cast<double>(elapsed_ms);
    fps_frames_ = view_->framesDrawn();
    fps_clock_.restart();
  }
  if (!live_ || !model_) {
    link_label_->setText(tr("no robot running"));
    stage_panel_->showNoRobot(tr("No robot runs: the message in the view says why."));
    showNoRobotBanner();
    placeViewLabels();
    view_->requestFrame();
    return;
  }
  live_->tick();
  if (live_->grabbing() && keyboard_mode_) {  // the hand takes over from the keys
    live_->setKeyboardMode(false);
    keyboard_mode_ = false;
  }
  driveKeyboard();
  const LiveSnapshot& s = live_->snapshot();
  handleEvents();
  watchRecording();
  stage_panel_->showSnapshot(s, robotMeasured(), live_->simulated());
  if (s.failed) {
    const auto end = std::find(s.failure.begin(), s.failure.end(), '\0');
    last_warning_ = tr("The robot stopped: %1").arg(QString::fromStdString(std::string(s.failure.begin(), end)));
  }
  // In the simulation only: a real arm's first state is where it stands, which no scene decides.
  if (!start_checked_ && s.cycle > 0 && s.dof == model_->dof() && live_->simulated()) {
    // An arm that starts in contact: the scene left it no free posture near the middle of its
    // limits (or its home posture touches something); the red links alone would not say why.
    start_checked_ = true;
    if (s.contact_link_count > 0) {
      QStringList links;
      for (int i = 0; i < s.contact_link_count && i < app::kMaxContactBodies; ++i) {
        if (s.contact_links[static_cast<std::size_t>(i)] != nullptr) links << QString::fromUtf8(s.contact_links[static_cast<std::size_t>(i)]);
      }
      reportProblem(Problem::kStartContact,
                    live_scene_.home_posture
                        ? tr("The arm starts in contact (%1): the scene's home_posture touches the scene").arg(links.join(QStringLiteral(", ")))
                        : tr("The arm starts in contact (%1): no posture near the middle of its limits keeps clear of the scene; "
                             "give the scene a collision-free home_posture")
                              .arg(links.join(QStringLiteral(", "))));
    }
  }
  if (s.cycle != shown_cycle_ && s.dof == model_->dof()) {
    recordItm(s, false);
    recordModel(s);
    updateOverlays(s);
    updateConfidence(s, false);
    updateGoalAndPath(s);
    updatePlots(s);
    shown_cycle_ = s.cycle;
    Eigen::VectorXd q(s.dof);
    for (int j = 0; j < s.dof; ++j) q[j] = s.q[static_cast<std::size_t>(j)];
    kinematics_->update(q);
    world_.robot()->setPosture(*kinematics_);
    joint_panel_->setPosture(q);

    // Links in contact turn red (issue #7 item 4, collisions).
    std::vector<std::string> touching;
    for (int i = 0; i < s.contact_link_count && i < app::kMaxContactBodies; ++i) {
      if (s.contact_links[static_cast<std::size_t>(i)] != nullptr) touching.emplace_back(s.contact_links[static_cast<std::size_t>(i)]);
    }
    if (touching != coloured_links_) {
      world_.robot()->resetColors();
      for (const std::string& link : touching) {
        world_.robot()->setLinkColor(link, collisionColour());
        for (const robot::Body& body : model_->bodies()) {
          if (body.name != link) continue;
          for (const std::string& folded : body.folded_links) world_.robot()->setLinkColor(folded, collisionColour());
        }
      }
      coloured_links_ = touching;
    }
    if (s.hand_active) {
      force_arrow_->show(Eigen::Vector3d(s.hand_point_W[0], s.hand_point_W[1], s.hand_point_W[2]),
                         Eigen::Vector3d(s.hand_force_W[0], s.hand_force_W[1], s.hand_force_W[2]));
    } else {
      force_arrow_->hide();
    }
    if (!last_warning_.isEmpty() || banner_label_->text().isEmpty() || banner_label_->property("warning").toString() != last_warning_ ||
        banner_label_->property("view_width").toInt() != view_->width() ||
        banner_label_->property("stage").toString() !=
            StagePanel::stageText(s.stage, s.sub_stage) + (robotMeasured() ? QString() : QStringLiteral("?"))) {
      showBanner(last_warning_);
    }
  }
  const app::LinkStatus link = live_->linkStatus();
  link_label_->setText(QString::fromStdString(link.summary()));
  link_label_->setStyleSheet(link.fault ? QStringLiteral("color: #c00000; font-weight: bold") : QString());
  if (reconnect_action_ != nullptr) reconnect_action_->setEnabled(link.fault);
  placeViewLabels();
  updateStatus();
  view_->requestFrame();
}

bool MainWindow::robotMeasured() const {
  if (!live_) return false;
  const app::LinkStatus link = live_->linkStatus();
  return link.kind == app::BackendKind::kSimulation || link.measurements > 0;
}

void MainWindow::showNoRobotBanner() {
  if (banner_label_->text() != tr("NO ROBOT")) {
    setBanner(tr("NO ROBOT"), StagePanel::stageColor(app::Stage::kIdle, app::SubStage::kNone), QString());
  }
}

void MainWindow::showBanner(const QString& warning) {
  const LiveSnapshot& s = live_->snapshot();
  const QString stage = StagePanel::stageText(s.stage, s.sub_stage);
  QString text = QString(stage).replace(QLatin1Char('\n'), QStringLiteral(" · "));
  const bool measured = robotMeasured();
  if (!measured) text += tr(" · no measurement yet");
  // One line of the warning: the whole of it is in the Teaching panel, and a banner as long as
  // the warning would cover the robot.
  if (!warning.isEmpty()) {
    text += QStringLiteral("\n⚠ ") +
            QFontMetrics(banner_label_->font()).elidedText(QString(warning).replace(QLatin1Char('\n'), QLatin1Char(' ')),
                                                           Qt::ElideRight, std::max(200, view_->width() - 24) - 60);
  }
  setBanner(text, StagePanel::stageColor(s.stage, s.sub_stage), stage + (measured ? QString() : QStringLiteral("?")));
  banner_label_->setProperty("warning", warning);  // a warning withdrawn leaves the banner too
}

void MainWindow::setBanner(const QString& text, const QColor& colour, const QString& key) {
  banner_label_->setProperty("stage", key);
  banner_label_->setProperty("view_width", view_->width());  // a resized view centres it anew
  const int widest = std::max(200, view_->width() - 24);
  QString lines = text;
  // A view narrower than "CONFIGURATION · RECORDING" (docks widened, a small screen) shows the
  // stage and its sub-stage on two lines rather than cut at both ends.
  const int stage_end = lines.indexOf(QLatin1Char('\n'));
  const QString stage_line = stage_end < 0 ? lines : lines.left(stage_end);
  if (QFontMetrics(banner_label_->font()).horizontalAdvance(stage_line) + 28 > widest) {
    lines = QString(stage_line).replace(QStringLiteral(" · "), QStringLiteral("\n")) + (stage_end < 0 ? QString() : lines.mid(stage_end));
  }
  banner_label_->setText(lines);
  banner_label_->setStyleSheet(
      QStringLiteral("QLabel { background: rgba(%1,%2,%3,215); color: white; border-radius: 6px; padding: 6px 14px; }")
          .arg(colour.red())
          .arg(colour.green())
          .arg(colour.blue()));
  banner_label_->setMaximumWidth(widest);
  banner_label_->adjustSize();
  banner_label_->move(std::max(0, (view_->width() - banner_label_->width()) / 2), 10);
  key_map_label_->move(12, std::max(0, view_->height() - key_map_label_->height() - 12));
}

void MainWindow::rememberForStandingWarnings(const LiveEvent& event) {
  // What app::standingWarnings() reads: the warnings about an area or the map, and the events
  // that take them back (an area removed or made anew, a new map, a pose given up).
  using K = app::WorkflowEvent::Kind;
  static const std::set<std::string> kAboutAreasAndMap = {"joint_limit", "small_area", "area_in_contact",
                                                          "transition_inconsistent"};
  const bool kept = event.kind == K::kWarning ? kAboutAreasAndMap.count(event.name) != 0
                                              : event.kind == K::kAreaRemoved || event.kind == K::kAreaCreated ||
                                                    event.kind == K::kModelLearned || event.kind == K::kStage ||
                                                    event.kind == K::kButton;
  if (!kept) return;
  app::WorkflowEvent remembered;
  remembered.time = event.time;
  remembered.kind = event.kind;
  remembered.area = event.area;
  remembered.name = event.name;
  remembered.detail = event.detail;
  standing_warning_events_.push_back(std::move(remembered));
}

void MainWindow::showWarnings() {
  // Every warning that still stands, not only the newest: a tutor who taught one area in
  // contact and the next near a joint limit must see both, until each area is re-taught or
  // removed. The last warning or refusal follows, until the stage changes.
  const QString text = standingWarningText(standing_warning_events_, last_warning_);
  if (text.isEmpty()) {
    stage_panel_->clearWarning();
  } else {
    stage_panel_->showWarning(text);
  }
}

void MainWindow::showLastWarning(const QString& text, bool refused) {
  last_warning_ = operatorWording(text);
  last_warning_refused_ = refused;
  showWarnings();
  showStatusMessage(statusBar(), last_warning_, 15000);
}

void MainWindow::handleEvents() {
  if (!live_) return;
  for (const LiveEvent& event : live_->takeEvents()) {
    using K = app::WorkflowEvent::Kind;
    if (recorder_) {
      if (event.kind == K::kStage) {
        const auto slash = event.name.find('/');
        recorder_->recordStage({event.time, event.name.substr(0, slash),
                                slash == std::string::npos ? std::string() : event.name.substr(slash + 1)});
      } else if (event.kind == K::kTrigger) {
        recorder_->recordTrigger(event.time, event.name);
      } else if (event.kind == K::kButton) {
        recorder_->recordButton(event.time, event.name);
      }
    }
    // The acoustic acknowledgement of on_converged (Sect. 2.3.1), detected or from the keyboard.
    if (event.kind == K::kTrigger && event.name == robot::toString(robot::TriggerKind::kOnConverged)) {
      chime_->play();
      ++chimes_;
    }
    if (event.kind == K::kRefused && event.name == "plan") clearGoal();  // the ball was drawn at the click
    rememberForStandingWarnings(event);
    if (event.kind == K::kWarning || event.kind == K::kRefused) {
      showLastWarning(QString::fromStdString(event.detail.empty() ? event.name : event.detail), event.kind == K::kRefused);
    } else if (event.kind == K::kStage || event.kind == K::kButton) {
      // A new stage: the last warning no longer applies to what the operator sees, in the
      // banner or in the status bar; the warnings about the areas and the map stand.
      if (!last_warning_.isEmpty() && fullStatusMessage(statusBar()) == last_warning_) statusBar()->clearMessage();
      last_warning_.clear();
      showWarnings();
      // Out of EXECUTION a goal and its path are no motion any more.
      if (event.kind == K::kStage && event.name.rfind(app::toString(app::Stage::kExecution), 0) != 0) clearGoal();
      if (event.kind == K::kButton && event.name == "reteach_area") {
        showStatusMessage(statusBar(), tr("The next area you record replaces '%1'").arg(QString::fromStdString(event.detail)), 15000);
      }
    } else if (event.kind == K::kAreaRemoved) {
      // A warning about the area, or about the map it made, goes with it.
      last_warning_.clear();
      showWarnings();
      showStatusMessage(statusBar(), tr("Area '%1' removed").arg(QString::fromStdString(event.detail)), 10000);
    } else if (event.kind == K::kExecution) {
      // A replay is no motion to the goal drawn; a plan accepted is, from now until it ends.
      if (event.name == "replay") {
        clearGoal();
        replay_moving_ = true;
        replay_time_ = event.time;
        replay_name_ = QString::fromStdString(event.detail);
        showStatusMessage(statusBar(), tr("Replaying %1: to its start, then along it").arg(replay_name_), 15000);
      }
      // A request refused before this accepted one no longer describes what the arm does.
      if (last_warning_refused_ && !last_warning_.isEmpty()) {
        if (fullStatusMessage(statusBar()) == last_warning_) statusBar()->clearMessage();
        last_warning_.clear();
        showWarnings();
      }
      if (event.name == "plan") {
        replay_moving_ = false;
        goal_moving_ = goal_.has_value();
        goal_plan_time_ = event.time;
      }
    } else if (event.kind == K::kCheck || event.kind == K::kModelLearned || event.kind == K::kAreaCreated) {
      showStatusMessage(statusBar(), QString::fromStdString(event.detail.empty() ? event.name : event.detail), 10000);
      if (event.kind == K::kModelLearned) stage_panel_->setModelSummary(QString::fromStdString(event.detail));
      showWarnings();  // a re-taught area's warnings go, a new map's checks replace the old ones
    }
  }
}

void MainWindow::updateOverlays(const LiveSnapshot& s) {
  using render::OverlayLayer;
  // The area the Teaching panel's controls name stands out: its ghost in the area's own colour
  // (the colour of its samples and of its swatch in the list), its samples drawn larger, so that
  // "Remove" and "Re-teach" name something the operator can see.
  const int chosen_area = stage_panel_->chosenArea();
  if (s.areas_version != shown_areas_version_ || chosen_area != shown_chosen_area_) {
    shown_areas_version_ = s.areas_version;
    shown_chosen_area_ = chosen_area;
    std::vector<render::AreaSamples> samples;
    render::AreaSamples chosen_samples;
    overlays_->setContent(OverlayLayer::kGhostArms, nullptr);
    if (s.area_data) {
      for (std::size_t k = 0; k < s.area_data->size(); ++k) {
        const app::TrainingArea& area = (*s.area_data)[k];
        const bool chosen = static_cast<int>(k) == chosen_area;
        render::AreaSamples cloud;
        cloud.area = static_cast<int>(k);
        for (Eigen::Index l = 0; l < area.X.cols(); ++l) cloud.points_W.emplace_back(area.X.col(l));
        if (chosen) chosen_samples = cloud;
        samples.push_back(std::move(cloud));
        if (area.q_fixed.size() == model_->dof()) {
          Eigen::Vector4f rgba = render::OverlayPalette::ghost();
          if (chosen) {
            rgba = render::OverlayPalette::area(static_cast<int>(k));
            rgba[3] = kChosenGhostAlpha;
          }
          overlays_->addContent(OverlayLayer::kGhostArms, render::makeGhostArm(*model_, area.q_fixed, rgba));
        }
      }
    }
    overlays_->setContent(OverlayLayer::kTrainingSamples, render::makeTrainingSamples(samples));
    if (!chosen_samples.points_W.empty()) {
      overlays_->addContent(OverlayLayer::kTrainingSamples,
                            render::makeTrainingSamples({chosen_samples}, kChosenSampleSizePx));
    }
  }
  if (s.teach_ins_version != shown_teach_ins_version_) {
    shown_teach_ins_version_ = s.teach_ins_version;
    overlays_->setContent(OverlayLayer::kTrajectories, nullptr);
    if (s.teach_in_data) {
      for (const Eigen::MatrixXd& trajectory : *s.teach_in_data) {
        std::vector<Eigen::Vector3d> points;
        for (Eigen::Index t = 0; t < trajectory.cols(); ++t) points.emplace_back(trajectory.col(t));
        overlays_->addContent(OverlayLayer::kTrajectories,
                              render::makePolyline(points, render::OverlayPalette::teachInTrajectory()));
      }
    }
  }
  if (s.itm_version != shown_itm_version_ && s.itm) {
    shown_itm_version_ = s.itm_version;
    std::vector<std::pair<int, Eigen::Vector3d>> nodes;
    std::vector<std::pair<int, int>> edges;
    for (const int id : s.itm->nodeIds()) {
      const auto omega = s.itm->prototype(id);
      nodes.emplace_back(id, Eigen::Vector3d(omega[0], omega[1], omega[2]));
      for (const int other : s.itm->neighbors(id)) {
        if (other > id && s.itm->isNode(other)) edges.emplace_back(id, other);
      }
    }
    overlays_->itm().setGraph(nodes, edges);
  }
}

void MainWindow::driveKeyboard() {
  // Held keys step the targets by velocity × the time since the last tick (Sect. 8.1).
  // A slow display (a software renderer at a few frames per second, a busy machine) must not eat
  // the motion of held keys; beyond 0.5 s (4 cm of target at the task speed) it is a stall, not
  // a tick.
  const double dt = key_clock_.isValid() ? std::min(0.5, static_cast<double>(key_clock_.restart()) * 1e-3) : 0.0;
  if (!key_clock_.isValid()) key_clock_.start();
  if (!live_ || !model_ || !teleop_.anyHeld() || dt <= 0.0) return;
  if (!keyboard_mode_) {
    live_->setKeyboardMode(true);
    keyboard_mode_ = true;
  }
  const Eigen::Vector3d v = teleop_.taskVelocity();
  if (v.squaredNorm() > 0.0) live_->nudgeTask(v * dt);
  const Eigen::VectorXd qd = teleop_.jointVelocities(model_->dof());
  for (int j = 0; j < qd.size(); ++j) {
    if (qd[j] != 0.0) live_->nudgeJoint(j, qd[j] * dt);
  }
}

void MainWindow::keyPressEvent(QKeyEvent* event) {
  const auto action = TeleopKeys::actionOf(event->key());
  if (!action || (event->modifiers() & (Qt::ControlModifier | Qt::AltModifier))) {
    QMainWindow::keyPressEvent(event);
    return;
  }
  event->accept();
  if (event->isAutoRepeat()) return;  // held keys act until released
  switch (action->kind) {
    case TeleopAction::Kind::kTask:
    case TeleopAction::Kind::kJoint:
      // The keys held until now move by the time up to this press, and the new one from here:
      // the time since the last display tick was counted for it too, so a tap on a slow display
      // moved the target by up to half a second of motion.
      driveKeyboard();
      teleop_.press(event->key());
      if (live_ && !keyboard_mode_) {
        live_->setKeyboardMode(true);
        keyboard_mode_ = true;
      }
      break;
    case TeleopAction::Kind::kTrigger:
    case TeleopAction::Kind::kButton:
    case TeleopAction::Kind::kReplay:
      if (!live_) {
        showStatusMessage(statusBar(), tr("No robot runs: the message in the view says why"), 8000);
      } else if (!robotMeasured()) {
        showStatusMessage(statusBar(), tr("The robot has not sent a measurement yet: teaching starts when it does"), 8000);
      } else if (action->kind == TeleopAction::Kind::kTrigger) {
        live_->fire(action->trigger);
      } else if (action->kind == TeleopAction::Kind::kReplay) {
        if (live_->snapshot().teach_ins == 0) {
          showLastWarning(QStringLiteral("replay: ") + tr("no teach-in to replay; record one in PROGRAMMING first"), true);
        } else {
          live_->replayTeachIn(stage_panel_->chosenTeachIn());
        }
      } else {
        live_->press(action->button);
      }
      break;
    case TeleopAction::Kind::kToggleMap:
      toggleKeyMap(!key_map_label_->isVisible());
      break;
  }
}

void MainWindow::toggleKeyMap(bool visible) {
  key_map_label_->setVisible(visible);
  key_map_label_->adjustSize();
  key_map_label_->move(12, std::max(0, view_->height() - key_map_label_->height() - 12));
  key_map_label_->raise();
  placeViewLabels();
}

void MainWindow::keyReleaseEvent(QKeyEvent* event) {
  if (event->isAutoRepeat()) {
    event->accept();
    return;
  }
  if (TeleopKeys::actionOf(event->key()) && !(event->modifiers() & (Qt::ControlModifier | Qt::AltModifier))) {
    // The time the key was held since the last display tick moves the target too: on a slow
    // display, most of a short press falls between ticks.
    driveKeyboard();
  }
  if (teleop_.release(event->key())) {
    event->accept();
    return;
  }
  QMainWindow::keyReleaseEvent(event);
}

void MainWindow::focusOutEvent(QFocusEvent* event) {
  // A key released while another window has the focus never arrives: let go of everything.
  teleop_.clear();
  QMainWindow::focusOutEvent(event);
}

void MainWindow::resizeEvent(QResizeEvent* event) {
  QMainWindow::resizeEvent(event);
  // Every pixel a window gains goes to the 3D view: grown back after a small screen, the Joints
  // dock had kept its squeezed width, its angles and ranges cut. It gets the width it asks for
  // back, at most 30 % of the window.
  if (!event->oldSize().isValid() || event->size().width() <= event->oldSize().width()) return;
  auto* joints_dock = findChild<QDockWidget*>(QStringLiteral("joints_dock"));
  if (joints_dock == nullptr || joints_dock->isFloating() || !joints_dock->isVisible()) return;
  const int wanted = std::min(joints_dock->sizeHint().width(), event->size().width() * 3 / 10);
  if (joints_dock->width() < wanted) resizeDocks({joints_dock}, {wanted}, Qt::Horizontal);
}

QString MainWindow::recordingAtRiskReason() const {
  QStringList reasons;
  if (recorder_ && recorder_->status().health == app::RecorderHealth::InMemory) {
    QString reason = QString::fromStdString(recorder_->status().message);
    reason.remove(QStringLiteral("; recording in memory"));  // the sentence says so already
    reasons << reason;
  } else if (recorder_ && !recorder_->fileHoldsTheRecording()) {
    reasons << tr("the session file %1 was removed or replaced while the run recorded").arg(session_file_);
  }
  if (!unsaved_recordings_.empty()) {
    reasons << tr("%n earlier recording(s) of this run found no file", nullptr, static_cast<int>(unsaved_recordings_.size()));
  }
  return reasons.join(QStringLiteral("; "));
}

void MainWindow::watchRecording() {
  if (!recordingAtRisk()) {
    clearProblem(Problem::kRecording);
    return;
  }
  const QString message =
      tr("The session is held in memory only (%1). File ▸ Save session as… keeps it.").arg(recordingAtRiskReason());
  const auto shown = problems_.find(Problem::kRecording);
  if (shown == problems_.end() || shown->second != message) reportProblem(Problem::kRecording, message);
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (recordingAtRisk()) {
    // Nothing on disk holds what the run recorded since its file failed. The recording ends
    // here (a new one would be held in memory again), and each held in memory is asked for
    // until all are saved or the rest discarded; Cancel records on.
    endRecording();
    while (!unsaved_recordings_.empty()) {
      const auto answer = QMessageBox::question(
          this, tr("Save session"),
          tr("This run's recording is held in memory only (%1). Save it before closing?").arg(recordingAtRiskReason()),
          QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, QMessageBox::Save);
      if (answer == QMessageBox::Discard) break;
      if (answer == QMessageBox::Cancel || !saveSessionAs()) {
        startRecording();
        event->ignore();
        return;
      }
    }
  } else if (teachingChangedSinceSave()) {
    const QString question =
        saved_session_ended_a_recording_
            ? tr("The teaching changed since the session was saved to %1, which holds the run up to its recording's "
                 "failure. Save the rest under another name?")
                  .arg(saved_session_file_)
            : tr("The teaching changed since the session was saved to %1. Save it there again?\n"
                 "(Every run is also recorded whole into %2.)")
                  .arg(saved_session_file_, session_file_.isEmpty() ? tr("no file: this run is not recorded") : session_file_);
    const auto answer = QMessageBox::question(this, tr("Save session"), question,
                                              QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, QMessageBox::Save);
    if (answer == QMessageBox::Cancel || (answer == QMessageBox::Save && !saveSessionAgain())) {
      event->ignore();
      return;
    }
  }
  if (options_.restore_layout) {
    QSettings settings;
    settings.setValue(QStringLiteral("window/geometry"), saveGeometry());
    settings.setValue(QStringLiteral("window/state"), saveState());
  }
  QMainWindow::closeEvent(event);
}

namespace {

// A coordinate shown to the millimetre: one that rounds to zero is shown as 0.000, not -0.000.
double shownMillimetres(double metres) { return std::abs(metres) < 0.0005 ? 0.0 : metres; }

}  // namespace

void MainWindow::updateStatus() {
  QString text;
  if (model_) {
    const Eigen::Vector3d p = kinematics_->p_WT();
    text = tr("robot %1 (%2 joints)   tip %3 at (%4, %5, %6) m   ")
               .arg(QString::fromStdString(model_->name()))
               .arg(model_->dof())
               .arg(QString::fromStdString(model_->tipLink()))
               .arg(shownMillimetres(p.x()), 0, 'f', 3)
               .arg(shownMillimetres(p.y()), 0, 'f', 3)
               .arg(shownMillimetres(p.z()), 0, 'f', 3);
  } else {
    text = tr("no robot   ");
  }
  // A long scene name would push the live fields off the bar.
  const QString scene_name = QString::fromStdString(scene_.name.empty() ? std::string("empty") : scene_.name);
  text += tr("scene %1").arg(status_label_->fontMetrics().elidedText(scene_name, Qt::ElideRight, 300));
  if (live_) {
    const app::CycleStatistics stats = live_->statistics();
    text += tr("   control %1 cycles, %2 late").arg(stats.cycles).arg(stats.deadline_misses);
    watchDeadlines(stats);
  }
  if (fps_ > 0.0) text += tr("   %1 fps").arg(fps_, 0, 'f', 1);
  status_label_->setText(text);
  // The fields sit right-aligned: a width that follows every sign, digit and cycle count would
  // shake them and the message beside them many times a second. The width only grows, until
  // another robot or scene starts.
  const QString fields_owner = QStringLiteral("%1 %2").arg(model_ ? QString::fromStdString(model_->name()) : QString(), scene_name);
  if (fields_owner != status_fields_owner_) {
    status_fields_owner_ = fields_owner;
    status_label_->setMinimumWidth(0);
  }
  // At most two thirds of the bar: a long text once must not hold the window wide for good.
  status_label_->setMinimumWidth(
      std::min(std::max(status_label_->minimumWidth(), status_label_->sizeHint().width()), statusBar()->width() * 2 / 3));
}

void MainWindow::watchDeadlines(const app::CycleStatistics& stats) {
  // Judged over windows of two seconds: a late cycle now and then is a busy machine, most
  // cycles late is an arm that no longer moves in real time (a scene of thousands of obstacles).
  if (!deadline_clock_.isValid() || stats.cycles < deadline_cycles_) {
    deadline_clock_.start();
    deadline_cycles_ = stats.cycles;
    deadline_misses_ = stats.deadline_misses;
    return;
  }
  if (deadline_clock_.elapsed() < 2000) return;
  const std::uint64_t cycles = stats.cycles - deadline_cycles_;
  const std::uint64_t misses = stats.deadline_misses - deadline_misses_;
  if (cycles >= 100 && 2 * misses > cycles) {
    reportProblem(Problem::kDeadlines,
                  tr("The control loop was late in %1 % of its last %2 cycles (the longest cycle since the start took %3 ms): "
                     "the robot does not move in real time. A scene of many obstacles or a busy machine does this.")
                      .arg(std::lround(100.0 * static_cast<double>(misses) / static_cast<double>(cycles)))
                      .arg(cycles)
                      .arg(stats.max_compute_us / 1000.0, 0, 'f', 1));
  } else {
    clearProblem(Problem::kDeadlines);
  }
  deadline_clock_.start();
  deadline_cycles_ = stats.cycles;
  deadline_misses_ = stats.deadline_misses;
}

void MainWindow::fillTeachingMenu() {
  // clear() leaves the submenus (their actions are theirs): they go with it.
  for (QMenu* submenu : teaching_menu_->findChildren<QMenu*>(QString(), Qt::FindDirectChildrenOnly)) delete submenu;
  teaching_menu_->clear();
  // Each entry clicks the panel's own control, so it is enabled exactly when that one is and
  // does what it does; one picked after the control was disabled changes no choice either.
  const auto add = [this](QMenu* menu, const QString& text, QAbstractButton* target, const std::function<void()>& choose = {}) {
    QAction* action = menu->addAction(text, this, [target, choose] {
      if (!target->isEnabled()) return;
      if (choose) choose();
      target->click();
    });
    action->setEnabled(target->isEnabled());
    return action;
  };
  add(teaching_menu_, tr("&Start configuration\tF5"), stage_panel_->button(app::Button::kStartConfiguration));
  add(teaching_menu_, tr("&Finish configuration\tF6"), stage_panel_->button(app::Button::kFinishedConfiguration));
  add(teaching_menu_, tr("Start &programming\tF7"), stage_panel_->button(app::Button::kStartProgramming));
  add(teaching_menu_, tr("Finish pro&gramming\tF8"), stage_panel_->button(app::Button::kFinishedProgramming));
  teaching_menu_->addSeparator();
  QMenu* replay = teaching_menu_->addMenu(tr("&Replay teach-in"));
  const int teach_ins = live_ ? live_->snapshot().teach_ins : 0;
  QSpinBox* replay_choice = stage_panel_->replayChoice();
  for (int k = 1; k <= teach_ins; ++k) {
    add(replay, tr("Teach-in %1").arg(k), stage_panel_->replayButton(), [replay_choice, k] { replay_choice->setValue(k); });
  }
  replay->setEnabled(stage_panel_->replayButton()->isEnabled());
  QComboBox* area_choice = stage_panel_->areaChoice();
  QMenu* remove = teaching_menu_->addMenu(tr("Re&move area"));
  QMenu* reteach = teaching_menu_->addMenu(tr("Re-&teach area"));
  for (int k = 0; k < area_choice->count(); ++k) {
    const auto choose = [area_choice, k] { area_choice->setCurrentIndex(k); };
    add(remove, area_choice->itemText(k), stage_panel_->removeAreaButton(), choose)->setIcon(area_choice->itemIcon(k));
    add(reteach, area_choice->itemText(k), stage_panel_->reteachAreaButton(), choose)->setIcon(area_choice->itemIcon(k));
  }
  remove->setEnabled(stage_panel_->removeAreaButton()->isEnabled());
  reteach->setEnabled(stage_panel_->reteachAreaButton()->isEnabled());
}

namespace {

// The menus' mnemonics underlined, so a keyboard user sees which Alt+letter opens which menu:
// Qt's Fusion style on Linux hides them. Alt-key navigation is asked for too; under Xvfb a bare
// Alt press still showed no highlight (docs/RELIABILITY.md, round twenty-two).
class MenuBarKeyboardStyle : public QProxyStyle {
 public:
  int styleHint(StyleHint hint, const QStyleOption* option, const QWidget* widget,
                QStyleHintReturn* returned) const override {
    if (hint == SH_MenuBar_AltKeyNavigation || hint == SH_UnderlineShortcut) return 1;
    return QProxyStyle::styleHint(hint, option, widget, returned);
  }
};

}  // namespace

void MainWindow::buildMenus() {
  auto* menu_bar_style = new MenuBarKeyboardStyle;
  menu_bar_style->setParent(menuBar());  // a widget does not own its style
  menuBar()->setStyle(menu_bar_style);
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("Open robot &URDF…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open robot description"), QString(),
                                                      tr("URDF (*.urdf *.xml);;All files (*)"));
    if (!path.isEmpty() && mayDiscardTeaching(tr("robot '%1'").arg(path))) loadRobot(path.toStdString());
  });
  file->addAction(tr("Open &scene…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open scene"), QString(),
                                                      tr("Scenes (*.yaml *.yml);;All files (*)"));
    if (!path.isEmpty() && mayDiscardTeaching(tr("scene '%1'").arg(path))) loadScene(path.toStdString());
  });
  file->addSeparator();
  file->addAction(tr("&Open recording…"), QKeySequence::Open, this, [this] {
    const QString path = QFileDialog::getOpenFileName(
        this, tr("Open a session recording"),
        saved_session_file_.isEmpty() ? sessionDirectory() : QFileInfo(saved_session_file_).absolutePath(),
        tr("FlexIRob sessions (*.flexirob *.sqlite *.db);;All files (*)"));
    if (!path.isEmpty() && openRecording(path) == nullptr) {
      QMessageBox::warning(this, tr("Open recording"), fullStatusMessage(statusBar()));
    }
  });
  file->addAction(tr("&Review this run"), this, [this] {
    if (session_file_.isEmpty()) {
      showStatusMessage(statusBar(), tr("This run is not recorded"), 10000);
      return;
    }
    handleEvents();
    if (live_) recordSnapshotData(live_->snapshot());
    if (recorder_) recorder_->flush();  // the review opens what is on disk
    openRecording(session_file_);
  });
  file->addAction(tr("&Save session"), QKeySequence::Save, this, &MainWindow::saveSessionAgain);
  file->addAction(tr("Save session &as…"), QKeySequence::SaveAs, this, &MainWindow::saveSessionAs);
  file->addAction(tr("Show session &folder"), this, [this] {
    QMessageBox::information(this, tr("Sessions"),
                             tr("Every run is recorded. This run: %1").arg(session_file_.isEmpty() ? tr("not recorded")
                                                                                                   : session_file_));
  });
  file->addAction(tr("Save &screenshot…"), this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Save screenshot"), QStringLiteral("flexirob.png"),
                                                      tr("PNG (*.png)"));
    if (!path.isEmpty() && !grab().save(path)) showStatusMessage(statusBar(), tr("Cannot write %1").arg(path), 10000);
  });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, this, &QWidget::close);

  // The Teaching panel's buttons take no keyboard focus (the keys tele-operate the arm): this
  // menu reaches each of them from the keyboard (Alt+T), with the keys the panel's buttons have.
  teaching_menu_ = menuBar()->addMenu(tr("&Teaching"));
  connect(teaching_menu_, &QMenu::aboutToShow, this, &MainWindow::fillTeachingMenu);
  fillTeachingMenu();

  robot_menu_ = menuBar()->addMenu(tr("&Robot"));
  auto* robots = new QActionGroup(this);
  for (const std::string& name : builtinRobotNames()) {
    QAction* action = robot_menu_->addAction(QString::fromStdString(name), this, [this, name] {
      if (mayDiscardTeaching(tr("robot '%1'").arg(QString::fromStdString(name)))) {
        loadRobot(name);
      } else {
        markLoadedChoices();
      }
    });
    action->setData(QString::fromStdString(name));
    action->setCheckable(true);
    robots->addAction(action);
  }

  scene_menu_ = menuBar()->addMenu(tr("&Scene"));
  auto* scenes = new QActionGroup(this);
  for (const std::string& name : robot::builtinSceneNames()) {
    QAction* action = scene_menu_->addAction(QString::fromStdString(name), this, [this, name] {
      if (mayDiscardTeaching(tr("scene '%1'").arg(QString::fromStdString(name)))) {
        chooseScene(name);
      } else {
        markLoadedChoices();
      }
    });
    action->setData(QString::fromStdString(name));
    action->setCheckable(true);
    scenes->addAction(action);
  }

  backend_menu_ = menuBar()->addMenu(tr("&Backend"));
  auto* backends = new QActionGroup(this);
  // A new backend restarts the teaching as a new robot does; taken back, the menu shows the
  // backend that runs.
  const auto markBackend = [this] {
    for (QAction* action : backend_menu_->actions()) {
      if (action->data().toString() == QStringLiteral("sim")) action->setChecked(backend_.kind == app::BackendKind::kSimulation);
      if (action->data().toString() == QStringLiteral("fri")) action->setChecked(backend_.kind == app::BackendKind::kFri);
    }
  };
  const auto switchBackend = [this, markBackend](const std::string& choice, const QString& what) {
    if (!mayDiscardTeaching(what) || !setBackend(choice)) markBackend();
  };
  // The simulation chosen while it runs changes nothing (it had offered to discard the teaching).
  const auto backToSimulation = [this, switchBackend, markBackend] {
    if (backend_.kind == app::BackendKind::kSimulation) {
      markBackend();
      return;
    }
    switchBackend("sim", tr("simulation"));
  };
  QAction* sim = backend_menu_->addAction(tr("&Simulation"), this, backToSimulation);
  sim->setData(QStringLiteral("sim"));
  sim->setCheckable(true);
  sim->setChecked(backend_.kind == app::BackendKind::kSimulation);
  backends->addAction(sim);
  QAction* fri = backend_menu_->addAction(tr("&Connect to the LWR IV over FRI…"), this, [this, switchBackend, markBackend] {
    bool ok = false;
    const QString address = QInputDialog::getText(this, tr("Connect to the robot"),
                                                  tr("Robot controller (fri://ADDRESS:PORT):"), QLineEdit::Normal,
                                                  QStringLiteral("fri://192.168.0.20:49938"), &ok);
    if (ok && !address.isEmpty()) {
      switchBackend(address.toStdString(), tr("robot at %1").arg(address));
    } else {
      markBackend();
    }
  });
  fri->setData(QStringLiteral("fri"));
  fri->setCheckable(true);
  fri->setChecked(backend_.kind == app::BackendKind::kFri);
  backends->addAction(fri);
  backend_menu_->addSeparator();
  QAction* disconnect = backend_menu_->addAction(tr("&Disconnect (back to the simulation)"), this, backToSimulation);
  disconnect->setObjectName(QStringLiteral("disconnect_backend"));
  connect(backend_menu_, &QMenu::aboutToShow, disconnect,
          [this, disconnect] { disconnect->setEnabled(backend_.kind != app::BackendKind::kSimulation); });
  disconnect->setEnabled(backend_.kind != app::BackendKind::kSimulation);
  reconnect_action_ = backend_menu_->addAction(tr("&Confirm reconnect after a fault"), this, [this] {
    if (!live_) return;
    if (QMessageBox::question(this, tr("Reconnect"),
                              tr("The link watchdog stopped commanding the robot. Is the robot's surrounding clear "
                                 "and should commanding resume?")) == QMessageBox::Yes) {
      live_->requestReconnect();
    }
  });
  reconnect_action_->setEnabled(false);

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), QKeySequence(Qt::Key_Home), view_, &OsgView::resetCamera);
  QAction* grid = view->addAction(tr("Ground &grid"));
  grid->setCheckable(true);
  grid->setChecked(true);
  connect(grid, &QAction::toggled, this, [this](bool on) {
    world_.setGridVisible(on);
    view_->requestFrame();
  });
  view->addAction(tr("&Key map (F1, H)"), this, [this] { toggleKeyMap(!key_map_label_->isVisible()); });
  view->addSeparator();
  for (QDockWidget* dock : findChildren<QDockWidget*>()) view->addAction(dock->toggleViewAction());
  auto* overlay_menu = new OverlayMenu(*overlays_, this);
  overlay_menu->setTitle(tr("&Overlays"));
  menuBar()->addMenu(overlay_menu);
  connect(overlay_menu, &OverlayMenu::toggled, this, [this] { view_->requestFrame(); });
  QMenu* help = menuBar()->addMenu(tr("&Help"));
  // In a box of its own: in the status bar the list was cut to the bar's width.
  help->addAction(tr("&Mouse"), this, [this] {
    QMessageBox::information(this, tr("Mouse"),
                             tr("<b>In the 3D view</b><ul>"
                                "<li>Left drag on a link: pull the arm (as a hand on the robot)</li>"
                                "<li>Left drag elsewhere: orbit the view</li>"
                                "<li>Middle or Shift+left drag: pan</li>"
                                "<li>Right drag or wheel: zoom</li>"
                                "<li>Double click: the home view (also View ▸ Reset camera, Home)</li>"
                                "<li>Ctrl+click in EXECUTION: set a goal, plan a path to it and execute it</li></ul>"));
  });
  help->addAction(tr("&Keys (F1, H)"), this, [this] { toggleKeyMap(true); });
  help->addAction(tr("&User guide"), this, [this] {
    const std::filesystem::path guide = flexirob::resourceDir().parent_path() / "docs" / "USER_GUIDE.md";
    std::error_code missing;
    QMessageBox::information(this, tr("User guide"),
                             std::filesystem::is_regular_file(guide, missing)
                                 ? tr("The user guide, with pictures, is %1").arg(QString::fromStdString(guide.string()))
                                 : tr("The user guide is docs/USER_GUIDE.md in FlexIRob's source folder."));
  });
  help->addSeparator();
  help->addAction(tr("&About FlexIRob"), this, [this] {
    QMessageBox::about(this, tr("About FlexIRob"),
                       tr("<b>FlexIRob %1</b><br>Teaching redundant robot arms: show the posture in a few "
                          "training areas, then guide only the tip.<br><br>Qt %2, OpenSceneGraph %3")
                           .arg(QStringLiteral(FLEXIROB_VERSION_STRING), QString::fromLatin1(qVersion()),
                                QString::fromLatin1(osgGetVersion())));
  });
  // A menu closed with Escape leaves the menu bar holding the keys: Space and Enter then opened
  // the File menu and ran its first entry instead of touching the arm. The keys go back where
  // they were before the menu opened (the view if nowhere), once no menu is open (not while the
  // arrow keys move from one menu to the next).
  for (QAction* entry : menuBar()->actions()) {
    if (entry->menu() == nullptr) continue;
    connect(entry->menu(), &QMenu::aboutToShow, this, [this] {
      QWidget* focus = QApplication::focusWidget();
      if (focus != nullptr && focus != menuBar() && qobject_cast<QMenu*>(focus) == nullptr) focus_before_menu_ = focus;
    });
    connect(entry->menu(), &QMenu::aboutToHide, this, [this] {
      QTimer::singleShot(0, this, [this] {
        if (QApplication::activePopupWidget() != nullptr || !menuBar()->hasFocus()) return;
        QWidget* back = focus_before_menu_ ? focus_before_menu_.data() : view_;
        back->setFocus(Qt::OtherFocusReason);
      });
    });
  }
}

// --- Plots, confidence slices, goals, recordings -------------------------------------------

void MainWindow::updatePlots(const LiveSnapshot& s) {
  if (plot_clock_.isValid() && plot_clock_.elapsed() < kPlotPeriodMs) return;
  plot_clock_.start();
  PlotSample sample;
  sample.time = s.time;
  // Task error of the interaction controller: |x_des − x| of the tip [m]; none (NaN, not drawn)
  // while π_q or π_rec holds a posture under the hand: x_des is then only where the tip began.
  sample.task_error = std::sqrt((s.p_des[0] - s.p_WT[0]) * (s.p_des[0] - s.p_WT[0]) +
                                (s.p_des[1] - s.p_WT[1]) * (s.p_des[1] - s.p_WT[1]) +
                                (s.p_des[2] - s.p_WT[2]) * (s.p_des[2] - s.p_WT[2]));
  sample.q.resize(s.dof);
  for (int j = 0; j < s.dof; ++j) sample.q[j] = s.q[static_cast<std::size_t>(j)];
  sample.compute_us = s.statistics.last_compute_us;
  sample.max_compute_us = s.statistics.max_compute_us;
  sample.deadline_misses = static_cast<double>(s.statistics.deadline_misses);
  plot_panel_->append(sample);
}

void MainWindow::updateConfidence(const LiveSnapshot& s, bool force) {
  if (!force && s.model_version == shown_model_version_) return;
  shown_model_version_ = s.model_version;
  const std::shared_ptr<const learning::ConfidenceModel> model = s.confidence;
  if (!model || model->areas() == 0) {
    overlays_->setContent(render::OverlayLayer::kConfidence, nullptr);
    confidence_slices_ = 0;
    confidence_panel_->setStatus(tr("No training area yet: the confidence field C(x) (Eq. 6.9) appears with the first."));
    return;
  }
  if (!operator_heights_) {
    // Until the operator picks heights, the middle slice passes through the areas' mean height.
    const QSignalBlocker block(confidence_panel_);
    confidence_panel_->setSettings(centredSlices(*model, confidence_panel_->settings()));
  }
  const std::vector<render::ConfidenceGrid> slices = confidenceSlices(*model, confidence_panel_->settings());
  overlays_->setContent(render::OverlayLayer::kConfidence, makeConfidenceOverlay(slices));
  confidence_slices_ = static_cast<int>(slices.size());
  double highest = 0.0;
  double at = 0.0;
  for (const render::ConfidenceGrid& grid : slices) {
    if (grid.values.maxCoeff() > highest) {
      highest = grid.values.maxCoeff();
      at = grid.z;
    }
  }
  const QString areas = model->areas() == 1 ? tr("1 area") : tr("%1 areas").arg(model->areas());
  confidence_panel_->setStatus(tr("%1; largest C on the slices %2 at z = %3 m")
                                   .arg(areas)
                                   .arg(highest, 0, 'f', 2)
                                   .arg(at, 0, 'f', 2));
}

QWidget* MainWindow::confidenceLegend() const { return confidence_legend_; }

void MainWindow::placeViewLabels() {
  // Overlays ▸ Legend hides it as it hides the rendered legends.
  const bool legend = confidence_slices_ > 0 && overlays_->visible(render::OverlayLayer::kConfidence) &&
                      overlays_->visible(render::OverlayLayer::kLegend);
  if (legend != confidence_legend_->isVisible()) confidence_legend_->setVisible(legend);
  // A key, not a panel: at most 30 % of the view's height (on a 600 px screen it hid the arm).
  const int legend_height = std::clamp(view_->height() * 3 / 10, 90, confidence_legend_->sizeHint().height());
  if (confidence_legend_->height() != legend_height) confidence_legend_->resize(confidence_legend_->sizeHint().width(), legend_height);
  QPoint corner(std::max(0, view_->width() - confidence_legend_->width() - 12),
               std::max(0, view_->height() - confidence_legend_->height() - 12));
  // The key map (lower left) can be wide, the 9-DoF arm's above all: the colour bar then
  // stands above it rather than behind it.
  if (key_map_label_->isVisible() && key_map_label_->geometry().right() + 8 > corner.x()) {
    corner.setY(std::max(0, key_map_label_->geometry().top() - confidence_legend_->height() - 8));
  }
  if (confidence_legend_->pos() != corner) confidence_legend_->move(corner);
  // The problems under the banner, across the view at most 720 px wide, every line whole.
  if (problem_label_->isVisible()) {
    const int width = std::clamp(view_->width() - 24, 120, 720);
    const int height = problem_label_->heightForWidth(width);
    problem_label_->resize(width, height > 0 ? height : problem_label_->sizeHint().height());
    const int top = banner_label_->isVisible() && !banner_label_->text().isEmpty() ? banner_label_->geometry().bottom() + 8 : 10;
    problem_label_->move(std::max(0, (view_->width() - width) / 2), top);
    problem_label_->raise();
  }
}

void MainWindow::clickGoal(const QPointF& position) {
  if (!live_ || !model_) return;
  const LiveSnapshot& s = live_->snapshot();
  std::vector<Eigen::Vector3d> nodes;
  if (s.itm) {
    for (const int id : s.itm->nodeIds()) {
      const auto omega = s.itm->prototype(id);
      nodes.emplace_back(omega[0], omega[1], omega[2]);
    }
  }
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
  view_->ray(position, origin, direction);
  const std::optional<GoalPick> pick = pickGoal(view_->currentCamera(), view_->width(), view_->height(),
                                                Eigen::Vector2d(position.x(), position.y()), nodes, origin,
                                                direction, s.p_WT[2]);
  if (!pick) {
    showStatusMessage(statusBar(), tr("No goal there: click on the explored region (the ITM graph)"), 8000);
    return;
  }
  setGoal(pick->goal_W);
}

double MainWindow::goalMarkerRadius() const {
  // 2.5 cm on the LWR IV; a 25 cm arm's goal is no ball as big as its forearm.
  return 0.025 * (model_ ? render::robotSizeScale(*model_) : 1.0);
}

bool MainWindow::setGoal(const Eigen::Vector3d& goal_W) {
  if (!live_ || !goal_W.allFinite()) return false;
  const bool executing = live_->snapshot().stage == app::Stage::kExecution;
  if (executing) {
    goal_ = goal_W;
    // The goal shows at once; the path joins it when the workflow has planned it.
    overlays_->setContent(render::OverlayLayer::kGoalAndPath, render::makeGoalMarker(goal_W, goalMarkerRadius()));
    showStatusMessage(statusBar(), tr("Goal (%1, %2, %3) m: planning through the ITM graph")
                                 .arg(shownMillimetres(goal_W.x()), 0, 'f', 3)
                                 .arg(shownMillimetres(goal_W.y()), 0, 'f', 3)
                                 .arg(shownMillimetres(goal_W.z()), 0, 'f', 3),
                             8000);
  }
  // Outside EXECUTION the workflow refuses and says why (shown as a warning).
  const bool posted = live_->planTo(goal_W);
  view_->requestFrame();
  return posted;
}

void MainWindow::clearGoal() {
  if (!goal_ && !goal_moving_) return;
  goal_.reset();
  goal_moving_ = false;
  overlays_->setContent(render::OverlayLayer::kGoalAndPath, nullptr);
  shown_path_version_ = live_ ? live_->snapshot().path_version : shown_path_version_;
  view_->requestFrame();
}

void MainWindow::updateGoalAndPath(const LiveSnapshot& s) {
  // A replay ends as a motion to a goal does: said, so that the operator knows the arm is free.
  if (replay_moving_ && (s.stage != app::Stage::kExecution || (s.execution_done && s.time > replay_time_))) {
    double fastest = 0.0;
    for (int j = 0; j < s.dof; ++j) fastest = std::max(fastest, std::abs(s.qd[static_cast<std::size_t>(j)]));
    if (s.stage != app::Stage::kExecution || fastest < 0.01) {
      replay_moving_ = false;
      if (s.stage == app::Stage::kExecution) showStatusMessage(statusBar(), tr("Replay of %1 done").arg(replay_name_), 10000);
    }
  }
  // The motion to a goal ends: say where the tip came to rest against it (the path is done when
  // its target arrives; the arm follows a moment later).
  if (goal_ && s.stage == app::Stage::kExecution) {
    double fastest = 0.0;  // [rad/s] (or [m/s] of a slide)
    for (int j = 0; j < s.dof; ++j) fastest = std::max(fastest, std::abs(s.qd[static_cast<std::size_t>(j)]));
    // A snapshot from before the plan was accepted shows the last motion done.
    if (s.execution_done && goal_moving_ && s.time > goal_plan_time_ && fastest < 0.01) {
      goal_moving_ = false;
      const double gap = (Eigen::Map<const Eigen::Vector3d>(s.p_WT.data()) - *goal_).norm();
      showStatusMessage(statusBar(), tr("Goal reached: the tip came to rest %1 mm from it").arg(gap * 1e3, 0, 'f', 1), 10000);
    }
  }
  if (s.path_version == shown_path_version_) return;
  shown_path_version_ = s.path_version;
  overlays_->setContent(render::OverlayLayer::kGoalAndPath, nullptr);
  if (goal_) overlays_->addContent(render::OverlayLayer::kGoalAndPath, render::makeGoalMarker(*goal_, goalMarkerRadius()));
  if (!s.path || !s.path->found) return;
  std::vector<Eigen::Vector3d> waypoints;
  for (Eigen::Index k = 0; k < s.path->waypoints.cols(); ++k) waypoints.emplace_back(s.path->waypoints.col(k));
  overlays_->addContent(render::OverlayLayer::kGoalAndPath,
                        render::makePolyline(waypoints, render::OverlayPalette::plannedPath(), 4.0F));
  overlays_->addContent(render::OverlayLayer::kGoalAndPath,
                        render::makePoints(waypoints, render::OverlayPalette::plannedPath(), 8.0F));
}

void MainWindow::recordItm(const LiveSnapshot& s, bool final) {
  if (!recorder_ || !s.itm || s.itm_version == recorded_itm_version_ || s.itm->nodeCount() == 0) return;
  const double period_ms = 1000.0 * app::itmSnapshotPeriod(kItmRecordPeriodMs / 1000.0, recorded_itm_bytes_);
  if (!final && itm_record_clock_.isValid() && static_cast<double>(itm_record_clock_.elapsed()) < period_ms) return;
  itm_record_clock_.start();
  recorded_itm_version_ = s.itm_version;
  try {
    app::ItmRecord record;
    record.time = s.time;
    record.nodes = s.itm->nodeCount();
    record.edges = s.itm->edgeCount();
    record.bytes = planning::itmToBytes(*s.itm);  // the graph's own format (planning/itm_file.hpp)
    recorded_itm_bytes_ = record.bytes.size();
    recorder_->recordItm(std::move(record));
  } catch (const std::exception& error) {
    reportError(tr("Cannot record the ITM graph"), error);
  }
}

void MainWindow::recordModel(const LiveSnapshot& s) {
  if (!recorder_ || !s.model || !s.model_ready || s.model == recorded_model_) return;
  recorded_model_ = s.model;
  try {
    app::ModelRecord record;
    record.time = s.time;
    record.learner_kind = s.model->kind();
    record.samples = s.model_samples;
    record.train_seconds = s.learning_seconds;
    const std::string text = s.model->modelText();
    record.bytes.assign(text.begin(), text.end());
    recorder_->recordModel(std::move(record));
  } catch (const std::exception& error) {
    reportError(tr("Cannot record the learned model"), error);
  }
}

void MainWindow::recordSnapshotData(const LiveSnapshot& s) {
  recordItm(s, true);
  recordModel(s);
}

ReviewWindow* MainWindow::openRecording(const QString& file) {
  auto* review = new ReviewWindow(this);  // a window of its own, closed with the main window
  review->setAttribute(Qt::WA_DeleteOnClose);
  if (!review->open(file.toStdString())) {
    showStatusMessage(statusBar(), tr("Cannot open %1: %2").arg(file, review->errorString()), 15000);
    delete review;
    return nullptr;
  }
  review->show();
  reviews_.emplace_back(review);
  return review;
}

std::vector<ReviewWindow*> MainWindow::reviewWindows() const {
  std::vector<ReviewWindow*> open;
  for (const QPointer<ReviewWindow>& review : reviews_) {
    if (!review.isNull()) open.push_back(review.data());
  }
  return open;
}

}  // namespace flexirob::ui
