// Nearest-neighbour index over a fixed 3D point set: a k-d tree (nanoflann, Debian's libnanoflann-dev)
// over a float copy of the points. Queries are const and thread-safe.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

namespace scanreg {

class PointIndex {
 public:
  explicit PointIndex(const std::vector<Eigen::Vector3d>& points);
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  std::size_t size() const { return size_; }
  // Memory held, bytes (about 28 per point).
  std::size_t Bytes() const;
  // Index of the nearest point within max_distance_m (-1 if none); squared distance in *d2.
  int Nearest(const Eigen::Vector3d& query, double max_distance_m, double* d2 = nullptr) const;
  // Indices of the k nearest points (fewer if the set is smaller), nearest first.
  std::vector<int> KNearest(const Eigen::Vector3d& query, int k) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t size_ = 0;
};

// Overlap of a child with a parent at a relative pose: the fraction of the child's samples (at most
// 2,000, evenly) with a parent point within distance_m. 0 without samples.
double SampleOverlap(const PointIndex& parent, const std::vector<Eigen::Vector3d>& child_samples,
                     const Eigen::Isometry3d& parent_from_child, double distance_m);
double SampleOverlap(const PointIndex& parent, const std::vector<Eigen::Vector3f>& child_samples,
                     const Eigen::Isometry3d& parent_from_child, double distance_m);

}  // namespace scanreg
