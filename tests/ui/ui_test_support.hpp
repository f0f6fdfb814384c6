#pragma once
// What the GUI test suites share: whether the platform can draw, and a main window that leaves
// no files behind.
#include <QGuiApplication>
#include <QWidget>

#include "ui/main_window.hpp"

namespace flexirob::ui::testing {

// Qt's offscreen platform has no OpenGL: the 3D view draws nothing there.
inline bool canDraw() { return QGuiApplication::platformName() != QStringLiteral("offscreen"); }

// No session files and no layout of an earlier run.
inline MainWindow::Options quietOptions() {
  MainWindow::Options options;
  options.record_sessions = false;
  options.restore_layout = false;
  return options;
}

inline void showIfDrawable(QWidget& window) {
  if (canDraw()) window.show();
}

}  // namespace flexirob::ui::testing
