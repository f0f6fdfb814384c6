#pragma once
// Plots of the running (or reviewed) robot with Qt Charts (issue #7 item 7): the task error, the
// joint values against their limits and the control thread's cycle statistics, stacked with one
// time axis each and a shared time cursor. Clicking or dragging in any plot moves the cursor and
// emits cursorTimeChanged (the review window scrubs its timeline with it).
//
// The panel takes plain samples (PlotSample), not the control thread's snapshot: the live window
// converts its ControlSnapshot / CycleStatistics, the review window its recorded states.
// Wiring into the main window: create a PlotPanel in a dock, call setJoints() when the robot
// changes and append() from the display timer; setWindowSeconds() picks the rolling window.
#include <QChartView>
#include <QWidget>

#include <Eigen/Core>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <QStringList>

class QChart;
class QLineSeries;
class QValueAxis;

namespace flexirob::ui {

/// One point in time of everything the panel plots; NaN (or an empty q) leaves a series out.
struct PlotSample {
  double time = 0.0;                                              ///< [s]
  double task_error = std::numeric_limits<double>::quiet_NaN();  ///< [m]
  Eigen::VectorXd q;                                              ///< joint positions [rad]
  double compute_us = std::numeric_limits<double>::quiet_NaN();  ///< control cycle work [µs]
  double max_compute_us = std::numeric_limits<double>::quiet_NaN();
  double deadline_misses = std::numeric_limits<double>::quiet_NaN();  ///< cumulative count
};

/// One chart against time with any number of line series and a vertical cursor line.
class TimePlot : public QChartView {
  Q_OBJECT

 public:
  TimePlot(const QString& title, const QString& value_label, QWidget* parent = nullptr);

  /// Adds a series; returns its index.
  int addSeries(const QString& name, const QColor& color, Qt::PenStyle style = Qt::SolidLine, qreal width = 1.5);
  void setSeriesData(int series, const QList<QPointF>& points);
  void setSeriesName(int series, const QString& name);
  void setTitle(const QString& title);
  QString title() const;
  void hideFromLegend(int series);
  /// The legend's name for `series` when the chart is too narrow for the full names (the joint
  /// chart's "A3" becomes "3"); an empty name leaves the entry out of a narrow legend.
  void setNarrowLegendName(int series, const QString& name);
  /// Whether the legend shows the narrow names now.
  bool narrowLegend() const { return narrow_legend_; }
  /// The value axis' tick labels as drawn (at most as many as the plot's height has room for).
  QStringList valueTickLabels() const;
  /// The series drawn as separate stretches, unjoined across the gaps between them (times with
  /// no value, such as the task error while no controller steers the tip).
  void setSeriesStretches(int series, const QList<QList<QPointF>>& stretches);
  /// How many line pieces draw `series` (1 + the stretches after its first).
  int drawnStretches(int series) const;
  int seriesCount() const { return static_cast<int>(series_.size()); }
  const QLineSeries* series(int index) const { return series_.at(static_cast<std::size_t>(index)); }
  /// Shows t0..t1 [s]; a recording of one instant (t1 <= t0) is shown over the second after it,
  /// so that its ticks read as times rather than as one value repeated.
  void setTimeRange(double t0, double t1);
  /// The time axis' range (t0, t1) and the labels of its ticks, as drawn.
  std::pair<double, double> timeRange() const;
  QStringList timeTickLabels() const;
  /// Fixed value range; without it, the range follows the data (with 5 % margins; data that
  /// are all non-negative, such as errors and times, keep the axis at zero and above).
  void setValueRange(double lower, double upper);
  /// The smallest span a range that follows the data shows (in the value's unit): a task error
  /// of zero reads on a scale of millimetres, not of nanometres.
  void setMinimumValueSpan(double span) { minimum_span_ = span; }
  /// The value axis' current range (lower, upper).
  std::pair<double, double> valueRange() const;
  void setCursorTime(double time);
  double cursorTime() const { return cursor_time_; }
  /// The time under a widget x coordinate.
  double timeAt(double widget_x) const;

 Q_SIGNALS:
  void cursorRequested(double time);

 protected:
  void resizeEvent(QResizeEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;

 private:
  void updateCursorLine();
  void autoscale();
  void roundValueTicks();
  void fitLegend();

  QChart* chart_ = nullptr;
  QValueAxis* time_axis_ = nullptr;
  QValueAxis* value_axis_ = nullptr;
  QLineSeries* cursor_ = nullptr;
  std::vector<QLineSeries*> series_;
  /// Further stretches of a series broken by gaps (setSeriesStretches), drawn with its pen and
  /// left out of the legend.
  std::map<int, std::vector<QLineSeries*>> stretches_;
  double cursor_time_ = 0.0;
  bool fixed_values_ = false;
  double minimum_span_ = 0.0;
  double legend_point_size_ = 0.0;  ///< the legend font's size before a narrow chart shrank it [pt]
  std::set<int> hidden_from_legend_;
  std::map<int, QString> narrow_names_;
  bool narrow_legend_ = false;
  bool legend_names_changed_ = false;  ///< a narrow name given since the legend's names were set
  int value_ticks_room_ = 0;  ///< value tick labels the plot's height has room for (0: not laid out yet)
};

/// The tick interval of 1, 2 or 5 times a power of ten that divides `span` into nearest
/// `intervals` parts (0 for an empty or non-finite span).
double niceTickInterval(double span, int intervals = 4);
/// As niceTickInterval, widened to the next 1-2-5 step until [lower, upper] holds at most
/// `max_ticks` ticks at the interval's multiples (a short chart has no room for more labels: Qt
/// Charts cuts each to "..."), but never to fewer than two.
double niceTickIntervalFor(double lower, double upper, int max_ticks);

class PlotPanel : public QWidget {
  Q_OBJECT

 public:
  explicit PlotPanel(QWidget* parent = nullptr);

  /// The joints plotted: names and hard limits [rad] (sizes equal). Clears the data.
  void setJoints(const std::vector<std::string>& names, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);
  /// Replaces every series with these samples (time order) and shows their whole time span.
  void setSamples(const std::vector<PlotSample>& samples);
  /// Appends one sample (live) and shows the last windowSeconds().
  void append(const PlotSample& sample);
  void setWindowSeconds(double seconds);
  /// Stacks the plots top to bottom (Qt::Vertical, the default) or side by side (a bottom dock).
  void setOrientation(Qt::Orientation orientation);
  /// Shows or hides the control-cycle plot (recordings hold no cycle statistics).
  void setCycleStatisticsVisible(bool visible);
  double windowSeconds() const { return window_seconds_; }

  /// Moves the cursor of every plot (no signal).
  void setCursorTime(double time);
  double cursorTime() const { return cursor_time_; }

  TimePlot* taskErrorPlot() const { return task_error_; }
  TimePlot* jointPlot() const { return joints_; }
  TimePlot* cyclePlot() const { return cycles_; }
  int sampleCount() const { return static_cast<int>(samples_.size()); }

 Q_SIGNALS:
  /// The user put the cursor at `time` in one of the plots.
  void cursorTimeChanged(double time);

 private:
  void rebuild();

 protected:
  void showEvent(QShowEvent* event) override;

 private:

  TimePlot* task_error_ = nullptr;
  TimePlot* joints_ = nullptr;
  TimePlot* cycles_ = nullptr;
  int compute_series_ = -1;
  int max_compute_series_ = -1;
  std::vector<std::string> joint_names_;
  Eigen::VectorXd lower_;
  Eigen::VectorXd upper_;
  std::deque<PlotSample> samples_;
  double window_seconds_ = 20.0;
  double cursor_time_ = 0.0;
  bool live_ = false;
  bool stale_ = false;  // samples appended while hidden, not drawn yet
};

}  // namespace flexirob::ui
