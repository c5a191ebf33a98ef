#include "ui/scan_cloud_actors.h"

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkLine.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkCellData.h>
#include <vtkPointData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkSphereSource.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>

namespace scanreg::ui {

void ScanColour(int index, double rgb[3]) {
  // Golden-angle hues: neighbouring indices get well separated colours.
  const double h = std::fmod(index * 0.618033988749895, 1.0) * 6.0;
  const double s = 0.75, v = 0.95;
  const int i = static_cast<int>(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  const double table[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
  for (int k = 0; k < 3; ++k) rgb[k] = table[i % 6][k];
}

std::vector<vtkSmartPointer<vtkActor>> MakeScanActors(const std::vector<Scan>& scans, const io::Project& project,
                                                      CloudColouring colouring, int max_points_per_scan) {
  std::vector<vtkSmartPointer<vtkActor>> actors;
  // Draw relative to the first registered scan's position so that UTM-sized coordinates keep
  // their precision in VTK's float pipeline.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < scans.size() && i < project.scans.size(); ++i) {
    if (project.scans[i].registered) {
      origin = project.scans[i].world_from_scan.translation();
      break;
    }
  }
  for (std::size_t i = 0; i < scans.size() && i < project.scans.size(); ++i) {
    if (!project.scans[i].registered) continue;
    const Scan& scan = scans[i];
    const Eigen::Isometry3d& pose = project.scans[i].world_from_scan;
    const std::size_t valid = scan.CountValid();
    const std::size_t step = std::max<std::size_t>(1, valid / std::max(1, max_points_per_scan));
    auto points = vtkSmartPointer<vtkPoints>::New();
    auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
    colours->SetNumberOfComponents(3);
    double rgb[3];
    ScanColour(static_cast<int>(i), rgb);
    std::size_t k = 0;
    for (std::size_t c = 0; c < scan.size(); ++c) {
      if (!scan.valid[c] || (k++ % step) != 0) continue;
      const Eigen::Vector3d p = pose * scan.points[c].cast<double>() - origin;
      points->InsertNextPoint(p.x(), p.y(), p.z());
      if (colouring == CloudColouring::kReflectance) {
        const unsigned char g = static_cast<unsigned char>(std::clamp(scan.reflectance[c], 0.0f, 1.0f) * 255);
        colours->InsertNextTuple3(g, g, g);
      } else {
        colours->InsertNextTuple3(rgb[0] * 255, rgb[1] * 255, rgb[2] * 255);
      }
    }
    auto verts = vtkSmartPointer<vtkCellArray>::New();
    for (vtkIdType v = 0; v < points->GetNumberOfPoints(); ++v) verts->InsertNextCell(1, &v);
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetVerts(verts);
    poly->GetPointData()->SetScalars(colours);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetPointSize(2);
    actors.push_back(actor);

    // The scanner position.
    auto sphere = vtkSmartPointer<vtkSphereSource>::New();
    const Eigen::Vector3d s = pose.translation() - origin;
    sphere->SetCenter(s.x(), s.y(), s.z());
    sphere->SetRadius(0.35);
    auto smapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    smapper->SetInputConnection(sphere->GetOutputPort());
    auto sactor = vtkSmartPointer<vtkActor>::New();
    sactor->SetMapper(smapper);
    sactor->GetProperty()->SetColor(rgb);
    actors.push_back(sactor);
  }
  // Links of the tree (ok: green, weak: orange), between scanner positions.
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
    const vtkIdType ia = points->InsertNextPoint(pa.data()), ib = points->InsertNextPoint(pb.data());
    const vtkIdType ids[2] = {ia, ib};
    lines->InsertNextCell(2, ids);
    if (l.status == io::LinkStatus::kOk) {
      colours->InsertNextTuple3(60, 220, 90);
    } else {
      colours->InsertNextTuple3(255, 160, 40);
    }
  }
  if (lines->GetNumberOfCells() > 0) {
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetLines(lines);
    poly->GetCellData()->SetScalars(colours);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetLineWidth(3);
    actors.push_back(actor);
  }
  return actors;
}

}  // namespace scanreg::ui
