// The virtual plane (W §4.2, SPEC §2 step 6): a virtual pinhole camera at the scanner origin,
// oriented like the scanner and looking horizontally, onto whose image plane the reliable 3D
// points of the new scan are projected, giving 3D (parent) <-> 2D (child) correspondences.
//
// Axes. Scanner frame: x forward, y left, z up. Camera frame (OpenCV convention): z_cam = x
// (optical axis), x_cam = -y (image right), y_cam = -z (image down). Image coordinates with the
// principal point at the origin: x' = -y / x * f, y' = -z / x * f.
//
// Points behind the camera (x < 0) are mapped by point symmetry p -> -p, i.e. onto the plane of
// a second camera looking the other way (W §4.2). A point and its antipode therefore project to
// the same image point: the camera model is really "the projective line through the origin",
// not "the ray in front of the camera". EPnP (Lepetit et al. 2009) only uses this line: its
// linear constraints f*X_c - x'*Z_c = 0 and f*Y_c - y'*Z_c = 0 are homogeneous in the camera-frame
// point, so they hold for a point in front of or behind the camera alike, and the true pose
// solves them. The only place where EPnP assumes "in front" is the overall sign of its solution,
// which OpenCV fixes by making the first correspondence's depth positive; the RANSAC in coarse.cc
// therefore puts a correspondence with x > 0 first in every sample.
#pragma once

#include <Eigen/Core>

namespace scanreg {

// Image point of p_scanner (scanner frame, metres) on the virtual plane, in pixels with the
// principal point at (0, 0). Points with x < 0 are projected as -p. Points with x == 0 (on the
// camera's own plane) have no image: the result is not finite; callers drop such points (in
// practice: points more than ~85° off the optical axis, whose images are huge and ill-conditioned).
Eigen::Vector2d ProjectToVirtualPlane(const Eigen::Vector3d& p_scanner, double focal);

// The virtual camera: intrinsics and its rotation relative to the scanner, cv-free.
struct VirtualCamera {
  double focal = 1000.0;  // pixels; any value works (W: "any convenient K"), 1000 keeps numbers O(1..1e4)

  // K = [f 0 0; 0 f 0; 0 0 1]: principal point at the image origin.
  Eigen::Matrix3d Intrinsics() const;
  // Rotation camera_from_scanner (rows: -y, -z, x of the scanner frame).
  static Eigen::Matrix3d CameraFromScanner();
  Eigen::Vector2d Project(const Eigen::Vector3d& p_scanner) const { return ProjectToVirtualPlane(p_scanner, focal); }
};

}  // namespace scanreg
