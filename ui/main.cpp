// flexirob: the teaching GUI. A thin main: options, the main window, automated screenshots.
#include <QApplication>
#include <QCommandLineParser>
#include <QSurfaceFormat>
#include <QTimer>
#include <cstdio>

#include "ui/main_window.hpp"

int main(int argc, char** argv) {
  // Depth buffer and multisampling for the 3D view; set before any GL context exists.
  QSurfaceFormat format;
  format.setDepthBufferSize(24);
  format.setStencilBufferSize(8);
  format.setSamples(4);
  QSurfaceFormat::setDefaultFormat(format);

  QApplication app(argc, argv);
  QApplication::setApplicationName(QStringLiteral("flexirob"));
  QApplication::setApplicationVersion(QStringLiteral("0.1.0"));

  QCommandLineParser parser;
  parser.setApplicationDescription(QStringLiteral("FlexIRob: teaching redundant robot arms"));
  parser.addHelpOption();
  parser.addVersionOption();
  const QCommandLineOption robot({QStringLiteral("r"), QStringLiteral("robot")},
                                 QStringLiteral("Built-in robot (lwr4, arm9) or a URDF file (default: the scene's robot)."),
                                 QStringLiteral("R"));
  const QCommandLineOption scene({QStringLiteral("s"), QStringLiteral("scene")},
                                 QStringLiteral("Built-in scene name or a scene file."), QStringLiteral("S"),
                                 QStringLiteral("setup_I"));
  const QCommandLineOption screenshot(QStringLiteral("screenshot"),
                                      QStringLiteral("Save a screenshot of the window to F.png before quitting."),
                                      QStringLiteral("F.png"));
  const QCommandLineOption quit_after(QStringLiteral("quit-after-ms"),
                                      QStringLiteral("Quit after N milliseconds (default with --screenshot: 1500)."),
                                      QStringLiteral("N"));
  parser.addOption(robot);
  parser.addOption(scene);
  parser.addOption(screenshot);
  parser.addOption(quit_after);
  parser.process(app);

  int quit_ms = -1;
  if (parser.isSet(quit_after)) {
    bool ok = false;
    quit_ms = parser.value(quit_after).toInt(&ok);
    if (!ok || quit_ms < 0) {
      std::fprintf(stderr, "error: --quit-after-ms: expected a non-negative integer, got '%s'\n",
                   qPrintable(parser.value(quit_after)));
      return 2;
    }
  } else if (parser.isSet(screenshot)) {
    quit_ms = 1500;
  }

  flexirob::ui::MainWindow window(parser.value(robot).toStdString(), parser.value(scene).toStdString());
  window.show();

  int exit_code = 0;
  if (quit_ms >= 0) {
    QTimer::singleShot(quit_ms, &window, [&] {
      if (parser.isSet(screenshot)) {
        const QString file = parser.value(screenshot);
        if (window.grab().save(file)) {
          std::fprintf(stderr, "screenshot written to %s\n", qPrintable(file));
        } else {
          std::fprintf(stderr, "error: cannot write screenshot '%s'\n", qPrintable(file));
          exit_code = 2;
        }
      }
      QApplication::quit();
    });
  }
  const int code = QApplication::exec();
  return exit_code != 0 ? exit_code : code;
}
