// Free-space consistency of two scans at a relative pose (after Huber & Hebert 2003, "Fully
// automatic registration of multiple 3D data sets"): a scanner's ray that returned from range R
// passed through everything nearer. A point of the other scan that lands in that free space
// contradicts the pose. Correct poses have almost no such points; wrong poses that still overlap
// well geometrically (a street shifted by one building on repeated façades) have many, because
// the unique objects (cars, posts, trees) end up where the observer saw through.
#pragma once

#include <Eigen/Geometry>

#include "core/geometry/scan.h"

namespace scanreg {

struct FreeSpaceResult {
  int tested = 0;      // samples of `other` that project onto a valid cell of `observer`
  int violations = 0;  // of those, samples nearer than the observer's surface by more than the margin
  double fraction() const { return tested ? double(violations) / tested : 0.0; }
};

// Samples `other`'s valid points (evenly, at most max_samples), maps them into the observer's frame
// and its panoramic grid (needs observer.angles; returns tested = 0 without them). A sample is a
// violation when even the nearest return in the 3x3 cells around its projection is farther than
// the sample's range + margin_m (the 3x3 minimum spares depth edges and mixed pixels).
FreeSpaceResult FreeSpaceViolations(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                                    double margin_m, int max_samples = 20000);

}  // namespace scanreg
