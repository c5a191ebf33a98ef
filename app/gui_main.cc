// scanreg: the desktop application. `--screenshot FILE` renders the main window to a PNG and exits
// (used under Xvfb to check what the GUI shows).
#include <QApplication>
#include <QCommandLineParser>
#include <QSurfaceFormat>
#include <QTimer>
#include <QVTKOpenGLNativeWidget.h>

#include <cstdio>

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
  QCommandLineOption screenshot("screenshot", "Render the main window to FILE (PNG) and exit.", "FILE");
  parser.addOption(screenshot);
  parser.process(app);

  scanreg::ui::MainWindow window;
  window.show();
  if (parser.isSet(screenshot)) {
    const QString path = parser.value(screenshot);
    QTimer::singleShot(1500, [&window, path] {
      const bool ok = window.SaveScreenshot(path);
      if (!ok) std::fprintf(stderr, "scanreg: could not write screenshot '%s'\n", qPrintable(path));
      QApplication::exit(ok ? 0 : 1);
    });
  }
  return app.exec();
}
