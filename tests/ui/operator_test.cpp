// The operator's interactions with the live robot: the stage panel's buttons drive the teaching
// workflow, the keyboard moves the 9-DoF arm, a mouse drag on a link pulls it, the force arrow
// and the key map show in the window, the joint-limit bars, parameters and sessions.
#include <QAction>
#include <QComboBox>
#include <QDir>
#include <QFileInfo>
#include <QScopeGuard>
#include <QApplication>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QFile>
#include <QFileDialog>
#include <QGuiApplication>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QMouseEvent>
#include <QPushButton>
#include <QRegularExpression>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTemporaryDir>
#include <QTest>
#include <QMenu>
#include <QMenuBar>
#include <QTimer>
#include <QWheelEvent>
#include <optional>
#include <osg/Material>
#include <chrono>
#include <thread>

#include "app/session_reader.hpp"
#include "robot/fri_protocol.hpp"
#include "robot/fri_simulated_controller.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "render/camera.hpp"
#include "render/overlays.hpp"
#include "robot/kinematics.hpp"
#include "ui/joint_panel.hpp"
#include "ui/live_teaching.hpp"
#include "ui/main_window.hpp"
#include "tests/common/cylinder_arms.hpp"
#include "tests/ui/ui_test_support.hpp"
#include "ui/mouse_perturbation.hpp"
#include "ui/osg_view.hpp"
#include "ui/parameter_panel.hpp"
#include "ui/stage_panel.hpp"
#include "ui/status_message.hpp"
#include "ui/teleop_keys.hpp"

using flexirob::app::Button;
using flexirob::app::Stage;
using flexirob::app::SubStage;
using flexirob::ui::MainWindow;

namespace {

using flexirob::ui::testing::canDraw;
using flexirob::ui::testing::quietOptions;
using flexirob::ui::testing::showIfDrawable;



Eigen::Vector3d tip(MainWindow& window) {
  const auto& s = window.live()->snapshot();
  return {s.p_WT[0], s.p_WT[1], s.p_WT[2]};
}

Eigen::Vector3d bodyOrigin(MainWindow& window, int body) {
  window.mirror();
  return window.kinematics()->X_WB(body).translation();
}

void waitRunning(MainWindow& window) {
  QTRY_VERIFY_WITH_TIMEOUT(window.live() != nullptr && window.live()->snapshot().running, 10000);
}

// In CONFIGURATION, one area with the keys: on_affected, on_converged, on_affected, recording,
// on_converged; then `areas_after` areas stand.
void recordAnArea(MainWindow& window, int areas_after) {
  QTest::keyClick(&window, Qt::Key_Space);
  QTest::keyClick(&window, Qt::Key_Return);
  QTest::keyClick(&window, Qt::Key_Space);
  QTest::qWait(400);
  QTest::keyClick(&window, Qt::Key_Return);
  QTRY_COMPARE(window.live()->snapshot().areas, areas_after);
}

// Starts configuration, drags `body` in the view 80 px left and 64 px up and holds it there for
// 1.5 s of the robot's time (a loaded machine runs the paced loop late), then lets go: where its origin was before and at the end of the pull, and the pixel the
// drag started at. The caller checks QTest::currentTestFailed().
// `hand_force`, when given, receives the hand's force [N, W] the spring pulled with at the end
// of the hold.
void pullBody(MainWindow& window, int body, Eigen::Vector3d& before, Eigen::Vector3d& pulled, Eigen::Vector2d& start_pixel,
              Eigen::Vector3d* hand_force = nullptr) {
  const auto& s = window.live()->snapshot();
  QTest::mouseClick(window.stagePanel()->button(Button::kStartConfiguration), Qt::LeftButton);
  QTRY_COMPARE(s.stage, Stage::kConfiguration);
  flexirob::ui::OsgView* view = window.view();
  view->grabFramebuffer();
  before = bodyOrigin(window, body);
  const auto pixel = flexirob::render::projectToPixel(view->currentCamera(), view->width(), view->height(), before);
  QVERIFY(pixel.has_value());
  start_pixel = *pixel;
  const auto send = [view](QEvent::Type type, QPointF at, Qt::MouseButton button, Qt::MouseButtons held) {
    QMouseEvent event(type, at, view->mapToGlobal(at), button, held, Qt::NoModifier);
    QApplication::sendEvent(view, &event);
  };
  const QPointF start(pixel->x(), pixel->y());
  send(QEvent::MouseButtonPress, start, Qt::LeftButton, Qt::LeftButton);
  QVERIFY2(window.perturbation()->grabbing(), "the press did not grab the link");
  // Pull to the upper left (the camera's left and up) and hold.
  for (int i = 1; i <= 8; ++i) {
    send(QEvent::MouseMove, start + QPointF(-10.0 * i, -8.0 * i), Qt::NoButton, Qt::LeftButton);
    QTest::qWait(30);
  }
  QTRY_VERIFY(s.hand_active);
  QTRY_VERIFY(window.forceArrow()->visible());
  QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);  // the pull is a touch: on_affected
  const double pulling_since = s.time;
  QTRY_VERIFY_WITH_TIMEOUT(s.time > pulling_since + 1.5, 15000);
  pulled = bodyOrigin(window, body);
  if (hand_force != nullptr) *hand_force = Eigen::Vector3d(s.hand_force_W[0], s.hand_force_W[1], s.hand_force_W[2]);
  send(QEvent::MouseButtonRelease, start + QPointF(-80.0, -64.0), Qt::LeftButton, Qt::NoButton);
  QVERIFY(!window.perturbation()->grabbing());
  QTRY_VERIFY(!window.forceArrow()->visible());
}

// A scene file `name` in `dir` holding `yaml`; its path, empty if it could not be written.
std::string writeScene(const QTemporaryDir& dir, const QString& name, const QByteArray& yaml) {
  const QString path = dir.filePath(name);
  QFile out(path);
  if (!out.open(QIODevice::WriteOnly) || out.write(yaml) != yaml.size()) return {};
  return path.toStdString();
}

}  // namespace

class OperatorTest : public QObject {
  Q_OBJECT

 private Q_SLOTS:
  void initTestCase() { QStandardPaths::setTestModeEnabled(true); }

  void buttonsDriveTheWorkflow() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    if (canDraw()) window.show();
    waitRunning(window);
    flexirob::ui::StagePanel* panel = window.stagePanel();
    const auto& s = window.live()->snapshot();
    window.mirror();
    // In IDLE without areas only "start configuration" makes sense.
    QVERIFY(panel->button(Button::kStartConfiguration)->isEnabled());
    QVERIFY(!panel->button(Button::kFinishedConfiguration)->isEnabled());
    QVERIFY(!panel->button(Button::kStartProgramming)->isEnabled());
    QVERIFY(!panel->button(Button::kFinishedProgramming)->isEnabled());

    QTest::mouseClick(panel->button(Button::kStartConfiguration), Qt::LeftButton);
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTRY_VERIFY(panel->stageLabel()->text().contains(QStringLiteral("CONFIGURATION")));
    QVERIFY(!panel->button(Button::kStartConfiguration)->isEnabled());
    QVERIFY(!panel->button(Button::kFinishedConfiguration)->isEnabled());  // no area yet

    // The keyboard's trigger keys walk through the sub-stages (Sect. 8.1); on_converged chimes.
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
    QTRY_VERIFY(panel->stageLabel()->text().contains(QStringLiteral("APPROACHING")));
    const int chimes = window.chimes();
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.sub_stage, SubStage::kPosed);
    QTRY_VERIFY(window.chimes() > chimes);
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kRecording);
    QVERIFY(!panel->button(Button::kFinishedConfiguration)->isEnabled());  // not while recording
    QTest::qWait(300);  // samples every 20 ms
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.areas, 1);
    QTRY_VERIFY(panel->button(Button::kFinishedConfiguration)->isEnabled());

    QTest::mouseClick(panel->button(Button::kFinishedConfiguration), Qt::LeftButton);
    QTRY_COMPARE(s.stage, Stage::kIdle);
    QTRY_VERIFY_WITH_TIMEOUT(s.model_ready, 30000);
    QTRY_VERIFY(panel->button(Button::kStartProgramming)->isEnabled());
    QTest::mouseClick(panel->button(Button::kStartProgramming), Qt::LeftButton);
    QTRY_COMPARE(s.stage, Stage::kProgramming);
    QTRY_VERIFY(panel->button(Button::kFinishedProgramming)->isEnabled());
    QTest::mouseClick(panel->button(Button::kFinishedProgramming), Qt::LeftButton);
    QTRY_COMPARE(s.stage, Stage::kExecution);
    QTRY_VERIFY(panel->stageLabel()->text().contains(QStringLiteral("EXECUTION")));
  }

  // A novice reads what to do next in the panel at every step, and in EXECUTION replays the
  // motion taught in PROGRAMMING with the panel's Replay button or F9.
  void theHintSaysWhatToDoNextAndATeachInIsReplayed() {
    MainWindow window("lwr4", "empty", quietOptions());
    if (canDraw()) window.show();
    waitRunning(window);
    flexirob::ui::StagePanel* panel = window.stagePanel();
    const auto& s = window.live()->snapshot();
    const auto hintSays = [panel](const char* words) { return panel->hintLabel()->text().contains(QLatin1String(words)); };
    QTRY_VERIFY(hintSays("Start configuration (F5)"));
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(s.sub_stage, SubStage::kWaiting);
    // The simulated arm is touched with the mouse; nothing was taught yet.
    QTRY_VERIFY(hintSays("First area") && hintSays("pull a link with the mouse"));
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
    QTRY_VERIFY(hintSays("keep still"));
    QTest::keyPress(&window, Qt::Key_Right);
    QTest::qWait(1500);
    QTest::keyRelease(&window, Qt::Key_Right);
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.sub_stage, SubStage::kPosed);
    // Moved with the keys: the keys are what the hint offers now.
    QTRY_VERIFY(hintSays("To record the area") && hintSays("move the arm with the keys"));
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kRecording);
    QTest::keyPress(&window, Qt::Key_Left);
    QTest::qWait(600);
    QTest::keyRelease(&window, Qt::Key_Left);
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.areas, 1);
    QTRY_VERIFY(hintSays("Next area") && hintSays("Finish configuration (F6) to learn from 1 area."));

    // Area 1 again: Re-teach has the next RECORDING replace it instead of adding a second.
    // While the area is re-taught, every step's hint says so.
    const auto recordArea = [&window, &s, &hintSays](Qt::Key direction, const char* reteaching = nullptr) {
      QTest::keyClick(&window, Qt::Key_Space);
      QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
      if (reteaching != nullptr) QTRY_VERIFY(hintSays(reteaching));
      QTest::keyClick(&window, Qt::Key_Return);
      QTRY_COMPARE(s.sub_stage, SubStage::kPosed);
      if (reteaching != nullptr) QTRY_VERIFY(hintSays(reteaching) && hintSays("Posture fixed"));
      QTest::keyClick(&window, Qt::Key_Space);
      QTRY_COMPARE(s.sub_stage, SubStage::kRecording);
      if (reteaching != nullptr) QTRY_VERIFY(hintSays(reteaching));
      QTest::keyPress(&window, direction);
      QTest::qWait(600);
      QTest::keyRelease(&window, direction);
      QTest::keyClick(&window, Qt::Key_Return);
      QTRY_COMPARE(s.sub_stage, SubStage::kWaiting);
    };
    QTRY_VERIFY(panel->reteachAreaButton()->isEnabled() && panel->removeAreaButton()->isEnabled());
    QCOMPARE(panel->areaChoice()->currentText(), QStringLiteral("area_1"));
    const Eigen::Vector3d first_centre = s.area_data->front().centre;
    QTest::mouseClick(panel->reteachAreaButton(), Qt::LeftButton);
    QTRY_VERIFY(flexirob::ui::fullStatusMessage(window.statusBar()).contains(QStringLiteral("replaces 'area_1'")));
    // The hint says it too, until the area is recorded again.
    QTRY_VERIFY(hintSays("Re-teaching 'area_1'"));
    recordArea(Qt::Key_Up, "Re-teaching 'area_1'");
    QTRY_VERIFY(s.area_data != nullptr && (s.area_data->front().centre - first_centre).norm() > 0.01);
    // The panel reads the snapshot on its own tick, so the hint may follow the new area a tick later.
    QTRY_VERIFY(!hintSays("Re-teaching"));
    QCOMPARE(s.areas, 1);
    // A second area: the newest is the one the choice names.
    recordArea(Qt::Key_Down);
    QTRY_COMPARE(s.areas, 2);
    QTRY_COMPARE(panel->chosenArea(), 1);
    // The chosen area stands out in the 3D view: its ghost in its own colour (the colour of its
    // samples and of its swatch in the list), its samples drawn a second time, larger.
    const auto ghostColour = [&window](unsigned area) -> osg::Vec4 {
      osg::Group* ghosts = window.overlays().layer(flexirob::render::OverlayLayer::kGhostArms);
      if (area >= ghosts->getNumChildren() || ghosts->getChild(area)->getStateSet() == nullptr) return {};
      const auto* material = dynamic_cast<const osg::Material*>(
          ghosts->getChild(area)->getStateSet()->getAttribute(osg::StateAttribute::MATERIAL));
      return material == nullptr ? osg::Vec4() : material->getDiffuse(osg::Material::FRONT);
    };
    const auto areaHue = [](int area) {
      const Eigen::Vector4f rgba = flexirob::render::OverlayPalette::area(area);
      return osg::Vec3(rgba[0], rgba[1], rgba[2]);
    };
    const auto ghostIsInItsAreasColour = [&](unsigned area) {
      const osg::Vec4 colour = ghostColour(area);
      return (osg::Vec3(colour.r(), colour.g(), colour.b()) - areaHue(static_cast<int>(area))).length() < 1e-3F;
    };
    const auto largerSamplesName = [&window]() -> std::string {
      osg::Group* samples = window.overlays().layer(flexirob::render::OverlayLayer::kTrainingSamples);
      if (samples->getNumChildren() != 2) return {};
      const osg::Group* chosen = samples->getChild(1)->asGroup();
      return chosen == nullptr || chosen->getNumChildren() != 1 ? std::string() : chosen->getChild(0)->getName();
    };
    QTRY_VERIFY(ghostIsInItsAreasColour(1));
    QVERIFY(!ghostIsInItsAreasColour(0));
    QCOMPARE(largerSamplesName(), std::string("samples:1"));
    panel->areaChoice()->setCurrentIndex(0);
    QTRY_VERIFY(ghostIsInItsAreasColour(0));
    QVERIFY(!ghostIsInItsAreasColour(1));
    QCOMPARE(largerSamplesName(), std::string("samples:0"));
    QVERIFY(!panel->areaChoice()->itemIcon(0).isNull());
    panel->areaChoice()->setCurrentIndex(1);
    // The Teaching menu reaches the panel's controls from the keyboard: it lists the areas,
    // and removes the one it names, not the one the panel's choice names.
    // The menu is rebuilt as it opens (each opening replaces the entries of the last).
    const auto openTeachingMenu = [&window] { Q_EMIT window.teachingMenu()->aboutToShow(); };
    const auto teachingEntry = [&window](const QString& text) -> QAction* {
      for (QAction* action : window.teachingMenu()->actions()) {
        if (action->text() == text) return action;
      }
      return nullptr;
    };
    // Opened again and again, it keeps one set of submenus.
    for (int k = 0; k < 3; ++k) openTeachingMenu();
    QCOMPARE(window.teachingMenu()->findChildren<QMenu*>(QString(), Qt::FindDirectChildrenOnly).size(), 3);
    // In CONFIGURATION: finishing it is offered, programming is not.
    QAction* start_programming = teachingEntry(QStringLiteral("Start &programming\tF7"));
    QAction* finish_configuration = teachingEntry(QStringLiteral("&Finish configuration\tF6"));
    QVERIFY(start_programming != nullptr && finish_configuration != nullptr);
    QVERIFY(!start_programming->isEnabled() && finish_configuration->isEnabled());
    QAction* remove_entry = teachingEntry(QStringLiteral("Re&move area"));
    QVERIFY(remove_entry != nullptr && remove_entry->menu() != nullptr && remove_entry->isEnabled());
    QCOMPARE(remove_entry->menu()->actions().size(), 2);
    QCOMPARE(remove_entry->menu()->actions().at(0)->text(), QStringLiteral("area_1"));
    // Removing asks first: Cancel keeps the area, "Remove the area" removes it.
    QString removal_question;
    QString removal_answer = QStringLiteral("Cancel");
    QTimer removal;
    connect(&removal, &QTimer::timeout, &window, [&] {
      auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
      if (box == nullptr) return;
      removal_question = box->text();
      for (QAbstractButton* button : box->buttons()) {
        if (button->text() == removal_answer) button->click();
      }
    });
    removal.start(50);
    remove_entry->menu()->actions().at(0)->trigger();
    QVERIFY2(removal_question.startsWith(QStringLiteral("Remove the area 'area_1'? Its ")), qPrintable(removal_question));
    QTest::qWait(200);
    QCOMPARE(s.areas, 2);
    removal_answer = QStringLiteral("Remove the area");
    remove_entry->menu()->actions().at(0)->trigger();
    removal.stop();
    QTRY_COMPARE(s.areas, 1);
    QTRY_COMPARE(panel->areaChoice()->count(), 1);
    QCOMPARE(panel->areaChoice()->itemText(0), QStringLiteral("area_2"));

    // Another scene from the menu would start the teaching afresh: asked first; Cancel keeps it.
    QAction* other_scene = nullptr;
    for (QAction* action : window.findChildren<QAction*>()) {
      if (action->data().toString() == QStringLiteral("setup_A")) other_scene = action;
    }
    QVERIFY(other_scene != nullptr);
    QString question;
    QTimer answer;
    connect(&answer, &QTimer::timeout, &window, [&question, &answer] {
      auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
      if (box == nullptr) return;
      question = box->text();
      for (const QAbstractButton* button : box->buttons()) question += QStringLiteral(" [%1]").arg(button->text());
      answer.stop();
      box->button(QMessageBox::Cancel)->click();
    });
    answer.start(50);
    other_scene->trigger();
    QVERIFY2(question.contains(QStringLiteral("The scene 'setup_A' starts the teaching afresh and clears this run from the window: "
                                              "its 1 training area (")),
             qPrintable(question));
    // No map was learned yet, and the button names what it does.
    QVERIFY2(!question.contains(QStringLiteral("map")) && question.contains(QStringLiteral("[Discard the teaching]")), qPrintable(question));
    QCOMPARE(s.areas, 1);
    QVERIFY(!other_scene->isChecked());
    QTest::keyClick(&window, Qt::Key_F6);
    QTRY_VERIFY_WITH_TIMEOUT(s.model_ready && s.stage == Stage::kIdle, 30000);
    QTRY_VERIFY(hintSays("Start programming (F7)"));
    // What the learning said stays under the counts after the status bar moved on.
    QTRY_VERIFY2(panel->countsLabel()->text().contains(QRegularExpression(QStringLiteral("\nmap: \\w+ from 1 area, \\d+ samples in "))),
                 qPrintable(panel->countsLabel()->text()));

    // A teach-in with the keys: F7, touch, fix the start, touch, hold `key` (none: the tip
    // stays) for `held_ms`, store.
    const auto teachIn = [&window, &s, &hintSays](std::optional<Qt::Key> key, int held_ms) {
      QTest::keyClick(&window, Qt::Key_F7);
      QTRY_COMPARE(s.stage, Stage::kProgramming);
      QTRY_VERIFY(hintSays("To teach a motion"));
      QTest::keyClick(&window, Qt::Key_Space);
      QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
      QTest::keyClick(&window, Qt::Key_Return);
      QTRY_COMPARE(s.sub_stage, SubStage::kPosed);
      QTest::keyClick(&window, Qt::Key_Space);
      QTRY_COMPARE(s.sub_stage, SubStage::kTeachIn);
      QTRY_VERIFY(hintSays("Recording the motion"));
      if (key) QTest::keyPress(&window, *key);
      QTest::qWait(held_ms);
      if (key) QTest::keyRelease(&window, *key);
      QTest::keyClick(&window, Qt::Key_Return);
    };
    // One teach-in: from where the arm is, 0.12 m along -x.
    QVERIFY(!panel->replayButton()->isEnabled());
    teachIn(Qt::Key_Left, 1500);
    if (QTest::currentTestFailed()) return;
    QTRY_COMPARE(s.teach_ins, 1);
    QTRY_VERIFY(s.teach_in_data != nullptr && s.teach_in_data->size() == 1);
    const Eigen::MatrixXd taught = s.teach_in_data->front();
    const Eigen::Vector3d start = taught.col(0);
    const Eigen::Vector3d end = taught.col(taught.cols() - 1);
    QVERIFY2((end - start).norm() > 0.05, "the teach-in is too short to tell a replay");

    QTest::keyClick(&window, Qt::Key_F8);
    QTRY_COMPARE(s.stage, Stage::kExecution);
    QTRY_VERIFY(panel->replayButton()->isEnabled());
    QCOMPARE(panel->chosenTeachIn(), 0);
    QTRY_VERIFY(hintSays("Replay a teach-in (F9)"));
    QVERIFY((tip(window) - end).norm() < 0.03);
    // F9 replays: the tip goes back to the teach-in's start, then along it to its end. The
    // closest it comes to the start is watched all along (it turns there in a moment).
    const auto replayed = [&window, &s, &start, &end] {
      QTRY_VERIFY_WITH_TIMEOUT(!s.execution_done, 5000);
      // Said while it moves, and when it ends: a replay that looks like nothing happening is not.
      QTRY_VERIFY(flexirob::ui::fullStatusMessage(window.statusBar()).startsWith(QStringLiteral("Replaying teach-in 1")));
      double closest = (tip(window) - start).norm();
      QElapsedTimer clock;
      clock.start();
      while (!(s.execution_done && (tip(window) - end).norm() < 0.01) && clock.elapsed() < 30000) {
        QTest::qWait(5);
        closest = std::min(closest, (tip(window) - start).norm());
      }
      QVERIFY2(closest < 0.02, qPrintable(QStringLiteral("the tip came within %1 m of the start").arg(closest)));
      QVERIFY(s.execution_done && (tip(window) - end).norm() < 0.01);
      QTRY_VERIFY_WITH_TIMEOUT(flexirob::ui::fullStatusMessage(window.statusBar()) == QStringLiteral("Replay of teach-in 1 done"), 10000);
    };
    QTest::keyClick(&window, Qt::Key_F9);
    replayed();
    if (QTest::currentTestFailed()) return;
    // So does the button.
    QTest::mouseClick(panel->replayButton(), Qt::LeftButton);
    replayed();
    if (QTest::currentTestFailed()) return;

    // A teach-in with no motion of the tip is kept, and the warning box says so after the
    // stage changed back to WAITING (a warning said before it was cleared with it).
    teachIn(std::nullopt, 300);
    if (QTest::currentTestFailed()) return;
    QTRY_COMPARE(s.teach_ins, 2);
    QTRY_COMPARE(s.sub_stage, SubStage::kWaiting);
    QTRY_VERIFY(panel->warningLabel()->text().contains(QStringLiteral("teach-in 2: the tip moved at most")));
    QTest::qWait(300);
    QVERIFY2(panel->warningLabel()->isVisible() && panel->warningLabel()->text().contains(QStringLiteral("teach-in 2")),
             qPrintable(panel->warningLabel()->text()));
  }

  // File opened and closed with Escape: the menu bar kept the keys, and Space opened File
  // again instead of touching the arm.
  void aMenuClosedWithEscapeGivesTheKeysBackToTheArm() {
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    waitRunning(window);
    window.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&window));
    QAction* file_entry = window.menuBar()->actions().front();
    QMenu* file = file_entry->menu();
    QVERIFY(file != nullptr);
    QTest::mouseClick(window.menuBar(), Qt::LeftButton, {}, window.menuBar()->actionGeometry(file_entry).center());
    QTRY_VERIFY(file->isVisible());
    QTest::keyClick(file, Qt::Key_Escape);
    QTRY_VERIFY(!file->isVisible());
    QTest::qWait(100);
    QVERIFY(!window.menuBar()->hasFocus());
    QTest::keyClick(QApplication::focusWidget() != nullptr ? QApplication::focusWidget() : static_cast<QWidget*>(&window), Qt::Key_Space);
    QTest::qWait(200);
    QVERIFY(!file->isVisible());
  }

  void aRefusedRequestIsShownAsAWarning() {
    MainWindow window("lwr4", "empty", quietOptions());
    waitRunning(window);
    // F6 (finish configuration) in IDLE: the workflow refuses and says why, naming the button.
    QTest::keyClick(&window, Qt::Key_F6);
    QTRY_VERIFY(window.stagePanel()->warningLabel()->text().startsWith(QStringLiteral("Finish configuration: not in CONFIGURATION")));
    QCOMPARE(window.live()->snapshot().stage, Stage::kIdle);
    // F9 with no teach-in, which the window refuses itself: said the same way, replacing the
    // refusal before it.
    QTest::keyClick(&window, Qt::Key_F9);
    QTRY_COMPARE(window.stagePanel()->warningLabel()->text(),
                 QStringLiteral("Replay: no teach-in to replay; record one in PROGRAMMING first"));
    QVERIFY(window.statusBar()->currentMessage().startsWith(QStringLiteral("Replay: no teach-in")));
  }

  // What the window says and allows when a robot, a scene or the link to the arm fails: the
  // reason whole in the view, no button that would teach on nothing.
  void aRobotThatCannotBeLoadedLeavesNoButtonToPressAndSaysWhy() {
    MainWindow window("/nonexistent/robot.urdf", "empty", quietOptions());
    window.mirror();
    QVERIFY(window.live() == nullptr);
    flexirob::ui::StagePanel* panel = window.stagePanel();
    for (const Button button : {Button::kStartConfiguration, Button::kFinishedConfiguration, Button::kStartProgramming,
                                Button::kFinishedProgramming}) {
      QVERIFY(!panel->button(button)->isEnabled());
    }
    QCOMPARE(panel->stageLabel()->text(), QStringLiteral("NO ROBOT"));
    QVERIFY(!window.problemLabel()->isHidden());
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("Cannot load robot '/nonexistent/robot.urdf'")));
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("no robot runs")));
    QTest::keyClick(&window, Qt::Key_F5);
    QVERIFY(window.statusBar()->currentMessage().contains(QStringLiteral("No robot runs")));
    // A robot that loads ends it.
    QVERIFY(window.loadRobot("lwr4"));
    waitRunning(window);
    QVERIFY(window.problemLabel()->isHidden());
    window.mirror();
    QVERIFY(panel->button(Button::kStartConfiguration)->isEnabled());
  }

  void aSceneThatCannotBeLoadedIsNamedWithItsReasonUntilAnotherLoads() {
    MainWindow window("lwr4", "/nonexistent/scene.yaml", quietOptions());
    waitRunning(window);
    QVERIFY(!window.problemLabel()->isHidden());
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("Cannot load scene '/nonexistent/scene.yaml'")));
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("the scene stays 'empty'")));
    QVERIFY(window.loadScene("setup_I"));
    QVERIFY(window.problemLabel()->isHidden());
  }

  // What the CLI notes about a robot description is said in the view, as a scene's notes are.
  void aRobotsNotesAreSaidInTheViewUntilAnotherLoads() {
    QTemporaryDir directory;
    std::string urdf = flexirob::testing::smallLightArmUrdf();
    const auto link = urdf.find("<link name=\"l3\">");
    const auto open = urdf.find("<collision>", link);
    const auto close = urdf.find("</collision>", link);
    QVERIFY(link != std::string::npos && open != std::string::npos && close != std::string::npos);
    urdf.replace(close, std::string("</collision>").size(), "</visual>");
    urdf.replace(open, std::string("<collision>").size(), "<visual>");
    const QString file = directory.filePath(QStringLiteral("drawn_only.urdf"));
    {
      QFile out(file);
      QVERIFY(out.open(QIODevice::WriteOnly));
      out.write(urdf.c_str());
    }
    MainWindow window(file.toStdString(), "empty", quietOptions());
    waitRunning(window);
    QVERIFY2(window.problemLabel()->text().contains(QStringLiteral("note: link 'l3' has a visual but no collision element")),
             qPrintable(window.problemLabel()->text()));
    QVERIFY(window.loadRobot("lwr4"));
    QVERIFY(window.problemLabel()->isHidden());
  }

  // The nine-joint arm in a scene made for the LWR IV: the scene's 13 postures do not fit, said
  // once (thirteen near-equal lines had filled the view over the arm), with the scene made for it.
  void aSceneMadeForAnotherArmIsOneLineNamingTheSceneMadeForThisOne() {
    MainWindow window("arm9", "setup_I", quietOptions());
    waitRunning(window);
    const QString text = window.problemLabel()->text();
    QVERIFY2(text.contains(QStringLiteral("postures have 7 joint values, the robot 'arm9' has 9 joints (the scene was made for 'lwr4')")),
             qPrintable(text));
    QCOMPARE(text.count(QStringLiteral("joint values")), 1);
    QVERIFY2(text.contains(QStringLiteral("made for it: Scene ▸ arm9_areas")), qPrintable(text));
    QVERIFY(!text.contains(QStringLiteral("--tip")));
    window.mirror();
    QVERIFY(window.stagePanel()->button(Button::kStartConfiguration)->isEnabled());
  }

  void aScenesHomePostureBeyondTheLimitsIsLeftOutAndTheArmRuns() {
    QTemporaryDir dir;
    const std::string file = writeScene(dir, QStringLiteral("beyond.yaml"), "name: beyond\nrobot: lwr4\nhome_posture: [0, 3.0, 0, 0, 0, 0, 0]\n");
    QVERIFY(!file.empty());
    MainWindow window("lwr4", file, quietOptions());
    waitRunning(window);
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("outside its limits")));
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("that posture is not used")));
    const auto& s = window.live()->snapshot();
    QVERIFY(std::abs(s.q[1]) < 2.0);  // A2, within its ±2.09 rad
    window.mirror();
    QVERIFY(window.stagePanel()->button(Button::kStartConfiguration)->isEnabled());
  }

  void aScenesNotesAndAnArmStartingInContactAreSaidInTheView() {
    QTemporaryDir dir;
    const std::string far = writeScene(dir, QStringLiteral("far.yaml"), "name: far\nobstacles:\n  - {name: crate, shape: box, size: [0.2, 0.2, 0.2], position: [-640, 0, 0.1]}\n");
    QVERIFY(!far.empty());
    MainWindow window("lwr4", far, quietOptions());
    waitRunning(window);
    QVERIFY2(window.problemLabel()->text().contains(QStringLiteral("note: obstacle 'crate' lies 640 m")),
             qPrintable(window.problemLabel()->text()));
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("millimetres")));
    QVERIFY(window.loadScene("empty"));
    QVERIFY(window.problemLabel()->isHidden());

    // A block round the wrist of the scene's own home posture: the arm starts touching it.
    const std::string block = writeScene(dir, QStringLiteral("block.yaml"), "name: block\nhome_posture: [0, 0, 0, 0, 0, 0, 0]\n"
                "obstacles:\n  - {name: block, shape: box, size: [0.3, 0.3, 0.3], position: [0, 0, 1.1]}\n");
    QVERIFY(!block.empty());
    QVERIFY(window.loadScene(block));
    waitRunning(window);
    QTRY_VERIFY_WITH_TIMEOUT((window.mirror(), window.problemLabel()->text().contains(QStringLiteral("The arm starts in contact"))), 20000);  // an upper bound: a loaded CI machine draws slowly
    QVERIFY(window.problemLabel()->text().contains(QStringLiteral("the scene's home_posture touches the scene")));
  }

  void anFriLinkThatHasMeasuredNothingTeachesNothing() {
    MainWindow window("lwr4", "empty", quietOptions());
    waitRunning(window);
    // Nobody answers there: the link waits for the arm's first measurement.
    if (!window.setBackend("fri://127.0.0.1:1")) QSKIP("the FRI port 49938 is taken on this machine");
    QCOMPARE(window.live()->linkStatus().measurements, std::uint64_t{0});
    window.mirror();
    QVERIFY(!window.stagePanel()->button(Button::kStartConfiguration)->isEnabled());
    QVERIFY(window.bannerLabel()->text().contains(QStringLiteral("no measurement yet")));
    QTest::keyClick(&window, Qt::Key_F5);
    QVERIFY(window.statusBar()->currentMessage().contains(QStringLiteral("has not sent a measurement")));
    QTest::qWait(200);
    QCOMPARE(window.live()->snapshot().stage, Stage::kIdle);
    QVERIFY(window.setBackend("sim"));
  }

  void keysMoveTheNineDofArm() {
    MainWindow window("arm9", "empty", quietOptions());
    if (canDraw()) window.show();
    waitRunning(window);
    QCOMPARE(window.robotModel()->dof(), 9);
    const auto& s = window.live()->snapshot();
    QTest::keyClick(&window, Qt::Key_F5);  // start configuration
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTest::keyClick(&window, Qt::Key_Space);  // on_affected: APPROACHING
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);

    // Holding → moves the tip along +x at the tele-operation speed.
    const Eigen::Vector3d before = tip(window);
    QTest::keyPress(&window, Qt::Key_Right);
    QTest::qWait(1500);
    QTest::keyRelease(&window, Qt::Key_Right);
    QTRY_VERIFY(s.keyboard_mode);
    QTest::qWait(500);
    const Eigen::Vector3d moved = tip(window);
    QVERIFY2(moved.x() - before.x() > 0.03,
             qPrintable(QStringLiteral("tip moved by (%1, %2, %3) m")
                            .arg(moved.x() - before.x())
                            .arg(moved.y() - before.y())
                            .arg(moved.z() - before.z())));
    QVERIFY(std::abs(moved.z() - before.z()) < 0.5 * (moved.x() - before.x()));

    // Holding 3 turns joint 3 (the null space: the tip stays about where it is).
    const double q3 = s.q[2];
    QTest::keyPress(&window, Qt::Key_3);
    QTest::qWait(1500);
    QTest::keyRelease(&window, Qt::Key_3);
    QTest::qWait(500);
    QVERIFY2(s.q[2] - q3 > 0.05, qPrintable(QStringLiteral("joint 3 moved by %1 rad").arg(s.q[2] - q3)));
  }

  // A tap after the display stalled (a busy machine, a software renderer) moves the target for
  // the tap only: the stall's 0.4 s had been counted as held, 3.2 cm at the task speed.
  void aTapAfterTheDisplayStalledMovesOnlyForTheTap() {
    MainWindow window("arm9", "empty", quietOptions());
    if (canDraw()) window.show();
    waitRunning(window);
    const auto& s = window.live()->snapshot();
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
    QTest::keyClick(&window, Qt::Key_Left);  // keyboard mode on, and the arm held where it is
    QTRY_VERIFY(s.keyboard_mode);
    QTest::qWait(800);
    const auto target = [&s] { return Eigen::Vector3d(s.p_des[0], s.p_des[1], s.p_des[2]); };
    const Eigen::Vector3d before = target();
    std::this_thread::sleep_for(std::chrono::milliseconds(400));  // no display tick meanwhile
    QTest::keyPress(&window, Qt::Key_Right);
    QTest::keyRelease(&window, Qt::Key_Right);
    QTest::qWait(300);
    const double moved = (target() - before).norm();
    QVERIFY2(moved < 0.004, qPrintable(QStringLiteral("a tap moved the task target %1 m").arg(moved)));
  }

  void aMouseDragOnALinkPullsIt() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    waitRunning(window);
    const int elbow = 4;
    Eigen::Vector3d before, pulled;
    Eigen::Vector2d pixel;
    pullBody(window, elbow, before, pulled, pixel);
    if (QTest::currentTestFailed()) return;
    QVERIFY2((pulled - before).norm() > 0.03,
             qPrintable(QStringLiteral("the elbow moved %1 m").arg((pulled - before).norm())));
    // It moved towards where the cursor went, in the picture.
    flexirob::ui::OsgView* view = window.view();
    const auto moved_pixel = flexirob::render::projectToPixel(view->currentCamera(), view->width(), view->height(), pulled);
    QVERIFY(moved_pixel.has_value());
    const Eigen::Vector2d drag(-80.0, -64.0);
    const double along = (*moved_pixel - pixel).dot(drag.normalized());
    QVERIFY2(along > 5.0, qPrintable(QStringLiteral("the elbow moved %1 px along the drag").arg(along)));
  }

  // A light arm under the LWR IV's gains and drift damping hardly moved under the mouse (1.2 cm
  // in 1.5 s); scaled to the arm (docs/CONTROL.md), the pull moves it, and let go it comes to
  // rest. The spring is scaled too: the LWR IV's 250 N/m and 80 N would pull its 50 g links
  // with tens of newtons; its arrow is as long, for the arm's size, as the LWR IV's.
  void aMouseDragOnALightArmPullsItAndItComesToRest() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    QTemporaryDir directory;
    const QString urdf = directory.filePath(QStringLiteral("small.urdf"));
    {
      QFile file(urdf);
      QVERIFY(file.open(QIODevice::WriteOnly));
      file.write(flexirob::testing::smallLightArmUrdf().c_str());
    }
    MainWindow window(urdf.toStdString(), "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    waitRunning(window);
    const int forearm = 5;
    Eigen::Vector3d before, pulled;
    Eigen::Vector2d pixel;
    Eigen::Vector3d force;
    pullBody(window, forearm, before, pulled, pixel, &force);
    if (QTest::currentTestFailed()) return;
    QVERIFY2((pulled - before).norm() > 0.02, qPrintable(QStringLiteral("the forearm moved %1 m").arg((pulled - before).norm())));
    const flexirob::app::ArmScale& scale = window.live()->armScale();
    QVERIFY(scale.force() < 0.05);
    QVERIFY2(force.norm() > 0.0 && force.norm() <= 80.0 * scale.force() + 1e-9,
             qPrintable(QStringLiteral("the hand pulled with %1 N").arg(force.norm())));
    // The arrow of the spring's largest pull is as long, for the arm's size, as the LWR IV's of
    // 80 N (0.4 m); a pull of 0.4 N on the LWR IV, scaled, hides it.
    const Eigen::Vector3d largest = Eigen::Vector3d::UnitX() * 80.0 * scale.force();
    QVERIFY(std::abs(window.forceArrow()->length(largest) - 0.4 * scale.length) < 1e-9);
    window.forceArrow()->show(pulled, Eigen::Vector3d::UnitX() * 0.4 * scale.force());
    QVERIFY(!window.forceArrow()->visible());
    // Let go, it comes to rest within 3 s of the robot's time.
    const auto& s = window.live()->snapshot();
    const auto fastest = [&s] {
      double speed = 0.0;
      for (int j = 0; j < s.dof; ++j) speed = std::max(speed, std::abs(s.qd[static_cast<std::size_t>(j)]));
      return speed;
    };
    const double let_go = s.time;
    QTRY_VERIFY_WITH_TIMEOUT(fastest() < 0.1 || s.time > let_go + 3.0, 30000);
    QVERIFY2(fastest() < 0.1, qPrintable(QStringLiteral("a joint still moves at %1 rad/s").arg(fastest())));
    // Grabbed 1 cm from where the forearm rests, unclipped: the spring is 250 N/m times the arm's
    // mass ratio (the LWR IV's 250 N/m would pull with 2.5 N).
    const Eigen::Vector3d at = bodyOrigin(window, forearm);
    QVERIFY(window.live()->grab(forearm, Eigen::Vector3d::Zero(), at + Eigen::Vector3d(0.0, 0.0, 0.01),
                                flexirob::ui::MousePerturbation::kStiffness));
    const double expected = flexirob::ui::MousePerturbation::kStiffness * scale.mass() * 0.01;
    QVERIFY(expected < 80.0 * scale.force());
    QTRY_VERIFY(s.hand_active);
    const double pulling = Eigen::Vector3d(s.hand_force_W[0], s.hand_force_W[1], s.hand_force_W[2]).norm();
    window.live()->release();
    QVERIFY2(pulling > 0.5 * expected && pulling < 1.1 * expected,
             qPrintable(QStringLiteral("the spring pulled with %1 N, %2 N expected").arg(pulling).arg(expected)));
  }

  void theForceArrowAndTheKeyMapShowInTheWindow() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    waitRunning(window);
    // The arrow at the tip, 40 N along −y: pixels change where it is drawn, and only there.
    const Eigen::Vector3d p = window.kinematics()->p_WT();
    window.forceArrow()->show(p, Eigen::Vector3d(0.0, -40.0, 0.0));
    const QImage with_arrow = window.view()->grabFramebuffer();
    window.forceArrow()->hide();
    const QImage without = window.view()->grabFramebuffer();
    QCOMPARE(with_arrow.size(), without.size());
    int changed = 0;
    for (int y = 0; y < with_arrow.height(); ++y) {
      for (int x = 0; x < with_arrow.width(); ++x) changed += with_arrow.pixel(x, y) != without.pixel(x, y) ? 1 : 0;
    }
    QVERIFY2(changed > 150, qPrintable(QStringLiteral("the arrow changed %1 pixels").arg(changed)));
    const auto middle = flexirob::render::projectToPixel(window.view()->currentCamera(), with_arrow.width(),
                                                         with_arrow.height(), p + Eigen::Vector3d(0.0, -0.1, 0.0));
    QVERIFY(middle.has_value());
    const QPoint m(static_cast<int>(middle->x()), static_cast<int>(middle->y()));
    QVERIFY2(with_arrow.pixel(m) != without.pixel(m), "the arrow is not drawn along the force");

    // H shows the key map over the view, H hides it.
    QVERIFY(!window.keyMapLabel()->isVisible());
    QTest::keyClick(&window, Qt::Key_H);
    QVERIFY(window.keyMapLabel()->isVisible());
    QVERIFY(window.keyMapLabel()->text().contains(QStringLiteral("on_affected")));
    QVERIFY(window.view()->geometry().contains(window.keyMapLabel()->geometry().translated(window.view()->pos())));
    QTest::keyClick(&window, Qt::Key_H);
    QVERIFY(!window.keyMapLabel()->isVisible());
  }

  void jointLimitBarsTurnAmberThenRed() {
    flexirob::robot::Joint joint;
    joint.limits.lower = joint.limits.soft_lower = -2.0;
    joint.limits.upper = joint.limits.soft_upper = 2.0;
    flexirob::ui::LimitDistanceBar bar(joint);
    using Level = flexirob::ui::LimitDistanceBar::Level;
    bar.setValue(0.0);
    QCOMPARE(bar.level(), Level::kOk);
    QCOMPARE(bar.distance(), 2.0);
    bar.setValue(2.0 - 0.30);  // 0.30 rad from the upper limit
    QCOMPARE(bar.level(), Level::kAmber);
    bar.setValue(-2.0 + 0.10);
    QCOMPARE(bar.level(), Level::kRed);
    QVERIFY(std::abs(bar.distance() - 0.10) < 1e-12);
  }

  // A slide of 12.6 cm: in metres, and within a tenth of its travel; mid-travel is far from
  // either end (it had been red there, measured against 0.17 "rad").
  void aShortSlidesBarIsGreenAtMidTravelAndRedNearItsEnds() {
    flexirob::robot::Joint slide;
    slide.type = flexirob::robot::JointType::kPrismatic;
    slide.limits.lower = slide.limits.soft_lower = 0.0;
    slide.limits.upper = slide.limits.soft_upper = 0.126;
    flexirob::ui::LimitDistanceBar bar(slide);
    using Level = flexirob::ui::LimitDistanceBar::Level;
    QVERIFY(std::abs(bar.redMargin() - 0.0126) < 1e-12);
    bar.setValue(0.063);
    QCOMPARE(bar.level(), Level::kOk);
    bar.setValue(0.020);
    QCOMPARE(bar.level(), Level::kAmber);
    bar.setValue(0.120);
    QCOMPARE(bar.level(), Level::kRed);
  }

  void theKeyMapCoversTaskJointsTriggersAndButtons() {
    using flexirob::ui::TeleopAction;
    using flexirob::ui::TeleopKeys;
    TeleopKeys keys;
    QVERIFY(keys.press(Qt::Key_Right));
    QVERIFY(keys.press(Qt::Key_PageDown));
    const Eigen::Vector3d v = keys.taskVelocity();
    QCOMPARE(v, Eigen::Vector3d(TeleopKeys::kTaskSpeed, 0.0, -TeleopKeys::kTaskSpeed));
    QVERIFY(keys.press(Qt::Key_9));  // joint 9 +
    QVERIFY(keys.press(Qt::Key_E));  // joint 3 −
    const Eigen::VectorXd arm9 = keys.jointVelocities(9);
    QCOMPARE(arm9[8], TeleopKeys::kJointSpeed);
    QCOMPARE(arm9[2], -TeleopKeys::kJointSpeed);
    QCOMPARE(keys.jointVelocities(7).cwiseAbs().sum(), TeleopKeys::kJointSpeed);  // the LWR has no joint 9
    QVERIFY(!keys.press(Qt::Key_Space));  // a trigger is a click, not held
    QCOMPARE(TeleopKeys::actionOf(Qt::Key_Space)->trigger, flexirob::app::Trigger::kOnAffected);
    QCOMPARE(TeleopKeys::actionOf(Qt::Key_Return)->trigger, flexirob::app::Trigger::kOnConverged);
    QCOMPARE(TeleopKeys::actionOf(Qt::Key_F7)->button, Button::kStartProgramming);
    QVERIFY(TeleopKeys::actionOf(Qt::Key_F9)->kind == TeleopAction::Kind::kReplay);
    QVERIFY(TeleopKeys::keyMapText(7).contains(QStringLiteral("F9 replay")));
    // The mouse and view keys the guide lists are on the map too.
    QVERIFY(TeleopKeys::keyMapText(7).contains(QStringLiteral("Ctrl+click a goal")));
    QVERIFY(TeleopKeys::keyMapText(7).contains(QStringLiteral("Home resets the camera")));
    QVERIFY(TeleopKeys::keyMapText(7).contains(QStringLiteral("Alt+T Teaching")));
    QVERIFY(!TeleopKeys::actionOf(Qt::Key_Z).has_value());
    QVERIFY(keys.release(Qt::Key_Right));
    QCOMPARE(keys.taskVelocity().x(), 0.0);
  }

  void appliedParametersRestartTheRobotWithThem() {
    MainWindow window("lwr4", "empty", quietOptions());
    waitRunning(window);
    // A copy: applying rebuilds the parameter set, and a reference into it would dangle.
    const flexirob::robot::ParameterDeclaration declaration = window.parameters().declarations().front();
    QDoubleSpinBox* box = window.parameterPanel()->spinBox(declaration.name);
    QVERIFY(box != nullptr);
    const double changed = declaration.min_value + 0.25 * (declaration.max_value - declaration.min_value);
    box->setValue(changed);
    const double shown = box->value();  // rounded to the box's decimals
    auto* apply = window.parameterPanel()->findChild<QPushButton*>(QStringLiteral("apply_parameters"));
    QVERIFY(apply != nullptr);
    QTest::mouseClick(apply, Qt::LeftButton);
    // The panel is rebuilt from the new parameter set: the new value stays shown.
    QCOMPARE(window.parameters().get(declaration.name), shown);
    QCOMPARE(window.parameterPanel()->spinBox(declaration.name)->value(), shown);
    waitRunning(window);
  }

  // A wheel turned over the Parameters panel while scrolling it changes no value; in a box the
  // operator clicked into, it does.
  void aWheelOverTheParametersChangesOnlyTheBoxClickedInto() {
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    window.activateWindow();
    const flexirob::robot::ParameterDeclaration declaration = window.parameters().declarations().front();
    QDoubleSpinBox* box = window.parameterPanel()->spinBox(declaration.name);
    QVERIFY(box != nullptr);
    box->setValue(declaration.min_value + 0.5 * (declaration.max_value - declaration.min_value));
    const double before = box->value();
    const auto turnWheel = [box] {
      const QPointF at(box->width() / 2.0, box->height() / 2.0);
      QWheelEvent wheel(at, box->mapToGlobal(at), QPoint(), QPoint(0, -120), Qt::NoButton, Qt::NoModifier,
                        Qt::NoScrollPhase, false);
      QApplication::sendEvent(box, &wheel);
    };
    window.view()->setFocus();
    QVERIFY(!box->hasFocus());
    turnWheel();
    QCOMPARE(box->value(), before);
    box->setFocus();
    QTRY_VERIFY(box->hasFocus());
    turnWheel();
    QVERIFY(box->value() != before);
  }

  void aSessionIsRecordedAndSaved() {
    MainWindow::Options options = quietOptions();
    options.record_sessions = true;
    MainWindow window("lwr4", "empty", options);
    waitRunning(window);
    QVERIFY(!window.sessionFile().isEmpty());
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(window.live()->snapshot().stage, Stage::kConfiguration);
    QTest::qWait(300);
    QTemporaryDir directory;
    const QString file = directory.filePath(QStringLiteral("saved.flexirob"));
    QVERIFY(window.saveSession(file));
    const flexirob::app::SessionReader reader(file.toStdString());
    QCOMPARE(reader.metadata().robot_name, std::string("lwr4"));
    QVERIFY(reader.stateCount() > 5);
    bool configuration = false;
    for (const auto& stage : reader.stages()) configuration = configuration || stage.stage == "CONFIGURATION";
    QVERIFY(configuration);
    // Recording goes on into the run's file, which holds the whole run: what the copy holds
    // and what came after.
    const QString run_file = window.sessionFile();
    QVERIFY(!run_file.isEmpty() && run_file != file);
    recordAnArea(window, 1);
    QCOMPARE(window.sessionFile(), run_file);
    QVERIFY(window.teachingChangedSinceSave());
    // A name typed without a suffix gets the one Open recording lists.
    const QString typed = directory.filePath(QStringLiteral("second run"));
    QVERIFY(window.saveSession(typed));
    QCOMPARE(window.savedSessionFile(), typed + QStringLiteral(".flexirob"));
    QVERIFY(!window.teachingChangedSinceSave());
    const flexirob::app::SessionReader second((typed + QStringLiteral(".flexirob")).toStdString());
    QCOMPARE(second.areas().size(), std::size_t{1});
    QVERIFY(second.stateCount() > reader.stateCount());
    // The first copy is as it was saved.
    QCOMPARE(flexirob::app::SessionReader(file.toStdString()).areas().size(), std::size_t{0});
    // Teaching after the last save: closing asks; Cancel keeps the window open, Save writes it
    // there again.
    recordAnArea(window, 2);
    QVERIFY(window.teachingChangedSinceSave());
    QMessageBox::StandardButton answer = QMessageBox::Cancel;
    QString question;
    QTimer answering;
    connect(&answering, &QTimer::timeout, &window, [&] {
      auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
      if (box == nullptr) return;
      question = box->text();
      box->button(answer)->click();
    });
    answering.start(50);
    window.show();
    QVERIFY(!window.close());
    QVERIFY(question.contains(QStringLiteral("second run.flexirob")));
    QVERIFY(window.isVisible());
    answer = QMessageBox::Save;
    QVERIFY(window.close());
    answering.stop();
    QCOMPARE(flexirob::app::SessionReader((typed + QStringLiteral(".flexirob")).toStdString()).areas().size(), std::size_t{2});
  }

  // The run's file removed under the running window (a cleaned-up folder): the recording is
  // still held by the recorder's connection, and Save session keeps all of it.
  void aSessionWhoseFileWasRemovedIsStillSavedWhole() {
    MainWindow::Options options = quietOptions();
    options.record_sessions = true;
    MainWindow window("lwr4", "empty", options);
    waitRunning(window);
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(window.live()->snapshot().stage, Stage::kConfiguration);
    recordAnArea(window, 1);
    const QString run_file = window.sessionFile();
    QVERIFY(QFile::remove(run_file));
    QTemporaryDir directory;
    const QString file = directory.filePath(QStringLiteral("rescued.flexirob"));
    QVERIFY(window.saveSession(file));
    const flexirob::app::SessionReader rescued(file.toStdString());
    QCOMPARE(rescued.areas().size(), std::size_t{1});
    QVERIFY(rescued.stateCount() > 5);
    // The run records on, into a new file of its own.
    QVERIFY(!window.sessionFile().isEmpty() && window.sessionFile() != run_file);
    QVERIFY(QFileInfo::exists(window.sessionFile()));
    // That file holds only what comes after: Save session asks for another name instead of
    // writing it over the rescued run.
    recordAnArea(window, 2);
    bool asked_for_a_name = false;
    QTimer answering;
    connect(&answering, &QTimer::timeout, &window, [&] {
      auto* dialog = qobject_cast<QFileDialog*>(QApplication::activeModalWidget());
      if (dialog == nullptr) return;
      asked_for_a_name = true;
      dialog->reject();
    });
    answering.start(50);
    QAction* save_again = nullptr;
    for (QAction* action : window.menuBar()->actions().front()->menu()->actions()) {
      if (action->text() == QStringLiteral("&Save session")) save_again = action;
    }
    QVERIFY(save_again != nullptr);
    save_again->trigger();
    answering.stop();
    QVERIFY(asked_for_a_name);
    QCOMPARE(flexirob::app::SessionReader(file.toStdString()).areas().size(), std::size_t{1});
    // The new file removed too: the view says so, and closing asks before the recording goes.
    QVERIFY(QFile::remove(window.sessionFile()));
    QTRY_VERIFY(window.problemLabel()->text().contains(QStringLiteral("was removed or replaced")));
    QString question;
    connect(&answering, &QTimer::timeout, &window, [&] {
      if (auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget())) {
        question = box->text();
        box->button(QMessageBox::Discard)->click();
      }
    });
    answering.start(50);
    window.show();
    QVERIFY(window.close());
    answering.stop();
    QVERIFY2(question.contains(QStringLiteral("held in memory only")), qPrintable(question));
  }

  // A sessions folder no file can be created in (it leads into /proc, which refuses even root):
  // the run records in memory, the view says so, and closing asks to save it.
  void aRecordingHeldInMemoryIsShownAndClosingAsksToSaveIt() {
    // The suites that record into this folder hold CTest's lock "qt_test_sessions"
    // (tests/ui/CMakeLists.txt), so none records while it leads elsewhere.
    const QString sessions = MainWindow::sessionDirectory();
    const QString aside = sessions + QStringLiteral(".aside");
    bool moved_aside = false;
    const auto restore = qScopeGuard([&] {
      if (QFileInfo(sessions).isSymLink()) QFile::remove(sessions);
      if (moved_aside) QDir().rename(aside, sessions);
    });
    QDir().mkpath(QFileInfo(sessions).absolutePath());
    if (QFileInfo(sessions).isSymLink()) QFile::remove(sessions);  // left by a run that was killed
    if (QFileInfo::exists(aside) && !QFileInfo::exists(sessions)) QDir().rename(aside, sessions);
    moved_aside = QFileInfo::exists(sessions) && QDir().rename(sessions, aside);
    QVERIFY(QFile::link(QStringLiteral("/proc/self"), sessions));
    MainWindow::Options options = quietOptions();
    options.record_sessions = true;
    MainWindow window("lwr4", "empty", options);
    waitRunning(window);
    QTRY_VERIFY(window.problemLabel()->text().contains(QStringLiteral("held in memory only")));
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(window.live()->snapshot().stage, Stage::kConfiguration);
    QTest::qWait(300);
    QTemporaryDir directory;
    const QString file = directory.filePath(QStringLiteral("kept.flexirob"));
    QString question;
    QTimer answering;
    int dialog_ticks = 0;
    connect(&answering, &QTimer::timeout, &window, [&] {
      QWidget* modal = QApplication::activeModalWidget();
      if (auto* box = qobject_cast<QMessageBox*>(modal)) {
        question = box->text();
        box->button(QMessageBox::Save)->click();
      } else if (auto* dialog = qobject_cast<QFileDialog*>(modal); dialog != nullptr && ++dialog_ticks > 200) {
        dialog->reject();  // 10 s without taking the name: the close fails below instead of waiting for ever
      } else if (dialog != nullptr) {
        // The whole path is typed into the name field, as a person would. selectFile() would
        // not do: it leaves the field as it was once the field has the focus, which depends
        // on when the dialog was activated, and the name offered would be saved instead.
        auto* name_field = dialog->findChild<QLineEdit*>(QStringLiteral("fileNameEdit"));
        if (name_field == nullptr) {
          dialog->reject();  // the question then fails below, naming no file
        } else if (dialog->selectedFiles().value(0) == file) {
          static_cast<QDialog*>(dialog)->accept();  // QFileDialog::accept() is protected
        } else if (name_field->text() != file) {
          name_field->setText(file);
        }
      }
    });
    answering.start(50);
    window.show();
    QVERIFY(window.close());
    answering.stop();
    QVERIFY2(question.contains(QStringLiteral("held in memory only")), qPrintable(question));
    const flexirob::app::SessionReader kept(file.toStdString());
    QVERIFY(kept.stateCount() > 5);
    bool configuration = false;
    for (const auto& stage : kept.stages()) configuration = configuration || stage.stage == "CONFIGURATION";
    QVERIFY(configuration);
  }

  // The window records the learned model as teach does (the control thread records the
  // rest); GUI sessions had held none, so `export --model` and the review found nothing.
  void theLearnedModelIsInTheSession() {
    MainWindow::Options options = quietOptions();
    options.record_sessions = true;
    MainWindow window("lwr4", "empty", options);
    waitRunning(window);
    // start_configuration, then one area.
    const auto configureAnArea = [&window](int areas_after) {
      QTest::keyClick(&window, Qt::Key_F5);
      QTRY_COMPARE(window.live()->snapshot().stage, Stage::kConfiguration);
      recordAnArea(window, areas_after);
    };
    configureAnArea(1);
    QTest::keyClick(&window, Qt::Key_F6);
    QTRY_VERIFY_WITH_TIMEOUT(window.live()->snapshot().model_ready, 20000);
    QTest::qWait(200);
    const auto learned = window.live()->snapshot().model;
    const int learned_from = static_cast<int>(window.live()->snapshot().area_data->front().X.cols());
    // A second area changes the confidence (the model version) but not the model: recorded once.
    configureAnArea(2);
    QTest::qWait(200);
    QTemporaryDir directory;
    const QString file = directory.filePath(QStringLiteral("learned.flexirob"));
    QVERIFY(window.saveSession(file));
    const flexirob::app::SessionReader reader(file.toStdString());
    const auto models = reader.models();
    QCOMPARE(models.size(), std::size_t{1});
    QCOMPARE(models[0].learner_kind, learned->kind());
    QCOMPARE(models[0].samples, learned_from);
    const std::string text = learned->modelText();
    QVERIFY(models[0].bytes == std::vector<std::uint8_t>(text.begin(), text.end()));
    // A later copy holds the one model, with the samples it was learned from, not those of the
    // areas there are now.
    QTest::qWait(300);
    const QString later = directory.filePath(QStringLiteral("later.flexirob"));
    QVERIFY(window.saveSession(later));
    const auto later_models = flexirob::app::SessionReader(later.toStdString()).models();
    QCOMPARE(later_models.size(), std::size_t{1});
    QCOMPARE(later_models[0].samples, learned_from);
  }

  void theRobotOverFriIsMirroredItsLinkShownAndDisconnected() {
    // The robot controller's stand-in on loopback, talking to the GUI's FRI port as a KRC would.
    const auto model = flexirob::robot::RobotModel::fromUrdfFile(flexirob::resolveRobotPath("lwr4"));
    flexirob::robot::FriSimulatedControllerConfig krc;
    krc.peer = flexirob::robot::UdpEndpoint::parse("127.0.0.1", flexirob::robot::fri::kDefaultPcPort, "pc");
    // The slowest cycle FRI allows (10 ms): the watchdog then forgives a GUI thread's 30 ms, which
    // a loaded test machine without a real-time kernel does not always keep below 3 ms.
    krc.cycle = 0.01;
    krc.q_initial = Eigen::VectorXd(7);
    krc.q_initial << 0.4, 0.5, -0.2, -1.3, 0.1, 0.9, 0.3;
    flexirob::robot::FriSimulatedController controller(model, krc);
    controller.start();

    MainWindow window("lwr4", "empty", quietOptions());
    showIfDrawable(window);
    const std::string address = "fri://" + controller.localEndpoint().toString();
    auto* disconnect = window.findChild<QAction*>(QStringLiteral("disconnect_backend"));
    QVERIFY(disconnect != nullptr);
    QVERIFY(!disconnect->isEnabled());  // on the simulation there is nothing to disconnect
    if (!window.setBackend(address)) QSKIP("the FRI port 49938 is taken on this machine");
    QVERIFY(!window.reconnectAction()->isEnabled());
    QMenu* backend_menu = nullptr;
    for (QAction* entry : window.menuBar()->actions()) {
      if (entry->text() == QStringLiteral("&Backend")) backend_menu = entry->menu();
    }
    QVERIFY(backend_menu != nullptr);
    Q_EMIT backend_menu->aboutToShow();
    QVERIFY(disconnect->isEnabled());  // on the robot it is offered
    // Monitor mode, then command mode once our answers make the quality good enough.
    QTRY_VERIFY2_WITH_TIMEOUT(window.live()->linkStatus().link == "commanding", window.live()->linkStatus().summary().c_str(), 10000);
    QTRY_VERIFY(window.linkLabel()->text().contains(QStringLiteral("commanding")));
    QVERIFY(window.linkLabel()->text().contains(QString::fromStdString(address)));
    // The mirror shows the real arm's posture (the stand-in's, as its measurements report it),
    // which starts away from the simulation's home posture.
    const auto mirrored = [&] {
      const auto& snapshot = window.live()->snapshot();
      const Eigen::VectorXd real = controller.stats().q;
      double largest = 0.0;
      for (int j = 0; j < 7; ++j) largest = std::max(largest, std::abs(snapshot.q[static_cast<std::size_t>(j)] - real[j]));
      return largest;
    };
    QTRY_VERIFY_WITH_TIMEOUT(mirrored() < 0.01, 20000);  // an upper bound: a loaded CI machine draws slowly
    flexirob::robot::Kinematics kinematics(model);
    kinematics.update(controller.stats().q);
    QTRY_VERIFY((window.kinematics()->p_WT() - kinematics.p_WT()).norm() < 0.01);

    // A burst of lost measurements: the watchdog stops commanding, the link turns red and the
    // operator is asked to confirm a reconnect.
    controller.dropNextMeasurements(200);
    QTRY_VERIFY_WITH_TIMEOUT(window.live()->linkStatus().fault, 20000);  // an upper bound: a loaded CI machine draws slowly
    QTRY_VERIFY(window.reconnectAction()->isEnabled());
    QVERIFY(window.linkLabel()->styleSheet().contains(QStringLiteral("#c00000")));

    // Disconnect: back to the simulation, the fault gone with the link.
    QVERIFY(window.setBackend("sim"));
    QCOMPARE(window.live()->linkStatus().link, std::string("simulated"));
    QTRY_VERIFY(!window.reconnectAction()->isEnabled());
    controller.stop();
  }
};

QTEST_MAIN(OperatorTest)
#include "operator_test.moc"
