// Voxel-grid downsampling: one point (the centroid) per occupied cube of side voxel_m.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg {

// The scan's points in double precision, scanner frame: the grid's valid cells in cell order, and
// for a cloud seen from several places (Scan::single_viewpoint false) then its listed points that
// repeat no point before them — what the steps that need no range image (dense ICP, the geometric
// features) work on.
std::vector<Eigen::Vector3d> ValidPoints(const Scan& scan);

// At most max_count of the points, taken at an even stride (all of them when max_count <= 0).
std::vector<Eigen::Vector3d> ThinEvenly(std::vector<Eigen::Vector3d> points, int max_count);
// The same of single-precision points, widened (only the kept ones are copied).
std::vector<Eigen::Vector3d> ThinEvenly(const std::vector<Eigen::Vector3f>& points, int max_count);

// Centroids of the points in each occupied voxel (cubes aligned to the frame's origin), in the order
// in which the voxels are first hit. voxel_m <= 0 returns the finite input points unchanged.
// Non-finite points are skipped.
std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points, double voxel_m);

// Points kept between uses in single precision (half the memory: ~4 um at 50 m from the scanner)
// and widened again for use.
std::vector<Eigen::Vector3f> ToFloat(const std::vector<Eigen::Vector3d>& points);
std::vector<Eigen::Vector3d> ToDouble(const std::vector<Eigen::Vector3f>& points);

}  // namespace scanreg
