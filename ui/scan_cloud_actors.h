// Converts registered scans into VTK actors for the 3D view: one point cloud per scan, coloured
// per scan, by reflectance or by the scanner's colour, the scanner positions, the links of the scan tree and the targets.
// Level of detail: a cloud is decimated to at most `max_points_per_scan` points (0 = every valid
// point); full-resolution clouds are level-of-detail actors that draw a subset while the camera
// moves, so a project of millions of points stays interactive.
#pragma once

#include <vtkSmartPointer.h>

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/scan_previews.h"

class vtkActor;

namespace scanreg::ui {

// kScannerColour: each point's colour from the scanner's camera (Scan::colour); a scan without colour
// is drawn by reflectance, as grey.
enum class CloudColouring { kPerScan, kReflectance, kScannerColour };

struct ScanActors {
  std::vector<vtkSmartPointer<vtkActor>> clouds;       // per project scan; null when the scan is not drawn
  std::vector<vtkSmartPointer<vtkActor>> markers;      // scanner positions, per project scan (or null)
  vtkSmartPointer<vtkActor> links;                     // the tree's links; null without links
  vtkSmartPointer<vtkActor> targets;                   // targets seen in registered scans (issue 15); null without
  std::vector<vtkSmartPointer<vtkActor>> All() const;  // the non-null actors
};

// The world point drawn at VTK's origin: the first registered scan's position, so that UTM-sized
// coordinates keep their precision in VTK's float pipeline. Every actor of a scene uses it.
Eigen::Vector3d SceneOrigin(const io::Project& project);

// Draws the registered scans of `project` from their previews (previews[i] belongs to
// project.scans[i]; max_points_per_scan 0: every point of the preview).
ScanActors MakeScanActors(const std::vector<pipeline::ScanPreview>& previews, const io::Project& project,
                          CloudColouring colouring, std::size_t max_points_per_scan);

// A distinct colour per scan index (RGB in [0, 1]).
void ScanColour(int index, double rgb[3]);

}  // namespace scanreg::ui
