#include "ui/main_window.h"

#include <QAction>
#include <QApplication>
#include <QMenuBar>
#include <QMessageBox>
#include <QPainter>
#include <QStatusBar>
#include <QVTKOpenGLNativeWidget.h>

#include "ui/view_3d.h"

namespace scanreg::ui {

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(tr("scanreg — terrestrial laser scan registration"));
  setObjectName("MainWindow");
  view3d_ = new View3d(this);
  view3d_->setObjectName("View3d");
  setCentralWidget(view3d_);
  CreateMenus();
  statusBar()->showMessage(tr("No project open."));
  resize(1280, 800);
}

MainWindow::~MainWindow() = default;

void MainWindow::CreateMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->setObjectName("FileMenu");
  QAction* open = file->addAction(tr("&Open project…"));
  open->setShortcut(QKeySequence::Open);
  open->setEnabled(false);  // project loading arrives with the desktop-application issue
  open->setToolTip(tr("Project loading arrives in a later version"));
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), view3d_, &View3d::ResetCamera);

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&About scanreg"), this, &MainWindow::ShowAbout);
}

void MainWindow::ShowAbout() {
  QMessageBox::about(this, tr("About scanreg"),
                     tr("<b>scanreg</b> %1<br>Registration of terrestrial laser scans.")
                         .arg(QApplication::applicationVersion()));
}

bool MainWindow::SaveScreenshot(const QString& path) {
  QImage image = grab().toImage();
  // QWidget::grab() does not capture the OpenGL frame buffer; paint the VTK frame on top.
  const QImage frame = view3d_->GrabImage();
  if (!frame.isNull()) {
    QPainter painter(&image);
    const QPoint origin = view3d_->vtkWidget()->mapTo(this, QPoint(0, 0));
    painter.drawImage(QRect(origin, view3d_->vtkWidget()->size()), frame);
  }
  return !image.isNull() && image.save(path);
}

}  // namespace scanreg::ui
