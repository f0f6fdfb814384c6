#include "ui/plot_panel.hpp"

#include <QChart>
#include <QFontMetricsF>
#include <QLegend>
#include <QLegendMarker>
#include <QLineSeries>
#include <QMouseEvent>
#include <QPen>
#include <QValueAxis>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>

namespace flexirob::ui {

namespace {

// Joint colours: distinct hues in joint order (Qt's own chart themes cycle five).
QColor jointColor(int joint) {
  static const QColor kColors[] = {QColor(0, 114, 178),  QColor(230, 159, 0),  QColor(0, 158, 115),
                                   QColor(204, 121, 167), QColor(213, 94, 0),   QColor(86, 180, 233),
                                   QColor(140, 90, 40),   QColor(100, 50, 150), QColor(60, 60, 60)};
  return kColors[joint % 9];
}

}  // namespace

// --- TimePlot -------------------------------------------------------------------------------

TimePlot::TimePlot(const QString& title, const QString& value_label, QWidget* parent)
    : QChartView(parent), chart_(new QChart) {
  chart_->setTitle(title);
  chart_->legend()->setAlignment(Qt::AlignBottom);  // the plot keeps the panel's width
  chart_->setMargins(QMargins(4, 2, 4, 2));
  chart_->setAnimationOptions(QChart::NoAnimation);
  time_axis_ = new QValueAxis;
  time_axis_->setTitleText(QStringLiteral("t [s]"));
  time_axis_->setLabelFormat(QStringLiteral("%.1f"));
  value_axis_ = new QValueAxis;
  value_axis_->setTitleText(value_label);
  value_axis_->setLabelFormat(QStringLiteral("%.6g"));  // 4000 and 25000 us, not 4e+03 or 2.5e+04
  chart_->addAxis(time_axis_, Qt::AlignBottom);
  chart_->addAxis(value_axis_, Qt::AlignLeft);
  cursor_ = new QLineSeries;
  cursor_->setName(QStringLiteral("cursor"));
  cursor_->setPen(QPen(QColor(200, 30, 30), 1.5, Qt::DashLine));
  chart_->addSeries(cursor_);
  cursor_->attachAxis(time_axis_);
  cursor_->attachAxis(value_axis_);
  chart_->legend()->markers(cursor_).front()->setVisible(false);
  setChart(chart_);
  setRenderHint(QPainter::Antialiasing, false);  // thousands of points stay cheap to draw
  setMinimumHeight(120);
  setTimeRange(0.0, 1.0);
  value_axis_->setRange(0.0, 1.0);
  // Qt Charts cuts a value label to "..." where the plot's height per tick is less than the
  // label's: a short chart (a small screen) gets fewer ticks instead.
  connect(chart_, &QChart::plotAreaChanged, this, [this](const QRectF& area) {
    // Labels centred on their ticks, one label's height apart at least; the end ones may reach
    // half a label beyond the plot.
    const double label_height = QFontMetricsF(value_axis_->labelsFont()).height();
    const int room = std::max(2, static_cast<int>(area.height() / label_height) + 1);
    if (room == value_ticks_room_) return;
    value_ticks_room_ = room;
    roundValueTicks();
  });
}

void TimePlot::resizeEvent(QResizeEvent* event) {
  QChartView::resizeEvent(event);
  fitLegend();
}

void TimePlot::fitLegend() {
  // The legend does not wrap: on a narrow chart (a small screen) its names were cut to nothing
  // and only the colour squares showed. The font shrinks with the room each entry has, to 60 %;
  // where even that is too little, the entries take their narrow names.
  constexpr double kRoomPerEntry = 64.0;  // [px] a marker, a name of a few letters and a gap
  constexpr double kSmallestFont = 0.6;
  const auto entries = [this](bool narrow) {
    int shown = 0;
    for (int i = 0; i < seriesCount(); ++i) {
      if (hidden_from_legend_.count(i) != 0) continue;
      const auto narrow_name = narrow_names_.find(i);
      if (narrow && narrow_name != narrow_names_.end() && narrow_name->second.isEmpty()) continue;
      ++shown;
    }
    return shown;
  };
  const double room = std::max(0.0, width() - 16.0);
  const int shown_wide = entries(false);
  if (shown_wide == 0) return;
  const bool narrow = !narrow_names_.empty() && room / shown_wide < kSmallestFont * kRoomPerEntry;
  if (narrow != narrow_legend_ || legend_names_changed_) {
    for (int i = 0; i < seriesCount(); ++i) {
      const auto narrow_name = narrow_names_.find(i);
      if (narrow_name == narrow_names_.end()) continue;
      for (QLegendMarker* marker : chart_->legend()->markers(series_[static_cast<std::size_t>(i)])) {
        marker->setVisible(hidden_from_legend_.count(i) == 0 && !(narrow && narrow_name->second.isEmpty()));
        marker->setLabel(narrow ? narrow_name->second : series_[static_cast<std::size_t>(i)]->name());
      }
    }
    narrow_legend_ = narrow;
    legend_names_changed_ = false;
  }
  if (legend_point_size_ <= 0.0) legend_point_size_ = chart_->legend()->font().pointSizeF();
  if (legend_point_size_ <= 0.0) return;  // a font sized in pixels is left alone
  const int shown = entries(narrow);
  if (shown == 0) return;
  const double per_entry = room / shown;
  const double wanted = legend_point_size_ * std::clamp(per_entry / kRoomPerEntry, kSmallestFont, 1.0);
  QFont font = chart_->legend()->font();
  if (std::abs(font.pointSizeF() - wanted) < 0.05) return;
  font.setPointSizeF(wanted);
  chart_->legend()->setFont(font);
}

void TimePlot::setNarrowLegendName(int series, const QString& name) {
  narrow_names_[series] = name;
  legend_names_changed_ = true;
  fitLegend();
}

int TimePlot::addSeries(const QString& name, const QColor& color, Qt::PenStyle style, qreal width) {
  auto* series = new QLineSeries;
  series->setName(name);
  series->setPen(QPen(color, width, style));
  series->setUseOpenGL(false);
  chart_->addSeries(series);
  series->attachAxis(time_axis_);
  series->attachAxis(value_axis_);
  series_.push_back(series);
  return static_cast<int>(series_.size()) - 1;
}

void TimePlot::setSeriesData(int series, const QList<QPointF>& points) {
  series_.at(static_cast<std::size_t>(series))->replace(points);
  if (!fixed_values_) autoscale();
}

void TimePlot::setSeriesStretches(int series, const QList<QList<QPointF>>& stretches) {
  QLineSeries* first = series_.at(static_cast<std::size_t>(series));
  first->replace(stretches.isEmpty() ? QList<QPointF>() : stretches.front());
  std::vector<QLineSeries*>& more = stretches_[series];
  for (qsizetype k = 1; k < stretches.size(); ++k) {
    const auto index = static_cast<std::size_t>(k - 1);
    if (index == more.size()) {
      auto* piece = new QLineSeries;
      piece->setPen(first->pen());
      piece->setUseOpenGL(false);
      chart_->addSeries(piece);
      piece->attachAxis(time_axis_);
      piece->attachAxis(value_axis_);
      for (QLegendMarker* marker : chart_->legend()->markers(piece)) marker->setVisible(false);
      more.push_back(piece);
    }
    more[index]->replace(stretches[k]);
  }
  for (std::size_t k = static_cast<std::size_t>(std::max<qsizetype>(stretches.size() - 1, 0)); k < more.size(); ++k) more[k]->clear();
  if (!fixed_values_) autoscale();
}

int TimePlot::drawnStretches(int series) const {
  int drawn = series_.at(static_cast<std::size_t>(series))->count() > 0 ? 1 : 0;
  const auto more = stretches_.find(series);
  if (more != stretches_.end()) {
    for (const QLineSeries* piece : more->second) drawn += piece->count() > 0 ? 1 : 0;
  }
  return drawn;
}

void TimePlot::hideFromLegend(int series) {
  hidden_from_legend_.insert(series);
  for (QLegendMarker* marker : chart_->legend()->markers(series_.at(static_cast<std::size_t>(series)))) marker->setVisible(false);
}

void TimePlot::setSeriesName(int series, const QString& name) { series_.at(static_cast<std::size_t>(series))->setName(name); }

double niceTickInterval(double span, int intervals) {
  if (!(span > 0.0) || !std::isfinite(span) || intervals < 1) return 0.0;
  const double raw = span / intervals;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  // The step whose count of intervals comes nearest the wish.
  double best = decade;
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    const double step = factor * decade;
    if (std::abs(span / step - intervals) < std::abs(span / best - intervals)) best = step;
  }
  return best;
}

double niceTickIntervalFor(double lower, double upper, int max_ticks) {
  const double span = upper - lower;
  double interval = niceTickInterval(span);
  if (interval <= 0.0 || max_ticks < 2) return interval;
  // Ticks at the multiples of the interval within [lower, upper], as QValueAxis draws them.
  const auto ticks = [lower, upper](double step) {
    return std::floor(upper / step + 1e-9) - std::ceil(lower / step - 1e-9) + 1.0;
  };
  // Widen through the 1-2-5 steps (0.2 -> 0.5 -> 1 -> 2 ...), but never to a single tick: a
  // lone "0" says nothing of the scale.
  while (ticks(interval) > max_ticks) {
    const double decade = std::pow(10.0, std::floor(std::log10(interval) + 1e-9));
    const double factor = interval / decade;
    const double wider = (factor < 1.5 ? 2.0 : factor < 3.5 ? 5.0 : 10.0) * decade;
    if (ticks(wider) < 2.0) break;
    interval = wider;
  }
  return interval;
}

namespace {
// Ticks at round values (multiples of a 1-2-5 interval from zero), wherever the range ends;
// at most `max_ticks` of them where that is positive.
void roundTicks(QValueAxis* axis, int max_ticks = 0) {
  const double span = axis->max() - axis->min();
  const double interval = max_ticks > 0 ? niceTickIntervalFor(axis->min(), axis->max(), max_ticks) : niceTickInterval(span);
  if (interval <= 0.0) return;
  axis->setTickType(QValueAxis::TicksDynamic);
  axis->setTickAnchor(0.0);
  axis->setTickInterval(interval);
}
// The labels QValueAxis draws with dynamic ticks: multiples of the interval from the anchor,
// within the range, in the axis' label format.
QStringList drawnTickLabels(const QValueAxis* axis) {
  QStringList labels;
  const double interval = axis->tickInterval();
  if (!(interval > 0.0)) return labels;
  const double anchor = axis->tickAnchor();
  // The plots' formats are "%.<precision><f|g>"; QString::number writes them as printf does.
  const QString format = axis->labelFormat();
  char conversion = 'g';
  int precision = 6;
  if (format.size() >= 4 && format.startsWith(QLatin1String("%.")) && QStringLiteral("fgeFGE").contains(format.back())) {
    bool ok = false;
    const int written = format.mid(2, format.size() - 3).toInt(&ok);
    if (ok) {
      precision = written;
      conversion = format.back().toLatin1();
    }
  }
  for (double k = std::ceil((axis->min() - anchor) / interval - 1e-9); anchor + k * interval <= axis->max() + 1e-9 * interval;
       k += 1.0) {
    labels << QString::number(anchor + k * interval, conversion, precision);
  }
  return labels;
}

}  // namespace

void TimePlot::setTimeRange(double t0, double t1) {
  if (!(t1 > t0)) t1 = t0 + 1.0;
  time_axis_->setRange(t0, t1);
  roundTicks(time_axis_);
  // As many decimals as the interval needs: 0.5 s ticks read 0.5, 1.0; 2 s ticks read 2, 4.
  const double interval = niceTickInterval(t1 - t0);
  const int decimals = interval > 0.0 ? std::clamp(static_cast<int>(std::ceil(-std::log10(interval) - 1e-9)), 0, 3) : 1;
  time_axis_->setLabelFormat(QStringLiteral("%.%1f").arg(decimals));
  updateCursorLine();
}

std::pair<double, double> TimePlot::timeRange() const { return {time_axis_->min(), time_axis_->max()}; }

QStringList TimePlot::timeTickLabels() const { return drawnTickLabels(time_axis_); }

void TimePlot::setValueRange(double lower, double upper) {
  fixed_values_ = true;
  value_axis_->setRange(lower, upper);
  roundValueTicks();
  updateCursorLine();
}

void TimePlot::roundValueTicks() { roundTicks(value_axis_, value_ticks_room_); }

QStringList TimePlot::valueTickLabels() const { return drawnTickLabels(value_axis_); }

void TimePlot::autoscale() {
  double lower = std::numeric_limits<double>::infinity();
  double upper = -lower;
  const auto include = [&](const QLineSeries* series) {
    for (const QPointF& p : series->points()) {
      lower = std::min(lower, p.y());
      upper = std::max(upper, p.y());
    }
  };
  for (const QLineSeries* series : series_) include(series);
  for (const auto& [series, pieces] : stretches_) {
    for (const QLineSeries* piece : pieces) include(piece);
  }
  if (!(upper >= lower)) return;
  if (upper - lower < minimum_span_) upper = lower + minimum_span_;
  const double margin = std::max(0.05 * (upper - lower), 1e-9 + 1e-3 * std::abs(upper));
  // A quantity that cannot be negative (an error norm, a compute time) is read against zero:
  // its axis starts there, never below, and not above either where all its values are large.
  value_axis_->setRange(lower >= 0.0 ? 0.0 : lower - margin, upper + margin);
  roundValueTicks();
  updateCursorLine();
}

std::pair<double, double> TimePlot::valueRange() const { return {value_axis_->min(), value_axis_->max()}; }

void TimePlot::setCursorTime(double time) {
  cursor_time_ = time;
  updateCursorLine();
}

void TimePlot::updateCursorLine() {
  cursor_->replace(QList<QPointF>{{cursor_time_, value_axis_->min()}, {cursor_time_, value_axis_->max()}});
}

double TimePlot::timeAt(double widget_x) const {
  const QPointF scene = mapToScene(QPoint(static_cast<int>(widget_x), height() / 2));
  const QPointF value = chart_->mapToValue(chart_->mapFromScene(scene), cursor_);
  return std::clamp(value.x(), time_axis_->min(), time_axis_->max());
}

void TimePlot::mousePressEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton) Q_EMIT cursorRequested(timeAt(event->position().x()));
  QChartView::mousePressEvent(event);
}

void TimePlot::mouseMoveEvent(QMouseEvent* event) {
  if ((event->buttons() & Qt::LeftButton) != 0) Q_EMIT cursorRequested(timeAt(event->position().x()));
  QChartView::mouseMoveEvent(event);
}

void TimePlot::setTitle(const QString& title) { chart_->setTitle(title); }

QString TimePlot::title() const { return chart_->title(); }

// --- PlotPanel ------------------------------------------------------------------------------

PlotPanel::PlotPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  task_error_ = new TimePlot(QStringLiteral("Task error: tip from its target"), QStringLiteral("[m]"), this);
  task_error_->addSeries(QStringLiteral("|x - x_des|"), QColor(0, 114, 178));
  task_error_->setMinimumValueSpan(0.001);  // [m]
  // Joint values scaled to their hard limits: every joint shares one axis, the limits are the
  // lines at 0 and 1 (Sect. 4.3.4).
  joints_ = new TimePlot(QStringLiteral("Joints: 0 lower, 1 upper limit"), QString(), this);
  joints_->setValueRange(-0.05, 1.05);
  cycles_ = new TimePlot(QStringLiteral("Control cycle"), QStringLiteral("[µs]"), this);
  compute_series_ = cycles_->addSeries(QStringLiteral("compute"), QColor(0, 158, 115));
  max_compute_series_ = cycles_->addSeries(QStringLiteral("max compute"), QColor(213, 94, 0), Qt::DotLine);
  cycles_->setMinimumValueSpan(10.0);  // [µs]
  for (TimePlot* plot : {task_error_, joints_, cycles_}) {
    layout->addWidget(plot, 1);
    connect(plot, &TimePlot::cursorRequested, this, [this](double time) {
      setCursorTime(time);
      Q_EMIT cursorTimeChanged(time);
    });
  }
}

void PlotPanel::setJoints(const std::vector<std::string>& names, const Eigen::VectorXd& lower,
                          const Eigen::VectorXd& upper) {
  joint_names_ = names;
  lower_ = lower;
  upper_ = upper;
  samples_.clear();
  // The joint chart's series are rebuilt: limit lines first, then one per joint.
  auto* fresh = new TimePlot(QStringLiteral("Joints: 0 lower, 1 upper limit"), QString(), this);
  fresh->setValueRange(-0.05, 1.05);
  fresh->addSeries(QStringLiteral("limits"), QColor(200, 30, 30), Qt::DashLine, 1.0);
  fresh->addSeries(QString(), QColor(200, 30, 30), Qt::DashLine, 1.0);
  fresh->hideFromLegend(1);  // one legend entry for both limit lines
  // Legend entries share one row of about 50 px each: names longer than the LWR IV's "A1"
  // would be cut to "…", so then every entry is the joint's number.
  const bool short_names = std::all_of(names.begin(), names.end(), [](const std::string& name) { return name.size() <= 4; });
  for (std::size_t j = 0; j < names.size(); ++j) {
    const int added = fresh->addSeries(short_names ? QString::fromStdString(names[j]) : QStringLiteral("q%1").arg(j + 1),
                                       jointColor(static_cast<int>(j)));
    fresh->setNarrowLegendName(added, QString::number(j + 1));
  }
  // The dashed red lines at 0 and 1 need no name where there is room for few.
  fresh->setNarrowLegendName(0, QString());
  static_cast<QVBoxLayout*>(layout())->replaceWidget(joints_, fresh);
  joints_->deleteLater();
  joints_ = fresh;
  connect(joints_, &TimePlot::cursorRequested, this, [this](double time) {
    setCursorTime(time);
    Q_EMIT cursorTimeChanged(time);
  });
  joints_->setCursorTime(cursor_time_);
  rebuild();
}

void PlotPanel::setSamples(const std::vector<PlotSample>& samples) {
  live_ = false;
  samples_.assign(samples.begin(), samples.end());
  rebuild();
}

void PlotPanel::append(const PlotSample& sample) {
  live_ = true;
  // Time running backwards is a robot started anew (another scene, robot or backend): its
  // curves begin again rather than join the last run's with a line back to zero.
  if (!samples_.empty() && sample.time < samples_.back().time) samples_.clear();
  samples_.push_back(sample);
  while (!samples_.empty() && samples_.front().time < sample.time - window_seconds_) samples_.pop_front();
  // Hidden (a closed dock), the samples are kept and drawn when the panel shows again.
  if (isVisible()) {
    rebuild();
  } else {
    stale_ = true;
  }
}

void PlotPanel::showEvent(QShowEvent* event) {
  QWidget::showEvent(event);
  if (stale_) {
    stale_ = false;
    rebuild();
  }
}

void PlotPanel::setCycleStatisticsVisible(bool visible) { cycles_->setVisible(visible); }

void PlotPanel::setOrientation(Qt::Orientation orientation) {
  static_cast<QBoxLayout*>(layout())->setDirection(orientation == Qt::Horizontal ? QBoxLayout::LeftToRight
                                                                                 : QBoxLayout::TopToBottom);
}

void PlotPanel::setWindowSeconds(double seconds) { window_seconds_ = std::max(0.5, seconds); }

void PlotPanel::setCursorTime(double time) {
  cursor_time_ = time;
  for (TimePlot* plot : {task_error_, joints_, cycles_}) plot->setCursorTime(time);
}

void PlotPanel::rebuild() {
  QList<QList<QPointF>> error{{}};  // stretches: no line across the times without a task target
  QList<QPointF> compute;
  QList<QPointF> max_compute;
  const auto joints = static_cast<int>(joint_names_.size());
  std::vector<QList<QPointF>> normalized(static_cast<std::size_t>(joints));
  double misses = std::numeric_limits<double>::quiet_NaN();
  for (const PlotSample& s : samples_) {
    if (std::isfinite(s.task_error)) {
      error.back().append({s.time, s.task_error});
    } else if (!error.back().isEmpty()) {
      error.append(QList<QPointF>());
    }
    if (std::isfinite(s.compute_us)) compute.append({s.time, s.compute_us});
    if (std::isfinite(s.max_compute_us)) max_compute.append({s.time, s.max_compute_us});
    if (std::isfinite(s.deadline_misses)) misses = s.deadline_misses;
    if (s.q.size() != joints) continue;
    for (int j = 0; j < joints; ++j) {
      const double range = upper_[j] - lower_[j];
      normalized[static_cast<std::size_t>(j)].append({s.time, range > 0.0 ? (s.q[j] - lower_[j]) / range : 0.5});
    }
  }
  double t0 = samples_.empty() ? 0.0 : samples_.front().time;
  const double t1 = samples_.empty() ? 1.0 : samples_.back().time;
  if (live_) t0 = std::max(t0, t1 - window_seconds_);
  if (error.back().isEmpty()) error.removeLast();
  task_error_->setSeriesStretches(0, error);
  cycles_->setSeriesData(compute_series_, compute);
  cycles_->setSeriesData(max_compute_series_, max_compute);
  cycles_->setSeriesName(compute_series_, std::isfinite(misses)
                                              ? QStringLiteral("compute (%1 late)").arg(static_cast<qint64>(misses))
                                              : QStringLiteral("compute"));
  if (joints_->seriesCount() == joints + 2) {
    joints_->setSeriesData(0, {{t0, 0.0}, {t1, 0.0}});
    joints_->setSeriesData(1, {{t0, 1.0}, {t1, 1.0}});
    for (int j = 0; j < joints; ++j) joints_->setSeriesData(j + 2, normalized[static_cast<std::size_t>(j)]);
  }
  for (TimePlot* plot : {task_error_, joints_, cycles_}) plot->setTimeRange(t0, t1);
}

}  // namespace flexirob::ui
