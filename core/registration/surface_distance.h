// Point-to-surface distances: how far each query point lies from a surface given by samples
// (point-to-plane to the PCA plane of the 8 nearest samples, so that the figure measures
// misalignment, not the sampling distance). Used for the overlap/RMS evidence of a pair and for
// the GUI's distance-coloured overlay.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace scanreg {

class PointIndex;

// For each query: its distance to the surface, metres, or a negative value when no surface sample
// lies within max_distance_m of it or the plane distance exceeds max_distance_m (not overlapping).
// `index` is built over `surface`. Parallel over the queries (OpenMP).
std::vector<double> PointToSurfaceDistances(const PointIndex& index, const std::vector<Eigen::Vector3d>& surface,
                                            const std::vector<Eigen::Vector3d>& queries, double max_distance_m);

}  // namespace scanreg
