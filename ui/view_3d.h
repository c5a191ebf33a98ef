// The 3D view: a QVTKOpenGLNativeWidget with a renderer, an orientation marker and a grid.
#pragma once

#include <QWidget>
#include <vtkSmartPointer.h>

#include <vector>

class QVTKOpenGLNativeWidget;
class vtkActor;
class vtkGenericOpenGLRenderWindow;
class vtkOrientationMarkerWidget;
class vtkRenderer;

namespace scanreg::ui {

class View3d : public QWidget {
  Q_OBJECT

 public:
  explicit View3d(QWidget* parent = nullptr);
  ~View3d() override;

  vtkRenderer* renderer() const;
  QVTKOpenGLNativeWidget* vtkWidget() const { return widget_; }
  // Number of actors (clouds, meshes, markers) in the scene; the orientation marker is not one.
  int PropCount() const;
  void ResetCamera();
  // Replaces the scene's actors (clouds, markers, links, meshes); with reset_camera, frames them
  // looking down from above, z up (otherwise the camera stays where the user left it).
  void SetActors(const std::vector<vtkSmartPointer<vtkActor>>& actors, bool reset_camera = true);
  // Renders the scene again (after an actor's visibility or colour changed).
  void Render();
  // Grabs the rendered frame buffer as an image (empty on failure).
  QImage GrabImage();

 private:
  QVTKOpenGLNativeWidget* widget_ = nullptr;
  vtkSmartPointer<vtkGenericOpenGLRenderWindow> render_window_;
  vtkSmartPointer<vtkRenderer> renderer_;
  vtkSmartPointer<vtkOrientationMarkerWidget> marker_;
};

}  // namespace scanreg::ui
