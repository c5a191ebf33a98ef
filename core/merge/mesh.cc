#include "core/merge/mesh.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>

namespace scanreg::merge {

namespace {

std::vector<int> Pieces(const Mesh& mesh) {  // union-find over vertices; returns root per triangle
  std::vector<int> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const auto& t : mesh.triangles) {
    const int a = find(t[0]), b = find(t[1]), c = find(t[2]);
    parent[b] = a;
    parent[find(c)] = a;
  }
  std::vector<int> root(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) root[i] = find(mesh.triangles[i][0]);
  return root;
}

}  // namespace

EdgeCounts CountEdges(const Mesh& mesh) {
  std::unordered_map<std::uint64_t, int> uses;
  uses.reserve(mesh.triangles.size() * 2);
  for (const auto& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      ++uses[(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b)];
    }
  }
  EdgeCounts c;
  for (const auto& [key, n] : uses) (n == 1 ? c.boundary : n == 2 ? c.manifold : c.non_manifold)++;
  return c;
}

bool IsWatertight(const Mesh& mesh) {
  const EdgeCounts c = CountEdges(mesh);
  return !mesh.triangles.empty() && c.boundary == 0 && c.non_manifold == 0;
}

std::vector<std::size_t> PieceSizes(const Mesh& mesh) {
  std::unordered_map<int, std::size_t> count;
  for (int r : Pieces(mesh)) ++count[r];
  std::vector<std::size_t> sizes;
  for (const auto& [r, n] : count) sizes.push_back(n);
  std::sort(sizes.rbegin(), sizes.rend());
  return sizes;
}

std::size_t RemoveSmallPieces(Mesh& mesh, double min_fraction) {
  // In place (a merged mesh may hold tens of millions of triangles: never a second copy).
  const std::vector<int> root = Pieces(mesh);
  std::vector<std::uint32_t> count(mesh.vertices.size(), 0);  // triangles per piece, by its root
  for (int r : root) ++count[r];
  const std::uint32_t largest = count.empty() ? 0 : *std::max_element(count.begin(), count.end());
  const double keep_from = min_fraction * double(largest);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (double(count[root[i]]) >= keep_from) mesh.triangles[kept++] = mesh.triangles[i];
  const std::size_t removed = mesh.triangles.size() - kept;
  mesh.triangles.resize(kept);
  // The vertices still used, kept in their order.
  std::vector<int> remap(mesh.vertices.size(), -1);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) remap[t[k]] = 0;
  int used = 0;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (remap[v] < 0) continue;
    remap[v] = used;
    if (!mesh.info.empty()) mesh.info[used] = mesh.info[v];
    if (!mesh.on_filled.empty()) mesh.on_filled[used] = mesh.on_filled[v];
    mesh.vertices[used++] = mesh.vertices[v];
  }
  mesh.vertices.resize(used);
  if (!mesh.info.empty()) mesh.info.resize(used);
  if (!mesh.on_filled.empty()) mesh.on_filled.resize(used);
  for (auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) t[k] = remap[t[k]];
  return removed;
}

}  // namespace scanreg::merge
