// Radius search over a uniform grid of cubic cells, as a PCL search method (for PCL's normal and
// FPFH estimation on voxel samples). It returns what PCL's KdTreeFLANN returns — every point whose
// squared distance, summed in float as FLANN sums it, is below the squared radius, sorted by distance
// and then by index — so the descriptors are bit-identical; on evenly spaced samples it finds them
// in a few cells instead of descending a k-d tree for every query (issue 36). Internal to the library
// (PCL types): geometric_features.cc and its test include it.
#pragma once

#include <pcl/point_types.h>
#include <pcl/search/search.h>

#include <cstdint>
#include <vector>

namespace scanreg {

class CellSearch : public pcl::search::Search<pcl::PointXYZ> {
 public:
  // cell_m: the cells' side; queries are fastest with radii up to it.
  explicit CellSearch(double cell_m);

  void setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices = IndicesConstPtr()) override;
  int nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override;
  int radiusSearch(const pcl::PointXYZ& point, double radius, pcl::Indices& k_indices,
                   std::vector<float>& k_sqr_distances, unsigned int max_nn = 0) const override;

 private:
  struct Key {
    std::int32_t x = 0, y = 0, z = 0;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
    bool operator<(const Key& o) const { return x != o.x ? x < o.x : y != o.y ? y < o.y : z < o.z; }
  };
  Key KeyOf(float x, float y, float z) const;
  // The points of one cell: [begin, end) in order_, or an empty range.
  std::pair<std::uint32_t, std::uint32_t> Cell(const Key& key) const;
  std::size_t Slot(const Key& key) const;
  // Every point within the squared radius (float, FLANN's sum order), unsorted.
  void Collect(const pcl::PointXYZ& q, float radius2, int reach, std::vector<std::pair<float, int>>* out) const;

  double cell_m_;
  std::vector<int> order_;             // point indices, grouped by cell
  std::vector<Key> slot_key_;          // open addressing: cell key per slot
  std::vector<std::uint32_t> slot_begin_, slot_end_;  // its range in order_ (begin == end: empty slot)
  std::size_t mask_ = 0;
};

}  // namespace scanreg
