#include "core/registration/icp.h"

#include <cmath>
#include <string>

#include "core/geometry/transform.h"
#include "core/registration/point_index.h"
#include "core/registration/rigid_fit.h"

namespace scanreg {

Status IcpOptions::Validate() const {
  auto bad = [](const std::string& m) { return Status(MakeError(ErrorCode::kInvalidArgument, "keypoint ICP: " + m)); };
  if (!(max_correspondence_m > 0.0) || !std::isfinite(max_correspondence_m)) return bad("max_correspondence_m must be > 0 metres");
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(convergence_translation_m >= 0.0) || !(convergence_rotation_rad >= 0.0)) return bad("convergence thresholds must be >= 0");
  if (min_correspondences < 3) return bad("min_correspondences must be >= 3");
  return Status::Ok();
}

Expected<IcpResult> KeypointIcp(const std::vector<Eigen::Vector3d>& parent_pts,
                                const std::vector<Eigen::Vector3d>& child_pts,
                                Eigen::Isometry3d initial_parent_from_child, const IcpOptions& options,
                                const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (parent_pts.empty() || child_pts.empty())
    return MakeError(ErrorCode::kInvalidArgument, "keypoint ICP: " + std::to_string(parent_pts.size()) + " parent and " +
                                                      std::to_string(child_pts.size()) + " child points; both need points");
  const PointIndex index(parent_pts);
  IcpResult out;
  out.parent_from_child = initial_parent_from_child;
  const double max_d = options.max_correspondence_m;
  std::vector<Eigen::Vector3d> src, dst;
  for (int it = 0; it < options.max_iterations; ++it) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "keypoint ICP cancelled");
    src.clear();
    dst.clear();
    for (const auto& p : child_pts) {
      const int j = index.Nearest(out.parent_from_child * p, max_d);
      if (j < 0) continue;
      src.push_back(p);
      dst.push_back(parent_pts[j]);
    }
    if (static_cast<int>(src.size()) < options.min_correspondences) {
      if (it == 0)
        return MakeError(ErrorCode::kFailed, "keypoint ICP: only " + std::to_string(src.size()) + " of " +
                                                 std::to_string(child_pts.size()) + " child keypoints have a parent keypoint within " +
                                                 std::to_string(max_d) + " m (need " +
                                                 std::to_string(options.min_correspondences) + ")");
      break;
    }
    auto fit = FitRigid(src, dst);
    if (!fit.ok()) break;
    const Eigen::Isometry3d delta = out.parent_from_child.inverse() * *fit;
    out.parent_from_child = *fit;
    out.iterations = it + 1;
    if (delta.translation().norm() < options.convergence_translation_m &&
        RotationAngle(delta.linear()) < options.convergence_rotation_rad) {
      out.converged = true;
      break;
    }
  }
  // Final statistics at the final pose.
  double sum2 = 0.0;
  int count = 0;
  for (const auto& p : child_pts) {
    double d2 = 0.0;
    if (index.Nearest(out.parent_from_child * p, max_d, &d2) < 0) continue;
    sum2 += d2;
    ++count;
  }
  out.correspondences = count;
  out.rms_m = count ? std::sqrt(sum2 / count) : 0.0;
  out.overlap = static_cast<double>(count) / child_pts.size();
  if (count < options.min_correspondences) out.converged = false;
  return out;
}

}  // namespace scanreg
