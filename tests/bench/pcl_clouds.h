// A scan as a PCL cloud, and PCL's voxel grid: the first steps both PCL-built baselines share
// (pcl_baseline.cc, fpfh_ransac_baseline.cc).
#pragma once

#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/geometry/scan.h"

namespace scanreg::bench {

// The scan's valid points within max_range_m of the scanner, in the scanner's frame.
inline pcl::PointCloud<pcl::PointXYZ>::Ptr PclPoints(const Scan& scan, double max_range_m) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr raw(new pcl::PointCloud<pcl::PointXYZ>);
  raw->reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i] && scan.points[i].norm() <= max_range_m)
      raw->push_back(pcl::PointXYZ(scan.points[i].x(), scan.points[i].y(), scan.points[i].z()));
  return raw;
}

inline pcl::PointCloud<pcl::PointXYZ>::Ptr Downsample(const pcl::PointCloud<pcl::PointXYZ>::Ptr& in, double voxel_m) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr down(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(in);
  const float leaf = static_cast<float>(voxel_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(*down);
  return down;
}

}  // namespace scanreg::bench
