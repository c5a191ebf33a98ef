// The merge dock (SPEC §4): the merge options (MergeOptions' defaults, then the user's last choice
// from QSettings), Merge on the worker thread (progress and Cancel in the status bar), the mesh
// kept on disk (merge::MeshSpill, in the project's cache folder) and previewed in the 3D view within
// a triangle budget (merge::PreviewMesh: simplified beyond it) with scans / mesh toggles, and Export
// of the whole mesh to PLY, OBJ or STL (also on the worker). The mesh is dropped when the
// registration changes (it would no longer match).
#pragma once

#include <QWidget>
#include <algorithm>
#include <any>
#include <memory>

#include "core/merge/merge_options.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_spill.h"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QTimer;
class QPushButton;
class QSpinBox;

namespace scanreg::ui {

class JobRunner;
class MainWindow;
class ScanScene;

class MergePanel : public QWidget {
  Q_OBJECT

 public:
  MergePanel(MainWindow* window, ScanScene* scene);

  merge::MergeOptions Options() const;
  // The user's choice (the voxel is no longer sized to the project).
  void SetOptions(const merge::MergeOptions& options);

  // Starts the merge of the registered scans; false when a job runs or nothing can be merged
  // (then a dialog names the next step). Completion: the window's jobs()->Succeeded / Failed.
  bool Run();
  // Writes the mesh (by extension: .ply, .obj, .stl) on the worker; false without a mesh.
  bool ExportMesh(const QString& path);
  // Whether the panel can be seen (its dock's tab in front); a stale estimate is counted on showing.
  void SetShown(bool shown);
  // The last merged mesh (on disk), or null.
  const merge::MeshSource* mesh() const { return mesh_.get(); }
  // What the 3D view shows of it: the mesh itself, or simplified to the preview budget; or null.
  const merge::Mesh* preview() const { return preview_.get(); }
  // The 3D view's budget for the merged mesh (triangles; default kPreviewTriangles), for the next merge.
  void SetPreviewTriangles(std::size_t triangles) { preview_triangles_ = std::max<std::size_t>(1, triangles); }
  static constexpr std::size_t kPreviewTriangles = 4'000'000;  // ~300 MB with VTK's copy

 private:
  struct MergedMesh;  // the merge job's result
  void OnMerged(const MergedMesh& merged);
  void ClearMesh();
  void ChooseExportFile();
  void SaveOptions() const;
  void UpdateButtons();
  // The estimate line, from the registered scans and the options: counted on estimator_'s worker
  // (seconds on a 100-station project) from a copy of the previews, only while the panel is shown
  // (else when it is next shown); a count whose inputs changed meanwhile is discarded and redone.
  void UpdateEstimate();
  void ShowError(const QString& title, const QString& message);

  MainWindow* window_;
  ScanScene* scene_;
  std::shared_ptr<const merge::MeshSpill> mesh_;  // immutable once merged: the export job reads it too
  std::shared_ptr<const merge::Mesh> preview_;
  std::size_t preview_triangles_ = kPreviewTriangles;
  QComboBox* method_ = nullptr;
  QDoubleSpinBox* voxel_mm_ = nullptr;
  QSpinBox* smooth_ = nullptr;
  QDoubleSpinBox* max_range_m_ = nullptr;
  QCheckBox* keep_pieces_ = nullptr;
  QCheckBox* fill_holes_ = nullptr;
  QCheckBox* keep_moving_ = nullptr;
  QCheckBox* show_scans_ = nullptr;
  QCheckBox* show_mesh_ = nullptr;
  QPushButton* run_ = nullptr;
  QPushButton* export_ = nullptr;
  QLabel* summary_ = nullptr;
  QLabel* estimate_ = nullptr;
  QTimer* estimate_timer_ = nullptr;
  JobRunner* estimator_ = nullptr;
  int estimate_generation_ = 0;   // bumped whenever what the estimate depends on changes
  bool estimate_again_ = false;   // count again when the running count ends
  bool shown_ = true;            // SetShown
  bool estimate_stale_ = false;  // asked for while hidden
  // The voxel is sized to the project (pipeline::SizedMergeOptions) until the user chooses one; a
  // new project is sized again.
  bool voxel_chosen_ = false;
  double sized_sigma_m_ = 0;  // the range noise sized with the voxel (0: the default's)
};

}  // namespace scanreg::ui
