#include "core/geometry/transform.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace scanreg {

bool ProjectToRotation(const Eigen::Matrix3d& m, Eigen::Matrix3d* rotation, double tolerance) {
  if (!m.allFinite()) return false;
  if ((m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > tolerance) return false;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) return false;
  *rotation = r;
  return true;
}

Eigen::Isometry3d IsometryFromRowMajor(const std::array<double, 16>& m) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m[4 * i + j];
  Eigen::Matrix3d clean;
  t.linear() = ProjectToRotation(r, &clean, 1.0) ? clean : r;
  t.translation() << m[3], m[7], m[11];
  return t;
}

std::array<double, 16> RowMajorFromIsometry(const Eigen::Isometry3d& t) {
  std::array<double, 16> m{};
  const Eigen::Matrix4d& mat = t.matrix();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m[4 * i + j] = mat(i, j);
  return m;
}

double RotationAngle(const Eigen::Matrix3d& r) {
  const double c = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

PoseError ComparePoses(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& reference) {
  PoseError e;
  e.position_m = (estimate.translation() - reference.translation()).norm();
  e.angle_rad = RotationAngle(estimate.linear().transpose() * reference.linear());
  return e;
}

}  // namespace scanreg
