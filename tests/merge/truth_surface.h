// The noise-free surface of a simulated project, to measure a merged surface (or the input points)
// against the truth (issue 35): the same stations simulated with every noise source off.
#pragma once

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg::test {

class TruthSurface {
 public:
  // The returns within max_range_m of their scanner, at the scans' reference poses.
  TruthSurface(const std::vector<Scan>& noise_free, double max_range_m);

  // Distance of p to the plane fitted to its 12 nearest noise-free points (the nearest one's
  // distance when that lies farther than 0.3 m: no true surface there).
  double Distance(const Eigen::Vector3d& p) const;

  // The share of the true surface (every 10th noise-free point) with no vertex within `radius`.
  double Holes(const std::vector<Eigen::Vector3d>& vertices, double radius) const;

 private:
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree_;
};

struct Accuracy {
  double rms_m = 0.0;     // over the points within 10 cm of the truth
  double spurious = 0.0;  // share farther than 10 cm
};

Accuracy Measure(const TruthSurface& truth, const std::vector<Eigen::Vector3d>& points);

}  // namespace scanreg::test
