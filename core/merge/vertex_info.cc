#include "core/merge/vertex_info.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/merge/point_tree.h"

namespace scanreg::merge {

namespace {

// The point of `tree` nearest x: its index and squared distance (false: the tree is empty).
bool Nearest(const PointTree& tree, const Eigen::Vector3f& x, std::uint32_t* index, float* d2) {
  nanoflann::KNNResultSet<float, std::uint32_t, std::size_t> result(1);
  result.init(index, d2);
  tree.findNeighbors(result, x.data(), nanoflann::SearchParams());
  return result.size() == 1;
}

}  // namespace

void DescribeVertices(const RangePatches& patches, double voxel_m, Mesh* mesh) {
  const std::size_t from = mesh->info.size(), to = mesh->vertices.size();
  if (from >= to) return;
  mesh->info.resize(to);
  const float max_gap = float(kMaxGapVoxels * voxel_m);
  for (std::size_t i = from; i < to; ++i) mesh->info[i].gap_m = max_gap;
  if (patches.points.empty()) return;
  // Colour from the coloured scans' points only: all of them, or (some scans without colour) a copy.
  const bool some = patches.colour.size() == patches.points.size() &&
                    std::any_of(patches.coloured.begin(), patches.coloured.end(), [](char c) { return c != 0; });
  const bool all = some && std::all_of(patches.coloured.begin(), patches.coloured.end(), [](char c) { return c != 0; });
  if (some) mesh->coloured = true;
  std::vector<Eigen::Vector3f> coloured_points;
  std::vector<std::uint32_t> coloured_index;
  if (some && !all) {
    for (std::size_t s = 0; s + 1 < patches.scan_begin.size(); ++s) {
      if (!patches.coloured[s]) continue;
      for (std::size_t k = patches.scan_begin[s]; k < patches.scan_begin[s + 1]; ++k) {
        coloured_points.push_back(patches.points[k]);
        coloured_index.push_back(std::uint32_t(k));
      }
    }
  }
  const PointTreeCloud cloud{&patches.points}, coloured_cloud{&coloured_points};
  const PointTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  std::optional<PointTree> coloured_tree;  // nanoflann builds no tree of no point
  if (!coloured_points.empty()) coloured_tree.emplace(3, coloured_cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  const float max_gap2 = max_gap * max_gap;
  // A vertex whose position rests on a filled value is interpolated surface, however near a scan
  // point: its gap is at least MarkedGap, clearly beyond FilledGap for any reader's threshold.
  const float marked = float(MarkedGap(voxel_m));
  auto on_filled = [&](long i) { return std::size_t(i) < mesh->on_filled.size() && mesh->on_filled[i] != 0; };
#pragma omp parallel for schedule(dynamic, 4096)
  for (long i = long(from); i < long(to); ++i) {
    const Eigen::Vector3f& x = mesh->vertices[i];
    VertexInfo& info = mesh->info[i];
    std::uint32_t k = 0;
    float d2 = 0.0f;
    if (!Nearest(tree, x, &k, &d2)) continue;
    info.gap_m = std::min(max_gap, std::sqrt(d2));
    if (on_filled(i)) info.gap_m = std::max(info.gap_m, marked);
    if (!some || d2 > max_gap2) continue;
    if (all) {
      info.colour = patches.colour[k];
    } else if (coloured_tree && Nearest(*coloured_tree, x, &k, &d2) && d2 <= max_gap2) {
      info.colour = patches.colour[coloured_index[k]];
    }
  }
}

Expected<std::size_t> CountInterpolated(const MeshSource& mesh, double voxel_m) {
  std::size_t count = 0;
  if (!mesh.described()) return count;
  const float gap = float(FilledGap(voxel_m));
  if (Status s = mesh.ForEachVertex([&](const Eigen::Vector3f&, const VertexInfo& info) {
        count += info.gap_m > gap;
        return Status::Ok();
      });
      !s)
    return s.error();
  return count;
}

}  // namespace scanreg::merge
