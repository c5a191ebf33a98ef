#include "tests/bench/fpfh_ransac_baseline.h"

// GCC 12 reports a false -Warray-bounds inside Eigen's umeyama, inlined from PCL's headers.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/search/kdtree.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "tests/bench/bench_table.h"
#include "tests/bench/pcl_clouds.h"

namespace scanreg::bench {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using NormalCloud = pcl::PointCloud<pcl::PointNormal>;
using Features = pcl::PointCloud<pcl::FPFHSignature33>;

// Normals by radius, oriented towards the scanner; points without one are dropped.
NormalCloud::Ptr WithNormals(const Cloud::Ptr& cloud, double radius_m) {
  pcl::PointCloud<pcl::Normal> normals;
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  ne.setRadiusSearch(radius_m);
  ne.setViewPoint(0, 0, 0);
  ne.compute(normals);
  NormalCloud::Ptr out(new NormalCloud);
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const pcl::Normal& n = normals[i];
    if (!std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) || !std::isfinite(n.normal_z)) continue;
    pcl::PointNormal p;
    p.x = (*cloud)[i].x, p.y = (*cloud)[i].y, p.z = (*cloud)[i].z;
    p.normal_x = n.normal_x, p.normal_y = n.normal_y, p.normal_z = n.normal_z;
    p.curvature = n.curvature;
    out->push_back(p);
  }
  return out;
}

bool Finite(const pcl::FPFHSignature33& f) {
  for (float v : f.histogram)
    if (!std::isfinite(v)) return false;
  return true;
}

struct Prepared {
  NormalCloud::Ptr icp;        // the ICP cloud with normals
  std::vector<Eigen::Vector3f> points;  // the coarse cloud's points that have a finite FPFH
  Features::Ptr features{new Features};
};

Prepared Prepare(const Scan& scan, const FpfhRansacOptions& o) {
  const Cloud::Ptr raw = PclPoints(scan, o.max_range_m);
  Prepared out;
  const Cloud::Ptr fine = Downsample(raw, o.icp_voxel_m);
  // Normals of the ICP cloud from about 30 neighbours (the tutorial's max_nn) at its spacing.
  out.icp = WithNormals(fine, 3 * o.icp_voxel_m);
  const NormalCloud::Ptr coarse = WithNormals(Downsample(fine, o.voxel_m), 2 * o.voxel_m);
  Cloud::Ptr xyz(new Cloud);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  for (const pcl::PointNormal& p : *coarse) {
    xyz->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    normals->push_back(pcl::Normal(p.normal_x, p.normal_y, p.normal_z));
  }
  Features all;
  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fpfh;
  fpfh.setInputCloud(xyz);
  fpfh.setInputNormals(normals);
  fpfh.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  fpfh.setRadiusSearch(5 * o.voxel_m);
  fpfh.compute(all);
  for (std::size_t i = 0; i < xyz->size(); ++i) {
    if (!Finite(all[i])) continue;
    out.points.push_back((*xyz)[i].getVector3fMap());
    out.features->push_back(all[i]);
  }
  return out;
}

// Nearest neighbour in feature space of every feature of `from` among `to`.
std::vector<int> Nearest(const Features::Ptr& from, const Features::Ptr& to) {
  pcl::KdTreeFLANN<pcl::FPFHSignature33> tree;
  tree.setInputCloud(to);
  std::vector<int> out(from->size(), -1);
  std::vector<int> index(1);
  std::vector<float> distance(1);
  for (std::size_t i = 0; i < from->size(); ++i)
    if (tree.nearestKSearch((*from)[i], 1, index, distance) == 1) out[i] = index[0];
  return out;
}

struct Correspondence {
  Eigen::Vector3f child, parent;
};

// Open3D's mutual filter: keep (i, j) when j is i's nearest and i is j's; with fewer than 9 such
// pairs it falls back to every nearest pair, as Open3D does.
std::vector<Correspondence> MutualMatches(const Prepared& child, const Prepared& parent) {
  std::vector<Correspondence> mutual, all;
  if (child.features->empty() || parent.features->empty()) return mutual;
  const std::vector<int> forward = Nearest(child.features, parent.features);
  const std::vector<int> backward = Nearest(parent.features, child.features);
  for (std::size_t i = 0; i < forward.size(); ++i) {
    if (forward[i] < 0) continue;
    const Correspondence c{child.points[i], parent.points[forward[i]]};
    all.push_back(c);
    if (backward[forward[i]] == static_cast<int>(i)) mutual.push_back(c);
  }
  return mutual.size() >= 9 ? mutual : all;
}

struct Hypothesis {
  std::size_t inliers = 0;
  double squared_error = 0;
  Eigen::Matrix4f parent_from_child = Eigen::Matrix4f::Identity();
};

// RANSAC over the correspondences, Open3D's way: 3 samples, the edge-length checker before the
// estimate and the distance checker after it, scored by the correspondences within `distance`; stops
// at max_iterations or once the best fitness makes more iterations needless at the confidence.
Hypothesis Ransac(const std::vector<Correspondence>& corr, double distance, const FpfhRansacOptions& o,
                  int* iterations) {
  Hypothesis best;
  if (corr.size() < 3) return best;
  const float d2 = static_cast<float>(distance * distance);
  std::atomic<long> next{0}, needed{o.max_iterations};
  std::mutex mutex;
  auto worker = [&](int thread) {
    std::mt19937_64 rng(o.seed * 7919 + thread);
    std::uniform_int_distribution<std::size_t> pick(0, corr.size() - 1);
    while (next.fetch_add(1) < std::min<long>(o.max_iterations, needed.load())) {
      std::size_t s[3] = {pick(rng), pick(rng), pick(rng)};
      if (s[0] == s[1] || s[1] == s[2] || s[0] == s[2]) continue;
      bool edges_agree = true;
      for (int a = 0; a < 3 && edges_agree; ++a)
        for (int b = a + 1; b < 3; ++b) {
          const float dc = (corr[s[a]].child - corr[s[b]].child).norm();
          const float dp = (corr[s[a]].parent - corr[s[b]].parent).norm();
          if (dc < 0.9f * dp || dp < 0.9f * dc) edges_agree = false;
        }
      if (!edges_agree) continue;
      Eigen::Matrix3f from, to;
      for (int k = 0; k < 3; ++k) from.col(k) = corr[s[k]].child, to.col(k) = corr[s[k]].parent;
      const Eigen::Matrix4f t = Eigen::umeyama(from, to, false);
      const Eigen::Matrix3f r = t.topLeftCorner<3, 3>();
      const Eigen::Vector3f shift = t.topRightCorner<3, 1>();
      bool close = true;
      for (int k = 0; k < 3; ++k) close = close && (r * from.col(k) + shift - to.col(k)).squaredNorm() <= d2;
      if (!close) continue;
      std::size_t inliers = 0;
      double error = 0;
      for (const Correspondence& c : corr) {
        const float e = (r * c.child + shift - c.parent).squaredNorm();
        if (e <= d2) ++inliers, error += e;
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (inliers > best.inliers || (inliers == best.inliers && inliers > 0 && error < best.squared_error)) {
        best = {inliers, error, t};
        const double fitness = static_cast<double>(inliers) / corr.size();
        const double k = std::log(1 - o.confidence) / std::log(1 - std::pow(fitness, 3));
        if (std::isfinite(k) && k < needed.load()) needed = static_cast<long>(std::ceil(k));
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::max(1, o.threads); ++t) threads.emplace_back(worker, t);
  for (std::thread& t : threads) t.join();
  *iterations = static_cast<int>(std::min<long>(next.load(), o.max_iterations));
  return best;
}

}  // namespace

FpfhRansacResult FpfhRansacPair(const Scan& parent, const Scan& child, const FpfhRansacOptions& o) {
  FpfhRansacResult r;
  Prepared p, c;
  r.seconds_features = Seconds([&] {
    p = Prepare(parent, o);
    c = Prepare(child, o);
  });
  Hypothesis best;
  r.seconds_ransac = Seconds([&] {
    const std::vector<Correspondence> corr = MutualMatches(c, p);
    r.correspondences = corr.size();
    best = Ransac(corr, 1.5 * o.voxel_m, o, &r.iterations);
  });
  r.inliers = best.inliers;
  r.accepted = best.inliers >= 3;
  r.fitness = r.correspondences ? static_cast<double>(best.inliers) / r.correspondences : 0.0;
  if (!r.accepted) return r;
  r.seconds_icp = Seconds([&] {
    NormalCloud aligned;
    pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp;  // point-to-plane
    icp.setInputSource(c.icp);
    icp.setInputTarget(p.icp);
    icp.setMaxCorrespondenceDistance(0.4 * o.voxel_m);
    icp.setMaximumIterations(o.icp_iterations);
    icp.align(aligned, best.parent_from_child);
    // PCL's float matrix, re-orthonormalised in double (a float rotation's trace hides small angles).
    const Eigen::Matrix4d m = icp.getFinalTransformation().cast<double>();
    r.parent_from_child.linear() =
        Eigen::Quaterniond(Eigen::Matrix3d(m.topLeftCorner<3, 3>())).normalized().toRotationMatrix();
    r.parent_from_child.translation() = m.topRightCorner<3, 1>();
  });
  return r;
}

}  // namespace scanreg::bench

#pragma GCC diagnostic pop
