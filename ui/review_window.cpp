#include "ui/review_window.hpp"

#include <QThread>

#include "ui/stage_panel.hpp"

#include <QComboBox>
#include <QDateTime>
#include <QDockWidget>
#include <QFontMetrics>
#include <QHBoxLayout>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMouseEvent>
#include <QPainter>
#include <QPushButton>
#include <QSplitter>
#include <QScreen>
#include <QStatusBar>
#include <QTimer>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>

#include "app/session_reader.hpp"
#include "app/session_teaching.hpp"
#include "learning/confidence.hpp"
#include "planning/itm_file.hpp"
#include "render/overlays.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"
#include "ui/confidence_panel.hpp"
#include "ui/osg_view.hpp"
#include "ui/overlay_menu.hpp"
#include "ui/plot_panel.hpp"
#include "ui/status_message.hpp"

namespace flexirob::ui {

// The whole name where there is room; on a narrow window (an 800 px screen) as much as fits,
// ended with an ellipsis, and whole in its tooltip. A QLabel would hold the window as wide as the
// longest stage name.
class StageLabel : public QLabel {
 public:
  using QLabel::QLabel;

  void setStage(const QString& stage) {
    if (stage == stage_) return;
    stage_ = stage;
    setToolTip(stage);
    updateGeometry();
    fit();
  }
  QSize sizeHint() const override {
    return {fontMetrics().horizontalAdvance(stage_) + kPadding, QLabel::sizeHint().height()};
  }
  QSize minimumSizeHint() const override { return {kShortest, QLabel::minimumSizeHint().height()}; }

 protected:
  void resizeEvent(QResizeEvent* event) override {
    QLabel::resizeEvent(event);
    fit();
  }

 private:
  static constexpr int kPadding = 20;   // the style sheet's 8 px each side, and the frame
  static constexpr int kShortest = 110;  // "CONFIGURATI…": enough to tell the stages apart

  void fit() { setText(fontMetrics().elidedText(stage_, Qt::ElideRight, std::max(0, width() - kPadding))); }

  QString stage_;
};

namespace {

// States picked for the plots: enough for a smooth curve across a wide window, few enough to
// read through the time index in milliseconds.
constexpr int kPlotPoints = 2000;
// A collision is shown for this long after it was recorded [s] (contacts are recorded as events).
constexpr double kCollisionHold = 0.1;

// The robot a recording was made with: the built-in or file model if it still resolves, else
// the recorded URDF text (meshes resolved against the robot resources).
// A recording made on another machine may name meshes this one lacks (the session holds the
// URDF's text, not its mesh files): the arm is then drawn without them, and `left_out` says
// which.
robot::RobotModel recordedRobot(const app::SessionMetadata& meta, std::vector<std::string>* left_out) {
  try {
    const std::filesystem::path path = resolveRobotPath(meta.robot_name);
    if (std::filesystem::exists(path)) return robot::RobotModel::fromUrdfFile(path, meta.tip_link);
  } catch (const InputError&) {
    // Neither a built-in name nor an existing file any more: the recorded text follows.
  }
  if (meta.robot_urdf.empty()) throw InputError("the recording holds no robot description");
  return robot::RobotModel::fromUrdfString(meta.robot_urdf, resourceDir() / "robots", meta.tip_link, left_out);
}

std::string bandLabel(const app::StageRecord& stage) {
  return stage.sub_stage.empty() ? stage.stage : stage.stage + " / " + stage.sub_stage;
}

}  // namespace

QColor stageColor(const std::string& label) {
  // The live window's colours (StagePanel::stageColor), so that a stage reads alike in both.
  const std::size_t slash = label.find(" / ");
  const std::string stage_name = label.substr(0, slash);
  const std::string sub_name = slash == std::string::npos ? std::string() : label.substr(slash + 3);
  std::optional<app::Stage> stage;
  for (const app::Stage candidate : {app::Stage::kIdle, app::Stage::kConfiguration, app::Stage::kProgramming, app::Stage::kExecution}) {
    if (stage_name == app::toString(candidate)) stage = candidate;
  }
  std::optional<app::SubStage> sub_stage;
  for (const app::SubStage candidate : {app::SubStage::kNone, app::SubStage::kWaiting, app::SubStage::kApproaching,
                                        app::SubStage::kPosed, app::SubStage::kRecording, app::SubStage::kTeachIn}) {
    if (sub_name == app::toString(candidate)) sub_stage = candidate;
  }
  if (stage && sub_stage) return StagePanel::stageColor(*stage, *sub_stage);
  // A stage this version does not know (a newer recording): a colour of its own.
  const auto hue = static_cast<int>(std::hash<std::string>{}(label) % 360U);
  return QColor::fromHsv(hue, 110, 230);
}

// --- Timeline -------------------------------------------------------------------------------

Timeline::Timeline(QWidget* parent) : QWidget(parent) {
  setMouseTracking(true);  // the tooltip follows the pointer without a button held
  setMinimumHeight(48);
  setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
  setFixedHeight(56);
}

void Timeline::setRange(double t0, double t1) {
  t0_ = t0;
  t1_ = t1 > t0 ? t1 : t0 + 1e-3;
  update();
}

void Timeline::setBands(std::vector<StageBand> bands) {
  bands_ = std::move(bands);
  update();
}

void Timeline::setMarkers(std::vector<TimelineMarker> markers) {
  markers_ = std::move(markers);
  update();
}

void Timeline::setTime(double time) {
  time_ = time;
  update();
}

double Timeline::xOf(double time) const { return 4.0 + (width() - 8.0) * (time - t0_) / (t1_ - t0_); }

double Timeline::timeAt(double x) const {
  return std::clamp(t0_ + (x - 4.0) / std::max(1.0, width() - 8.0) * (t1_ - t0_), t0_, t1_);
}

QString Timeline::describeAt(double x) const {
  QStringList lines;
  const double time = timeAt(x);
  for (const StageBand& band : bands_) {
    if (time < band.t0 || time > band.t1) continue;
    // To the millisecond, as the time readout: a phase of 40 ms is one of those to be read here.
    lines << QStringLiteral("%1: %2 s to %3 s (%4 s)")
                 .arg(QString::fromStdString(band.label))
                 .arg(band.t0, 0, 'f', 3)
                 .arg(band.t1, 0, 'f', 3)
                 .arg(band.t1 - band.t0, 0, 'f', 3);
    break;
  }
  // Within the reach of a pointer: a tick or a triangle is 2-10 px wide.
  constexpr double kNearPixels = 5.0;
  for (const TimelineMarker& marker : markers_) {
    if (std::abs(xOf(marker.time) - x) > kNearPixels) continue;
    lines << QStringLiteral("%1 %2 at %3 s")
                 .arg(marker.trigger ? QStringLiteral("trigger") : QStringLiteral("button"))
                 .arg(QString::fromStdString(marker.name))
                 .arg(marker.time, 0, 'f', 3);
  }
  return lines.join(QLatin1Char('\n'));
}

void Timeline::paintEvent(QPaintEvent* /*event*/) {
  QPainter painter(this);
  painter.fillRect(rect(), QColor(245, 246, 248));
  const int band_top = 14;
  const int band_height = height() - 28;
  for (const StageBand& band : bands_) {
    const double x0 = xOf(band.t0);
    const double x1 = xOf(band.t1);
    const QRectF area(x0, band_top, std::max(1.0, x1 - x0), band_height);
    painter.fillRect(area, stageColor(band.label));
    // The whole "STAGE / SUB-STAGE" where it fits, else the sub-stage, which tells neighbouring
    // bands apart, elided as far as needed; a cut-off word reads as another label.
    const QRectF text_area = area.adjusted(3, 0, -3, 0);
    const QString label = QString::fromStdString(band.label);
    const QFontMetrics metrics = painter.fontMetrics();
    QString shown = label;
    if (metrics.horizontalAdvance(shown) > text_area.width()) {
      shown = metrics.elidedText(label.section(QStringLiteral(" / "), -1), Qt::ElideRight, static_cast<int>(text_area.width()));
    }
    if (text_area.width() > 20.0 && shown != QStringLiteral("…")) {
      painter.setPen(Qt::white);  // on the stage colours, as the live window's banner writes
      painter.drawText(text_area, Qt::AlignVCenter | Qt::AlignLeft, shown);
    }
  }
  // Triggers as ticks above the bands, buttons as triangles below.
  for (const TimelineMarker& marker : markers_) {
    const double x = xOf(marker.time);
    if (marker.trigger) {
      painter.setPen(QPen(QColor(20, 20, 25), 2.0));
      painter.drawLine(QPointF(x, 2), QPointF(x, band_top + 4));
    } else {
      painter.setPen(Qt::NoPen);
      painter.setBrush(QColor(20, 60, 160));
      const double y = band_top + band_height + 2;
      painter.drawPolygon(QPolygonF({QPointF(x, y), QPointF(x - 5, y + 9), QPointF(x + 5, y + 9)}));
    }
  }
  const double x = xOf(time_);
  painter.setPen(QPen(QColor(200, 30, 30), 2.0));
  painter.drawLine(QPointF(x, 0), QPointF(x, height()));
}

void Timeline::mousePressEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton) Q_EMIT timeRequested(timeAt(event->position().x()));
}

void Timeline::mouseMoveEvent(QMouseEvent* event) {
  // The tooltip Qt shows where the pointer rests says what lies there.
  setToolTip(describeAt(event->position().x()));
  if ((event->buttons() & Qt::LeftButton) != 0) Q_EMIT timeRequested(timeAt(event->position().x()));
}

// --- ReviewWindow ---------------------------------------------------------------------------

struct ReviewWindow::Events {
  std::vector<app::SampleRecord> samples;
  std::vector<app::AreaRecord> areas;
  std::vector<app::SignalRecord> signals;
  std::vector<app::TrajectoryRecord> trajectories;
  std::vector<app::CollisionRecord> collisions;
  std::vector<app::ItmRecord> itm;  // in time order, thinned
};

ReviewWindow::ReviewWindow(QWidget* parent)
    : QMainWindow(parent), world_(std::make_unique<render::World>()), events_(std::make_unique<Events>()) {
  setWindowTitle(QStringLiteral("FlexIRob review"));
  auto* central = new QWidget(this);
  auto* layout = new QVBoxLayout(central);
  auto* splitter = new QSplitter(Qt::Horizontal, central);
  view_ = new OsgView(splitter);
  view_->setSceneRoot(world_->root());
  view_->setMinimumSize(360, 300);
  plots_ = new PlotPanel(splitter);
  splitter->addWidget(view_);
  splitter->addWidget(plots_);
  splitter->setStretchFactor(0, 3);
  splitter->setStretchFactor(1, 2);
  splitter->setSizes({700, 480});
  plots_->setCycleStatisticsVisible(false);  // recordings hold no control-cycle statistics
  layout->addWidget(splitter, 1);

  timeline_ = new Timeline(central);
  layout->addWidget(timeline_);
  auto* controls = new QHBoxLayout();
  // Arrows alone, the words in their tooltips: the row leaves the stage's name room on an 800 px screen.
  auto* back = new QPushButton(QStringLiteral("◀"), central);
  back->setToolTip(QStringLiteral("One frame back (←; Shift+← a second)"));
  play_button_ = new QPushButton(QStringLiteral("Play"), central);
  auto* forward = new QPushButton(QStringLiteral("▶"), central);
  forward->setToolTip(QStringLiteral("One frame on (→; Shift+→ a second)"));
  for (QPushButton* arrow : {back, forward}) arrow->setFixedWidth(arrow->fontMetrics().horizontalAdvance(arrow->text()) + 28);
  speed_box_ = new QComboBox(central);
  for (double speed : {-4.0, -2.0, -1.0, -0.5, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0}) {
    speed_box_->addItem(QStringLiteral("%1×").arg(speed), speed);
  }
  speed_box_->setCurrentIndex(speed_box_->findData(1.0));
  speed_box_->setToolTip(QStringLiteral("Playback speed (negative: backwards)"));
  time_label_ = new QLabel(central);
  stage_label_ = new StageLabel(central);
  QFont big = stage_label_->font();
  big.setBold(true);
  stage_label_->setFont(big);
  // The controls take no keyboard focus: Space, the arrows, Home and End belong to the window
  // (playback, stepping), not to whichever control was clicked last (a focused speed box would
  // open on Space and change the speed on Home).
  for (QWidget* control : std::initializer_list<QWidget*>{back, play_button_, forward, speed_box_}) {
    control->setFocusPolicy(Qt::NoFocus);
  }
  for (QWidget* widget : std::initializer_list<QWidget*>{back, play_button_, forward, speed_box_, time_label_}) {
    controls->addWidget(widget);
  }
  controls->addStretch(1);
  controls->addWidget(stage_label_);
  layout->addLayout(controls);
  setCentralWidget(central);

  timer_ = new QTimer(this);
  timer_->setInterval(33);
  connect(timer_, &QTimer::timeout, this, &ReviewWindow::advance);
  connect(play_button_, &QPushButton::clicked, this, [this] { playing() ? pause() : play(); });
  connect(back, &QPushButton::clicked, this, [this] { stepFrames(-1); });
  connect(forward, &QPushButton::clicked, this, [this] { stepFrames(1); });
  connect(speed_box_, &QComboBox::currentIndexChanged, this,
          [this](int index) { setSpeed(speed_box_->itemData(index).toDouble()); });
  connect(timeline_, &Timeline::timeRequested, this, &ReviewWindow::setTime);
  connect(plots_, &PlotPanel::cursorTimeChanged, this, &ReviewWindow::setTime);
  auto* overlay_menu = new OverlayMenu(world_->overlays(), this);
  menuBar()->addMenu(overlay_menu);
  connect(overlay_menu, &OverlayMenu::toggled, view_, [this] { view_->requestFrame(); });

  confidence_panel_ = new ConfidencePanel(this);
  auto* confidence_dock = new QDockWidget(QStringLiteral("Confidence"), this);
  confidence_dock->setObjectName(QStringLiteral("confidence_dock"));
  confidence_dock->setWidget(confidence_panel_);
  addDockWidget(Qt::LeftDockWidgetArea, confidence_dock);
  connect(confidence_panel_, &ConfidencePanel::settingsChanged, this, [this] {
    operator_heights_ = true;
    updateConfidence(true);
    view_->requestFrame();
  });
  const QRect room = screen() != nullptr ? screen()->availableGeometry() : QRect(0, 0, 1200, 760);
  resize(std::min(1200, room.width()), std::min(760, room.height()));
  showStatusMessage(statusBar(), QStringLiteral("Open a session recording"));
}

ReviewWindow::~ReviewWindow() {
  // A check still reading a large file is waited for: it writes into what it was given only.
  for (QThread* check : damage_checks_) check->wait();
  // The view draws the world: detach it before the world goes.
  view_->setSceneRoot(nullptr);
}

void ReviewWindow::checkForDamage(const std::filesystem::path& file) {
  // The quick check reads every page (seconds for a long recording at 1 kHz): on a thread of its
  // own, so that the window plays at once; the verdict comes when the check ends.
  auto finding = std::make_shared<std::string>();
  QThread* check = QThread::create([file, finding] { *finding = app::SessionReader::damageOf(file); });
  check->setParent(this);  // freed with the window if it closes before the verdict is taken
  damage_checks_.push_back(check);
  connect(check, &QThread::finished, this, [this, check, finding, file] {
    std::erase(damage_checks_, check);
    check->deleteLater();
    if (finding->empty() || !reader_ || reader_->file() != file) return;
    damage_ = QString::fromUtf8(printable(*finding, 300).c_str());
    setWindowTitle(QStringLiteral("FlexIRob review — %1 (damaged)").arg(QString::fromStdString(file.filename().string())));
    // Played as far as it reads: a file damaged at its end still holds the session before.
    const QString status = QStringLiteral("session file %1 is damaged (%2); what could be read is shown")
                               .arg(QString::fromStdString(file.string()), damage_);
    qWarning("warning: %s", qPrintable(status));
    showStatusMessage(statusBar(), status, 30000);
  });
  check->start();
}

bool ReviewWindow::open(const std::filesystem::path& file) {
  try {
    auto reader = std::make_unique<app::SessionReader>(file);
    const std::string name = file.filename().string();
    std::unique_ptr<robot::RobotModel> model;
    std::vector<std::string> left_out;
    try {
      model = std::make_unique<robot::RobotModel>(recordedRobot(reader->metadata(), &left_out));
    } catch (const InputError& error) {
      throw InputError("the robot stored in " + name + ": " + error.what());
    }
    robot::Scene scene;
    if (!reader->metadata().scene_text.empty()) {
      // Lines are counted in the stored scene text, not in the session file.
      scene = robot::parseScene(reader->metadata().scene_text, resourceDir() / "scenes", "the scene stored in " + name,
                                robot::SceneText::kSessionCopy);
    }
    // States of another arm would be replayed as nothing at all.
    if (reader->stateCount() > 0) {
      if (const std::optional<app::StateRecord> first = reader->stateAt(reader->startTime());
          first && first->dof != model->dof()) {
        throw InputError("session file " + name + ": its states hold " + std::to_string(first->dof) +
                         " joint values, its robot '" + model->name() + "' has " + std::to_string(model->dof()) + " joints");
      }
    }
    // Everything is read before anything shown changes: a read that fails (a damaged page) leaves
    // the open recording as it was, not half replaced, with objects on a model that is gone.
    auto kinematics = std::make_unique<robot::Kinematics>(*model);
    auto collision_world = std::make_unique<robot::CollisionWorld>(*model, scene);
    auto events = std::make_unique<Events>();
    events->samples = reader->samples();
    events->areas = reader->areas();
    events->signals = reader->signals();
    events->trajectories = reader->trajectories();
    events->collisions = reader->collisions();
    events->itm = reader->itmSnapshots();
    std::stable_sort(events->itm.begin(), events->itm.end(),
                     [](const app::ItmRecord& a, const app::ItmRecord& b) { return a.time < b.time; });
    if (static_cast<int>(events->itm.size()) > kMaxItmSnapshots) {
      // Evenly thinned, the last (the final graph) always kept: a long session's graphs would
      // otherwise hold hundreds of megabytes.
      std::vector<app::ItmRecord> kept;
      const std::size_t n = events->itm.size();
      for (int i = 0; i < kMaxItmSnapshots; ++i) {
        kept.push_back(std::move(events->itm[static_cast<std::size_t>(i) * (n - 1) / (kMaxItmSnapshots - 1)]));
      }
      events->itm = std::move(kept);
    }
    // The states' times; a recording without states (none recorded, or deleted since) spans its events.
    const std::pair<double, double> span = reader->recordedTimeSpan();
    const std::vector<app::StageRecord> stages = reader->stages();
    std::vector<StageBand> bands;
    for (std::size_t i = 0; i < stages.size(); ++i) {
      const double t1 = i + 1 < stages.size() ? stages[i + 1].time : span.second;
      bands.push_back({stages[i].time, std::max(t1, stages[i].time), bandLabel(stages[i])});
    }
    const double t0 = span.first;
    const double t1 = std::max(span.second, t0 + 1e-3);
    std::vector<TimelineMarker> markers;
    for (const app::SignalRecord& signal : events->signals) {
      const bool trigger = signal.kind == app::SignalKind::Trigger;
      markers.push_back({signal.time, trigger, trigger ? signal.name : operatorSignalName(signal.name).toStdString()});
    }

    // Plots from states picked through the time index (never a scan of the whole table).
    std::vector<std::string> names;
    Eigen::VectorXd lower(model->dof());
    Eigen::VectorXd upper(model->dof());
    for (int j = 0; j < model->dof(); ++j) {
      const robot::Joint& joint = model->joints()[static_cast<std::size_t>(j)];
      names.push_back(joint.name);
      lower[j] = joint.limits.lower;
      upper[j] = joint.limits.upper;
    }
    std::vector<PlotSample> samples;
    const int points = reader->stateCount() > 0 ? static_cast<int>(std::min<std::int64_t>(kPlotPoints, reader->stateCount())) : 0;
    double last_time = -1e300;
    for (int i = 0; i < points; ++i) {
      const double t = points > 1 ? t0 + (t1 - t0) * i / (points - 1) : t0;
      const std::optional<app::StateRecord> state = reader->stateAt(t);
      if (!state || state->time <= last_time) continue;
      last_time = state->time;
      PlotSample sample;
      sample.time = state->time;
      sample.q = state->qVector();
      // No desired task position is recorded with the states: the task error shown is how far
      // the commanded posture's tip is from the measured one, |FK(q_cmd) - FK(q)|.
      if (sample.q.size() == model->dof()) {
        kinematics->update(state->qCmdVector());
        const Eigen::Vector3d commanded = kinematics->p_WT();
        sample.task_error = (commanded - state->position()).norm();
      }
      samples.push_back(std::move(sample));
    }

    // Shown from here on: nothing below reads the file.
    pause();
    world_->setRobot(*model);
    world_->setScene(scene);
    for (render::OverlayLayer layer : render::kAllOverlayLayers) world_->overlays().setContent(layer, nullptr);
    world_->overlays().itm().clear();
    kinematics_ = std::move(kinematics);
    collision_world_ = std::move(collision_world);
    bands_ = std::move(bands);
    timeline_->setRange(t0, t1);
    timeline_->setBands(bands_);
    timeline_->setMarkers(std::move(markers));
    plots_->setJoints(names, lower, upper);
    plots_->setSamples(samples);
    // Not the live plot's |x - x_des|: the title says which error this is.
    plots_->taskErrorPlot()->setTitle(QStringLiteral("Tip vs. commanded tip"));
    plots_->taskErrorPlot()->setSeriesName(0, QStringLiteral("|FK(q_cmd) - x|"));

    reader_ = std::move(reader);
    span_ = span;
    model_ = std::move(model);
    events_ = std::move(events);
    shown_samples_ = shown_areas_ = shown_trajectories_ = static_cast<std::size_t>(-1);
    shown_collisions_.clear();
    shown_itm_ = -2;
    shown_confidence_areas_ = static_cast<std::size_t>(-1);
    confidence_slices_ = 0;
    operator_heights_ = false;
    error_.clear();
    damage_.clear();
    view_->setFloor(scene.table ? std::optional<double>(0.0) : std::nullopt);
    view_->setHomeCamera(world_->defaultCamera(static_cast<double>(std::max(1, view_->width())) /
                                               std::max(1, view_->height())));
    setWindowTitle(QStringLiteral("FlexIRob review — %1").arg(QString::fromStdString(file.filename().string())));
    QString status = QStringLiteral("%1: %2 states, %3 s, robot %4")
                         .arg(QString::fromStdString(file.string()))
                         .arg(reader_->stateCount())
                         .arg(t1 - t0, 0, 'f', 1)
                         .arg(QString::fromStdString(model_->name()));
    if (reader_->stateCount() == 0) status += QStringLiteral(" (no robot states: none recorded, or deleted since)");
    if (!left_out.empty()) {
      // Said on stderr as well: the status bar may be too narrow for the reason.
      status += QStringLiteral(", drawn without %1 mesh(es) not on this machine: %2")
                    .arg(left_out.size())
                    .arg(QString::fromStdString(left_out.front()));
      qWarning("note: %s", qPrintable(status));
    }
    showStatusMessage(statusBar(), status);
    checkForDamage(file);
    time_ = t0 - 1.0;  // force a redraw
    setTime(t0);
    return true;
  } catch (const std::exception& error) {
    // Every reason names the file (SQLite's own, read later, do not).
    const std::string what = error.what();
    const std::string name = file.filename().string();
    error_ = QString::fromUtf8(what.find(name) == std::string::npos ? ("session file " + file.string() + ": " + printable(what, 300)).c_str()
                                                                    : printable(what, 300).c_str());
    showStatusMessage(statusBar(), QStringLiteral("cannot open %1: %2").arg(QString::fromStdString(file.string()), error_));
    return false;
  }
}

void ReviewWindow::setTime(double time) {
  if (!reader_) return;
  time = std::clamp(time, span_.first, std::max(span_.first, span_.second));
  time_ = time;
  if (const std::optional<app::StateRecord> state = reader_->stateAt(time)) {
    const Eigen::VectorXd q = state->qVector();
    if (q.size() == model_->dof()) {
      kinematics_->update(q);
      world_->robot()->setPosture(*kinematics_);
      shown_q_ = q;
    }
  }
  updateOverlays();
  timeline_->setTime(time);
  plots_->setCursorTime(time);
  updateLabels();
  view_->requestFrame();
}

void ReviewWindow::updateOverlays() {
  // Everything recorded up to now, in time order: counts decide whether a layer changed.
  const auto before = [this](double t) { return t <= time_; };
  const auto samples_now = static_cast<std::size_t>(
      std::count_if(events_->samples.begin(), events_->samples.end(), [&](const app::SampleRecord& s) { return before(s.time); }));
  const auto areas_now = static_cast<std::size_t>(
      std::count_if(events_->areas.begin(), events_->areas.end(), [&](const app::AreaRecord& a) { return before(a.time); }));
  // Trajectories grow point by point as their times pass: count the points shown.
  std::size_t trajectories_now = 0;
  for (const app::TrajectoryRecord& t : events_->trajectories) {
    trajectories_now += t.times.size() == 0 ? static_cast<std::size_t>(t.positions.cols())
                                            : static_cast<std::size_t>(std::count_if(t.times.begin(), t.times.end(), before));
  }
  render::Overlays& overlays = world_->overlays();
  if (samples_now != shown_samples_) {
    std::map<int, render::AreaSamples> per_area;
    for (const app::SampleRecord& sample : events_->samples) {
      if (!before(sample.time)) continue;
      render::AreaSamples& area = per_area[sample.area];
      area.area = sample.area;
      if (sample.x.size() >= 3) area.points_W.emplace_back(sample.x.head<3>());
    }
    std::vector<render::AreaSamples> areas;
    for (auto& [index, area] : per_area) areas.push_back(std::move(area));
    overlays.setContent(render::OverlayLayer::kTrainingSamples, render::makeTrainingSamples(areas));
    shown_samples_ = samples_now;
  }
  if (areas_now != shown_areas_) {
    overlays.setContent(render::OverlayLayer::kGhostArms, nullptr);
    for (const app::AreaRecord& area : events_->areas) {
      if (!before(area.time) || area.q_fixed.size() != model_->dof()) continue;
      Eigen::Vector4f rgba = render::OverlayPalette::area(area.area);
      rgba[3] = 0.3F;
      overlays.addContent(render::OverlayLayer::kGhostArms, render::makeGhostArm(*model_, area.q_fixed, rgba));
    }
    shown_areas_ = areas_now;
  }
  if (trajectories_now != shown_trajectories_) {
    overlays.setContent(render::OverlayLayer::kTrajectories, nullptr);
    for (const app::TrajectoryRecord& trajectory : events_->trajectories) {
      if (trajectory.times.size() > 0 && !before(trajectory.times[0])) continue;
      std::vector<Eigen::Vector3d> points;
      for (Eigen::Index k = 0; k < trajectory.positions.cols(); ++k) {
        if (k < trajectory.times.size() && !before(trajectory.times[k])) break;  // drawn as far as recorded
        points.emplace_back(trajectory.positions.col(k));
      }
      const Eigen::Vector4f rgba = trajectory.kind == app::TrajectoryKind::TeachIn ? render::OverlayPalette::teachInTrajectory()
                                   : trajectory.kind == app::TrajectoryKind::Target ? render::OverlayPalette::targetTrajectory()
                                                                                    : render::OverlayPalette::executedTrajectory();
      overlays.addContent(render::OverlayLayer::kTrajectories, render::makePolyline(points, rgba));
    }
    shown_trajectories_ = trajectories_now;
  }
  std::vector<std::string> touching;
  for (const app::CollisionRecord& collision : events_->collisions) {
    if (collision.time > time_ || collision.time < time_ - kCollisionHold) continue;
    touching.push_back(collision.body_a);
    touching.push_back(collision.body_b);
  }
  // A posture held in contact (posed through the table) is red as long as it is shown, as it
  // was live.
  if (collision_world_ && shown_q_.size() == model_->dof()) {
    collision_world_->update(shown_q_);
    for (const robot::Contact& contact : collision_world_->contacts()) {
      touching.push_back(model_->bodies()[static_cast<std::size_t>(contact.body)].name);
      if (contact.isSelfCollision()) touching.push_back(model_->bodies()[static_cast<std::size_t>(contact.other_body)].name);
    }
  }
  std::sort(touching.begin(), touching.end());
  touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
  if (touching != shown_collisions_) {
    render::showCollisions(*world_->robot(), touching);
    shown_collisions_ = touching;
  }
  updateItm();
  updateConfidence(false);
}

int ReviewWindow::itmSnapshots() const { return static_cast<int>(events_->itm.size()); }

int ReviewWindow::itmNodesShown() const {
  return world_->overlays().itm().nodeCount();
}

void ReviewWindow::updateItm() {
  // The last snapshot recorded at or before now (-1: none yet).
  const auto after = std::upper_bound(events_->itm.begin(), events_->itm.end(), time_,
                                      [](double t, const app::ItmRecord& record) { return t < record.time; });
  const std::ptrdiff_t index = (after - events_->itm.begin()) - 1;
  if (index == shown_itm_) return;
  shown_itm_ = index;
  render::ItmGraphOverlay& overlay = world_->overlays().itm();
  if (index < 0) {
    overlay.clear();
    return;
  }
  const app::ItmRecord& record = events_->itm[static_cast<std::size_t>(index)];
  try {
    const planning::Itm graph = planning::itmFromBytes(record.bytes.data(), record.bytes.size(), "ITM snapshot");
    std::vector<std::pair<int, Eigen::Vector3d>> nodes;
    std::vector<std::pair<int, int>> edges;
    for (const int id : graph.nodeIds()) {
      const auto omega = graph.prototype(id);
      nodes.emplace_back(id, Eigen::Vector3d(omega[0], omega[1], omega[2]));
      for (const int other : graph.neighbors(id)) {
        if (other > id && graph.isNode(other)) edges.emplace_back(id, other);
      }
    }
    overlay.setGraph(nodes, edges);
  } catch (const std::exception& error) {
    overlay.clear();
    showStatusMessage(statusBar(), QStringLiteral("ITM snapshot at %1 s unreadable: %2").arg(record.time).arg(QString::fromUtf8(error.what())),
                             10000);
  }
}

void ReviewWindow::updateConfidence(bool force) {
  // The areas completed by now, each with the samples of its latest take, replayed as every
  // reader of a recording does (app/session_teaching.hpp).
  std::size_t records_now = 0;
  for (const app::AreaRecord& area : events_->areas) records_now += area.time <= time_ ? 1 : 0;
  for (const app::SignalRecord& signal : events_->signals) records_now += signal.time <= time_ ? 1 : 0;
  if (!force && records_now == shown_confidence_areas_) return;
  shown_confidence_areas_ = records_now;
  // Eq. 6.7 - 6.9 with the workflow's default d = 15 (WorkflowOptions::confidence_d).
  learning::ConfidenceModel model;
  try {
    for (const app::RecordedArea& area : app::replayTeaching(events_->areas, events_->samples, events_->signals, time_)) {
      if (area.complete && area.X.cols() > 0) model.addArea(area.X);
    }
  } catch (const std::exception& error) {
    showStatusMessage(statusBar(), QStringLiteral("Training areas unreadable: %1").arg(QString::fromUtf8(error.what())), 10000);
  }
  if (model.areas() == 0) {
    world_->overlays().setContent(render::OverlayLayer::kConfidence, nullptr);
    confidence_slices_ = 0;
    confidence_panel_->setStatus(QStringLiteral("No training area complete at this moment."));
    return;
  }
  if (!operator_heights_) {
    const QSignalBlocker block(confidence_panel_);
    confidence_panel_->setSettings(centredSlices(model, confidence_panel_->settings()));
  }
  const std::vector<render::ConfidenceGrid> slices = confidenceSlices(model, confidence_panel_->settings());
  world_->overlays().setContent(render::OverlayLayer::kConfidence, makeConfidenceOverlay(slices));
  confidence_slices_ = static_cast<int>(slices.size());
  confidence_panel_->setStatus((model.areas() == 1 ? QStringLiteral("1 area complete at this moment")
                                                     : QStringLiteral("%1 areas complete at this moment").arg(model.areas())));
}

void ReviewWindow::updateLabels() {
  time_label_->setText(QStringLiteral("t = %1 s / %2 s").arg(time_, 0, 'f', 3).arg(reader_ ? span_.second : 0.0, 0, 'f', 3));
  const std::string stage = stageAt(time_);
  stage_label_->setStage(QString::fromStdString(stage));
  const QColor color = stageColor(stage);
  stage_label_->setStyleSheet(stage.empty() ? QString()
                                            : QStringLiteral("background: %1; color: white; padding: 2px 8px;").arg(color.name()));
}

std::string ReviewWindow::stageAt(double time) const {
  for (auto band = bands_.rbegin(); band != bands_.rend(); ++band) {
    if (band->t0 <= time) return band->label;
  }
  return {};
}

void ReviewWindow::play() {
  if (!reader_) return;
  // At an end, playing starts again from the other end.
  if (speed_ > 0 && time_ >= span_.second) setTime(span_.first);
  if (speed_ < 0 && time_ <= span_.first) setTime(span_.second);
  last_tick_ms_ = QDateTime::currentMSecsSinceEpoch();
  timer_->start();
  play_button_->setText(QStringLiteral("Pause"));
}

void ReviewWindow::pause() {
  timer_->stop();
  play_button_->setText(QStringLiteral("Play"));
}

bool ReviewWindow::playing() const { return timer_->isActive(); }

void ReviewWindow::setSpeed(double speed) {
  if (speed == 0.0 || !std::isfinite(speed)) return;
  speed_ = speed;
  const int index = speed_box_->findData(speed);
  if (index >= 0 && index != speed_box_->currentIndex()) speed_box_->setCurrentIndex(index);
}

void ReviewWindow::stepFrames(int frames) {
  pause();
  setTime(time_ + frames * kFrameSeconds);
}

void ReviewWindow::keyPressEvent(QKeyEvent* event) {
  // The window has no menu to close it from: the platform's close key does (Ctrl+W).
  if (event->matches(QKeySequence::Close)) {
    event->accept();
    close();
    return;
  }
  if (!reader_) {
    QMainWindow::keyPressEvent(event);
    return;
  }
  const bool by_second = event->modifiers().testFlag(Qt::ShiftModifier);
  const int frames_per_second = static_cast<int>(std::lround(1.0 / kFrameSeconds));
  // A held Space would toggle playback on and off with the key's repeat, a held Home or End jump
  // again; held arrows step on, and keys that are not the window's pass on.
  const bool toggle_or_jump = event->key() == Qt::Key_Space || event->key() == Qt::Key_Home || event->key() == Qt::Key_End;
  if (event->isAutoRepeat() && toggle_or_jump) {
    event->accept();
    return;
  }
  switch (event->key()) {
    case Qt::Key_Space: playing() ? pause() : play(); break;
    case Qt::Key_Left: stepFrames(by_second ? -frames_per_second : -1); break;
    case Qt::Key_Right: stepFrames(by_second ? frames_per_second : 1); break;
    case Qt::Key_Home: pause(); setTime(span_.first); break;
    case Qt::Key_End: pause(); setTime(span_.second); break;
    default: QMainWindow::keyPressEvent(event); return;
  }
  event->accept();
}

void ReviewWindow::advance() {
  const qint64 now = QDateTime::currentMSecsSinceEpoch();
  const double elapsed = static_cast<double>(now - last_tick_ms_) * 1e-3;
  last_tick_ms_ = now;
  setTime(time_ + speed_ * elapsed);
  if ((speed_ > 0 && time_ >= span_.second) || (speed_ < 0 && time_ <= span_.first)) pause();
}

}  // namespace flexirob::ui
