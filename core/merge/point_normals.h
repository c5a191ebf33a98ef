// Normals of points without grid neighbours (a scan's listed points, Scan::list_points) for the
// merge (issue 34, item 2): such a point has no adjacent cells to form triangles with, so it enters
// the field as a small disc on the plane of its nearest neighbours.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/common/progress.h"

namespace scanreg::merge {

struct PointNormals {
  // Per point: unit normal, or zero where the neighbours span no plane (too few, or too far apart).
  std::vector<Eigen::Vector3f> normal;
  float spacing = 0.0f;  // median distance of a point to its nearest neighbour; 0 without neighbours
};

// The plane of each point's k nearest neighbours among `points` (least squares, PCA). Orientation:
// towards the sensor that saw the point where `eyes` holds one position per point (a cloud with
// per-point sensor positions), towards eyes[0] where it holds one (the scanner); otherwise (empty)
// grown over the
// k-nearest-neighbour graph, the most parallel neighbour first (Hoppe et al. 1992's minimum
// spanning tree), from the point nearest `fallback_eye` facing it — for a cloud seen from several
// places, its origin: the side the surfaces are seen from carries over to the points beside them.
// A point whose k-th neighbour lies beyond 8 x the median of that distance is isolated: zero normal.
// Empty result when cancelled.
PointNormals EstimatePointNormals(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& eyes,
                                  const Eigen::Vector3f& fallback_eye, int k, const CancelToken& cancel);

}  // namespace scanreg::merge
