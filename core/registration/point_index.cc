#include "core/registration/point_index.h"

#include <cmath>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/registration/voxel_filter.h"

namespace scanreg {

struct PointIndex::Impl {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  // Coordinates are stored as float relative to the centroid, to keep precision far from the origin.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

PointIndex::PointIndex(const std::vector<Eigen::Vector3d>& points) : impl_(std::make_unique<Impl>()), size_(points.size()) {
  if (points.empty()) return;
  for (const auto& p : points) impl_->origin += p;
  impl_->origin /= static_cast<double>(points.size());
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f q = (points[i] - impl_->origin).cast<float>();
    (*cloud)[i] = pcl::PointXYZ(q.x(), q.y(), q.z());
  }
  impl_->tree.setInputCloud(cloud);
}

PointIndex::~PointIndex() = default;

int PointIndex::Nearest(const Eigen::Vector3d& query, double max_distance_m, double* d2) const {
  if (size_ == 0) return -1;
  const Eigen::Vector3f q = (query - impl_->origin).cast<float>();
  if (!q.allFinite()) return -1;
  pcl::Indices idx(1);
  std::vector<float> dist(1);
  // A radius-bounded search (FLANN's k-nearest within a radius): an unbounded nearest search from
  // far outside the cloud visits most of the tree (ICP from a wrong start pose took seconds).
  if (!std::isfinite(max_distance_m)) {
    if (impl_->tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, idx, dist) < 1) return -1;
  } else if (impl_->tree.radiusSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), max_distance_m, idx, dist, 1) < 1) {
    return -1;
  }
  if (dist[0] > max_distance_m * max_distance_m) return -1;
  if (d2) *d2 = dist[0];
  return idx[0];
}

std::vector<int> PointIndex::KNearest(const Eigen::Vector3d& query, int k) const {
  if (size_ == 0 || k <= 0) return {};
  const Eigen::Vector3f q = (query - impl_->origin).cast<float>();
  pcl::Indices idx(k);
  std::vector<float> dist(k);
  const int found = impl_->tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), k, idx, dist);
  return std::vector<int>(idx.begin(), idx.begin() + std::max(found, 0));
}

double SampleOverlap(const PointIndex& parent, const std::vector<Eigen::Vector3d>& child_samples,
                     const Eigen::Isometry3d& parent_from_child, double distance_m) {
  const std::vector<Eigen::Vector3d> pts = ThinEvenly(child_samples, 2000);
  if (pts.empty()) return 0.0;
  int near = 0;
  for (const Eigen::Vector3d& p : pts) near += parent.Nearest(parent_from_child * p, distance_m) >= 0;
  return double(near) / double(pts.size());
}

}  // namespace scanreg
