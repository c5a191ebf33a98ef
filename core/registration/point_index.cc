#include "core/registration/point_index.h"

#include <cmath>
#include <limits>

#include <nanoflann.hpp>

#include "core/registration/voxel_filter.h"

namespace scanreg {
namespace {

// The points as nanoflann reads them: float, relative to the centroid (precision far from the origin).
struct Cloud {
  std::vector<Eigen::Vector3f> pts;
  std::size_t kdtree_get_point_count() const { return pts.size(); }
  float kdtree_get_pt(std::uint32_t i, std::size_t d) const { return pts[i][static_cast<Eigen::Index>(d)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud, float, std::uint32_t>,
                                                 Cloud, 3, std::uint32_t>;

// The nearest point closer than a bound (squared distance): the search prunes every branch beyond
// the best found so far, and beyond the bound from the start.
struct NearestWithin {
  float worst;
  std::uint32_t index = 0;
  bool found = false;
  explicit NearestWithin(float bound2) : worst(bound2) {}
  float worstDist() const { return worst; }
  bool addPoint(float d2, std::uint32_t i) {  // nanoflann offers every point of a leaf under the bound it had on entering it
    if (!(d2 < worst)) return true;
    worst = d2;
    index = i;
    found = true;
    return true;
  }
  bool full() const { return found; }
};

}  // namespace

struct PointIndex::Impl {
  Cloud cloud;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::unique_ptr<Tree> tree;  // over `cloud`, which must not move while it lives
};

PointIndex::PointIndex(const std::vector<Eigen::Vector3d>& points) : impl_(std::make_unique<Impl>()), size_(points.size()) {
  if (points.empty()) return;
  for (const auto& p : points) impl_->origin += p;
  impl_->origin /= static_cast<double>(points.size());
  impl_->cloud.pts.reserve(points.size());
  for (const Eigen::Vector3d& p : points) impl_->cloud.pts.push_back((p - impl_->origin).cast<float>());
  impl_->tree = std::make_unique<Tree>(3, impl_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
}

PointIndex::~PointIndex() = default;

std::size_t PointIndex::Bytes() const {
  // The float copy, nanoflann's index permutation and its nodes (measured: 28 bytes a point in all).
  return size_ * (sizeof(Eigen::Vector3f) + sizeof(std::uint32_t) + 12);
}

int PointIndex::Nearest(const Eigen::Vector3d& query, double max_distance_m, double* d2) const {
  if (size_ == 0) return -1;
  const Eigen::Vector3f q = (query - impl_->origin).cast<float>();
  if (!q.allFinite()) return -1;
  // Bounded by the radius: an unbounded nearest search from far outside the cloud visits most of
  // the tree (ICP from a wrong start pose took seconds).
  const float bound = std::isfinite(max_distance_m) ? static_cast<float>(max_distance_m * max_distance_m)
                                                    : std::numeric_limits<float>::max();
  NearestWithin result(bound);
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams(32, 0.0f, false));
  if (!result.found || result.worst > max_distance_m * max_distance_m) return -1;
  if (d2) *d2 = result.worst;
  return static_cast<int>(result.index);
}

std::vector<int> PointIndex::KNearest(const Eigen::Vector3d& query, int k) const {
  if (size_ == 0 || k <= 0) return {};
  const Eigen::Vector3f q = (query - impl_->origin).cast<float>();
  if (!q.allFinite()) return {};
  const std::size_t want = std::min<std::size_t>(static_cast<std::size_t>(k), size_);
  std::vector<std::uint32_t> idx(want);
  std::vector<float> dist(want);
  nanoflann::KNNResultSet<float, std::uint32_t, std::size_t> result(want);
  result.init(idx.data(), dist.data());
  impl_->tree->findNeighbors(result, q.data(), nanoflann::SearchParams());
  return std::vector<int>(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(result.size()));
}
namespace {

// The samples ThinEvenly(child, 2000) would keep, without copying them.
template <class Point>
double Overlap(const PointIndex& parent, const std::vector<Point>& child, const Eigen::Isometry3d& parent_from_child,
               double distance_m) {
  constexpr int kMax = 2000;
  if (child.empty()) return 0.0;
  const int count = int(std::min<std::size_t>(child.size(), kMax));
  const double stride = double(child.size()) / count;
  int near = 0;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p = child[static_cast<std::size_t>(i * stride)].template cast<double>();
    near += parent.Nearest(parent_from_child * p, distance_m) >= 0;
  }
  return double(near) / double(count);
}

}  // namespace

double SampleOverlap(const PointIndex& parent, const std::vector<Eigen::Vector3d>& child_samples,
                     const Eigen::Isometry3d& parent_from_child, double distance_m) {
  return Overlap(parent, child_samples, parent_from_child, distance_m);
}

double SampleOverlap(const PointIndex& parent, const std::vector<Eigen::Vector3f>& child_samples,
                     const Eigen::Isometry3d& parent_from_child, double distance_m) {
  return Overlap(parent, child_samples, parent_from_child, distance_m);
}

}  // namespace scanreg
