// A nanoflann k-d tree over a vector of points (not copied: the vector must outlive the tree), for
// the merge's nearest-neighbour searches (point_normals, vertex_info). Never built over no point.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include <nanoflann.hpp>

namespace scanreg::merge {

struct PointTreeCloud {
  const std::vector<Eigen::Vector3f>* pts;
  std::size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(std::uint32_t i, std::size_t d) const { return (*pts)[i][static_cast<Eigen::Index>(d)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using PointTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointTreeCloud, float, std::uint32_t>,
                                        PointTreeCloud, 3, std::uint32_t>;

}  // namespace scanreg::merge
