// The review window replays a session recording: stepping frames moves the arm to the recorded
// posture, the timeline shows the stage bands, playback runs forwards and backwards, and a file
// that is no recording is refused with its reason.
#include <QApplication>
#include <QImage>
#include <QKeyEvent>
#include <QLineSeries>
#include <QTemporaryDir>
#include <QtTest>

#include <cmath>
#include <fstream>
#include <sstream>

#include "app/session_reader.hpp"
#include "app/session_schema.hpp"

#include <QStatusBar>
#include <sqlite3.h>
#include "ui/stage_panel.hpp"
#include "app/session_recorder.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "ui/plot_panel.hpp"
#include "ui/confidence_panel.hpp"
#include "ui/review_window.hpp"

using namespace flexirob;

namespace {

constexpr double kDuration = 6.0;  // [s] of recorded states at 1 kHz
constexpr double kJointAmplitude = 0.6;

// Joint 1 swings sinusoidally (period 2 s) about the middle posture; everything else rests.
Eigen::VectorXd postureAt(const robot::RobotModel& model, double t) {
  Eigen::VectorXd q = model.midPosture();
  q[0] += kJointAmplitude * std::sin(M_PI * t);
  return q;
}

// A recording as the workflow writes one: stages with sub-stages, triggers and buttons, a
// training area with samples, a teach-in trajectory and the robot's states at 1 kHz.
// `robot_name` names the robot in the metadata (the states are the LWR IV's in any case);
// a non-empty `model_text` is stored as a learned model.
void writeRecording(const std::filesystem::path& file, const std::string& robot_name = "lwr4", const std::string& model_text = "",
                    const std::string& scene_text = "") {
  const auto path = resolveRobotPath("lwr4");
  const robot::RobotModel model = robot::RobotModel::fromUrdfFile(path);
  app::SessionMetadata meta;
  meta.robot_name = robot_name;
  std::ostringstream urdf;
  urdf << std::ifstream(path).rdbuf();
  meta.robot_urdf = urdf.str();
  meta.tip_link = model.tipLink();
  meta.software_version = "test";
  meta.scene_text = scene_text;
  app::SessionRecorder recorder(file, meta);
  recorder.recordStage({0.0, "IDLE", ""});
  recorder.recordStage({1.0, "CONFIGURATION", "APPROACHING"});
  recorder.recordStage({2.5, "CONFIGURATION", "RECORDING"});
  recorder.recordStage({4.0, "PROGRAMMING", "TEACH-IN"});
  recorder.recordButton(0.9, "start_configuration");
  recorder.recordTrigger(2.5, "on_converged");
  app::AreaRecord area;
  area.area = 0;
  area.time = 2.5;
  area.x_init = Eigen::Vector3d(-0.5, 0.0, 0.5);
  area.q_fixed = model.midPosture();
  recorder.recordArea(area);
  for (int k = 0; k < 20; ++k) {
    recorder.recordSample({2.5 + 0.05 * k, 0, Eigen::Vector3d(-0.5, 0.01 * k, 0.5), model.midPosture()});
  }
  if (!model_text.empty()) {
    app::ModelRecord learned;
    learned.time = 3.9;
    learned.learner_kind = "elm";
    learned.bytes.assign(model_text.begin(), model_text.end());
    recorder.recordModel(std::move(learned));
  }
  robot::Kinematics kinematics(model);
  for (int i = 0; i <= static_cast<int>(kDuration * 1000); ++i) {
    const double t = i * 1e-3;
    const Eigen::VectorXd q = postureAt(model, t);
    kinematics.update(q);
    app::StateRecord state;
    state.time = t;
    state.dof = static_cast<std::int32_t>(model.dof());
    for (int j = 0; j < model.dof(); ++j) {
      state.q[static_cast<std::size_t>(j)] = q[j];
      state.q_cmd[static_cast<std::size_t>(j)] = q[j];
    }
    const Eigen::Vector3d p = kinematics.p_WT();
    state.p_WT = {p.x(), p.y(), p.z()};
    while (!recorder.recordState(state)) QThread::msleep(1);
  }
  recorder.close();
}

}  // namespace

class ReviewWindowTest : public QObject {
  Q_OBJECT

 private Q_SLOTS:
  void initTestCase() {
    QVERIFY(dir_.isValid());
    file_ = std::filesystem::path(dir_.path().toStdString()) / "session.db";
    writeRecording(file_);
  }

  void opensARecordingWithItsStagesAndPlots() {
    ui::ReviewWindow window;
    QVERIFY2(window.open(file_), qPrintable(window.errorString()));
    QCOMPARE(window.reader()->stateCount(), static_cast<std::int64_t>(kDuration * 1000) + 1);
    QCOMPARE(window.timeline()->t0(), 0.0);
    QCOMPARE(window.timeline()->t1(), kDuration);
    QCOMPARE(window.stageAt(3.0), std::string("CONFIGURATION / RECORDING"));
    QCOMPARE(window.stageAt(5.0), std::string("PROGRAMMING / TEACH-IN"));
    QVERIFY(window.plots()->sampleCount() > 1000);
    // A recording holds no desired tip position: its error plot is another error than the live
    // one, and its title says so.
    const ui::PlotPanel live_plots;
    QVERIFY(window.plots()->taskErrorPlot()->title() != live_plots.taskErrorPlot()->title());
    // Joint 1 plotted within its limits: at t = 0.5 s the swing is at its top.
    const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
    const auto& limits = model.joints()[0].limits;
    const double expected = (model.midPosture()[0] + kJointAmplitude - limits.lower) / (limits.upper - limits.lower);
    const QLineSeries* joint1 = window.plots()->jointPlot()->series(2);
    double at_half = std::nan("");
    for (const QPointF& p : joint1->points()) {
      if (std::abs(p.x() - 0.5) < 0.004) at_half = p.y();
    }
    QVERIFY(std::abs(at_half - expected) < 1e-3);
  }

  // The review window has no menu: Ctrl+W closes it, as the platform's close key.
  void theCloseKeyClosesTheWindow() {
    ui::ReviewWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QVERIFY2(window.open(file_), qPrintable(window.errorString()));
    QTest::keyClick(&window, Qt::Key_W, Qt::ControlModifier);
    QTRY_VERIFY(!window.isVisible());
  }

  // Scrubbing changes the Confidence panel's status between a short and a long text: the 3D
  // view beside it must not move sideways with it.
  void theConfidenceStatusDoesNotResizeTheViewBesideIt() {
    ui::ReviewWindow window;
    window.resize(1280, 760);
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QVERIFY2(window.open(file_), qPrintable(window.errorString()));
    window.confidencePanel()->setStatus(QStringLiteral("No training area complete at this moment."));
    QTest::qWait(100);
    QWidget* view = window.centralWidget();
    const QRect before = view->geometry();
    window.confidencePanel()->setStatus(QStringLiteral("4 areas complete at this moment; the slices show the confidence of all of them"));
    QTest::qWait(100);
    QCOMPARE(view->geometry(), before);
    window.confidencePanel()->setStatus(QStringLiteral("1"));
    QTest::qWait(100);
    QCOMPARE(view->geometry(), before);
  }

  void steppingFramesMovesTheArmToTheRecordedPosture() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
    window.setTime(1.0);
    const Eigen::VectorXd before = window.shownPosture();
    QVERIFY((before - postureAt(model, 1.0)).norm() < 1e-9);
    const osg::Matrixd link2_before = window.world().robot()->body(2)->getMatrix();
    window.stepFrames(6);  // 0.2 s later
    const double t = 1.0 + 6 * ui::ReviewWindow::kFrameSeconds;
    QVERIFY(std::abs(window.time() - t) < 1e-9);
    // The state at or before t: recorded every millisecond.
    const Eigen::VectorXd expected = postureAt(model, std::floor(t * 1000 + 1e-6) * 1e-3);
    QVERIFY((window.shownPosture() - expected).norm() < 1e-9);
    QVERIFY(std::abs(window.shownPosture()[0] - before[0]) > 0.1);
    QVERIFY(!(window.world().robot()->body(2)->getMatrix() == link2_before));
    window.stepFrames(-6);
    QVERIFY((window.shownPosture() - before).norm() < 1e-9);
    // The plots' cursor follows.
    QVERIFY(std::abs(window.plots()->cursorTime() - 1.0) < 1e-9);
  }

  // The controls, the stage's name and the plots leave the window narrow enough for an 800 px
  // screen (the stage's name cut to fit, whole in its tooltip).
  void theWindowFitsAnEightHundredPixelScreen() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    window.setTime(3.2);
    QVERIFY2(window.minimumSizeHint().width() <= 800, qPrintable(QString::number(window.minimumSizeHint().width())));
    window.resize(800, 600);
    QTRY_COMPARE(window.width(), 800);
  }

  // A phase too short for its label, and a tick or a triangle, are read by pointing at them.
  void timelineTooltipNamesThePhaseAndTheSignalsUnderThePointer() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    const ui::Timeline* timeline = window.timeline();
    QCOMPARE(timeline->describeAt(timeline->xOf(3.2)), QStringLiteral("CONFIGURATION / RECORDING: 2.500 s to 4.000 s (1.500 s)"));
    QCOMPARE(timeline->describeAt(timeline->xOf(2.5) + 3.0),
             QStringLiteral("CONFIGURATION / RECORDING: 2.500 s to 4.000 s (1.500 s)\ntrigger on_converged at 2.500 s"));
    QCOMPARE(timeline->describeAt(timeline->xOf(0.9)), QStringLiteral("IDLE: 0.000 s to 1.000 s (1.000 s)\nbutton Start configuration at 0.900 s"));
    // The pointer moved there (no button held): the tooltip Qt shows is that text.
    QTest::mouseMove(window.timeline(), QPoint(static_cast<int>(std::lround(timeline->xOf(4.5))), timeline->height() / 2));
    QTRY_COMPARE(timeline->toolTip(), QStringLiteral("PROGRAMMING / TEACH-IN: 4.000 s to 6.000 s (2.000 s)"));
  }

  void timelineScreenshotShowsTheStageBandsAndTheCursor() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    window.setTime(5.5);
    QApplication::processEvents();
    const QImage strip = window.timeline()->grab().toImage();
    // Just inside the bands' top edge (14 px from the top), above their centred labels.
    const int y = static_cast<int>(17 * strip.devicePixelRatio());
    for (const auto& [time, label] : std::vector<std::pair<double, std::string>>{
             {0.5, "IDLE"}, {1.7, "CONFIGURATION / APPROACHING"}, {3.2, "CONFIGURATION / RECORDING"}, {4.6, "PROGRAMMING / TEACH-IN"}}) {
      const int x = static_cast<int>(window.timeline()->xOf(time) * strip.devicePixelRatio());
      QCOMPARE(strip.pixelColor(x, y).rgb(), ui::stageColor(label).rgb());
    }
    const int cursor_x = static_cast<int>(std::round(window.timeline()->xOf(5.5) * strip.devicePixelRatio()));
    const QColor cursor = strip.pixelColor(cursor_x, y);
    QVERIFY(cursor.red() > 150 && cursor.green() < 80 && cursor.blue() < 80);  // not the magenta band under it
    // A stage has the live window's colour, so that a reviewer reads both windows alike.
    using flexirob::app::Stage;
    using flexirob::app::SubStage;
    QCOMPARE(ui::stageColor("EXECUTION").rgb(), ui::StagePanel::stageColor(Stage::kExecution, SubStage::kNone).rgb());
    QCOMPARE(ui::stageColor("CONFIGURATION / WAITING").rgb(),
             ui::StagePanel::stageColor(Stage::kConfiguration, SubStage::kWaiting).rgb());
    QCOMPARE(ui::stageColor("PROGRAMMING / WAITING").rgb(),
             ui::StagePanel::stageColor(Stage::kProgramming, SubStage::kWaiting).rgb());
    QVERIFY(ui::stageColor("LATER-STAGE") != ui::stageColor("IDLE"));
    if (!qEnvironmentVariableIsEmpty("FLEXIROB_REVIEW_SCREENSHOT")) {
      window.grab().save(qEnvironmentVariable("FLEXIROB_REVIEW_SCREENSHOT"));
    }
  }

  void playsForwardsAndBackwards() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.setTime(3.0);
    window.setSpeed(2.0);
    window.play();
    QTest::qWait(300);
    window.pause();
    QVERIFY(window.time() > 3.2);
    const double reached = window.time();
    window.setSpeed(-4.0);
    window.play();
    QTest::qWait(300);
    window.pause();
    QVERIFY(window.time() < reached - 0.4);
  }

  void keysPlayStepAndJumpToTheEnds() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    window.setTime(2.0);
    QTest::keyClick(&window, Qt::Key_Right);
    QVERIFY(std::abs(window.time() - (2.0 + ui::ReviewWindow::kFrameSeconds)) < 1e-9);
    QTest::keyClick(&window, Qt::Key_Left, Qt::ShiftModifier);  // a second back
    QVERIFY(std::abs(window.time() - (1.0 + ui::ReviewWindow::kFrameSeconds)) < 1e-9);
    QTest::keyClick(&window, Qt::Key_End);
    QCOMPARE(window.time(), kDuration);
    QTest::keyClick(&window, Qt::Key_Home);
    QCOMPARE(window.time(), 0.0);
    QTest::keyClick(&window, Qt::Key_Space);
    QVERIFY(window.playing());
    QTest::keyClick(&window, Qt::Key_Space);
    QVERIFY(!window.playing());
  }

  void aHeldKeyRepeatsOnlyWhereRepeatingMeansSomethingAndOtherKeysPassOn() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    window.setTime(2.0);
    const auto sendRepeated = [&window](Qt::Key key) {
      QKeyEvent press(QEvent::KeyPress, key, Qt::NoModifier, QString(), /*autorep=*/true);
      QApplication::sendEvent(&window, &press);
      return press.isAccepted();
    };
    QVERIFY(sendRepeated(Qt::Key_Space));  // held Space: taken, but playback does not flicker on
    QVERIFY(!window.playing());
    QVERIFY(sendRepeated(Qt::Key_End));
    QCOMPARE(window.time(), 2.0);
    QVERIFY(sendRepeated(Qt::Key_Right));  // a held arrow steps on
    QVERIFY(std::abs(window.time() - (2.0 + ui::ReviewWindow::kFrameSeconds)) < 1e-9);
    QVERIFY(!sendRepeated(Qt::Key_A));  // not the window's: left to whoever handles it
    QVERIFY(!sendRepeated(Qt::Key_F5));
  }

  void refusesAFileThatIsNoRecordingAndKeepsTheOpenOne() {
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    const auto junk = std::filesystem::path(dir_.path().toStdString()) / "junk.db";
    std::ofstream(junk) << "not a database";
    QVERIFY(!window.open(junk));
    QVERIFY(window.errorString().contains(QStringLiteral("junk.db")));
    QVERIFY(window.isOpen());
    QCOMPARE(window.reader()->file(), file_);
  }

  // A page overwritten (a disk fault) where the window does not read when it opens the file, in
  // the middle of a stored model: what reads is shown, and the window says the file is damaged
  // rather than playing it as if it were whole.
  void saysAFileWithADamagedPageIsDamagedAndShowsWhatReads() {
    ui::ReviewWindow whole;
    QVERIFY(whole.open(file_));
    QTRY_VERIFY(!whole.checkingForDamage());
    QVERIFY2(whole.damage().isEmpty(), qPrintable(whole.damage()));
    QVERIFY(!whole.windowTitle().contains(QStringLiteral("damaged")));

    const auto damaged = std::filesystem::path(dir_.path().toStdString()) / "damaged.db";
    const std::string marker = "<<the middle of the stored model>>";
    writeRecording(damaged, "lwr4", std::string(20000, 'a') + marker + std::string(20000, 'b'));
    std::ostringstream read;
    read << std::ifstream(damaged, std::ios::binary).rdbuf();
    const std::string bytes = read.str();
    const std::size_t at = bytes.find(marker);
    QVERIFY(at != std::string::npos);
    constexpr std::size_t kPage = 4096;
    {
      std::fstream out(damaged, std::ios::in | std::ios::out | std::ios::binary);
      out.seekp(static_cast<std::streamoff>(at / kPage * kPage));
      const std::string garbage(kPage, '\xA5');
      out.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
    }
    ui::ReviewWindow window;
    QVERIFY2(window.open(damaged), qPrintable(window.errorString()));
    QTRY_VERIFY(!window.checkingForDamage());
    QVERIFY2(window.damage().startsWith(QStringLiteral("On tree page")), qPrintable(window.damage()));
    QVERIFY(window.windowTitle().contains(QStringLiteral("(damaged)")));
    QCOMPARE(window.reader()->stateCount(), static_cast<std::int64_t>(kDuration * 1000) + 1);
  }

  // A posture held inside an obstacle for the whole recording (no contact event recorded): its
  // links are red whenever it is shown, as they were live.
  void linksInsideAnObstacleAreRedWhereverThePostureIsShown() {
    const auto boxed = std::filesystem::path(dir_.path().toStdString()) / "boxed.db";
    writeRecording(boxed, "lwr4", "", "name: boxed\nobstacles:\n  - {name: block, shape: box, size: [0.3, 0.3, 0.3], position: [0, 0, 0.6]}\n");
    ui::ReviewWindow window;
    QVERIFY2(window.open(boxed), qPrintable(window.errorString()));
    window.setTime(3.0);
    QVERIFY(!window.linksShownInContact().empty());
    ui::ReviewWindow clear;
    QVERIFY(clear.open(file_));
    clear.setTime(3.0);
    QVERIFY(clear.linksShownInContact().empty());
  }

  // A file that fails while its rows are read (a sample's posture of 2 bytes) leaves the open
  // recording whole: its robot, its timeline, and a scrub that still moves its arm.
  void aFileFailingMidwayLeavesTheOpenRecordingWhole() {
    const auto broken = std::filesystem::path(dir_.path().toStdString()) / "broken_row.db";
    writeRecording(broken);
    {
      app::SqliteDatabase database(broken.string(), SQLITE_OPEN_READWRITE);
      database.exec("UPDATE sample SET q = x'0102' WHERE id = (SELECT MIN(id) FROM sample)");
    }
    ui::ReviewWindow window;
    QVERIFY(window.open(file_));
    const QString title = window.windowTitle();
    QVERIFY(!window.open(broken));
    QVERIFY(window.errorString().contains(QStringLiteral("broken_row.db")));
    QCOMPARE(window.reader()->file(), file_);
    QCOMPARE(window.windowTitle(), title);
    QCOMPARE(window.timeline()->t1(), kDuration);
    window.setTime(0.5);
    QCOMPARE(window.shownPosture().size(), 7);
    QVERIFY(std::abs(window.shownPosture()[0] - postureAt(*window.robotModel(), 0.5)[0]) < 1e-3);
  }

  // A recording whose states were deleted spans its events: its phases on the timeline, a scrub
  // through them, and the status bar saying why the arm does not move.
  void aRecordingWithoutStatesSpansItsEvents() {
    const auto cut = std::filesystem::path(dir_.path().toStdString()) / "no_states.db";
    writeRecording(cut);
    {
      app::SqliteDatabase database(cut.string(), SQLITE_OPEN_READWRITE);
      database.exec("DELETE FROM state");
    }
    ui::ReviewWindow window;
    QVERIFY2(window.open(cut), qPrintable(window.errorString()));
    const ui::Timeline* timeline = window.timeline();
    QVERIFY2(timeline->t1() >= 4.0, qPrintable(QString::number(timeline->t1())));
    QCOMPARE(timeline->describeAt(timeline->xOf(3.2)), QStringLiteral("CONFIGURATION / RECORDING: 2.500 s to 4.000 s (1.500 s)"));
    window.setTime(3.0);
    QCOMPARE(window.time(), 3.0);
    QVERIFY2(window.statusBar()->currentMessage().contains(QStringLiteral("no robot states")),
             qPrintable(window.statusBar()->currentMessage()));
  }

  // The states of a 7-joint arm under the name of the 9-joint one: refused, not replayed as a
  // robot that never moves.
  void refusesARecordingWhoseStatesAreOfAnotherArm() {
    const auto other = std::filesystem::path(dir_.path().toStdString()) / "named_arm9.db";
    writeRecording(other, "arm9");
    ui::ReviewWindow window;
    QVERIFY(!window.open(other));
    QVERIFY2(window.errorString().contains(QStringLiteral("its states hold 7 joint values, its robot")),
             qPrintable(window.errorString()));
    QVERIFY(window.errorString().contains(QStringLiteral("has 9 joints")));
  }

 private:
  QTemporaryDir dir_;
  std::filesystem::path file_;
};

QTEST_MAIN(ReviewWindowTest)
#include "review_window_test.moc"
