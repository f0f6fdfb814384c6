#include "ui/stage_panel.hpp"

#include <algorithm>

#include <QFontMetrics>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QVBoxLayout>

namespace flexirob::ui {

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
  warning_label_->setVisible(false);
  layout->addWidget(warning_label_);
  layout->addStretch(1);
}

QPushButton* StagePanel::button(app::Button button) const { return buttons_[static_cast<int>(button)]; }

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
  learning_bar_->setVisible(false);
  counts_label_->clear();
}

void StagePanel::showSnapshot(const LiveSnapshot& s, bool robot_measured) {
  const QString text = stageText(s.stage, s.sub_stage);
  if (text != shown_stage_) {
    shown_stage_ = text;
    stage_label_->setText(text);
    const QColor colour = stageColor(s.stage, s.sub_stage);
    stage_label_->setStyleSheet(QStringLiteral("QLabel { background: %1; color: white; border-radius: 6px; }")
                                    .arg(colour.name()));
  }
  controller_label_->setText(robot_measured ? tr("controller: %1%2").arg(QString::fromLatin1(app::toString(s.controller)),
                                                                       s.keyboard_mode ? tr(" (keyboard)") : QString())
                                           : tr("waiting for the robot's first measurement"));
  for (int b = 0; b < 4; ++b) {
    buttons_[b]->setEnabled(robot_measured && s.running && buttonMakesSense(static_cast<app::Button>(b), s));
  }
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
                             .arg(s.collision_events));
}

void StagePanel::showWarning(const QString& text) {
  warning_label_->setText(text);
  warning_label_->setVisible(true);
}

void StagePanel::clearWarning() {
  warning_label_->clear();
  warning_label_->setVisible(false);
}

}  // namespace flexirob::ui
