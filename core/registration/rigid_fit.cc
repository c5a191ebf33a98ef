#include "core/registration/rigid_fit.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <string>

namespace scanreg {
namespace {

// True when the weighted scatter of the points is (close to) rank <= 1: collinear or coincident.
bool IsDegenerate(const Eigen::Matrix3d& scatter) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  return !(ev(2) > 0.0) || ev(1) <= 1e-10 * ev(2);
}

}  // namespace

Expected<Eigen::Isometry3d> FitRigid(const std::vector<Eigen::Vector3d>& source,
                                     const std::vector<Eigen::Vector3d>& target,
                                     const std::vector<double>& weights) {
  const std::size_t n = source.size();
  if (target.size() != n)
    return MakeError(ErrorCode::kInvalidArgument, "rigid fit: " + std::to_string(n) + " source but " +
                                                      std::to_string(target.size()) + " target points");
  if (!weights.empty() && weights.size() != n)
    return MakeError(ErrorCode::kInvalidArgument, "rigid fit: " + std::to_string(weights.size()) + " weights for " +
                                                      std::to_string(n) + " point pairs");
  double wsum = 0.0;
  int used = 0;
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), ct = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    if (!(w >= 0.0) || !std::isfinite(w))
      return MakeError(ErrorCode::kInvalidArgument, "rigid fit: weight " + std::to_string(i) + " is negative or NaN");
    if (w == 0.0) continue;
    ++used;
    wsum += w;
    cs += w * source[i];
    ct += w * target[i];
  }
  if (used < 3)
    return MakeError(ErrorCode::kFailed, "rigid fit needs at least 3 point pairs of positive weight, got " +
                                             std::to_string(used));
  cs /= wsum;
  ct /= wsum;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // sum w (s - cs)(t - ct)^T
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero(), tt = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    if (w == 0.0) continue;
    const Eigen::Vector3d s = source[i] - cs, t = target[i] - ct;
    cov += w * s * t.transpose();
    ss += w * s * s.transpose();
    tt += w * t * t.transpose();
  }
  if (IsDegenerate(ss) || IsDegenerate(tt))
    return MakeError(ErrorCode::kFailed, "rigid fit: the " + std::to_string(used) +
                                             " points are collinear or coincident; the rotation is undetermined");
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((v * u.transpose()).determinant() < 0.0) d(2, 2) = -1.0;  // reflection fix (Umeyama)
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = v * d * u.transpose();
  out.translation() = ct - out.linear() * cs;
  return out;
}

std::optional<Eigen::Isometry3d> FitHeading(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                                            const std::vector<double>& weights) {
  const std::size_t n = src.size();
  if (n < 2) return std::nullopt;
  const auto w = [&](std::size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  double wsum = 0.0;
  for (std::size_t i = 0; i < n; ++i) cs += w(i) * src[i], cd += w(i) * dst[i], wsum += w(i);
  if (!(wsum > 0.0)) return std::nullopt;
  cs /= wsum;
  cd /= wsum;
  double sin_sum = 0.0, cos_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d a = (src[i] - cs).head<2>(), b = (dst[i] - cd).head<2>();
    cos_sum += w(i) * a.dot(b);
    sin_sum += w(i) * (a.x() * b.y() - a.y() * b.x());
  }
  if (std::hypot(sin_sum, cos_sum) < 1e-12) return std::nullopt;  // horizontally coincident
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(std::atan2(sin_sum, cos_sum), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out.translation() = cd - out.linear() * cs;
  return out;
}

}  // namespace scanreg
