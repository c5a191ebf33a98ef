// Converts registered scans into VTK actors for the 3D view: one decimated point cloud per scan
// (level of detail: at most `max_points_per_scan`), coloured per scan or by reflectance, the
// scanner positions and the links of the scan tree.
#pragma once

#include <vtkSmartPointer.h>

#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"

class vtkActor;

namespace scanreg::ui {

enum class CloudColouring { kPerScan, kReflectance };

std::vector<vtkSmartPointer<vtkActor>> MakeScanActors(const std::vector<Scan>& scans, const io::Project& project,
                                                      CloudColouring colouring, int max_points_per_scan);

// A distinct colour per scan index (RGB in [0, 1]).
void ScanColour(int index, double rgb[3]);

}  // namespace scanreg::ui
