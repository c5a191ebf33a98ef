#include "ui/view_3d.h"

#include <QImage>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor.h>
#include <vtkAxesActor.h>
#include <vtkCamera.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkOrientationMarkerWidget.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkActorCollection.h>
#include <vtkRenderer.h>

namespace scanreg::ui {

View3d::View3d(QWidget* parent) : QWidget(parent) {
  widget_ = new QVTKOpenGLNativeWidget(this);
  render_window_ = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  widget_->setRenderWindow(render_window_);
  renderer_ = vtkSmartPointer<vtkRenderer>::New();
  renderer_->GradientBackgroundOn();
  renderer_->SetBackground(0.10, 0.11, 0.13);
  renderer_->SetBackground2(0.30, 0.33, 0.38);
  render_window_->AddRenderer(renderer_);

  auto axes = vtkSmartPointer<vtkAxesActor>::New();
  marker_ = vtkSmartPointer<vtkOrientationMarkerWidget>::New();
  marker_->SetOrientationMarker(axes);
  marker_->SetInteractor(widget_->interactor());
  marker_->SetViewport(0.0, 0.0, 0.18, 0.18);
  marker_->SetEnabled(1);
  marker_->InteractiveOff();

  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->addWidget(widget_);
}

View3d::~View3d() = default;

vtkRenderer* View3d::renderer() const { return renderer_; }

int View3d::PropCount() const { return renderer_->GetActors()->GetNumberOfItems(); }

void View3d::ResetCamera() {
  renderer_->ResetCamera();
  render_window_->Render();
}

void View3d::SetActors(const std::vector<vtkSmartPointer<vtkActor>>& actors, bool reset_camera) {
  renderer_->RemoveAllViewProps();
  for (const auto& a : actors) renderer_->AddActor(a);
  if (!reset_camera) {
    Render();
    return;
  }
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->SetPosition(-0.6, -1.0, 0.8);  // looking down the street from above, z up
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 0, 1);
  renderer_->ResetCamera();
  render_window_->Render();
}

void View3d::Render() { render_window_->Render(); }

QImage View3d::GrabImage() { return widget_->grabFramebuffer(); }

}  // namespace scanreg::ui
