#pragma once
// Messages in a status bar that share its line with permanent fields (the link, the loop's
// deadlines, the scene): a long message is cut at a word's end with "…" where the fields begin,
// instead of running into them mid-word, and the whole of it stays in the bar's tooltip.
#include <QString>

class QStatusBar;

namespace flexirob::ui {

/// Shows `message` for `timeout_ms` (0: until replaced), elided to the room the permanent
/// widgets leave.
void showStatusMessage(QStatusBar* bar, const QString& message, int timeout_ms = 0);

/// The whole of the message last shown by showStatusMessage(), while the bar still shows it;
/// else the bar's current message.
QString fullStatusMessage(const QStatusBar* bar);

}  // namespace flexirob::ui
