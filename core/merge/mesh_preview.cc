#include "core/merge/mesh_preview.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>

namespace scanreg::merge {
namespace {

struct Cell {
  std::int32_t x, y, z;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  std::size_t operator()(const Cell& c) const {
    return (std::size_t(std::uint32_t(c.x)) * 73856093u) ^ (std::size_t(std::uint32_t(c.y)) * 19349663u) ^
           (std::size_t(std::uint32_t(c.z)) * 83492791u);
  }
};

Expected<Mesh> WholeMesh(const MeshSource& source) {
  Mesh mesh;
  mesh.origin = source.origin();
  mesh.vertices.reserve(source.vertex_count());
  mesh.triangles.reserve(source.triangle_count());
  mesh.coloured = source.coloured();
  if (source.described()) mesh.info.reserve(source.vertex_count());
  if (Status s = source.ForEachVertex([&](const Eigen::Vector3f& v, const VertexInfo& info) {
        mesh.vertices.push_back(v);
        if (source.described()) mesh.info.push_back(info);
        return Status::Ok();
      });
      !s)
    return s.error();
  if (Status s = source.ForEachTriangle([&](const Eigen::Vector3i& t) {
        mesh.triangles.push_back(t);
        return Status::Ok();
      });
      !s)
    return s.error();
  return mesh;
}

// The source clustered on cells of `cell` metres; an empty optional when more than `limit` distinct
// triangles would remain (the caller tries a larger cell).
Expected<std::optional<Mesh>> Cluster(const MeshSource& source, double cell, std::size_t limit,
                                      const CancelToken& cancel) {
  std::unordered_map<Cell, std::uint32_t, CellHash> cells;
  std::vector<std::uint32_t> cluster_of;  // per source vertex
  cluster_of.reserve(source.vertex_count());
  std::vector<Eigen::Vector3d> sums;
  std::vector<Eigen::Vector3f> colour_sums;  // when the source is coloured
  std::vector<float> gaps;                   // the largest per cluster, when described
  std::vector<std::uint32_t> counts;
  const bool coloured = source.coloured(), described = source.described();
  if (Status s = source.ForEachVertex([&](const Eigen::Vector3f& v, const VertexInfo& info) {
        const Cell key{std::int32_t(std::floor(v.x() / cell)), std::int32_t(std::floor(v.y() / cell)),
                       std::int32_t(std::floor(v.z() / cell))};
        auto [it, added] = cells.emplace(key, std::uint32_t(sums.size()));
        if (added) {
          sums.emplace_back(Eigen::Vector3d::Zero()), counts.push_back(0);
          if (coloured) colour_sums.emplace_back(Eigen::Vector3f::Zero());
          if (described) gaps.push_back(0.0f);
        }
        if (coloured) colour_sums[it->second] += Eigen::Vector3f(info.colour[0], info.colour[1], info.colour[2]);
        if (described) gaps[it->second] = std::max(gaps[it->second], info.gap_m);
        sums[it->second] += v.cast<double>();
        ++counts[it->second];
        cluster_of.push_back(it->second);
        return Status::Ok();
      });
      !s)
    return s.error();
  cells = {};
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "mesh preview cancelled");
  // Triangles over three cells, rotated to start at their smallest corner (orientation kept) so that
  // repeats are equal; sorted and made unique in batches so their memory stays near the preview's.
  std::vector<Eigen::Vector3i> triangles;
  bool too_many = false;
  auto compact = [&] {
    std::sort(triangles.begin(), triangles.end(), [](const Eigen::Vector3i& a, const Eigen::Vector3i& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
  };
  std::size_t next_compact = 4 * limit + 1024;
  if (Status s = source.ForEachTriangle([&](const Eigen::Vector3i& t) {
        if (too_many || cancel.IsCancelled()) return Status::Ok();
        Eigen::Vector3i c(int(cluster_of[t[0]]), int(cluster_of[t[1]]), int(cluster_of[t[2]]));
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) return Status::Ok();
        while (c[0] > c[1] || c[0] > c[2]) c = Eigen::Vector3i(c[1], c[2], c[0]);
        triangles.push_back(c);
        if (triangles.size() >= next_compact) {
          compact();
          too_many = triangles.size() > limit;
          next_compact = triangles.size() + 4 * limit + 1024;
        }
        return Status::Ok();
      });
      !s)
    return s.error();
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "mesh preview cancelled");
  if (too_many) return std::optional<Mesh>();
  compact();
  if (triangles.size() > limit) return std::optional<Mesh>();
  // Only the clusters some triangle uses become vertices.
  std::vector<std::int32_t> index(sums.size(), -1);
  Mesh mesh;
  mesh.origin = source.origin();
  mesh.coloured = coloured;
  for (Eigen::Vector3i& t : triangles)
    for (int k = 0; k < 3; ++k) {
      std::int32_t& id = index[t[k]];
      if (id < 0) {
        id = std::int32_t(mesh.vertices.size());
        mesh.vertices.push_back((sums[t[k]] / double(counts[t[k]])).cast<float>());
        if (described) {
          VertexInfo info;
          info.gap_m = gaps[t[k]];
          if (coloured) {
            const Eigen::Vector3f c = colour_sums[t[k]] / float(counts[t[k]]);
            info.colour = ToRgb(c.x(), c.y(), c.z());
          }
          mesh.info.push_back(info);
        }
      }
      t[k] = id;
    }
  mesh.triangles = std::move(triangles);
  return std::optional<Mesh>(std::move(mesh));
}

}  // namespace

Expected<MeshPreview> PreviewMesh(const MeshSource& source, std::size_t max_triangles, double voxel_m,
                                  const CancelToken& cancel) {
  if (max_triangles == 0 || !(voxel_m > 0.0))
    return MakeError(ErrorCode::kInvalidArgument, "mesh preview: the triangle budget and the voxel must be positive");
  MeshPreview preview;
  if (source.triangle_count() <= max_triangles) {
    auto whole = WholeMesh(source);
    if (!whole) return whole.error();
    preview.mesh = std::move(*whole);
    return preview;
  }
  // A surface clustered on cells k voxels across keeps about 1/k^2 of its triangles.
  double cell = voxel_m * std::max(2.0, 1.2 * std::sqrt(double(source.triangle_count()) / double(max_triangles)));
  for (int attempt = 0; attempt < 40; ++attempt, cell *= 2.0) {
    auto clustered = Cluster(source, cell, max_triangles, cancel);
    if (!clustered) return clustered.error();
    if (!*clustered) continue;
    preview.mesh = std::move(**clustered);
    preview.cell_m = cell;
    return preview;
  }
  return MakeError(ErrorCode::kFailed, "mesh preview: no cell size brought the mesh within the budget");
}

}  // namespace scanreg::merge
