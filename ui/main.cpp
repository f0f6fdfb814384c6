// flexirob: the teaching GUI. A thin main: options, the main window, automated screenshots.
#include <QApplication>
#include <QOffscreenSurface>
#include <QOpenGLContext>
#include <QOpenGLFunctions>
#include <QCommandLineParser>
#include <QKeyEvent>
#include <QKeySequence>
#include <QSurfaceFormat>
#include <QTimer>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "app/backend_factory.hpp"
#include "robot/scene.hpp"
#include "ui/live_teaching.hpp"
#include "ui/main_window.hpp"
#include "ui/review_window.hpp"

namespace {

constexpr int kAutomaticSamples = -2;

// --keys: the comma-separated Qt key names (e.g. F5,Space,Shift+Right); nullopt, with the reason
// printed, for a name Qt does not know. Read before any window opens.
std::optional<std::vector<QKeyCombination>> parseKeys(const QString& keys) {
  std::vector<QKeyCombination> parsed;
  for (const QString& name : keys.split(QLatin1Char(','), Qt::SkipEmptyParts)) {
    const QKeySequence sequence = QKeySequence::fromString(name.trimmed());
    if (sequence.isEmpty() || sequence[0].key() == Qt::Key_unknown) {
      std::fprintf(stderr, "error: --keys: unknown key '%s'\n", qPrintable(name));
      return std::nullopt;
    }
    parsed.push_back(sequence[0]);
  }
  return parsed;
}

// Types `keys` into `window`, one every 800 ms from start-up (a scripted operator).
void scheduleKeys(QWidget* window, const std::vector<QKeyCombination>& keys) {
  int delay_ms = 800;
  for (const QKeyCombination combination : keys) {
    QTimer::singleShot(delay_ms, window, [window, combination] {
      QKeyEvent press(QEvent::KeyPress, combination.key(), combination.keyboardModifiers());
      QApplication::sendEvent(window, &press);
      QKeyEvent release(QEvent::KeyRelease, combination.key(), combination.keyboardModifiers());
      QApplication::sendEvent(window, &release);
    });
    delay_ms += 800;
  }
}

// --screenshot: the window as it is now into `file`; false with the reason printed.
bool saveScreenshot(QWidget* window, const QString& file) {
  if (!window->grab().save(file)) {
    std::fprintf(stderr, "error: cannot write screenshot '%s'\n", qPrintable(file));
    return false;
  }
  std::fprintf(stderr, "screenshot written to %s\n", qPrintable(file));
  return true;
}

// --msaa N is read before QApplication exists: the GL surface format must be set before the
// view's context is made. Returns the samples, kAutomaticSamples when not given, or -1 with the
// reason printed.
int multisamplesOption(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    std::string value;
    if (argument == "--msaa" && i + 1 < argc) {
      value = argv[i + 1];
    } else if (argument.rfind("--msaa=", 0) == 0) {
      value = argument.substr(7);
    } else {
      continue;
    }
    char* end = nullptr;
    const long samples = std::strtol(value.c_str(), &end, 10);
    if (value.empty() || *end != '\0' || samples < 0 || samples > 16) {
      std::fprintf(stderr, "error: --msaa: expected 0...16 samples, got '%s'\n", value.c_str());
      return -1;
    }
    return static_cast<int>(samples);
  }
  return kAutomaticSamples;
}

// A software rasterizer (Mesa's llvmpipe under Xvfb, a VM without a GPU) pays for every sample
// on the CPU: multisampling there halves the frame rate, so it is used only on hardware. Asks a
// throw-away context which renderer this display gives.
bool softwareRenderer() {
  QOffscreenSurface surface;
  surface.create();
  QOpenGLContext context;
  if (!context.create() || !context.makeCurrent(&surface)) return false;
  const auto* renderer = reinterpret_cast<const char*>(context.functions()->glGetString(GL_RENDERER));
  const QString name = renderer != nullptr ? QString::fromLatin1(renderer).toLower() : QString();
  context.doneCurrent();
  return name.contains(QStringLiteral("llvmpipe")) || name.contains(QStringLiteral("softpipe")) ||
         name.contains(QStringLiteral("software")) || name.contains(QStringLiteral("swiftshader"));
}

}  // namespace

int main(int argc, char** argv) {
  // Depth buffer and multisampling for the 3D view; set before the view's context exists.
  int samples = multisamplesOption(argc, argv);
  if (samples == -1) return 2;
  QSurfaceFormat format;
  format.setDepthBufferSize(24);
  format.setStencilBufferSize(8);
  format.setSamples(samples == kAutomaticSamples ? 4 : samples);
  QSurfaceFormat::setDefaultFormat(format);

  // --help and --version print and exit: they must work without a display (a terminal over
  // ssh, a CI log), so the window system is not needed for them.
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--help" || argument == "-h" || argument == "--help-all" || argument == "--version" || argument == "-v") {
      if (std::getenv("DISPLAY") == nullptr && std::getenv("WAYLAND_DISPLAY") == nullptr) setenv("QT_QPA_PLATFORM", "offscreen", 1);
    }
  }
  // Without a window system Qt aborts (exit 134, a core dump) before any option is read: one
  // line saying what is missing, and the exit code of every other bad start.
  // Qt's own -platform option names a platform that needs no display variable (offscreen).
  const bool asks_for_text_or_platform = [&] {
    for (int i = 1; i < argc; ++i) {
      const std::string argument = argv[i];
      if (argument == "--help" || argument == "-h" || argument == "--help-all" || argument == "--version" || argument == "-v" ||
          argument == "-platform" || argument == "--platform" || argument.rfind("-platform=", 0) == 0 ||
          argument.rfind("--platform=", 0) == 0) {
        return true;
      }
    }
    return false;
  }();
  const char* platform = std::getenv("QT_QPA_PLATFORM");
  if (!asks_for_text_or_platform && std::getenv("DISPLAY") == nullptr && std::getenv("WAYLAND_DISPLAY") == nullptr &&
      std::getenv("WAYLAND_SOCKET") == nullptr && (platform == nullptr || *platform == '\0')) {
    std::fprintf(stderr,
                 "error: no display to open the window on (DISPLAY and WAYLAND_DISPLAY are unset); run it on a desktop, "
                 "under xvfb-run, or with QT_QPA_PLATFORM=offscreen\n");
    return 2;
  }
  QApplication app(argc, argv);
  QApplication::setApplicationName(QStringLiteral("flexirob"));
  QApplication::setApplicationVersion(QStringLiteral(FLEXIROB_VERSION_STRING));
  QApplication::setOrganizationName(QStringLiteral("flexirob"));
  if (samples == kAutomaticSamples && QGuiApplication::platformName() != QStringLiteral("offscreen") && softwareRenderer()) {
    format.setSamples(0);
    QSurfaceFormat::setDefaultFormat(format);
  }

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
  const QCommandLineOption backend(QStringLiteral("backend"),
                                   QStringLiteral("Robot backend: sim (default) or fri://ADDRESS:PORT (the real LWR IV)."),
                                   QStringLiteral("B"), QStringLiteral("sim"));
  const QCommandLineOption key_map(QStringLiteral("show-keys"), QStringLiteral("Show the key map in the view."));
  const QCommandLineOption fresh_layout(QStringLiteral("default-layout"),
                                        QStringLiteral("Ignore the window layout remembered from the last run."));
  const QCommandLineOption keys(QStringLiteral("keys"),
                                QStringLiteral("Type these keys into the window, one every 800 ms from start-up, comma-separated "
                                               "Qt key names (e.g. F5,Space,Return): a scripted operator for demonstrations."),
                                QStringLiteral("K"));
  parser.addOption(keys);
  const QCommandLineOption msaa(QStringLiteral("msaa"),
                                QStringLiteral("Multisamples of the 3D view (default: 4 on graphics hardware, 0 on a software renderer such as llvmpipe under Xvfb)."),
                                QStringLiteral("N"));
  parser.addOption(msaa);
  parser.addOption(backend);
  parser.addOption(key_map);
  parser.addOption(fresh_layout);
  parser.addOption(robot);
  parser.addOption(scene);
  parser.addOption(screenshot);
  parser.addOption(quit_after);
  const QCommandLineOption review(QStringLiteral("review"),
                                  QStringLiteral("Review a session recording F in the review window."), QStringLiteral("F"));
  parser.addOption(review);
  const QCommandLineOption no_record(QStringLiteral("no-record"),
                                     QStringLiteral("Do not record this run into a session file (by default every run is "
                                                    "recorded under the user's data directory, sessions/)."));
  parser.addOption(no_record);
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

  std::vector<QKeyCombination> scripted_keys;
  if (parser.isSet(keys)) {
    const auto parsed = parseKeys(parser.value(keys));
    if (!parsed) return 2;
    scripted_keys = *parsed;
  }

  // A mistyped backend is refused as any other bad option is: starting the simulation instead
  // would let the operator believe the real arm is connected.
  if (parser.isSet(backend)) {
    try {
      flexirob::app::parseBackendChoice(parser.value(backend).toStdString());
    } catch (const std::exception& error) {
      std::fprintf(stderr, "error: --backend: %s\n", error.what());
      return 2;
    }
  }

  // A robot or scene named on the command line that cannot be read is refused as a bad option
  // is: a window on the default scene, with the reason in a panel, hides the typing mistake.
  // The menus keep the window's own behaviour (the robot or scene before stays).
  // What was read here is what the window shows.
  flexirob::ui::MainWindow::Options window_options;
  if (!parser.isSet(review)) {
    try {
      if (parser.isSet(scene)) window_options.scene_read = flexirob::ui::MainWindow::readScene(parser.value(scene).toStdString());
      // A scene naming a robot file this machine lacks runs with a robot given, as in the CLI.
      if (window_options.scene_read && !parser.isSet(robot)) flexirob::robot::robotFor("", *window_options.scene_read);
    } catch (const std::exception& error) {
      std::fprintf(stderr, "error: --scene: %s\n", error.what());
      return 2;
    }
    try {
      if (parser.isSet(robot)) window_options.robot_read = flexirob::ui::MainWindow::readRobot(parser.value(robot).toStdString());
    } catch (const std::exception& error) {
      std::fprintf(stderr, "error: --robot: %s\n", error.what());
      return 2;
    }
  }

  int exit_code = 0;
  if (parser.isSet(review)) {
    if (parser.isSet(robot) || parser.isSet(scene) || parser.isSet(backend)) {
      std::fprintf(stderr, "note: --review shows the recording's own robot and scene; --robot, --scene and --backend are not used\n");
    }
    flexirob::ui::ReviewWindow review_window;
    if (!review_window.open(parser.value(review).toStdString())) {
      std::fprintf(stderr, "error: %s\n", qPrintable(review_window.errorString()));
      return 2;
    }
    review_window.show();
    scheduleKeys(&review_window, scripted_keys);
    if (quit_ms >= 0) {
      QTimer::singleShot(quit_ms, &review_window, [&] {
        if (parser.isSet(screenshot) && !saveScreenshot(&review_window, parser.value(screenshot))) exit_code = 2;
        QApplication::quit();
      });
    }
    const int code = QApplication::exec();
    return exit_code != 0 ? exit_code : code;
  }

  window_options.backend = parser.value(backend).toStdString();
  window_options.restore_layout = !parser.isSet(fresh_layout) && !parser.isSet(screenshot);
  window_options.record_sessions = !parser.isSet(no_record);
  flexirob::ui::MainWindow window(parser.value(robot).toStdString(), parser.value(scene).toStdString(), window_options);
  window.show();
  if (parser.isSet(key_map)) {
    QTimer::singleShot(0, &window, [&] { window.toggleKeyMap(true); });
  }

  scheduleKeys(&window, scripted_keys);

  if (quit_ms >= 0) {
    QTimer::singleShot(quit_ms, &window, [&] {
      if (parser.isSet(screenshot) && !saveScreenshot(&window, parser.value(screenshot))) exit_code = 2;
      // Figures for the operator's record: display rate and the control worker's punctuality.
      if (window.live() != nullptr) {
        const flexirob::app::CycleStatistics stats = window.live()->statistics();
        std::fprintf(stderr, "view %.1f fps (%.1f in the last second); control %llu cycles, %llu deadline misses, max cycle %.0f us\n",
                     window.meanFramesPerSecond(), window.framesPerSecond(), static_cast<unsigned long long>(stats.cycles),
                     static_cast<unsigned long long>(stats.deadline_misses), stats.max_compute_us);
      }
      window.close();
      QApplication::quit();
    });
  }
  const int code = QApplication::exec();
  return exit_code != 0 ? exit_code : code;
}
