// The scanreg main window: menus, a 3D view and a status bar. Panels (scan list, panorama,
// confusion matrix, network, pair, merge, log) arrive with the desktop-application issue.
#pragma once

#include <QMainWindow>

class QAction;
class QVTKOpenGLNativeWidget;

namespace scanreg::ui {

class View3d;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  View3d* view3d() const { return view3d_; }
  // Renders the window (including the VTK view) into a PNG; returns false on failure.
  bool SaveScreenshot(const QString& path);

 private:
  void CreateMenus();
  void ShowAbout();

  View3d* view3d_ = nullptr;
};

}  // namespace scanreg::ui
