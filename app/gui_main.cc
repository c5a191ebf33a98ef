// scanreg: the desktop application.
//   --demo              open the simulated demo project (and register it with --register)
//   --screenshot FILE   render the main window to a PNG once the jobs are done, then exit
// (the last two are how the GUI is checked under Xvfb).
#include <QApplication>
#include <QCommandLineParser>
#include <QDir>
#include <QSurfaceFormat>
#include <QTimer>
#include <QVTKOpenGLNativeWidget.h>

#include <cstdio>

#include "ui/job_runner.h"
#include "ui/main_window.h"

int main(int argc, char** argv) {
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
  QCommandLineOption screenshot("screenshot", "Render the main window to FILE (PNG) when done, and exit.", "FILE");
  parser.addOptions({demo, reg, screenshot});
  parser.addPositionalArgument("project", "A project file (*.scanreg.json) to open.", "[project]");
  parser.process(app);

  scanreg::ui::MainWindow window;
  window.show();
  const QString shot = parser.value(screenshot);
  auto finish = [&window, shot] {
    if (shot.isEmpty()) return;
    QTimer::singleShot(1000, [&window, shot] {
      const bool ok = window.SaveScreenshot(shot);
      if (!ok) std::fprintf(stderr, "scanreg: could not write screenshot '%s'\n", qPrintable(shot));
      QApplication::exit(ok ? 0 : 1);
    });
  };
  const bool want_register = parser.isSet(reg);
  QObject::connect(window.jobs(), &scanreg::ui::JobRunner::Succeeded, &window,
                   [&window, want_register, finish](const QString& title, const std::any&) {
                     if (want_register && !title.startsWith(QObject::tr("Registering"))) {
                       window.RegisterProject();
                     } else {
                       finish();
                     }
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
