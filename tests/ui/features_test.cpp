// The main window's plots, confidence slices, goals and recordings: the plot dock follows the
// live arm and the control cycle; a taught area shows as confidence slices at the chosen heights
// with their legend; in EXECUTION a goal (set, or Ctrl+clicked on the ITM graph) is planned and
// executed; the run's recording opens in a review window with the ITM graph and the slices of
// the moment; keyboard triggers are counted.
#include <QAction>
#include <QApplication>
#include <QDockWidget>
#include <QFile>
#include <QGuiApplication>
#include <QChart>
#include <QFontMetricsF>
#include <QLabel>
#include <QLegend>
#include <QLegendMarker>
#include <QLineSeries>
#include <QMenu>
#include <QMenuBar>
#include <QMouseEvent>
#include <QPushButton>
#include <QSpinBox>
#include <QStandardPaths>
#include <QStatusBar>
#include <QStyle>
#include <QTemporaryDir>
#include <QAbstractAxis>
#include <limits>
#include <QScrollArea>
#include <QScrollBar>
#include <QSet>
#include <QTest>

#include <cmath>
#include <utility>

#include "app/session_reader.hpp"
#include "learning/confidence.hpp"
#include "render/camera.hpp"
#include "render/overlays.hpp"
#include "ui/confidence_panel.hpp"
#include "ui/goal_picking.hpp"
#include "ui/live_teaching.hpp"
#include "ui/main_window.hpp"
#include "ui/status_message.hpp"
#include "tests/ui/ui_test_support.hpp"
#include "ui/osg_view.hpp"
#include "ui/plot_panel.hpp"
#include "ui/review_window.hpp"
#include "ui/stage_panel.hpp"

using flexirob::app::Stage;
using flexirob::app::SubStage;
using flexirob::ui::MainWindow;

namespace {

using flexirob::ui::testing::canDraw;
using flexirob::ui::testing::quietOptions;



Eigen::Vector3d tip(const flexirob::ui::LiveSnapshot& s) { return {s.p_WT[0], s.p_WT[1], s.p_WT[2]}; }

// With FLEXIROB_SCREENSHOT_DIR set, the scenario leaves screenshots of its moments there (the
// user guide's pictures are taken this way, under Xvfb).
void screenshot(QWidget& widget, const char* name) {
  const QString directory = qEnvironmentVariable("FLEXIROB_SCREENSHOT_DIR");
  if (directory.isEmpty() || !canDraw()) return;
  QTest::qWait(300);
  QVERIFY2(widget.grab().save(directory + QLatin1Char('/') + QLatin1String(name)), name);
}

int changedPixels(const QImage& a, const QImage& b) {
  int changed = 0;
  for (int y = 0; y < a.height(); ++y) {
    for (int x = 0; x < a.width(); ++x) changed += a.pixel(x, y) != b.pixel(x, y) ? 1 : 0;
  }
  return changed;
}

// A Teaching panel as the window holds it: in a scroll area, at its narrowest, shown.
struct PanelAsTheWindowHoldsIt {
  QScrollArea scroll;
  flexirob::ui::StagePanel* panel = new flexirob::ui::StagePanel;  // owned by the scroll area
  bool exposed = false;
  PanelAsTheWindowHoldsIt() {
    scroll.setWidget(panel);
    scroll.setWidgetResizable(true);
    scroll.resize(panel->minimumSizeHint().width() + 30, 900);
    scroll.show();
    exposed = QTest::qWaitForWindowExposed(&scroll);
  }
};

}  // namespace

class FeaturesTest : public QObject {
  Q_OBJECT

 private Q_SLOTS:
  void initTestCase() { QStandardPaths::setTestModeEnabled(true); }

  void aGoalIsTheNodeNearestTheClickElseThePlanePoint() {
    flexirob::render::CameraPose camera;
    camera.eye_W = Eigen::Vector3d(0.0, -3.0, 0.5);
    camera.center_W = Eigen::Vector3d(0.0, 0.0, 0.5);
    const int width = 400;
    const int height = 300;
    // The centre of the picture is the point looked at; a node there is picked from 5 px away.
    const std::vector<Eigen::Vector3d> nodes = {Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::Vector3d(0.5, 0.0, 0.5)};
    const auto centre = flexirob::render::projectToPixel(camera, width, height, nodes[0]);
    QVERIFY(centre.has_value());
    QVERIFY(std::abs(centre->x() - 200.0) < 1e-6 && std::abs(centre->y() - 150.0) < 1e-6);
    const Eigen::Vector3d down(0.0, 0.0, -1.0);
    auto pick = flexirob::ui::pickGoal(camera, width, height, *centre + Eigen::Vector2d(3.0, 4.0), nodes,
                                       Eigen::Vector3d(0.3, 0.2, 1.0), down, 0.25);
    QVERIFY(pick.has_value());
    QCOMPARE(pick->node, 0);
    QVERIFY(pick->goal_W.isApprox(nodes[0]));
    // 40 px from every node: the ray (0.3, 0.2, 1) + s (0, 0, -1) meets z = 0.25 at s = 0.75.
    pick = flexirob::ui::pickGoal(camera, width, height, *centre + Eigen::Vector2d(0.0, 40.0), nodes,
                                  Eigen::Vector3d(0.3, 0.2, 1.0), down, 0.25);
    QVERIFY(pick.has_value());
    QCOMPARE(pick->node, -1);
    QVERIFY((pick->goal_W - Eigen::Vector3d(0.3, 0.2, 0.25)).norm() < 1e-12);
    // A horizontal ray never meets the plane; one pointing up never meets a plane below it.
    QVERIFY(!flexirob::ui::pickGoal(camera, width, height, {0.0, 0.0}, {}, Eigen::Vector3d(0, 0, 1),
                                    Eigen::Vector3d(1, 0, 0), 0.25)
                 .has_value());
    QVERIFY(!flexirob::ui::pickGoal(camera, width, height, {0.0, 0.0}, {}, Eigen::Vector3d(0, 0, 1),
                                    Eigen::Vector3d(0, 0, 1), 0.25)
                 .has_value());
  }

  void confidenceSlicesSampleTheFieldAtTheirHeights() {
    // One area: samples on a 10 cm square at z = 0.5 (their mean), one more area far away.
    Eigen::MatrixXd area(3, 4);
    area << -0.55, -0.45, -0.55, -0.45,  //
        -0.05, -0.05, 0.05, 0.05,        //
        0.5, 0.5, 0.5, 0.5;
    flexirob::learning::ConfidenceModel model;
    model.addArea(area);
    model.addArea(area.colwise() + Eigen::Vector3d(0.0, 0.6, 0.2));
    flexirob::ui::ConfidenceSliceSettings settings;
    settings.count = 3;
    settings.spacing = 0.1;
    settings = flexirob::ui::centredSlices(model, settings);
    // The middle slice passes through the mean height of the centres, (0.5 + 0.7) / 2.
    QCOMPARE(settings.heights().size(), std::size_t(3));
    QVERIFY(std::abs(settings.heights()[1] - 0.6) < 1e-9);
    QVERIFY(std::abs(settings.heights()[2] - settings.heights()[0] - 0.2) < 1e-9);
    settings.lowest_z = 0.5;
    settings.count = 1;
    settings.resolution = 41;
    const auto slices = flexirob::ui::confidenceSlices(model, settings);
    QCOMPARE(slices.size(), std::size_t(1));
    const auto& grid = slices.front();
    QCOMPARE(grid.z, 0.5);
    // The extent holds both areas' centres.
    QVERIFY(grid.lower_xy.x() < -0.5 && grid.upper_xy.x() > -0.5);
    QVERIFY(grid.lower_xy.y() < 0.0 && grid.upper_xy.y() > 0.6);
    // Every value is C at its grid point, and C peaks (= 1) at the first area's mean.
    Eigen::Index best_i = 0;
    Eigen::Index best_j = 0;
    grid.values.maxCoeff(&best_i, &best_j);
    const auto point = [&](Eigen::Index i, Eigen::Index j) {
      return Eigen::Vector3d(grid.lower_xy.x() + (grid.upper_xy.x() - grid.lower_xy.x()) * static_cast<double>(i) / 40.0,
                             grid.lower_xy.y() + (grid.upper_xy.y() - grid.lower_xy.y()) * static_cast<double>(j) / 40.0,
                             0.5);
    };
    for (Eigen::Index i = 0; i < 41; i += 7) {
      for (Eigen::Index j = 0; j < 41; j += 5) QVERIFY(std::abs(grid.values(i, j) - model.evaluate(point(i, j))) < 1e-12);
    }
    const double cell = (grid.upper_xy - grid.lower_xy).maxCoeff() / 40.0;
    QVERIFY((point(best_i, best_j) - Eigen::Vector3d(-0.5, 0.0, 0.5)).norm() <= cell);
    // Far from both areas (a corner of the slice) there is next to no confidence.
    QVERIFY(grid.values(0, 0) < 0.05);
    // No area: no slice.
    QVERIFY(flexirob::ui::confidenceSlices(flexirob::learning::ConfidenceModel(), settings).empty());
  }

  void plotTicksFallOnRoundNumbers() {
    using flexirob::ui::niceTickInterval;
    QCOMPARE(niceTickInterval(9.0), 2.0);        // 0, 2, 4, 6, 8 s
    QCOMPARE(niceTickInterval(1.1), 0.2);        // -0.05 ... 1.05 of the joints
    QCOMPARE(niceTickInterval(0.00105), 0.0002);  // a task error of about a millimetre
    QCOMPARE(niceTickInterval(58300.0), 20000.0);
    QCOMPARE(niceTickInterval(0.0), 0.0);
    // Limited to what a short plot has room for, never to a single tick.
    using flexirob::ui::niceTickIntervalFor;
    QCOMPARE(niceTickIntervalFor(-0.05, 1.05, 3), 0.5);  // 0, 0.5, 1
    QCOMPARE(niceTickIntervalFor(-0.05, 1.05, 10), 0.2);
    QCOMPARE(niceTickIntervalFor(0.1, 0.9, 2), 0.2);     // 0.5 would leave "0.5" alone: 0.2's four stay
    QCOMPARE(niceTickIntervalFor(0.0, 420.0, 2), 200.0); // 0, 200, 400: 500 would leave "0" alone
    QCOMPARE(niceTickInterval(std::numeric_limits<double>::infinity()), 0.0);
    flexirob::ui::TimePlot plot(QStringLiteral("t"), QStringLiteral("[m]"));
    plot.addSeries(QStringLiteral("zero"), Qt::blue);
    plot.setMinimumValueSpan(0.001);
    plot.setSeriesData(0, {QPointF(0.0, 0.0), QPointF(1.0, 0.0)});
    QVERIFY(plot.valueRange().second >= 0.001);  // a millimetre scale, not one of nanometres
    // A recording of one state: its second is shown, and the ticks read as distinct times
    // (they had all read "0.0").
    plot.setTimeRange(3.5, 3.5);
    QCOMPARE(plot.timeRange(), std::make_pair(3.5, 4.5));
    const QStringList ticks = plot.timeTickLabels();
    QVERIFY2(ticks.size() >= 3, qPrintable(ticks.join(QStringLiteral(" "))));
    QVERIFY(ticks.front().toDouble() >= 3.5 && ticks.front().toDouble() < 3.75);
    QCOMPARE(QSet<QString>(ticks.begin(), ticks.end()).size(), ticks.size());
    // Two seconds of a session: 0.5 s apart, one decimal.
    plot.setTimeRange(0.0, 2.0);
    QCOMPARE(plot.timeTickLabels(), QStringList({"0.0", "0.5", "1.0", "1.5", "2.0"}));
  }

  void thePlotsFollowTheLiveArmAndTheControlCycle() {
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();  // a hidden panel keeps its samples without drawing them
    QTRY_VERIFY_WITH_TIMEOUT(window.live() != nullptr && window.live()->snapshot().running, 10000);
    flexirob::ui::PlotPanel* plots = window.plotPanel();
    QVERIFY(plots != nullptr);
    QCOMPARE(plots->jointPlot()->seriesCount(), 7 + 2);  // two limit lines and seven joints
    QTRY_VERIFY_WITH_TIMEOUT(plots->sampleCount() >= 5, 5000);
    // The joint lines are the live joints scaled to their limits, inside [0, 1].
    const QLineSeries* a1 = plots->jointPlot()->series(2);
    QVERIFY(a1->count() >= 5);
    const double q1 = window.live()->snapshot().q[0];
    const auto& joint = window.robotModel()->joints().front();
    const double expected = (q1 - joint.limits.lower) / (joint.limits.upper - joint.limits.lower);
    QVERIFY2(std::abs(a1->points().back().y() - expected) < 0.02,
             qPrintable(QStringLiteral("A1 plotted at %1, expected %2").arg(a1->points().back().y()).arg(expected)));
    // The control cycle's compute time is plotted (positive, in microseconds).
    QVERIFY(plots->cyclePlot()->series(0)->count() >= 5);
    QVERIFY(plots->cyclePlot()->series(0)->points().back().y() > 0.0);
    // Times and error norms are never negative, nor are their axes.
    QCOMPARE(plots->cyclePlot()->valueRange().first, 0.0);
    QCOMPARE(plots->taskErrorPlot()->valueRange().first, 0.0);
  }

  // The status bar's live fields (the tip, cycles, fps) sit right-aligned: as the tip's y goes
  // from 0.000 through negative to positive, their left edge never moves right, so they and the
  // message beside them do not shake.
  void theStatusFieldsKeepTheirPlaceAsTheArmMoves() {
    MainWindow window("lwr4", "empty", quietOptions());
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTRY_VERIFY_WITH_TIMEOUT(window.live() != nullptr && window.live()->snapshot().running, 10000);
    auto* fields = window.statusBar()->findChild<QLabel*>(QStringLiteral("status_fields"));
    QVERIFY(fields != nullptr);
    QTRY_VERIFY(fields->text().contains(QStringLiteral(" fps")));
    // The keys move the tip while the arm approaches a posture.
    const auto& s = window.live()->snapshot();
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
    int leftmost = fields->mapTo(&window, QPoint(0, 0)).x();
    bool saw_negative_y = false;
    bool saw_positive_y = false;
    const auto watch = [&](Qt::Key key, int ms) {
      QTest::keyPress(&window, key);
      for (int t = 0; t < ms; t += 40) {
        QTest::qWait(40);
        const int left = fields->mapTo(&window, QPoint(0, 0)).x();
        QVERIFY2(left <= leftmost, qPrintable(QStringLiteral("moved right by %1 px at '%2'").arg(left - leftmost).arg(fields->text())));
        leftmost = left;
        const double y = s.p_WT[1];
        saw_negative_y = saw_negative_y || (y < -0.0005 && fields->text().contains(QStringLiteral(", -0.")));
        saw_positive_y = saw_positive_y || (y > 0.0005 && !fields->text().contains(QStringLiteral(", -0.")));
      }
      QTest::keyRelease(&window, key);
    };
    // Out of the upright start first: there the tip does not move sideways.
    QTest::keyPress(&window, Qt::Key_Right);
    QTest::qWait(1500);
    QTest::keyRelease(&window, Qt::Key_Right);
    watch(Qt::Key_Down, 1500);
    watch(Qt::Key_Up, 3000);
    QVERIFY2(saw_negative_y && saw_positive_y, "the tip did not cross y = 0: nothing to keep the fields from");
  }

  // A narrow joint chart (a 1024 px screen) shrinks its legend's font rather than cut the names.
  void aNarrowChartShrinksItsLegendInsteadOfCuttingTheNames() {
    flexirob::ui::PlotPanel plots;
    plots.setJoints({"A1", "A2", "A3", "A4", "A5", "A6", "A7"}, Eigen::VectorXd::Constant(7, -1.0), Eigen::VectorXd::Constant(7, 1.0));
    flexirob::ui::TimePlot* joints = plots.jointPlot();
    joints->setParent(nullptr);  // sized alone, not by the panel's layout
    joints->show();
    joints->resize(1200, 300);
    QCoreApplication::processEvents();
    const double wide = joints->chart()->legend()->font().pointSizeF();
    joints->resize(300, 300);
    QCoreApplication::processEvents();
    const double narrow = joints->chart()->legend()->font().pointSizeF();
    QVERIFY2(narrow < 0.8 * wide, qPrintable(QStringLiteral("%1 pt, then %2 pt").arg(wide).arg(narrow)));
    QVERIFY(narrow >= 0.6 * wide - 1e-9);
    // Too narrow for "A1" at the smallest font (an 800 px screen): the joints' numbers, and no
    // entry for the dashed limit lines.
    const auto labels = [joints] {
      QStringList shown;
      for (QLegendMarker* marker : joints->chart()->legend()->markers()) {
        if (marker->isVisible()) shown << marker->label();
      }
      return shown;
    };
    QVERIFY(joints->narrowLegend());
    QCOMPARE(labels(), (QStringList{"1", "2", "3", "4", "5", "6", "7"}));
    joints->resize(1200, 300);
    QCoreApplication::processEvents();
    QCOMPARE(joints->chart()->legend()->font().pointSizeF(), wide);
    QVERIFY(!joints->narrowLegend());
    QCOMPARE(labels(), (QStringList{"limits", "A1", "A2", "A3", "A4", "A5", "A6", "A7"}));
    delete joints;
  }

  // A long warning in the scrolled Teaching panel keeps every line: the panel's vertical bar
  // narrows the text after its lines were counted, and the last line was cut.
  void aLongWarningInTheTeachingPanelShowsWhole() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    window.resize(1280, 600);  // the panel scrolls
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTRY_VERIFY(window.live() != nullptr);
    QTest::keyClick(&window, Qt::Key_F5);  // CONFIGURATION: the hint and the area controls grow the panel
    QTRY_COMPARE(window.live()->snapshot().stage, flexirob::app::Stage::kConfiguration);
    QTest::qWait(300);
    const QString warning = QStringLiteral(
        "area_2: 171 of 171 samples were recorded with the arm touching something (drawn red); the map of free space "
        "keeps none of them and the learned postures lead into the contact: re-teach the area with the arm clear of it");
    window.stagePanel()->showWarning(warning);
    QTRY_VERIFY(window.stagePanel()->warningLabel()->isVisible());
    QTest::qWait(200);
    QLabel* label = window.stagePanel()->warningLabel();
    auto* scroll = window.findChild<QScrollArea*>(QStringLiteral("stage_scroll"));
    QVERIFY(scroll != nullptr);
    if (!scroll->verticalScrollBar()->isVisible()) QSKIP("the Teaching panel fits without scrolling with this font");
    QVERIFY2(label->height() >= label->heightForWidth(label->width()),
             qPrintable(QStringLiteral("%1 px high, %2 px needed at %3 px wide")
                            .arg(label->height())
                            .arg(label->heightForWidth(label->width()))
                            .arg(label->width())));
    // Wrapped as it is drawn, inside the frame and padding of its style sheet.
    const QRect text = label->fontMetrics().boundingRect(QRect(0, 0, label->contentsRect().width(), 100000),
                                                         Qt::TextWordWrap, warning);
    QVERIFY2(label->contentsRect().height() >= text.height(),
             qPrintable(QStringLiteral("%1 px inside the frame, %2 px of text").arg(label->contentsRect().height()).arg(text.height())));
    // And the panel holds it: below the panel's edge it could not be scrolled to.
    const int bottom = label->mapTo(window.stagePanel(), QPoint(0, label->height())).y();
    QVERIFY2(bottom <= window.stagePanel()->height(),
             qPrintable(QStringLiteral("the warning ends at %1 px, the panel at %2 px").arg(bottom).arg(window.stagePanel()->height())));
  }

  // The task error has no value while π_q or π_rec holds a posture under the hand; the line
  // stops there and starts again after, instead of joining the two sides with one made up.
  void theTaskErrorIsNotJoinedAcrossTimesWithoutATarget() {
    flexirob::ui::PlotPanel panel;
    panel.show();  // a hidden panel keeps its samples for later
    for (int k = 0; k <= 30; ++k) {
      flexirob::ui::PlotSample sample;
      sample.time = 0.1 * k;
      if (k < 10 || k > 20) sample.task_error = 0.001 * (k % 4);
      panel.append(sample);
    }
    flexirob::ui::TimePlot* plot = panel.taskErrorPlot();
    QCOMPARE(plot->drawnStretches(0), 2);
    QCOMPARE(plot->series(0)->count(), 10);  // the first stretch, 0-0.9 s
    for (const QPointF& p : plot->series(0)->points()) QVERIFY(p.x() < 1.0);
    // Values again throughout: one line.
    flexirob::ui::PlotSample sample;
    sample.time = 3.1;
    sample.task_error = 0.002;
    std::vector<flexirob::ui::PlotSample> later(2, sample);
    later[1].time = 3.2;
    panel.setSamples(later);
    QCOMPARE(plot->drawnStretches(0), 1);
  }

  // A window squeezed onto a small screen and grown back: the Joints dock gets its width back
  // (the 3D view had taken every pixel gained, the joint angles stayed cut).
  void theJointsDockGetsItsWidthBackWhenTheWindowGrows() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    window.resize(1280, 800);
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    auto* dock = window.findChild<QDockWidget*>(QStringLiteral("joints_dock"));
    QVERIFY(dock != nullptr);
    QTRY_COMPARE(window.width(), 1280);
    QTest::qWait(200);
    const int roomy = dock->width();
    window.resize(800, 600);
    QTRY_COMPARE(window.width(), 800);
    QTest::qWait(200);
    if (dock->width() >= roomy - 2) QSKIP("the dock kept its width at 800 px with this font");
    window.resize(1280, 800);
    QTRY_COMPARE(window.width(), 1280);
    QTRY_VERIFY2(dock->width() >= std::min(roomy, 1280 * 3 / 10) - 2,
                 qPrintable(QStringLiteral("%1 px, %2 px before").arg(dock->width()).arg(roomy)));
  }

  // Warnings pile up (every area's, a failed transition check): the box shows a short one
  // whole, scrolls a long list within at most kWarningLines lines with the newest, last, in
  // view, and the panel itself does not grow past them.
  void theWarningBoxScrollsToTheNewestWithinItsLines() {
    PanelAsTheWindowHoldsIt held;
    QVERIFY(held.exposed);
    flexirob::ui::StagePanel& panel = *held.panel;
    panel.showWarning(QStringLiteral("area_1: near a joint limit"));
    QTRY_VERIFY(panel.warningScroll()->isVisible());
    QCoreApplication::sendPostedEvents(nullptr, QEvent::LayoutRequest);
    QTRY_COMPARE(panel.warningScroll()->verticalScrollBar()->maximum(), 0);
    const int short_height = panel.warningScroll()->height();
    QStringList many;
    for (int k = 1; k <= 12; ++k) {
      many << QStringLiteral("• area_%1: 35 of 76 samples were recorded with the arm touching something (drawn red); re-teach it").arg(k);
    }
    panel.showWarning(many.join(QLatin1Char('\n')));
    QCoreApplication::sendPostedEvents(nullptr, QEvent::LayoutRequest);
    const int most = flexirob::ui::StagePanel::kWarningLines * panel.warningLabel()->fontMetrics().lineSpacing() + 12;
    QTRY_VERIFY(panel.warningScroll()->height() > short_height);
    QVERIFY2(panel.warningScroll()->height() <= most, qPrintable(QStringLiteral("%1 px > %2 px").arg(panel.warningScroll()->height()).arg(most)));
    QScrollBar* bar = panel.warningScroll()->verticalScrollBar();
    QTRY_VERIFY(bar->maximum() > 0);
    QTRY_COMPARE(bar->value(), bar->maximum());
    panel.clearWarning();
    QTRY_VERIFY(!panel.warningScroll()->isVisible());
  }

  // The hint above the Teaching panel's buttons grows and shrinks by a line or two as the stage
  // changes; the buttons under it stay put, where the operator's hand is.
  void theTeachingButtonsStayPutAsTheHintChanges() {
    PanelAsTheWindowHoldsIt held;
    QVERIFY(held.exposed);
    flexirob::ui::StagePanel& panel = *held.panel;
    flexirob::ui::LiveSnapshot s;
    s.dof = 7;
    using Controller = flexirob::app::InteractionController;
    const struct {
      Stage stage;
      SubStage sub_stage;
      bool execution_done;
      Controller controller;
      bool keyboard;
    } states[] = {{Stage::kIdle, SubStage::kNone, true, Controller::kHierarchicalControl, false},
                  {Stage::kExecution, SubStage::kNone, false, Controller::kHierarchicalControl, false},
                  {Stage::kProgramming, SubStage::kApproaching, true, Controller::kAssistedGravityCompensation, false},
                  {Stage::kProgramming, SubStage::kApproaching, true, Controller::kAssistedGravityCompensation, true},
                  {Stage::kConfiguration, SubStage::kPosed, true, Controller::kCompliantRecording, false},
                  {Stage::kExecution, SubStage::kNone, true, Controller::kHierarchicalControl, true}};
    QPushButton* first = panel.button(flexirob::app::Button::kStartConfiguration);
    QSet<int> button_tops;
    QSet<int> text_heights;
    for (const auto& state : states) {
      s.stage = state.stage;
      s.sub_stage = state.sub_stage;
      s.execution_done = state.execution_done;
      s.controller = state.controller;
      s.keyboard_mode = state.keyboard;
      panel.showSnapshot(s);
      QCoreApplication::sendPostedEvents(nullptr, QEvent::LayoutRequest);
      QLabel* hint = panel.hintLabel();
      const int text_height = hint->fontMetrics()
                                  .boundingRect(QRect(0, 0, hint->contentsRect().width(), 100000), Qt::TextWordWrap, hint->text())
                                  .height();
      text_heights << text_height;
      button_tops << first->mapTo(&panel, QPoint(0, 0)).y();
      QVERIFY2(hint->contentsRect().height() >= text_height, qPrintable(hint->text()));  // and the hint shows whole
    }
    QVERIFY2(text_heights.size() > 1, "every hint took as many lines: nothing to keep the buttons from");
    QCOMPARE(button_tops.size(), 1);
  }

  // The Scene menu's arm9_areas with the LWR IV loaded: the scene's postures have nine joints,
  // so its own robot comes with it (as the command line starts it); setup_A keeps the robot.
  void aSceneChosenInTheMenuBringsItsRobotWhereTheLoadedOneDoesNotFit() {
    MainWindow window("lwr4", "setup_I", quietOptions());
    window.show();
    const auto choose = [&window](const QString& scene) {
      for (QAction* action : window.findChildren<QAction*>()) {
        if (action->data().toString() == scene && action->isCheckable()) {
          action->trigger();
          return true;
        }
      }
      return false;
    };
    QVERIFY(choose(QStringLiteral("arm9_areas")));
    QVERIFY(window.robotModel() != nullptr);
    QCOMPARE(window.robotModel()->dof(), 9);
    QVERIFY(flexirob::ui::fullStatusMessage(window.statusBar()).contains(QStringLiteral("made for the robot 'arm9'")));
    QVERIFY(choose(QStringLiteral("setup_I")));
    QCOMPARE(window.robotModel()->dof(), 7);
    QVERIFY(choose(QStringLiteral("empty")));  // made for the LWR IV, no posture to fit: it stays
    QCOMPARE(window.robotModel()->dof(), 7);
  }

  void aRefusalNamesWhatTheOperatorPressed() {
    using flexirob::ui::operatorWording;
    QCOMPARE(operatorWording(QStringLiteral("finished_configuration: not in CONFIGURATION but EXECUTION")),
             QStringLiteral("Finish configuration: not in CONFIGURATION but EXECUTION"));
    QCOMPARE(operatorWording(QStringLiteral("plan: the goal is 796.2 mm from the nearest explored position")),
             QStringLiteral("Goal (Ctrl+click): the goal is 796.2 mm from the nearest explored position"));
    // A warning about an area keeps its name.
    QCOMPARE(operatorWording(QStringLiteral("area_2: near a joint limit")), QStringLiteral("area_2: near a joint limit"));
    // A session's button signals, as the review window's timeline names them: areas counted
    // from 1, as the Teaching panel counts them.
    using flexirob::ui::operatorSignalName;
    QCOMPARE(operatorSignalName("remove_area 0"), QStringLiteral("Remove area: area 1"));
    QCOMPARE(operatorSignalName("reteach_area 2"), QStringLiteral("Re-teach area: area 3"));
    QCOMPARE(operatorSignalName("start_programming"), QStringLiteral("Start programming"));
    QCOMPARE(operatorSignalName("remove_area x"), QStringLiteral("Remove area: x"));
    QCOMPARE(operatorSignalName("remove_areas 0"), QStringLiteral("remove_areas 0"));
  }

  // Links red while the arm is led to an area's posture: said then, while the operator can
  // still move it clear, not only once the area is stored in the contact.
  void theHintSaysToMoveClearWhileTheArmTouchesSomethingOnItsWayToAPosture() {
    flexirob::ui::LiveSnapshot s;
    s.stage = flexirob::app::Stage::kConfiguration;
    s.sub_stage = flexirob::app::SubStage::kApproaching;
    s.contacts = 0;
    QVERIFY(!flexirob::ui::StagePanel::nextStepHint(s, true).contains(QStringLiteral("touches something")));
    s.contacts = 2;
    QVERIFY(flexirob::ui::StagePanel::nextStepHint(s, true).startsWith(QStringLiteral("The arm touches something (drawn red): move it clear")));
    s.keyboard_mode = true;
    QVERIFY(flexirob::ui::StagePanel::nextStepHint(s, true).contains(QStringLiteral("with the keys")));
    // Fixed or recording in the contact all the same: said while it lasts, not only once stored.
    for (const auto sub_stage : {flexirob::app::SubStage::kPosed, flexirob::app::SubStage::kRecording}) {
      s.sub_stage = sub_stage;
      s.contacts = 1;
      QVERIFY(flexirob::ui::StagePanel::nextStepHint(s, true).contains(QStringLiteral("touching something (drawn red)")));
      s.contacts = 0;
      QVERIFY(!flexirob::ui::StagePanel::nextStepHint(s, true).contains(QStringLiteral("touching")));
    }
  }

  // The warning box lists every warning that stands, not only the newest: an area taught in
  // contact stays warned about while the next area warns of a joint limit, until it is removed.
  void theWarningBoxListsEveryStandingWarningUntilItsAreaGoes() {
    using Kind = flexirob::app::WorkflowEvent::Kind;
    std::vector<flexirob::app::WorkflowEvent> events;
    const auto add = [&](Kind kind, const std::string& name, const std::string& detail, int area) {
      flexirob::app::WorkflowEvent event;
      event.kind = kind;
      event.name = name;
      event.detail = detail;
      event.area = area;
      events.push_back(event);
    };
    add(Kind::kAreaCreated, "area_created", "area_1", 0);
    add(Kind::kWarning, "area_in_contact", "area_1: touching", 0);
    add(Kind::kStage, "CONFIGURATION/POSED", "", -1);
    add(Kind::kWarning, "joint_limit", "area_2: near a limit", 1);
    add(Kind::kAreaCreated, "area_created", "area_2", 1);
    using flexirob::ui::standingWarningText;
    QCOMPARE(standingWarningText(events, QString()), QStringLiteral("\u2022 area_1: touching\n\u2022 area_2: near a limit"));
    // The newest refusal follows once; a warning that stands is not said twice.
    QCOMPARE(standingWarningText(events, QStringLiteral("Replay: no teach-in")),
             QStringLiteral("\u2022 area_1: touching\n\u2022 area_2: near a limit\n\u2022 Replay: no teach-in"));
    QCOMPARE(standingWarningText(events, QStringLiteral("area_2: near a limit")),
             QStringLiteral("\u2022 area_1: touching\n\u2022 area_2: near a limit"));
    add(Kind::kAreaRemoved, "area_removed", "area_1", 0);
    QCOMPARE(standingWarningText(events, QString()), QStringLiteral("area_2: near a limit"));
    add(Kind::kAreaRemoved, "area_removed", "area_2", 0);
    QCOMPARE(standingWarningText(events, QString()), QString());
  }

  // A short chart (a 600 px screen) gets as many value ticks as its height has room for: Qt
  // Charts cut every label of a crowded axis to "...". Never fewer than two.
  void aShortChartHasFewerValueTicksSoThatTheirLabelsShow() {
    flexirob::ui::TimePlot plot(QStringLiteral("joints"), QString());
    plot.setValueRange(-0.05, 1.05);
    plot.show();
    plot.resize(400, 600);
    QCoreApplication::processEvents();
    QCOMPARE(plot.valueTickLabels(), (QStringList{"0", "0.2", "0.4", "0.6", "0.8", "1"}));
    plot.resize(400, 170);
    QCoreApplication::processEvents();
    const QStringList short_labels = plot.valueTickLabels();
    QVERIFY2(short_labels.size() >= 2 && short_labels.size() <= 4, qPrintable(short_labels.join(QLatin1Char(' '))));
    const double apart = plot.chart()->plotArea().height() / (short_labels.size() - 1);
    QVERIFY2(apart >= QFontMetricsF(plot.chart()->axes(Qt::Vertical).front()->labelsFont()).height(),
             qPrintable(QStringLiteral("ticks %1 px apart").arg(apart)));
    plot.resize(400, 600);
    QCoreApplication::processEvents();
    QCOMPARE(plot.valueTickLabels().size(), 6);
  }

  // Another scene restarts the robot's clock: the new run's curves start afresh, not joined to
  // the old run's by a line back to zero, and the old peak leaves the axis.
  void aRestartedRobotStartsThePlotsAfresh() {
    flexirob::ui::PlotPanel plots;
    plots.setJoints({"A1"}, Eigen::VectorXd::Constant(1, -1.0), Eigen::VectorXd::Constant(1, 1.0));
    flexirob::ui::PlotSample sample;
    sample.q = Eigen::VectorXd::Zero(1);
    for (int i = 0; i < 50; ++i) {
      sample.time = 100.0 + 0.1 * i;
      sample.compute_us = i == 25 ? 2200.0 : 50.0;
      plots.append(sample);
    }
    QCOMPARE(plots.sampleCount(), 50);
    sample.time = 0.0;
    sample.compute_us = 40.0;
    plots.append(sample);
    sample.time = 0.1;
    plots.append(sample);
    QCOMPARE(plots.sampleCount(), 2);
  }

  void aTaughtAreaShowsAsSlicesAndAGoalIsPlannedAndReviewed() {
    MainWindow::Options options = quietOptions();
    options.record_sessions = true;
    MainWindow window("lwr4", "empty", options);
    if (canDraw()) {
      window.show();
      QVERIFY(QTest::qWaitForWindowExposed(&window));
    }
    QTRY_VERIFY_WITH_TIMEOUT(window.live() != nullptr && window.live()->snapshot().running, 10000);
    const auto& s = window.live()->snapshot();
    QCOMPARE(window.confidenceSlicesShown(), 0);

    // Keyboard triggers are counted like detected ones.
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kApproaching);
    QTRY_COMPARE(s.on_affected, std::uint64_t(1));
    // Approach a posture ~0.4 m away with the keys (0.08 m/s), out of the upright start and
    // down: the ITM graph grows along the way, a node per e_max = 0.1 m.
    for (const auto& [key, ms] : {std::pair{Qt::Key_Right, 2500}, std::pair{Qt::Key_PageDown, 1500}, std::pair{Qt::Key_Up, 1500}}) {
      QTest::keyPress(&window, key);
      QTest::qWait(ms);
      QTest::keyRelease(&window, key);
    }
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.sub_stage, SubStage::kPosed);
    QTRY_COMPARE(s.on_converged, std::uint64_t(1));
    QTest::keyClick(&window, Qt::Key_Space);
    QTRY_COMPARE(s.sub_stage, SubStage::kRecording);
    // Move about inside the area while it records (samples every 20 ms).
    for (const Qt::Key key : {Qt::Key_Left, Qt::Key_Down, Qt::Key_PageUp}) {
      QTest::keyPress(&window, key);
      QTest::qWait(600);
      QTest::keyRelease(&window, key);
    }
    QTest::keyClick(&window, Qt::Key_Return);
    QTRY_COMPARE(s.areas, 1);
    QTRY_VERIFY(s.itm_nodes >= 2);

    // The area's confidence field: three slices, centred on the area, and the legend.
    QTRY_COMPARE(window.confidenceSlicesShown(), 3);
    const auto heights = window.confidencePanel()->settings().heights();
    QVERIFY(std::abs(heights[1] - s.confidence->mean(0)[2]) < 0.006);
    window.confidencePanel()->countBox()->setValue(2);
    QCOMPARE(window.confidenceSlicesShown(), 2);
    window.confidencePanel()->countBox()->setValue(3);
    window.findChild<QDockWidget*>(QStringLiteral("confidence_dock"))->raise();
    if (!qEnvironmentVariableIsEmpty("FLEXIROB_SCREENSHOT_DIR")) {
      // The pictures look at the explored region from closer than the home view does.
      const Eigen::Vector3d centre = s.confidence->mean(0) + Eigen::Vector3d(-0.1, 0.0, -0.15);
      window.view()->setHomeCamera(flexirob::render::frameSphere(
          centre, 0.45, static_cast<double>(window.view()->width()) / window.view()->height()));
    }
    screenshot(window, "06-confidence.png");
    window.findChild<QDockWidget*>(QStringLiteral("joints_dock"))->raise();
    if (canDraw()) {
      window.mirror();
      QVERIFY(window.confidenceLegend()->isVisible());
      QVERIFY(window.view()->geometry().contains(window.confidenceLegend()->geometry().translated(window.view()->pos())));
      // A key, not a panel over the arm: at most 30 % of the view's height (90 px at least).
      QVERIFY2(window.confidenceLegend()->height() <= std::max(90, window.view()->height() * 3 / 10),
               qPrintable(QStringLiteral("%1 px of %2").arg(window.confidenceLegend()->height()).arg(window.view()->height())));
      // Overlays ▸ Legend hides the colour bar too.
      window.overlays().setVisible(flexirob::render::OverlayLayer::kLegend, false);
      window.mirror();
      QVERIFY(!window.confidenceLegend()->isVisible());
      window.overlays().setVisible(flexirob::render::OverlayLayer::kLegend, true);
      window.mirror();
      QVERIFY(window.confidenceLegend()->isVisible());
      // The slices are drawn where they are: hiding the layer changes the picture.
      const QImage with = window.view()->grabFramebuffer();
      window.overlays().setVisible(flexirob::render::OverlayLayer::kConfidence, false);
      const QImage without = window.view()->grabFramebuffer();
      window.overlays().setVisible(flexirob::render::OverlayLayer::kConfidence, true);
      QVERIFY2(changedPixels(with, without) > 200,
               qPrintable(QStringLiteral("the slices changed %1 pixels").arg(changedPixels(with, without))));
    }

    // Learn, skip the teach-in, and go to EXECUTION.
    QTest::keyClick(&window, Qt::Key_F6);
    QTRY_VERIFY_WITH_TIMEOUT(s.model_ready && s.stage == Stage::kIdle, 30000);
    QTest::keyClick(&window, Qt::Key_F7);
    QTRY_COMPARE(s.stage, Stage::kProgramming);
    QTest::keyClick(&window, Qt::Key_F8);
    QTRY_COMPARE(s.stage, Stage::kExecution);

    // The goal: the explored node farthest from the tip, Ctrl+clicked where it is drawn (or set).
    QVERIFY(s.itm != nullptr);
    // The node nearest the tip: a second goal, on the way back.
    const Eigen::Vector3d tip_before = tip(s);
    Eigen::Vector3d start_tip = s.itm->prototype(s.itm->nodeIds().front()).head<3>();
    for (const int id : s.itm->nodeIds()) {
      const Eigen::Vector3d p = s.itm->prototype(id).head<3>();
      if ((p - tip_before).norm() < (start_tip - tip_before).norm()) start_tip = p;
    }
    Eigen::Vector3d goal = tip(s);
    for (const int id : s.itm->nodeIds()) {
      const Eigen::Vector3d p = s.itm->prototype(id).head<3>();
      if ((p - tip(s)).norm() > (goal - tip(s)).norm()) goal = p;
    }
    QVERIFY2((goal - tip(s)).norm() > 0.05, "the explored region is too small for a goal");
    const std::uint64_t path_version = s.path_version;
    if (canDraw()) {
      window.mirror();
      flexirob::ui::OsgView* view = window.view();
      const auto pixel = flexirob::render::projectToPixel(view->currentCamera(), view->width(), view->height(), goal);
      QVERIFY(pixel.has_value());
      const QPointF at(pixel->x(), pixel->y());
      QMouseEvent press(QEvent::MouseButtonPress, at, view->mapToGlobal(at), Qt::LeftButton, Qt::LeftButton,
                        Qt::ControlModifier);
      QApplication::sendEvent(view, &press);
      QMouseEvent release(QEvent::MouseButtonRelease, at, view->mapToGlobal(at), Qt::LeftButton, Qt::NoButton,
                          Qt::ControlModifier);
      QApplication::sendEvent(view, &release);
      QVERIFY(window.goal().has_value());
      // Some node drawn within the pick radius of the click: the goal is an explored position.
      const auto picked = flexirob::render::projectToPixel(view->currentCamera(), view->width(), view->height(), *window.goal());
      QVERIFY(picked.has_value() && (*picked - *pixel).norm() <= 18.0);
      goal = *window.goal();
    } else {
      QVERIFY(window.setGoal(goal));
    }
    QTRY_VERIFY_WITH_TIMEOUT(s.path_version != path_version, 5000);
    QVERIFY(s.path != nullptr && s.path->found);
    window.mirror();
    QVERIFY(window.overlays().layer(flexirob::render::OverlayLayer::kGoalAndPath)->getNumChildren() >= 2);
    // Executed: the tip arrives at the goal.
    QTRY_VERIFY_WITH_TIMEOUT((tip(s) - goal).norm() < 0.02, 20000);
    screenshot(window, "07-goal.png");
    // The status bar says the motion ended, not that it is still being planned.
    QTRY_VERIFY_WITH_TIMEOUT(flexirob::ui::fullStatusMessage(window.statusBar()).startsWith(QStringLiteral("Goal reached")), 20000);
    // A goal 2 m above everything explored is refused: its ball goes with the refusal.
    QVERIFY(window.setGoal(goal + Eigen::Vector3d(0.0, 0.0, 2.0)));
    QTRY_VERIFY(!window.goal().has_value());
    window.mirror();
    QCOMPARE(window.overlays().layer(flexirob::render::OverlayLayer::kGoalAndPath)->getNumChildren(), 0U);
    QTRY_VERIFY(!window.stagePanel()->warningLabel()->text().isEmpty());
    QTRY_VERIFY(window.bannerLabel()->text().contains(QStringLiteral("⚠")));
    // Another goal, then CONFIGURATION again: the goal and its path are no motion any more.
    const std::uint64_t before_second = s.path_version;
    QVERIFY(window.setGoal(start_tip));
    QTRY_VERIFY_WITH_TIMEOUT(s.path_version != before_second, 5000);
    // Accepted after the refusal: the refusal no longer describes what the arm does.
    QTRY_VERIFY(window.stagePanel()->warningLabel()->text().isEmpty());
    QTRY_VERIFY(!window.bannerLabel()->text().contains(QStringLiteral("⚠")));
    window.mirror();
    QVERIFY(window.overlays().layer(flexirob::render::OverlayLayer::kGoalAndPath)->getNumChildren() >= 2);
    QTest::keyClick(&window, Qt::Key_F5);
    QTRY_COMPARE(s.stage, Stage::kConfiguration);
    QTRY_VERIFY(!window.goal().has_value());
    window.mirror();
    QCOMPARE(window.overlays().layer(flexirob::render::OverlayLayer::kGoalAndPath)->getNumChildren(), 0U);

    // The run's recording in the review window: the graph and the slices of the end.
    // Recorded into the one sessions folder, not into flexirob/flexirob/sessions.
    QVERIFY2(window.sessionFile().startsWith(MainWindow::sessionDirectory() + QStringLiteral("/")), qPrintable(window.sessionFile()));
    QVERIFY(MainWindow::sessionDirectory().endsWith(QStringLiteral("/share/flexirob/sessions")) ||
            !qEnvironmentVariableIsEmpty("XDG_DATA_HOME"));
    QVERIFY(!MainWindow::sessionDirectory().contains(QStringLiteral("flexirob/flexirob")));
    QTemporaryDir directory;
    const QString file = directory.filePath(QStringLiteral("run.flexirob"));
    QVERIFY(window.saveSession(file));
    flexirob::ui::ReviewWindow* review = window.openRecording(file);
    QVERIFY2(review != nullptr, qPrintable(window.statusBar()->currentMessage()));
    QCOMPARE(window.reviewWindows().size(), std::size_t(1));
    QVERIFY(review->itmSnapshots() >= 1);
    review->setTime(review->reader()->endTime());
    QVERIFY(review->itmNodesShown() >= 2);
    QVERIFY(review->confidenceSlicesShown() >= 1);
    screenshot(*review, "08-review.png");
    // Before anything was recorded there is neither.
    review->setTime(review->reader()->startTime());
    QCOMPARE(review->confidenceSlicesShown(), 0);
    // The bands begin with the recording: IDLE until the first key (F5), not a gap.
    QCOMPARE(review->stageAt(review->reader()->startTime()), std::string("IDLE"));

    // A file that is no recording is refused with its reason, and no window opens.
    const QString bogus = directory.filePath(QStringLiteral("bogus.flexirob"));
    {
      QFile out(bogus);
      QVERIFY(out.open(QIODevice::WriteOnly));
      out.write("not a session");
    }
    QVERIFY(window.openRecording(bogus) == nullptr);
    QVERIFY(window.statusBar()->currentMessage().contains(QStringLiteral("bogus.flexirob")));
    QCOMPARE(window.reviewWindows().size(), std::size_t(1));
  }
};

QTEST_MAIN(FeaturesTest)
#include "features_test.moc"
