// What the 3D view shows: the registered scans (colour per scan or by reflectance, per-scan
// visibility, decimated or full resolution), the scanner positions and links, and the merged mesh;
// scans and mesh can each be switched off. The main window calls ShowScans whenever its project
// changes, and ScansReplaced before that when the points are new; the scene keeps a pointer to the
// scans until the next call (GUI thread only).
#pragma once

#include <QObject>
#include <QSet>
#include <QString>
#include <memory>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/merge/mesh.h"
#include "ui/scan_cloud_actors.h"

namespace scanreg::ui {

class View3d;

class ScanScene : public QObject {
  Q_OBJECT

 public:
  // Points drawn in all (the budget is shared among the scans) while the display is decimated.
  static constexpr std::size_t kDecimatedPoints = 800000;
  void SetDecimatedPoints(std::size_t points);
  std::size_t decimatedPoints() const { return decimated_points_; }

  ScanScene(View3d* view, QObject* parent);

  void ShowScans(const io::Project& project, const std::vector<pipeline::ScanPreview>& scans);
  // The scans' points were replaced (scans added, or another project: then the camera frames it
  // again): the next ShowScans rebuilds the clouds.
  void ScansReplaced(bool new_project);
  void SetMesh(std::shared_ptr<const merge::Mesh> mesh);  // null: no mesh
  void SetColouring(CloudColouring colouring);
  void SetFullResolution(bool full);
  void SetScanVisible(const QString& name, bool visible);
  void SetShowScans(bool show);
  void SetShowMesh(bool show);

  CloudColouring colouring() const { return colouring_; }
  bool fullResolution() const { return full_resolution_; }
  bool showScans() const { return show_scans_; }
  bool showMesh() const { return show_mesh_; }
  // The drawn actors (null when the scan is not drawn / there is no mesh), for tests.
  vtkActor* CloudActor(const QString& name) const;
  vtkActor* MeshActor() const;
  // Points held by the drawn clouds.
  std::size_t DrawnPoints() const;

 private:
  void Rebuild(bool reset_camera);
  void ApplyVisibility();  // sets the actors' visibility and renders
  void SetVisibilities();
  bool ViewShowsScene() const;  // the view still holds the actors this scene gave it

  View3d* view_;
  io::Project project_;
  const std::vector<pipeline::ScanPreview>* scans_ = nullptr;
  bool points_replaced_ = false;
  bool new_project_ = false;
  std::shared_ptr<const merge::Mesh> mesh_;
  ScanActors actors_;
  vtkSmartPointer<vtkActor> mesh_actor_;
  vtkSmartPointer<vtkActor> first_shown_;  // of the actors given to the view
  int shown_count_ = 0;
  QSet<QString> hidden_;
  CloudColouring colouring_ = CloudColouring::kPerScan;
  bool full_resolution_ = false;
  std::size_t decimated_points_ = kDecimatedPoints;
  bool show_scans_ = true;
  bool show_mesh_ = true;
};

}  // namespace scanreg::ui
