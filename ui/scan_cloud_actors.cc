#include "ui/scan_cloud_actors.h"

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkLODActor.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkSphereSource.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace scanreg::ui {
namespace {

// Points drawn by a full-resolution cloud while the camera moves.
constexpr int kInteractivePointsPerScan = 60000;

// A well-mixed hash of a cell index (splitmix64's finaliser).
std::uint64_t MixIndex(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// About one point in `step`, spread without a pattern (every step-th cell of the row-major grid
// would draw stripes), at most max_points; every point when max_points is 0. Indices below
// scan.size() are grid cells, the others scan.size() + the index of a list point.
std::vector<std::size_t> SampleCells(const Scan& scan, std::size_t max_points) {
  const std::size_t valid = scan.CountPoints();
  // 3 % fewer than the budget on average, so that the random count stays below it.
  const double keep = max_points == 0 ? 1.0 : std::min(1.0, 0.97 * max_points / std::max<double>(1.0, valid));
  const std::uint64_t threshold = keep >= 1.0 ? ~0ULL : static_cast<std::uint64_t>(keep * 18446744073709551615.0);
  std::vector<std::size_t> cells;
  cells.reserve(static_cast<std::size_t>(keep * valid) + 16);
  const std::size_t all = scan.size() + scan.list_points.size();
  for (std::size_t i = 0; i < all; ++i) {
    if ((i < scan.size() && !scan.valid[i]) || MixIndex(i) > threshold) continue;
    if (max_points != 0 && cells.size() == max_points) break;
    cells.push_back(i);
  }
  return cells;
}

// The sampled valid points as vertices with colours.
vtkSmartPointer<vtkPolyDataMapper> MakeCloudMapper(const Scan& scan, const Eigen::Isometry3d& pose,
                                                   const Eigen::Vector3d& origin, CloudColouring colouring,
                                                   const double rgb[3], std::size_t max_points) {
  const std::vector<std::size_t> cells = SampleCells(scan, max_points);
  const std::size_t n = cells.size();
  auto xyz = vtkSmartPointer<vtkFloatArray>::New();
  xyz->SetNumberOfComponents(3);
  xyz->SetNumberOfTuples(static_cast<vtkIdType>(n));
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(static_cast<vtkIdType>(n));
  float* p = xyz->WritePointer(0, static_cast<vtkIdType>(3 * n));
  unsigned char* c = colours->WritePointer(0, static_cast<vtkIdType>(3 * n));
  const Eigen::Isometry3d shifted = Eigen::Translation3d(-origin) * pose;
  const bool by_colour = colouring == CloudColouring::kScannerColour && scan.HasColour();
  const bool by_scan = colouring == CloudColouring::kPerScan;
  for (std::size_t out = 0; out < n; ++out) {
    const std::size_t i = cells[out];
    const bool on_grid = i < scan.size();
    const Eigen::Vector3f& point = on_grid ? scan.points[i] : scan.list_points[i - scan.size()];
    const float reflectance = on_grid ? scan.reflectance[i] : scan.list_reflectance[i - scan.size()];
    const Eigen::Vector3d q = shifted * point.cast<double>();
    for (int d = 0; d < 3; ++d) p[3 * out + d] = static_cast<float>(q[d]);
    if (by_colour) {
      const Rgb& own = on_grid ? scan.colour[i] : scan.list_colour[i - scan.size()];
      for (int d = 0; d < 3; ++d) c[3 * out + d] = own[d];
    } else {
      for (int d = 0; d < 3; ++d) {
        c[3 * out + d] = by_scan ? static_cast<unsigned char>(rgb[d] * 255)
                                 : static_cast<unsigned char>(std::clamp(reflectance, 0.0f, 1.0f) * 255);
      }
    }
  }
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetData(xyz);
  auto ids = vtkSmartPointer<vtkIdTypeArray>::New();
  ids->SetNumberOfValues(static_cast<vtkIdType>(n));
  for (vtkIdType v = 0; v < static_cast<vtkIdType>(n); ++v) ids->SetValue(v, v);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(1, ids);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(verts);
  poly->GetPointData()->SetScalars(colours);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(poly);
  return mapper;
}

// Full resolution (max_points 0): a level-of-detail actor that draws a decimated copy while the
// camera moves. Its lower level is our own mapper (VTK's default ones copy the mapper's deprecated
// shader settings and flood the log with warnings).
vtkSmartPointer<vtkActor> MakeCloudActor(const Scan& scan, const Eigen::Isometry3d& pose, const Eigen::Vector3d& origin,
                                         CloudColouring colouring, const double rgb[3], std::size_t max_points) {
  vtkSmartPointer<vtkActor> actor;
  if (max_points == 0) {
    auto lod = vtkSmartPointer<vtkLODActor>::New();
    lod->AddLODMapper(MakeCloudMapper(scan, pose, origin, colouring, rgb, kInteractivePointsPerScan));
    actor = lod;
  } else {
    actor = vtkSmartPointer<vtkActor>::New();
  }
  actor->SetMapper(MakeCloudMapper(scan, pose, origin, colouring, rgb, max_points));
  actor->GetProperty()->SetPointSize(2);
  return actor;
}

vtkSmartPointer<vtkActor> MakeMarkerActor(const Eigen::Vector3d& centre, const double rgb[3]) {
  auto sphere = vtkSmartPointer<vtkSphereSource>::New();
  sphere->SetCenter(centre.x(), centre.y(), centre.z());
  sphere->SetRadius(0.35);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputConnection(sphere->GetOutputPort());
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
  return actor;
}

// The targets seen in the registered scans (issue 15), where their scan's pose puts them: white
// round points drawn at a fixed screen size so that a 145 mm sphere shows at street scale; red when
// the observation's residual after the adjustment exceeds 1 cm.
vtkSmartPointer<vtkActor> MakeTargetsActor(const io::Project& project, const Eigen::Vector3d& origin) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetNumberOfComponents(3);
  for (const io::TargetRecord& t : project.targets) {
    const int s = project.FindScan(t.scan);
    if (s < 0 || !project.scans[s].registered) continue;
    const Eigen::Vector3d p = project.scans[s].world_from_scan * t.center - origin;
    const vtkIdType id = points->InsertNextPoint(p.data());
    cells->InsertNextCell(1, &id);
    const bool off = t.residual_m > 0.01;
    const unsigned char rgb[3] = {255, static_cast<unsigned char>(off ? 60 : 255), static_cast<unsigned char>(off ? 60 : 255)};
    colours->InsertNextTypedTuple(rgb);
  }
  if (points->GetNumberOfPoints() == 0) return nullptr;
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(cells);
  poly->GetPointData()->SetScalars(colours);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(poly);
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetPointSize(12);
  actor->GetProperty()->SetRenderPointsAsSpheres(true);
  return actor;
}

// Links of the tree (ok: green, weak: orange), between scanner positions.
vtkSmartPointer<vtkActor> MakeLinksActor(const io::Project& project, const Eigen::Vector3d& origin) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetNumberOfComponents(3);
  for (const io::LinkRecord& l : project.links) {
    if (l.status == io::LinkStatus::kFailed) continue;
    const int a = project.FindScan(l.parent), b = project.FindScan(l.child);
    if (a < 0 || b < 0 || !project.scans[a].registered || !project.scans[b].registered) continue;
    const Eigen::Vector3d pa = project.scans[a].world_from_scan.translation() - origin;
    const Eigen::Vector3d pb = project.scans[b].world_from_scan.translation() - origin;
    const vtkIdType ids[2] = {points->InsertNextPoint(pa.data()), points->InsertNextPoint(pb.data())};
    lines->InsertNextCell(2, ids);
    if (l.status == io::LinkStatus::kOk) {
      colours->InsertNextTuple3(60, 220, 90);
    } else {
      colours->InsertNextTuple3(255, 160, 40);
    }
  }
  if (lines->GetNumberOfCells() == 0) return nullptr;
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetLines(lines);
  poly->GetCellData()->SetScalars(colours);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(poly);
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetLineWidth(3);
  return actor;
}

}  // namespace

void ScanColour(int index, double rgb[3]) {
  // Golden-angle hues: neighbouring indices get well separated colours.
  const double h = std::fmod(index * 0.618033988749895, 1.0) * 6.0;
  const double s = 0.75, v = 0.95;
  const int i = static_cast<int>(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  const double table[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
  for (int k = 0; k < 3; ++k) rgb[k] = table[i % 6][k];
}

std::vector<vtkSmartPointer<vtkActor>> ScanActors::All() const {
  std::vector<vtkSmartPointer<vtkActor>> all;
  for (const auto* group : {&clouds, &markers})
    for (const auto& a : *group)
      if (a) all.push_back(a);
  if (links) all.push_back(links);
  if (targets) all.push_back(targets);
  return all;
}

Eigen::Vector3d SceneOrigin(const io::Project& project) {
  for (const io::ProjectScan& s : project.scans)
    if (s.registered) return s.world_from_scan.translation();
  return Eigen::Vector3d::Zero();
}

ScanActors MakeScanActors(const std::vector<pipeline::ScanPreview>& previews, const io::Project& project,
                          CloudColouring colouring, std::size_t max_points_per_scan) {
  ScanActors actors;
  actors.clouds.resize(project.scans.size());
  actors.markers.resize(project.scans.size());
  const Eigen::Vector3d origin = SceneOrigin(project);
  for (std::size_t i = 0; i < previews.size() && i < project.scans.size(); ++i) {
    if (!project.scans[i].registered) continue;
    const Eigen::Isometry3d& pose = project.scans[i].world_from_scan;
    double rgb[3];
    ScanColour(static_cast<int>(i), rgb);
    actors.clouds[i] = MakeCloudActor(previews[i].scan, pose, origin, colouring, rgb, max_points_per_scan);
    actors.markers[i] = MakeMarkerActor(pose.translation() - origin, rgb);
  }
  actors.links = MakeLinksActor(project, origin);
  actors.targets = MakeTargetsActor(project, origin);
  return actors;
}

}  // namespace scanreg::ui
