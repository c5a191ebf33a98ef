// Drives the real main window under Xvfb (or QT_QPA_PLATFORM=offscreen).
#include <QMenuBar>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QVTKOpenGLNativeWidget.h>
#include <QtTest/QtTest>

#include "ui/main_window.h"
#include "ui/view_3d.h"

class MainWindowTest : public QObject {
  Q_OBJECT

 private slots:
  void HasMenusAndAnEmpty3dView() {
    scanreg::ui::MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QStringList menus;
    for (QAction* a : window.menuBar()->actions()) menus << a->text().remove('&');
    QCOMPARE(menus, QStringList({"File", "View", "Help"}));
    QVERIFY(window.view3d() != nullptr);
    QCOMPARE(window.view3d()->PropCount(), 0);
  }

  void ScreenshotShowsTheRenderedView() {
    scanreg::ui::MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTest::qWait(200);
    QTemporaryDir dir;
    const QString path = dir.filePath("shot.png");
    QVERIFY(window.SaveScreenshot(path));
    QImage image(path);
    QVERIFY(!image.isNull());
    // The 3D view's background is a dark gradient, not the widget's default grey: sample its centre.
    const QPoint centre = window.view3d()->mapTo(&window, window.view3d()->rect().center());
    const QColor c = image.pixelColor(centre);
    QVERIFY2(c.red() < 120 && c.blue() > c.red(), qPrintable(QString("centre colour %1").arg(c.name())));
  }
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  MainWindowTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "main_window_test.moc"
