#include "tests/merge/truth_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace scanreg::test {

TruthSurface::TruthSurface(const std::vector<Scan>& noise_free, double max_range_m)
    : cloud_(new pcl::PointCloud<pcl::PointXYZ>) {
  for (const Scan& s : noise_free)
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (!s.valid[k] || s.points[k].norm() > max_range_m) continue;
      const Eigen::Vector3d w = *s.reference_world_from_scan * s.points[k].cast<double>();
      cloud_->push_back(pcl::PointXYZ(float(w.x()), float(w.y()), float(w.z())));
    }
  tree_.setInputCloud(cloud_);
}

double TruthSurface::Distance(const Eigen::Vector3d& p) const {
  std::vector<int> idx(12);
  std::vector<float> d2(12);
  const int found = tree_.nearestKSearch(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())), 12, idx, d2);
  if (found < 3) return std::numeric_limits<double>::infinity();
  if (d2[0] > 0.09f) return std::sqrt(double(d2[0]));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < found; ++i) mean += (*cloud_)[idx[i]].getVector3fMap().cast<double>();
  mean /= found;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < found; ++i) {
    const Eigen::Vector3d q = (*cloud_)[idx[i]].getVector3fMap().cast<double>() - mean;
    cov += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  return std::abs((p - mean).dot(es.eigenvectors().col(0)));
}

double TruthSurface::Holes(const std::vector<Eigen::Vector3d>& vertices, double radius) const {
  pcl::PointCloud<pcl::PointXYZ>::Ptr v(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Eigen::Vector3d& p : vertices) v->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  if (v->empty()) return 1.0;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(v);
  std::vector<int> idx(1);
  std::vector<float> d2(1);
  std::size_t tested = 0, holes = 0;
  for (std::size_t k = 0; k < cloud_->size(); k += 10, ++tested)
    holes += tree.nearestKSearch((*cloud_)[k], 1, idx, d2) < 1 || d2[0] > radius * radius;
  return double(holes) / std::max<std::size_t>(tested, 1);
}

Accuracy Measure(const TruthSurface& truth, const std::vector<Eigen::Vector3d>& points) {
  Accuracy a;
  std::size_t near = 0, far = 0;
  double s2 = 0.0;
  for (const Eigen::Vector3d& p : points) {
    const double d = truth.Distance(p);
    if (d > 0.1) {
      ++far;
      continue;
    }
    s2 += d * d, ++near;
  }
  a.rms_m = std::sqrt(s2 / std::max<std::size_t>(near, 1));
  a.spurious = double(far) / std::max<std::size_t>(near + far, 1);
  return a;
}

}  // namespace scanreg::test
