#include "ui/stage_panel.hpp"

#include <QCoreApplication>

#include <algorithm>

#include <QFontMetrics>
#include <QIcon>
#include <QPixmap>
#include <QLabel>
#include <QProgressBar>
#include <QComboBox>
#include <QHBoxLayout>
#include <QPushButton>
#include <QResizeEvent>
#include <QScrollArea>
#include <QScrollBar>
#include <QTimer>
#include <QSpinBox>
#include <QVBoxLayout>

#include "render/overlays.hpp"

namespace flexirob::ui {

namespace {

// A square of the area's colour in the 3D view (its samples, its ghost when chosen): the list
// and the picture name the same area.
constexpr int kSwatchPx = 10;  // small: the narrow panel's list keeps room for the name

QIcon areaSwatch(int area) {
  const Eigen::Vector4f rgba = render::OverlayPalette::area(area);
  QPixmap swatch(kSwatchPx, kSwatchPx);
  swatch.fill(QColor::fromRgbF(rgba[0], rgba[1], rgba[2]));
  return QIcon(swatch);
}

}  // namespace

StagePanel::StagePanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  stage_label_ = new QLabel;
  stage_label_->setObjectName(QStringLiteral("stage_label"));
  stage_label_->setAlignment(Qt::AlignCenter);
  stage_label_->setMinimumHeight(64);
  QFont big = stage_label_->font();
  big.setPointSize(big.pointSize() + 8);
  big.setBold(true);
  stage_label_->setFont(big);
  stage_label_->setWordWrap(true);
  layout->addWidget(stage_label_);
  // As wide as the longest stage name needs, and no wider or narrower as the stage changes:
  // a panel that grew with its text would shift the 3D view beside it at every stage.
  setFixedWidth(std::max(240, QFontMetrics(big).horizontalAdvance(QStringLiteral("CONFIGURATION")) + 48));

  controller_label_ = new QLabel;
  controller_label_->setAlignment(Qt::AlignCenter);
  controller_label_->setWordWrap(true);
  layout->addWidget(controller_label_);

  hint_label_ = new QLabel;
  hint_label_->setObjectName(QStringLiteral("hint_label"));
  hint_label_->setWordWrap(true);
  hint_label_->setStyleSheet(QStringLiteral("QLabel { background: #e8f0fa; color: #1a3550; border: 1px solid #9ab4d0;"
                                            " padding: 4px; }"));
  layout->addWidget(hint_label_);

  const struct {
    app::Button button;
    const char* text;
    const char* tip;
  } buttons[] = {
      {app::Button::kStartConfiguration, QT_TR_NOOP("Start configuration"),
       QT_TR_NOOP("Teach training areas: touch the robot to approach, let go to fix a posture, move it to record.")},
      {app::Button::kFinishedConfiguration, QT_TR_NOOP("Finish configuration"),
       QT_TR_NOOP("Stop teaching areas and learn the redundancy resolution from them.")},
      {app::Button::kStartProgramming, QT_TR_NOOP("Start programming"),
       QT_TR_NOOP("Guide the end-effector; the learned redundancy resolution keeps the arm's posture.")},
      {app::Button::kFinishedProgramming, QT_TR_NOOP("Finish programming"),
       QT_TR_NOOP("Stop teaching trajectories and execute.")},
  };
  for (const auto& b : buttons) {
    auto* push = new QPushButton(tr(b.text));
    push->setToolTip(tr(b.tip));
    push->setMinimumHeight(36);
    push->setObjectName(QString::fromLatin1(app::toString(b.button)));
    push->setFocusPolicy(Qt::NoFocus);  // the keys belong to the 3D view's tele-operation
    const app::Button which = b.button;
    connect(push, &QPushButton::clicked, this, [this, which] { Q_EMIT buttonPressed(which); });
    buttons_[static_cast<int>(b.button)] = push;
    layout->addWidget(push);
  }

  // EXECUTION replays a teach-in of PROGRAMMING (Sect. 2.3): which one, and the button (F9).
  auto* replay_row = new QHBoxLayout;
  replay_choice_ = new QSpinBox;
  replay_choice_->setObjectName(QStringLiteral("replay_choice"));
  replay_choice_->setPrefix(tr("teach-in "));
  replay_choice_->setRange(1, 1);
  replay_choice_->setFocusPolicy(Qt::NoFocus);  // the keys stay the view's: arrows and digits move the arm
  replay_choice_->setToolTip(tr("The teach-in to replay: 1 is the first recorded."));
  replay_button_ = new QPushButton(tr("Replay"));
  replay_button_->setObjectName(QStringLiteral("replay"));
  replay_button_->setToolTip(tr("Move the tip to the teach-in's start and along it (F9)."));
  replay_button_->setFocusPolicy(Qt::NoFocus);
  replay_button_->setEnabled(false);
  replay_choice_->setEnabled(false);
  connect(replay_button_, &QPushButton::clicked, this, [this] { Q_EMIT replayRequested(chosenTeachIn()); });
  replay_row->addWidget(replay_choice_, 1);
  replay_row->addWidget(replay_button_);
  layout->addLayout(replay_row);

  // One area undone: removed (the map is learned again from the rest) or recorded again (the
  // next RECORDING replaces it).
  auto* area_row = new QHBoxLayout;
  area_choice_ = new QComboBox;
  area_choice_->setObjectName(QStringLiteral("area_choice"));
  area_choice_->setFocusPolicy(Qt::NoFocus);  // the keys stay the view's: arrows and digits move the arm
  area_choice_->setToolTip(tr("The training area to remove or to record again; the 3D view shows its posture in its colour."));
  area_choice_->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
  area_choice_->setMinimumContentsLength(6);
  area_choice_->setIconSize(QSize(kSwatchPx, kSwatchPx));
  remove_area_button_ = new QPushButton(tr("Remove"));
  remove_area_button_->setObjectName(QStringLiteral("remove_area"));
  remove_area_button_->setToolTip(tr("Forget this area; the redundancy resolution is learned again from the others."));
  reteach_area_button_ = new QPushButton(tr("Re-teach"));
  reteach_area_button_->setObjectName(QStringLiteral("reteach_area"));
  reteach_area_button_->setToolTip(tr("The next area you record (in CONFIGURATION) replaces this one."));
  for (QWidget* widget : {static_cast<QWidget*>(area_choice_), static_cast<QWidget*>(remove_area_button_),
                          static_cast<QWidget*>(reteach_area_button_)}) {
    widget->setEnabled(false);
  }
  remove_area_button_->setFocusPolicy(Qt::NoFocus);
  reteach_area_button_->setFocusPolicy(Qt::NoFocus);
  connect(remove_area_button_, &QPushButton::clicked, this, [this] {
    if (chosenArea() >= 0) Q_EMIT removeAreaRequested(chosenArea());
  });
  connect(reteach_area_button_, &QPushButton::clicked, this, [this] {
    if (chosenArea() >= 0) Q_EMIT reteachAreaRequested(chosenArea());
  });
  area_row->addWidget(area_choice_, 1);
  area_row->addWidget(remove_area_button_);
  area_row->addWidget(reteach_area_button_);
  layout->addLayout(area_row);

  learning_bar_ = new QProgressBar;
  learning_bar_->setObjectName(QStringLiteral("learning_bar"));
  learning_bar_->setFormat(tr("learning q_c(x)…"));
  learning_bar_->setRange(0, 0);  // busy: the fit reports no fraction
  learning_bar_->setVisible(false);
  layout->addWidget(learning_bar_);

  counts_label_ = new QLabel;
  counts_label_->setWordWrap(true);
  layout->addWidget(counts_label_);

  warning_label_ = new QLabel;
  warning_label_->setObjectName(QStringLiteral("warning_label"));
  warning_label_->setWordWrap(true);
  warning_label_->setStyleSheet(QStringLiteral("QLabel { background: #fff3c4; color: #5a4300; border: 1px solid #e0b000;"
                                               " padding: 4px; }"));
  // Warnings pile up (every area's, a failed transition check): in a box of their own that
  // scrolls, the buttons above stay in view and the newest, last, is scrolled to.
  warning_scroll_ = new QScrollArea;
  warning_scroll_->setObjectName(QStringLiteral("warning_scroll"));
  warning_scroll_->setWidget(warning_label_);
  warning_scroll_->setWidgetResizable(true);
  warning_scroll_->setFrameShape(QFrame::NoFrame);
  warning_scroll_->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  warning_scroll_->setFocusPolicy(Qt::NoFocus);  // the keys stay the view's
  warning_scroll_->setVisible(false);
  layout->addWidget(warning_scroll_);
  layout->addStretch(1);
}

QPushButton* StagePanel::button(app::Button button) const { return buttons_[static_cast<int>(button)]; }

int StagePanel::chosenTeachIn() const { return replay_choice_->value() - 1; }

int StagePanel::chosenArea() const { return area_choice_->currentIndex(); }

QColor StagePanel::stageColor(app::Stage stage, app::SubStage sub_stage) {
  using app::Stage;
  using app::SubStage;
  switch (sub_stage) {
    case SubStage::kApproaching:
      return QColor(0xf0, 0xa0, 0x20);  // amber: the robot follows the hand
    case SubStage::kRecording:
      return QColor(0xd0, 0x30, 0x30);  // red: data is being recorded
    case SubStage::kTeachIn:
      return QColor(0xb0, 0x30, 0xb0);  // magenta: a trajectory is being recorded
    case SubStage::kPosed:
      return QColor(0x30, 0x90, 0x50);  // green: posture fixed, waiting for the next touch
    case SubStage::kWaiting:
      return stage == Stage::kProgramming ? QColor(0x80, 0x60, 0xa0) : QColor(0x50, 0x80, 0x60);
    case SubStage::kNone:
      break;
  }
  switch (stage) {
    case Stage::kExecution:
      return QColor(0x30, 0x60, 0xc0);
    case Stage::kIdle:
    default:
      return QColor(0x70, 0x70, 0x78);
  }
}

QString StagePanel::stageText(app::Stage stage, app::SubStage sub_stage) {
  QString text = QString::fromLatin1(app::toString(stage));
  if (sub_stage != app::SubStage::kNone) text += QStringLiteral("\n") + QString::fromLatin1(app::toString(sub_stage));
  return text;
}

QString StagePanel::nextStepHint(const LiveSnapshot& s, bool hand_can_pull) {
  using app::Stage;
  using app::SubStage;
  const QString touch = s.keyboard_mode   ? tr("press Space, then move the arm with the keys")
                        : hand_can_pull ? tr("pull a link with the mouse (or press Space)")
                                        : tr("push the arm by hand (or press Space)");
  const QString areas = s.areas == 1 ? tr("1 area") : tr("%1 areas").arg(s.areas);
  switch (s.stage) {
    case Stage::kIdle:
      if (s.learning) return tr("Learning the redundancy resolution from %1; the buttons wait for it.").arg(areas);
      if (s.areas == 0) return tr("Next: Start configuration (F5), then show the robot a posture in each training area.");
      if (s.model_ready) {
        return tr("Next: Start programming (F7) to guide the tip along a motion, or Start configuration (F5) to add "
                  "areas.");
      }
      return tr("Next: Start configuration (F5) to add areas; the map is learned when you finish.");
    case Stage::kConfiguration: {
      const bool reteaching = s.reteach_area >= 0 && s.reteach_area < s.areas;
      const bool named = reteaching && s.area_data && s.reteach_area < static_cast<int>(s.area_data->size());
      const QString reteach_name = named ? QString::fromStdString((*s.area_data)[static_cast<std::size_t>(s.reteach_area)].name)
                                         : tr("area %1").arg(s.reteach_area + 1);
      // Re-teach pressed: said until the area is recorded again, through the posing and the
      // recording too.
      const QString reteach_prefix =
          reteaching && s.sub_stage != SubStage::kWaiting && s.sub_stage != SubStage::kNone ? tr("Re-teaching '%1'. ").arg(reteach_name) : QString();
      return reteach_prefix + [&]() -> QString {
      switch (s.sub_stage) {
        case SubStage::kApproaching:
          // Said while the operator can still act: once posed, the area would be recorded in
          // the contact and warned about only when stored.
          if (s.contacts > 0) {
            return s.keyboard_mode ? tr("The arm touches something (drawn red): move it clear with the keys before you fix the posture.")
                                   : tr("The arm touches something (drawn red): move it clear before you let go and fix the posture.");
          }
          if (s.keyboard_mode) return tr("Move the arm with the keys to the posture wanted here, then press Enter (or leave the keys for 2 s).");
          return tr("Move the arm to the posture wanted here, then let go and keep still for 2 s (or press Enter).");
        case SubStage::kPosed:
          // Fixed in a contact (kept still for 2 s, or Enter, while red): the area will be
          // warned about when stored; the operator learns it now, and how to show it again.
          if (s.contacts > 0) {
            return tr("Posture fixed touching something (drawn red): an area recorded in the contact is warned about. To "
                      "record anyway, %1 again.")
                .arg(touch);
          }
          return tr("Posture fixed. To record the area, %1 again and move the tip around inside it.").arg(touch);
        case SubStage::kRecording:
          if (s.contacts > 0) {
            return tr("Recording touching something (drawn red): move the tip away from it; an area recorded in the contact "
                      "is warned about.");
          }
          if (s.keyboard_mode) {
            return tr("Recording: move the tip around inside the area with the keys; press Enter (or leave the keys for 2 s) to "
                      "store it.");
          }
          return tr("Recording: move the tip around inside the area; let go and keep still (or press Enter) to store it.");
        default:
          if (reteaching) {
            return tr("Re-teaching '%1': %2 and move the arm to the posture wanted there; its new recording replaces it.")
                .arg(reteach_name, touch);
          }
          if (s.areas == 0) return tr("First area: %1 and move the arm to the posture wanted there.").arg(touch);
          return tr("Next area: %1 — or Finish configuration (F6) to learn from %2.").arg(touch, areas);
      }
      }();
    }
    case Stage::kProgramming:
      switch (s.sub_stage) {
        case SubStage::kApproaching:
          if (s.keyboard_mode) {
            return tr("Move the tip with the keys to where the motion starts (the learned map keeps the posture), then press "
                      "Enter (or leave the keys for 2 s).");
          }
          return tr("Guide the tip to where the motion starts (the learned map keeps the posture); keep still for 2 s "
                    "(or press Enter).");
        case SubStage::kPosed:
          return tr("At the start. To record the motion, %1 again and guide the tip along it.").arg(touch);
        case SubStage::kTeachIn:
          if (s.keyboard_mode) {
            return tr("Recording the motion: move the tip along it with the keys; press Enter (or leave the keys for 2 s) to "
                      "store it.");
          }
          return tr("Recording the motion: guide the tip along it; let go and keep still (or press Enter) to store it.");
        default:
          return tr("To teach a motion, %1 and guide the tip to its start — or Finish programming (F8) to execute.")
              .arg(touch);
      }
    case Stage::kExecution:
      if (!s.execution_done) return tr("The arm moves on its own; wait for it to arrive.");
      return s.teach_ins > 0 ? tr("Ctrl+click a point in the view to send the arm there, or Replay a teach-in (F9).")
                             : tr("Ctrl+click a point in the view to send the arm there.");
  }
  return {};
}

namespace {

// The texts shown besides nextStepHint() and controllerText(), one place each: the heights
// reserved for them (reserveHintHeight) must be those of the texts shown.
QString noRobotHint() { return StagePanel::tr("Choose a robot in the Robot menu."); }
QString unmeasuredHint() { return StagePanel::tr("Teaching starts when the robot sends its first measurement."); }
QString unmeasuredController() { return StagePanel::tr("waiting for the robot's first measurement"); }

QString controllerText(app::InteractionController controller, bool keyboard) {
  return StagePanel::tr("controller: %1%2").arg(QString::fromLatin1(app::toString(controller)), keyboard ? StagePanel::tr(" (keyboard)") : QString());
}

// Every text the hint shows, for the height it reserves.
const QStringList& everyHint() {
  static const QStringList hints = [] {
    QStringList all{noRobotHint(), unmeasuredHint()};
    LiveSnapshot s;
    for (const app::Stage stage : {app::Stage::kIdle, app::Stage::kConfiguration, app::Stage::kProgramming, app::Stage::kExecution}) {
      for (const app::SubStage sub : {app::SubStage::kNone, app::SubStage::kWaiting, app::SubStage::kApproaching, app::SubStage::kPosed,
                                      app::SubStage::kRecording, app::SubStage::kTeachIn}) {
        for (int flags = 0; flags < 64; ++flags) {
          for (const int areas : {0, 1, 12}) {
            s.stage = stage;
            s.sub_stage = sub;
            s.keyboard_mode = (flags & 1) != 0;
            s.learning = (flags & 2) != 0;
            s.model_ready = (flags & 4) != 0;
            s.execution_done = (flags & 8) != 0;
            s.contacts = (flags & 16) != 0 ? 1 : 0;
            s.areas = areas;
            s.reteach_area = (flags & 32) != 0 && areas > 0 ? areas - 1 : -1;  // named "area 12" without area data
            s.teach_ins = areas > 0 ? 1 : 0;
            for (const bool hand_can_pull : {false, true}) {
              const QString hint = StagePanel::nextStepHint(s, hand_can_pull);
              if (!all.contains(hint)) all << hint;
            }
          }
        }
      }
    }
    return all;
  }();
  return hints;
}

}  // namespace

void StagePanel::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  if (event->size().width() != event->oldSize().width()) fitWarningBox();
  if (event->size().width() != hint_reserved_for_width_) reserveHintHeight();
}

void StagePanel::reserveHintHeight() {
  // From the panel's width: the label itself may not be laid out yet.
  const QMargins margins = layout()->contentsMargins();
  const int frame_width = hint_label_->width() - hint_label_->contentsRect().width();
  const int inner_width = width() - margins.left() - margins.right() - frame_width;
  if (inner_width <= 0) return;
  hint_reserved_for_width_ = width();
  int tallest = 0;
  for (const QString& hint : everyHint()) {
    tallest = std::max(tallest, hint_label_->fontMetrics().boundingRect(QRect(0, 0, inner_width, 100000), Qt::TextWordWrap, hint).height());
  }
  // The frame and padding of the label's style sheet around the text.
  hint_label_->setMinimumHeight(tallest + hint_label_->height() - hint_label_->contentsRect().height());
  // The controller's line above it wraps too ("assisted_gravity_compensation (keyboard)").
  int tallest_controller = 0;
  QStringList controllers{unmeasuredController()};
  for (const app::InteractionController controller :
       {robot::InteractionMode::kGravityCompensation, robot::InteractionMode::kCompliantRecording, robot::InteractionMode::kHierarchicalControl,
        robot::InteractionMode::kAssistedGravityCompensation, robot::InteractionMode::kAssistanceBlending}) {
    for (const bool keyboard : {false, true}) controllers << controllerText(controller, keyboard);
  }
  const int controller_width = width() - margins.left() - margins.right();
  for (const QString& text : controllers) {
    tallest_controller = std::max(
        tallest_controller, controller_label_->fontMetrics().boundingRect(QRect(0, 0, controller_width, 100000), Qt::TextWordWrap, text).height());
  }
  controller_label_->setMinimumHeight(tallest_controller);
}

void StagePanel::showNoRobot(const QString& reason) {
  const QString text = tr("NO ROBOT");
  if (text != shown_stage_) {
    shown_stage_ = text;
    stage_label_->setText(text);
    stage_label_->setStyleSheet(QStringLiteral("QLabel { background: %1; color: white; border-radius: 6px; }")
                                    .arg(stageColor(app::Stage::kIdle, app::SubStage::kNone).name()));
  }
  controller_label_->setText(reason);
  for (QPushButton* button : buttons_) button->setEnabled(false);
  replay_button_->setEnabled(false);
  replay_choice_->setEnabled(false);
  area_choice_->setEnabled(false);
  remove_area_button_->setEnabled(false);
  reteach_area_button_->setEnabled(false);
  hint_label_->setText(noRobotHint());
  learning_bar_->setVisible(false);
  counts_label_->clear();
}

void StagePanel::showSnapshot(const LiveSnapshot& s, bool robot_measured, bool hand_can_pull) {
  const QString text = stageText(s.stage, s.sub_stage);
  if (text != shown_stage_) {
    shown_stage_ = text;
    stage_label_->setText(text);
    const QColor colour = stageColor(s.stage, s.sub_stage);
    stage_label_->setStyleSheet(QStringLiteral("QLabel { background: %1; color: white; border-radius: 6px; }")
                                    .arg(colour.name()));
  }
  controller_label_->setText(robot_measured ? controllerText(s.controller, s.keyboard_mode) : unmeasuredController());
  for (int b = 0; b < 4; ++b) {
    buttons_[b]->setEnabled(robot_measured && s.running && buttonMakesSense(static_cast<app::Button>(b), s));
  }
  // A new teach-in is the one a replay names next; the operator's choice stands otherwise.
  if (s.teach_ins != shown_teach_ins_) {
    shown_teach_ins_ = s.teach_ins;
    replay_choice_->setRange(1, std::max(1, s.teach_ins));
    replay_choice_->setValue(std::max(1, s.teach_ins));
  }
  const bool can_replay = robot_measured && s.running && s.stage == app::Stage::kExecution && s.teach_ins > 0;
  replay_button_->setEnabled(can_replay);
  replay_choice_->setEnabled(can_replay && s.teach_ins > 1);
  if (s.areas_version != shown_areas_version_) {
    shown_areas_version_ = s.areas_version;
    const int chosen = area_choice_->currentIndex();
    const int before = area_choice_->count();
    area_choice_->clear();
    if (s.area_data) {
      for (std::size_t k = 0; k < s.area_data->size(); ++k) {
        area_choice_->addItem(areaSwatch(static_cast<int>(k)), QString::fromStdString((*s.area_data)[k].name));
      }
    }
    // A new area is the one named next; after a removal or a re-teach the choice stays put.
    const int count = area_choice_->count();
    area_choice_->setCurrentIndex(count > before || chosen < 0 ? count - 1 : std::min(chosen, count - 1));
  }
  const bool outside_recording = s.sub_stage != app::SubStage::kRecording && s.sub_stage != app::SubStage::kTeachIn;
  const bool has_area = robot_measured && s.running && area_choice_->count() > 0 && !s.learning;
  const bool can_remove = has_area && (s.stage == app::Stage::kIdle || (s.stage == app::Stage::kConfiguration && outside_recording));
  const bool can_reteach = has_area && s.stage == app::Stage::kConfiguration && outside_recording;
  area_choice_->setEnabled(can_remove || can_reteach);
  remove_area_button_->setEnabled(can_remove);
  reteach_area_button_->setEnabled(can_reteach);
  const QString hint = robot_measured ? nextStepHint(s, hand_can_pull) : unmeasuredHint();
  if (hint_label_->text() != hint) hint_label_->setText(hint);
  learning_bar_->setVisible(s.learning);
  counts_label_->setText(tr("areas %1   teach-ins %2   model %3\non_affected %4   on_converged %5\nITM nodes %6, edges %7   "
                            "collisions %8")
                             .arg(s.areas)
                             .arg(s.teach_ins)
                             .arg(s.model_ready ? tr("learned") : (s.learning ? tr("learning") : tr("none")))
                             .arg(s.on_affected)
                             .arg(s.on_converged)
                             .arg(s.itm_nodes)
                             .arg(s.itm_edges)
                             .arg(s.collision_events) +
                         (s.model_ready && !model_summary_.isEmpty() ? tr("\nmap: %1").arg(model_summary_) : QString()));
}

void StagePanel::setModelSummary(const QString& text) { model_summary_ = text; }

void StagePanel::showWarning(const QString& text) {
  warning_label_->setText(text);
  warning_label_->setVisible(true);
  warning_scroll_->setVisible(true);
  fitWarningBox();
}

void StagePanel::clearWarning() {
  warning_label_->clear();
  warning_label_->setVisible(false);
  warning_scroll_->setVisible(false);
}

void StagePanel::fitWarningBox() {
  if (!warning_scroll_->isVisibleTo(this)) return;
  const QMargins margins = layout()->contentsMargins();
  const int width = this->width() - margins.left() - margins.right();
  if (width <= 0) return;
  const int whole = warning_label_->heightForWidth(width);
  const int most = kWarningLines * warning_label_->fontMetrics().lineSpacing() + 12;
  warning_scroll_->setFixedHeight(std::min(whole, most));
  // Once laid out at that height, the end (the newest warning) in view.
  QTimer::singleShot(0, warning_scroll_, [scroll = warning_scroll_] {
    scroll->verticalScrollBar()->setValue(scroll->verticalScrollBar()->maximum());
  });
}

namespace {

// The workflow names its requests as the session file records them; the window says which
// button, key or click they came from.
struct RequestName {
  const char* request;
  const char* operator_name;
};

const std::vector<RequestName>& requestNames() {
  static const std::vector<RequestName> names{
      {"start_configuration", QT_TRANSLATE_NOOP("StagePanel", "Start configuration")},
      {"finished_configuration", QT_TRANSLATE_NOOP("StagePanel", "Finish configuration")},
      {"start_programming", QT_TRANSLATE_NOOP("StagePanel", "Start programming")},
      {"finished_programming", QT_TRANSLATE_NOOP("StagePanel", "Finish programming")},
      {"replay", QT_TRANSLATE_NOOP("StagePanel", "Replay")},
      {"plan", QT_TRANSLATE_NOOP("StagePanel", "Goal (Ctrl+click)")},
      {"execute", QT_TRANSLATE_NOOP("StagePanel", "Execute")},
      {"remove_area", QT_TRANSLATE_NOOP("StagePanel", "Remove area")},
      {"reteach_area", QT_TRANSLATE_NOOP("StagePanel", "Re-teach area")},
      {"nudge_joint", QT_TRANSLATE_NOOP("StagePanel", "Joint key")},
      {"nudge_task", QT_TRANSLATE_NOOP("StagePanel", "Tip key")},
  };
  return names;
}

}  // namespace

QString operatorSignalName(const std::string& recorded) {
  const QString text = QString::fromStdString(recorded);
  const QString request = text.section(QLatin1Char(' '), 0, 0);
  const QString rest = text.section(QLatin1Char(' '), 1);
  for (const RequestName& name : requestNames()) {
    if (request != QLatin1String(name.request)) continue;
    const QString shown = QCoreApplication::translate("StagePanel", name.operator_name);
    if (rest.isEmpty()) return shown;
    bool is_index = false;
    const int index = rest.toInt(&is_index);
    const bool about_an_area = request == QLatin1String("remove_area") || request == QLatin1String("reteach_area");
    if (about_an_area && is_index && index >= 0) return shown + QStringLiteral(": ") + QCoreApplication::translate("StagePanel", "area %1").arg(index + 1);
    return shown + QStringLiteral(": ") + rest;
  }
  return text;
}

QString operatorWording(const QString& message) {
  for (const RequestName& name : requestNames()) {
    const QString prefix = QString::fromLatin1(name.request) + QStringLiteral(": ");
    if (message.startsWith(prefix)) {
      return QCoreApplication::translate("StagePanel", name.operator_name) + QStringLiteral(": ") + message.mid(prefix.size());
    }
  }
  return message;
}

QString standingWarningText(const std::vector<app::WorkflowEvent>& events, const QString& last) {
  QStringList lines;
  for (const std::string& line : app::standingWarnings(events, true)) lines.push_back(operatorWording(QString::fromStdString(line)));
  if (!last.isEmpty() && !lines.contains(last)) lines.push_back(last);
  if (lines.size() <= 1) return lines.join(QString());
  return QStringLiteral("\u2022 ") + lines.join(QStringLiteral("\n\u2022 "));
}

}  // namespace flexirob::ui
