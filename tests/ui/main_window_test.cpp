// The main window: it builds, its joint sliders pose the robot the view shows, its menus list
// the built-in robots and scenes.
#include <QAction>
#include <QApplication>
#include <QMouseEvent>
#include <QWheelEvent>
#include <QGuiApplication>
#include <QLabel>
#include <QMainWindow>
#include <QMenu>
#include <QPushButton>
#include <QStatusBar>
#include <QSignalSpy>
#include <QTest>

#include "render/shapes.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/scene.hpp"
#include "ui/joint_panel.hpp"
#include "ui/main_window.hpp"
#include "tests/ui/ui_test_support.hpp"
#include "ui/osg_view.hpp"
#include "ui/status_message.hpp"

using flexirob::ui::MainWindow;

namespace {

using flexirob::ui::testing::canDraw;
using flexirob::ui::testing::quietOptions;
using flexirob::ui::testing::showIfDrawable;

QStringList actionNames(const QMenu* menu) {
  QStringList names;
  for (const QAction* action : menu->actions()) names << action->data().toString();
  return names;
}

QStringList toQStringList(const std::vector<std::string>& names) {
  QStringList list;
  for (const auto& name : names) list << QString::fromStdString(name);
  return list;
}




// Largest entry-wise difference between two OSG matrices.
double maxDifference(const osg::Matrixd& a, const osg::Matrixd& b) {
  double worst = 0.0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(a(r, c) - b(r, c)));
  }
  return worst;
}

}  // namespace

class MainWindowTest : public QObject {
  Q_OBJECT

 private Q_SLOTS:
  void buildsWithTheDefaultRobotAndScene() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    showIfDrawable(window);
    QVERIFY(window.robotModel() != nullptr);
    QCOMPARE(window.robotModel()->name(), std::string("lwr4"));
    QCOMPARE(window.jointPanel()->jointCount(), 7);
    QCOMPARE(window.scene().name, std::string("setup_I"));
    QVERIFY(!window.scene().obstacles.empty());
    // One transform per body in the view's tree.
    QCOMPARE(window.world().robot()->bodyCount(), static_cast<int>(window.robotModel()->bodies().size()));
  }

  // A message longer than the room left of the permanent fields ran into them mid-word
  // ("… posture erro" + "sim simulated"); it is cut at a word's end, the whole in the tooltip.
  void aLongStatusMessageIsCutAtAWordEndBeforeThePermanentFields() {
    QMainWindow window;
    auto* field = new QLabel(QStringLiteral("sim simulated, 1.0 ms   robot lwr4 (7 joints)"));
    field->setFixedWidth(320);
    window.statusBar()->addPermanentWidget(field);
    window.resize(760, 300);
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    const QString message = QStringLiteral(
        "area_1 -> area_2: mean error 0.4 mm, max 1.2 mm, posture error 0.03 rad; the straight way between the two "
        "areas keeps 4.1 cm from the box");
    QVERIFY(window.statusBar()->fontMetrics().horizontalAdvance(message) > field->geometry().left());
    flexirob::ui::showStatusMessage(window.statusBar(), message, 0);
    const QString shown = window.statusBar()->currentMessage();
    QVERIFY2(shown.endsWith(QStringLiteral(" …")), qPrintable(shown));
    const QString kept = shown.chopped(2);
    QVERIFY(message.startsWith(kept));
    QCOMPARE(message.at(kept.size()), QLatin1Char(' '));  // no word shown in part
    QVERIFY(kept.size() > message.size() / 3);
    QVERIFY2(window.statusBar()->fontMetrics().horizontalAdvance(shown) < field->geometry().left(), qPrintable(shown));
    QCOMPARE(flexirob::ui::fullStatusMessage(window.statusBar()), message);
    QCOMPARE(window.statusBar()->toolTip(), message);
    // Replaced by a message of Qt's own, the tooltip goes with it.
    window.statusBar()->showMessage(QStringLiteral("a menu's status tip"));
    QVERIFY(window.statusBar()->toolTip().isEmpty());
    // A message that fits is shown whole, without a tooltip.
    flexirob::ui::showStatusMessage(window.statusBar(), QStringLiteral("Session saved"), 0);
    QCOMPARE(window.statusBar()->currentMessage(), QStringLiteral("Session saved"));
    QCOMPARE(flexirob::ui::fullStatusMessage(window.statusBar()), QStringLiteral("Session saved"));
    QVERIFY(window.statusBar()->toolTip().isEmpty());
  }

  void theViewAndTheJointPanelMirrorTheLiveArm() {
    MainWindow window("lwr4", "empty", quietOptions());
    showIfDrawable(window);
    QTRY_VERIFY(window.live() != nullptr && window.live()->snapshot().running);
    QTest::qWait(100);
    window.mirror();
    const auto& snapshot = window.live()->snapshot();
    Eigen::VectorXd q(snapshot.dof);
    for (int j = 0; j < snapshot.dof; ++j) q[j] = snapshot.q[static_cast<std::size_t>(j)];
    window.mirror();  // the arm is held still in IDLE: the newest snapshot shows the same posture
    QVERIFY((window.jointPanel()->posture() - q).cwiseAbs().maxCoeff() < 2e-3);  // slider steps of 1e-3
    // The view's flange body is where an independent forward kinematics of the live posture
    // puts it; the sliders only show the posture (the arm is the backend's).
    flexirob::robot::Kinematics kinematics(*window.robotModel());
    kinematics.update(window.kinematics()->q());
    const int last_body = window.world().robot()->bodyCount() - 1;
    QVERIFY(maxDifference(window.world().robot()->body(last_body)->getMatrix(),
                          flexirob::render::toOsgMatrix(kinematics.X_WB(last_body))) < 1e-9);
    QVERIFY((window.kinematics()->q() - q).cwiseAbs().maxCoeff() < 1e-3);
    QVERIFY(!window.jointPanel()->slider(0)->isEnabled());
  }

  void menusListTheBuiltInRobotsAndScenes() {
    MainWindow window("lwr4", "empty", quietOptions());
    QCOMPARE(actionNames(window.robotMenu()), toQStringList(flexirob::builtinRobotNames()));
    QCOMPARE(actionNames(window.sceneMenu()), toQStringList(flexirob::robot::builtinSceneNames()));
    // Choosing the 9-DoF arm from the menu rebuilds the joint panel.
    for (QAction* action : window.robotMenu()->actions()) {
      if (action->data().toString() == QStringLiteral("arm9")) action->trigger();
    }
    QCOMPARE(window.jointPanel()->jointCount(), 9);
    // The new rows mirror the arm as the old ones did.
    QVERIFY(!window.jointPanel()->slider(8)->isEnabled());
    QVERIFY(window.robotMenu()->actions().at(1)->isChecked());
    for (QAction* action : window.sceneMenu()->actions()) {
      if (action->data().toString() == QStringLiteral("setup_II")) action->trigger();
    }
    QCOMPARE(window.scene().name, std::string("setup_II"));
  }

  void badChoicesKeepTheCurrentRobotAndScene() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    QVERIFY(!window.loadRobot("/nonexistent/robot.urdf"));
    QVERIFY(!window.loadScene("no_such_scene"));
    QCOMPARE(window.robotModel()->name(), std::string("lwr4"));
    QCOMPARE(window.scene().name, std::string("setup_I"));
    QCOMPARE(window.jointPanel()->jointCount(), 7);
  }

  void viewDrawsTheRobotWhereItStands() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    const QImage shown = window.view()->grabFramebuffer();
    if (window.view()->framesDrawn() == 0 || shown.isNull()) QSKIP("no OpenGL context on this platform");
    // Hide the robot: the pixels that change are the arm's, and they surround the projection of
    // the elbow (body 4) that the view's camera sees.
    window.world().robot()->root()->setNodeMask(0);
    const QImage hidden = window.view()->grabFramebuffer();
    window.world().robot()->root()->setNodeMask(~0U);
    QCOMPARE(shown.size(), hidden.size());
    int changed = 0;
    for (int y = 0; y < shown.height(); ++y) {
      for (int x = 0; x < shown.width(); ++x) changed += shown.pixel(x, y) != hidden.pixel(x, y) ? 1 : 0;
    }
    QVERIFY2(changed > 1000, qPrintable(QStringLiteral("only %1 pixels show the robot").arg(changed)));
    const auto camera = window.view()->currentCamera();
    const auto elbow = flexirob::render::projectToPixel(camera, shown.width(), shown.height(),
                                                        window.kinematics()->X_WB(4).translation());
    QVERIFY(elbow.has_value());
    const QPoint p(static_cast<int>(elbow->x()), static_cast<int>(elbow->y()));
    QVERIFY(shown.rect().contains(p));
    QVERIFY2(shown.pixel(p) != hidden.pixel(p), "the elbow is not drawn where the camera projects it");
  }

  void windowScreenshotShowsTheViewsLastFrameWithoutDrawingAgain() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    const QImage frame = window.view()->grabFramebuffer().convertToFormat(QImage::Format_RGB32);
    if (frame.isNull()) QSKIP("no OpenGL context on this platform");
    const long frames = window.view()->framesDrawn();
    // A repaint that asks for no new frame (a label over the view, a screenshot) shows the last one.
    const QRect view_rect(window.view()->mapTo(&window, QPoint(0, 0)), window.view()->size());
    const QImage shot = window.grab(view_rect).toImage().convertToFormat(QImage::Format_RGB32);
    QCOMPARE(window.view()->framesDrawn(), frames);
    QCOMPARE(shot.size(), frame.size());
    int equal = 0;
    for (int y = 0; y < frame.height(); ++y) {
      for (int x = 0; x < frame.width(); ++x) equal += shot.pixel(x, y) == frame.pixel(x, y) ? 1 : 0;
    }
    // Everything but the labels laid over the view (stage banner, legend) is the frame itself.
    const double fraction = static_cast<double>(equal) / (frame.width() * frame.height());
    QVERIFY2(fraction > 0.8, qPrintable(QStringLiteral("only %1 of the screenshot is the view's frame").arg(fraction)));
    // Asking for a frame draws one.
    window.view()->requestFrame();
    window.grab(view_rect);
    QCOMPARE(window.view()->framesDrawn(), frames + 1);
  }

  void mouseOrbitsPansAndZooms() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    flexirob::ui::OsgView* view = window.view();
    view->grabFramebuffer();
    const auto home = view->currentCamera();
    const auto send = [view](QEvent::Type type, QPointF at, Qt::MouseButton button, Qt::MouseButtons held,
                             Qt::KeyboardModifiers modifiers = Qt::NoModifier) {
      QMouseEvent event(type, at, view->mapToGlobal(at), button, held, modifiers);
      QApplication::sendEvent(view, &event);
    };
    const auto drag = [&](Qt::MouseButton button, Qt::KeyboardModifiers modifiers) {
      // From the sky in the upper left corner: a press on the arm would grab it instead.
      const QPointF start(view->width() * 0.08, view->height() * 0.08);
      send(QEvent::MouseButtonPress, start, button, button, modifiers);
      for (int i = 1; i <= 5; ++i) {
        send(QEvent::MouseMove, start + QPointF(12.0 * i, 4.0 * i), Qt::NoButton, button, modifiers);
      }
      send(QEvent::MouseButtonRelease, start + QPointF(60.0, 20.0), button, Qt::NoButton, modifiers);
      view->grabFramebuffer();  // the viewer handles its events when it draws
    };
    // Left drag orbits: the eye moves, the centre stays, the distance stays.
    drag(Qt::LeftButton, Qt::NoModifier);
    const auto orbited = view->currentCamera();
    QVERIFY((orbited.eye_W - home.eye_W).norm() > 0.05);
    QVERIFY((orbited.center_W - home.center_W).norm() < 1e-6);
    QVERIFY(std::abs((orbited.eye_W - orbited.center_W).norm() - (home.eye_W - home.center_W).norm()) < 1e-6);
    // Shift + left drag pans: eye and centre move together.
    drag(Qt::LeftButton, Qt::ShiftModifier);
    const auto panned = view->currentCamera();
    QVERIFY((panned.center_W - orbited.center_W).norm() > 1e-3);
    QVERIFY(((panned.eye_W - panned.center_W) - (orbited.eye_W - orbited.center_W)).norm() < 1e-6);
    // The wheel zooms: closer to the centre.
    QWheelEvent wheel(QPointF(50, 50), view->mapToGlobal(QPointF(50, 50)), QPoint(), QPoint(0, 120), Qt::NoButton,
                      Qt::NoModifier, Qt::NoScrollPhase, false);
    QApplication::sendEvent(view, &wheel);
    view->grabFramebuffer();
    const auto zoomed = view->currentCamera();
    QVERIFY((zoomed.eye_W - zoomed.center_W).norm() < (panned.eye_W - panned.center_W).norm() - 1e-3);
    // A double click goes home.
    view->resetCamera();
    QVERIFY((view->currentCamera().eye_W - home.eye_W).norm() < 1e-9);
  }

  void theEyeStaysAboveTheTableWhileOrbiting() {
    if (!canDraw()) QSKIP("no OpenGL on Qt's offscreen platform");
    MainWindow window("lwr4", "setup_I", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    flexirob::ui::OsgView* view = window.view();
    view->grabFramebuffer();
    const auto send = [view](QEvent::Type type, QPointF at, Qt::MouseButton button, Qt::MouseButtons held) {
      QMouseEvent event(type, at, view->mapToGlobal(at), button, held, Qt::NoModifier);
      QApplication::sendEvent(view, &event);
    };
    // Vertical drags in the sky's corner: the eye swings over the top and down the far side,
    // or down towards and through the table.
    const auto drag = [&](double dy) {
      const QPointF start(view->width() * 0.08, view->height() * (dy < 0 ? 0.9 : 0.08));
      send(QEvent::MouseButtonPress, start, Qt::LeftButton, Qt::LeftButton);
      for (int i = 1; i <= 5; ++i) send(QEvent::MouseMove, start + QPointF(0.0, dy * i / 5.0), Qt::NoButton, Qt::LeftButton);
      send(QEvent::MouseButtonRelease, start + QPointF(0.0, dy), Qt::LeftButton, Qt::NoButton);
      view->grabFramebuffer();
      return view->currentCamera().eye_W.z();
    };
    const double step = 0.6 * view->height();
    double lowest = view->currentCamera().eye_W.z();
    for (const double dy : {step, step, step, step, -step, -step, -step, -step, -step, -step, -step, -step}) lowest = std::min(lowest, drag(dy));
    QVERIFY2(lowest > 0.0, qPrintable(QStringLiteral("the eye went to z = %1 m").arg(lowest)));
    // Without a floor (a robot that hangs) the same drags go below: the check above can fail.
    view->setFloor(std::nullopt);
    view->resetCamera();
    double unbounded = view->currentCamera().eye_W.z();
    for (const double dy : {step, step, step, step, -step, -step, -step, -step, -step, -step, -step, -step}) unbounded = std::min(unbounded, drag(dy));
    QVERIFY2(unbounded < 0.0, qPrintable(QStringLiteral("the lowest eye without a floor: z = %1 m").arg(unbounded)));
  }
};

QTEST_MAIN(MainWindowTest)
#include "main_window_test.moc"
