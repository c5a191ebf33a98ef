#include "core/registration/epnp_pose.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "core/registration/virtual_plane.h"

namespace scanreg {

std::optional<Eigen::Isometry3d> EpnpParentFromChild(const std::vector<Eigen::Vector3d>& parent,
                                                     const std::vector<Eigen::Vector3d>& child, double focal) {
  const int n = static_cast<int>(parent.size());
  if (n < 4 || child.size() != parent.size() || !(child[0].x() > 0.0)) return std::nullopt;
  cv::Mat object(n, 3, CV_64F), image(n, 2, CV_64F);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d uv = ProjectToVirtualPlane(child[i], focal);
    if (!uv.allFinite()) return std::nullopt;
    for (int k = 0; k < 3; ++k) object.at<double>(i, k) = parent[i](k);
    image.at<double>(i, 0) = uv.x();
    image.at<double>(i, 1) = uv.y();
  }
  const cv::Matx33d k(focal, 0, 0, 0, focal, 0, 0, 0, 1);
  cv::Mat rvec, tvec;
  try {
    if (!cv::solvePnP(object, image, k, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_EPNP)) return std::nullopt;
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  Eigen::Isometry3d camera_from_parent = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) camera_from_parent.linear()(i, j) = r(i, j);
    camera_from_parent.translation()(i) = tvec.at<double>(i);
  }
  if (!camera_from_parent.matrix().allFinite()) return std::nullopt;
  Eigen::Isometry3d scanner_from_camera = Eigen::Isometry3d::Identity();
  scanner_from_camera.linear() = VirtualCamera::CameraFromScanner().transpose();
  const Eigen::Isometry3d child_from_parent = scanner_from_camera * camera_from_parent;
  return child_from_parent.inverse();
}

}  // namespace scanreg
