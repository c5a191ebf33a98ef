// The pair panel's 3D preview: both scans of a pair in the parent's frame, each point coloured by
// its distance to the other scan's surface (blue at 0 through red at the scale's maximum), points
// outside the overlap in grey, with a colour scale and its legend.
#pragma once

#include <vtkSmartPointer.h>

#include <vector>

#include "core/pipeline/inspect_pair.h"

class vtkActor;
class vtkScalarBarActor;

namespace scanreg::ui {

struct DistanceOverlay {
  std::vector<vtkSmartPointer<vtkActor>> clouds;  // parent, child
  vtkSmartPointer<vtkScalarBarActor> legend;      // the colour scale, in millimetres
};

// scale_max_m: distance drawn red (and beyond), metres.
DistanceOverlay MakeDistanceOverlay(const pipeline::PairInspection& pair, double scale_max_m);

}  // namespace scanreg::ui
