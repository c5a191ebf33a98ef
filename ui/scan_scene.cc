#include "ui/scan_scene.h"

#include <vtkActor.h>
#include <vtkActorCollection.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkRenderer.h>

#include <algorithm>

#include "ui/mesh_actor.h"
#include "ui/view_3d.h"

namespace scanreg::ui {

namespace {

// Whether the drawing of `b` would be that of `a` (with the same points): the same scans, poses,
// registered flags and drawn links.
bool SameDrawing(const io::Project& a, const io::Project& b) {
  if (a.file != b.file || a.scans.size() != b.scans.size() || a.links.size() != b.links.size() ||
      a.targets.size() != b.targets.size())
    return false;
  for (std::size_t i = 0; i < a.scans.size(); ++i) {
    const io::ProjectScan &x = a.scans[i], &y = b.scans[i];
    if (x.name != y.name || x.registered != y.registered || x.world_from_scan.matrix() != y.world_from_scan.matrix())
      return false;
  }
  for (std::size_t i = 0; i < a.links.size(); ++i) {
    const io::LinkRecord &x = a.links[i], &y = b.links[i];
    if (x.parent != y.parent || x.child != y.child || x.status != y.status) return false;
  }
  return true;
}

}  // namespace

ScanScene::ScanScene(View3d* view, QObject* parent) : QObject(parent), view_(view) {}

void ScanScene::ScansReplaced(bool new_project) {
  points_replaced_ = true;
  new_project_ |= new_project;
}

void ScanScene::ShowScans(const io::Project& project, const std::vector<pipeline::ScanPreview>& scans) {
  // Nothing to redraw after a job that changed neither (an export, a merge): no GUI-thread stall;
  // unless another view (the pair overlay) has replaced the scene's actors meanwhile.
  if (!points_replaced_ && scans_ == &scans && SameDrawing(project, project_) && ViewShowsScene()) return;
  // Frame the scene again when it is another one: another project, or the registration moved the
  // origin (the first registered scan).
  const bool reframe = new_project_ || scans_ == nullptr || SceneOrigin(project) != SceneOrigin(project_);
  project_ = project;
  scans_ = &scans;
  points_replaced_ = new_project_ = false;
  Rebuild(reframe);
}

void ScanScene::SetMesh(std::shared_ptr<const merge::Mesh> mesh) {
  mesh_ = std::move(mesh);
  Rebuild(false);
}

void ScanScene::SetColouring(CloudColouring colouring) {
  if (colouring == colouring_) return;
  colouring_ = colouring;
  Rebuild(false);
}

void ScanScene::SetFullResolution(bool full) {
  if (full == full_resolution_) return;
  full_resolution_ = full;
  Rebuild(false);
}

void ScanScene::SetDecimatedPoints(std::size_t points) {
  decimated_points_ = std::max<std::size_t>(1, points);
  Rebuild(false);
}

void ScanScene::SetScanVisible(const QString& name, bool visible) {
  if (visible) {
    hidden_.remove(name);
  } else {
    hidden_.insert(name);
  }
  ApplyVisibility();
}

void ScanScene::SetShowScans(bool show) {
  show_scans_ = show;
  ApplyVisibility();
}

void ScanScene::SetShowMesh(bool show) {
  show_mesh_ = show;
  ApplyVisibility();
}

vtkActor* ScanScene::CloudActor(const QString& name) const {
  const int i = project_.FindScan(name.toStdString());
  return i >= 0 && i < static_cast<int>(actors_.clouds.size()) ? actors_.clouds[i].Get() : nullptr;
}

bool ScanScene::ViewShowsScene() const {
  if (view_->PropCount() != shown_count_) return false;
  return !first_shown_ || view_->renderer()->GetActors()->IsItemPresent(first_shown_) != 0;
}

vtkActor* ScanScene::MeshActor() const { return mesh_actor_; }

std::size_t ScanScene::DrawnPoints() const {
  std::size_t n = 0;
  for (const auto& a : actors_.clouds)
    if (a) n += static_cast<std::size_t>(vtkPolyData::SafeDownCast(a->GetMapper()->GetInput())->GetNumberOfPoints());
  return n;
}

void ScanScene::Rebuild(bool reset_camera) {
  if (scans_ == nullptr) return;
  std::size_t per_scan = 0;  // full resolution
  if (!full_resolution_) {
    std::size_t drawn = 0;
    for (const io::ProjectScan& s : project_.scans) drawn += s.registered;
    per_scan = decimated_points_ / std::max<std::size_t>(1, drawn);
  }
  actors_ = MakeScanActors(*scans_, project_, colouring_, per_scan);
  mesh_actor_ = mesh_ ? MakeMeshActor(*mesh_, SceneOrigin(project_), colouring_ == CloudColouring::kScannerColour)
                      : nullptr;
  std::vector<vtkSmartPointer<vtkActor>> all = actors_.All();
  if (mesh_actor_) all.push_back(mesh_actor_);
  first_shown_ = all.empty() ? nullptr : all.front();
  shown_count_ = static_cast<int>(all.size());
  SetVisibilities();
  view_->SetActors(all, reset_camera);
}

void ScanScene::ApplyVisibility() {
  SetVisibilities();
  view_->Render();
}

void ScanScene::SetVisibilities() {
  for (std::size_t i = 0; i < project_.scans.size() && i < actors_.clouds.size(); ++i) {
    const bool visible = show_scans_ && !hidden_.contains(QString::fromStdString(project_.scans[i].name));
    for (const auto* group : {&actors_.clouds, &actors_.markers})
      if ((*group)[i]) (*group)[i]->SetVisibility(visible);
  }
  if (actors_.links) actors_.links->SetVisibility(show_scans_);
  if (actors_.targets) actors_.targets->SetVisibility(show_scans_);
  if (mesh_actor_) mesh_actor_->SetVisibility(show_mesh_);
}

}  // namespace scanreg::ui
