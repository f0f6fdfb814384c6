#include "ui/status_message.hpp"

#include <QFontMetrics>
#include <QStatusBar>
#include <QStyle>
#include <QVariant>
#include <algorithm>

namespace flexirob::ui {
namespace {

constexpr const char* kFullMessage = "flexirobFullMessage";
constexpr const char* kShownMessage = "flexirobShownMessage";
constexpr const char* kWatched = "flexirobStatusWatched";

// What QStatusBar leaves for its temporary message: its width less the visible widgets it holds
// (the permanent fields, the size grip) and the spacing about each.
int messageRoom(const QStatusBar* bar) {
  const int spacing = bar->style()->pixelMetric(QStyle::PM_LayoutHorizontalSpacing);
  int room = bar->contentsRect().width() - 2 * std::max(spacing, 6);
  for (const QObject* child : bar->children()) {
    const auto* widget = qobject_cast<const QWidget*>(child);
    if (widget == nullptr || !widget->isVisible() || widget->isWindow()) continue;
    room -= widget->width() + std::max(spacing, 6);
  }
  return std::max(room, 0);
}

}  // namespace

void showStatusMessage(QStatusBar* bar, const QString& message, int timeout_ms) {
  if (bar == nullptr) return;
  QString shown = message;
  const QFontMetrics metrics = bar->fontMetrics();
  const int room = messageRoom(bar);
  // Without room for a word (a window squeezed to nothing) the message goes as it is.
  if (bar->isVisible() && room > metrics.horizontalAdvance(QStringLiteral("mmmm …")) && metrics.horizontalAdvance(message) > room) {
    shown = metrics.elidedText(message, Qt::ElideRight, room);
    // Cut at the last word's end that fits, so that no word or number is shown in part.
    const int cut = shown.lastIndexOf(QLatin1Char(' '), shown.size() - 2);
    if (cut > shown.size() / 2) shown = shown.left(cut) + QStringLiteral(" …");
  }
  bar->setProperty(kFullMessage, message);
  bar->setProperty(kShownMessage, shown);
  bar->setToolTip(shown == message ? QString() : message);
  if (!bar->property(kWatched).toBool()) {
    // The tooltip goes with the message: when it times out or another replaces it.
    bar->setProperty(kWatched, true);
    QObject::connect(bar, &QStatusBar::messageChanged, bar, [bar](const QString& text) {
      if (text != bar->property(kShownMessage).toString()) bar->setToolTip(QString());
    });
  }
  bar->showMessage(shown, timeout_ms);
}

QString fullStatusMessage(const QStatusBar* bar) {
  if (bar == nullptr) return {};
  const QString current = bar->currentMessage();
  if (!current.isEmpty() && current == bar->property(kShownMessage).toString()) return bar->property(kFullMessage).toString();
  return current;
}

}  // namespace flexirob::ui
