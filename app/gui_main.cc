// scanreg: the desktop application.
//   --demo              open the simulated demo project (and register it with --register)
//   --screenshot FILE   render the main window to a PNG once the jobs are done, then exit
//   --register, --merge register / merge the opened project first
//   --screenshots DIR   open, register and merge the demo project, save a PNG of each main view
// (the last two are how the GUI is checked under Xvfb).
#include <QApplication>
#include <QCommandLineParser>
#include <QDir>
#include <QSettings>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QTimer>
#include <QVTKOpenGLNativeWidget.h>

#include <cstdio>

#include "core/common/allocator.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/merge_panel.h"
#include "ui/screenshot_tour.h"

int main(int argc, char** argv) {
  scanreg::ReuseFreedMemory();
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  QApplication::setApplicationName("scanreg");
  QApplication::setOrganizationName("scanreg");
  QApplication::setApplicationVersion(SCANREG_VERSION);

  QCommandLineParser parser;
  parser.setApplicationDescription("scanreg: registration of terrestrial laser scans");
  parser.addHelpOption();
  parser.addVersionOption();
  QCommandLineOption demo("demo", "Open the simulated demo project.");
  QCommandLineOption reg("register", "Register the opened project.");
  QCommandLineOption merge("merge", "Merge the registered scans (the merge panel's options) once the project is open "
                                    "(and registered, with --register).");
  QCommandLineOption screenshot("screenshot", "Render the main window to FILE (PNG) when done, and exit.", "FILE");
  QCommandLineOption screenshots("screenshots",
                                 "Open, register and merge the demo project, save a PNG of each "
                                 "main view into DIR, and exit.",
                                 "DIR");
  parser.addOptions({demo, reg, merge, screenshot, screenshots});
  parser.addPositionalArgument("project", "A project file (*.scanreg.json) to open.", "[project]");
  parser.process(app);

  // Screenshots do not depend on (or change) the user's settings: they get their own, empty ones.
  QTemporaryDir settings_dir;
  if (parser.isSet(screenshots)) {
    QSettings::setDefaultFormat(QSettings::IniFormat);
    QSettings::setPath(QSettings::IniFormat, QSettings::UserScope, settings_dir.path());
  }

  scanreg::ui::MainWindow window;
  window.show();
  if (parser.isSet(screenshots)) {
    window.resize(1500, 940);
    auto* tour = new scanreg::ui::ScreenshotTour(&window, parser.value(screenshots));
    QObject::connect(tour, &scanreg::ui::ScreenshotTour::Finished, &window, [](bool ok, const QString& message) {
      std::fprintf(ok ? stdout : stderr, "scanreg: %s\n", qPrintable(message));
      QApplication::exit(ok ? 0 : 1);
    });
    tour->StartDemo(settings_dir.filePath("demo"));
    return app.exec();
  }
  const QString shot = parser.value(screenshot);
  auto finish = [&window, shot] {
    if (shot.isEmpty()) return;
    QTimer::singleShot(1000, [&window, shot] {
      const bool ok = window.SaveScreenshot(shot);
      if (!ok) std::fprintf(stderr, "scanreg: could not write screenshot '%s'\n", qPrintable(shot));
      QApplication::exit(ok ? 0 : 1);
    });
  };
  // Open, then register (--register), then merge (--merge), then the screenshot.
  bool want_register = parser.isSet(reg), want_merge = parser.isSet(merge);
  QObject::connect(window.jobs(), &scanreg::ui::JobRunner::Succeeded, &window,
                   [&window, &want_register, &want_merge, finish](const QString&) {
                     if (want_register) {
                       want_register = false;
                       if (window.RegisterProject()) return;
                     } else if (want_merge) {
                       want_merge = false;
                       if (window.mergePanel()->Run()) return;
                     }
                     finish();
                   });
  QObject::connect(window.jobs(), &scanreg::ui::JobRunner::Failed, &window,
                   [finish](const QString&, const QString& message, bool) {
                     std::fprintf(stderr, "scanreg: %s\n", qPrintable(message));
                     finish();
                   });
  if (parser.isSet(demo)) {
    window.OpenDemoProject(QDir::tempPath() + "/scanreg-demo");
  } else if (!parser.positionalArguments().isEmpty()) {
    window.OpenProject(parser.positionalArguments().first());
  } else {
    finish();
  }
  return app.exec();
}
