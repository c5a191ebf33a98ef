#include "core/merge/point_normals.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <queue>

#include "core/merge/point_tree.h"

namespace scanreg::merge {

PointNormals EstimatePointNormals(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& eyes,
                                  const Eigen::Vector3f& fallback_eye, int k, const CancelToken& cancel) {
  PointNormals out;
  const std::size_t n = points.size();
  const bool per_point = eyes.size() == n && n > 1, seen = per_point || eyes.size() == 1;
  out.normal.assign(n, Eigen::Vector3f::Zero());
  if (n < 3) return out;
  k = std::clamp(k, 3, int(std::min<std::size_t>(n, 64)));
  PointTreeCloud cloud{&points};
  PointTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  // The neighbours of every point (itself first), kept for the orientation.
  std::vector<std::uint32_t> neighbours(n * std::size_t(k));
  std::vector<float> nearest(n), kth(n);
#pragma omp parallel for schedule(dynamic, 4096)
  for (long i = 0; i < long(n); ++i) {
    std::vector<float> d2(k);
    nanoflann::KNNResultSet<float, std::uint32_t, std::size_t> result(k);
    result.init(neighbours.data() + std::size_t(i) * k, d2.data());
    tree.findNeighbors(result, points[i].data(), nanoflann::SearchParams());
    const std::size_t found = result.size();
    for (std::size_t j = found; j < std::size_t(k); ++j) neighbours[std::size_t(i) * k + j] = std::uint32_t(i);
    nearest[i] = found > 1 ? std::sqrt(d2[1]) : INFINITY;
    kth[i] = found > 0 ? std::sqrt(d2[found - 1]) : INFINITY;
  }
  if (cancel.IsCancelled()) return {};
  std::vector<float> finite;
  for (float d : nearest)
    if (std::isfinite(d)) finite.push_back(d);
  if (finite.empty()) return out;
  std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
  out.spacing = finite[finite.size() / 2];
  std::vector<float> spans;
  for (float d : kth)
    if (std::isfinite(d)) spans.push_back(d);
  std::nth_element(spans.begin(), spans.begin() + spans.size() / 2, spans.end());
  const float isolated = 8.0f * spans[spans.size() / 2];
#pragma omp parallel for schedule(dynamic, 4096)
  for (long i = 0; i < long(n); ++i) {
    if (!(kth[i] <= isolated)) continue;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    for (int j = 0; j < k; ++j) mean += points[neighbours[std::size_t(i) * k + j]];
    mean /= float(k);
    Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
    for (int j = 0; j < k; ++j) {
      const Eigen::Vector3f d = points[neighbours[std::size_t(i) * k + j]] - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(cov);
    if (eig.info() != Eigen::Success || !(eig.eigenvalues()(1) > 0.0f)) continue;  // a line or a point: no plane
    Eigen::Vector3f normal = eig.eigenvectors().col(0);
    if (seen && normal.dot(eyes[per_point ? std::size_t(i) : 0] - points[i]) < 0.0f) normal = -normal;
    out.normal[i] = normal;
  }
  if (seen || cancel.IsCancelled()) return out;
  // Orientation: best-first growth over the neighbour graph.
  std::vector<char> done(n, 0);
  using Edge = std::pair<float, std::pair<std::uint32_t, std::uint32_t>>;  // (1 - |cos|, (from, to))
  std::priority_queue<Edge, std::vector<Edge>, std::greater<Edge>> queue;
  auto push_from = [&](std::uint32_t i) {
    for (int j = 1; j < k; ++j) {
      const std::uint32_t to = neighbours[std::size_t(i) * k + j];
      if (done[to] || out.normal[to].isZero()) continue;
      queue.push({1.0f - std::abs(out.normal[i].dot(out.normal[to])), {i, to}});
    }
  };
  auto grow = [&]() {
    while (!queue.empty()) {
      const auto [cost, edge] = queue.top();
      queue.pop();
      const std::uint32_t to = edge.second;
      if (done[to]) continue;
      done[to] = 1;
      if (out.normal[edge.first].dot(out.normal[to]) < 0.0f) out.normal[to] = -out.normal[to];
      push_from(to);
    }
  };
  // Each connected piece grown from its point nearest the fallback eye (the surface a cloud's origin
  // sees best), that point facing it.
  std::vector<std::uint32_t> order;
  for (std::size_t i = 0; i < n; ++i)
    if (!done[i] && !out.normal[i].isZero()) order.push_back(std::uint32_t(i));
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return (points[a] - fallback_eye).squaredNorm() < (points[b] - fallback_eye).squaredNorm();
  });
  for (std::uint32_t i : order) {
    if (done[i]) continue;
    if (cancel.IsCancelled()) return {};
    if (out.normal[i].dot(fallback_eye - points[i]) < 0.0f) out.normal[i] = -out.normal[i];
    done[i] = 1;
    push_from(i);
    grow();
  }
  return out;
}

}  // namespace scanreg::merge
