// The angular spacing of an organized scan's grid, shared by the target finders: they size their
// stencils in cells from a metric size and the range.
#pragma once

#include "core/geometry/scan.h"

namespace scanreg::georef {

// Median angle between the lines of sight of neighbouring cells (radians): along rows (*dc, from
// column to column) and along columns (*dr, from row to row). From the points' directions, so range
// noise does not widen it. 0 when the scan has too few neighbouring valid cells.
void AngularSteps(const Scan& scan, double* dc, double* dr);

}  // namespace scanreg::georef
