// Free space seen from a depth camera's pixel grid (a perspective grid, no angular grid): a room
// with a cabinet rendered by two pinhole cameras with known poses. At the true relative pose no
// point of one lies in the other's free space; a pose 0.3 m off puts the cabinet and walls there;
// a grid that is neither panoramic nor perspective (the same points with the cells shuffled) has
// no viewpoint and is not tested.
#include "core/registration/visibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace scanreg {
namespace {

// Distance along the unit ray o + t d to the first surface: the inside of the room box, or the
// outside of the cabinet box (slab method).
double CastRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::AlignedBox3d room(Eigen::Vector3d(-3, -3, 0), Eigen::Vector3d(3, 3, 2.5));
  const Eigen::AlignedBox3d cabinet(Eigen::Vector3d(-0.4, -0.3, 0), Eigen::Vector3d(0.4, 0.3, 1.2));
  double exit = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0) exit = std::min(exit, (room.max()[a] - o[a]) / d[a]);
    if (d[a] < 0) exit = std::min(exit, (room.min()[a] - o[a]) / d[a]);
  }
  double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < cabinet.min()[a] || o[a] > cabinet.max()[a]) return exit;
      continue;
    }
    double ta = (cabinet.min()[a] - o[a]) / d[a], tb = (cabinet.max()[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1 && t0 > 0 ? std::min(exit, t0) : exit;
}

// A 160 x 120 depth image (f = 140 px) from a camera at `centre` looking at the cabinet; points in
// the camera frame turned by `frame` (a camera frame with z forward, or any other axes convention).
Scan Render(const Eigen::Vector3d& centre, const Eigen::Matrix3d& frame, Eigen::Isometry3d* world_from_scan) {
  const Eigen::Vector3d forward = (Eigen::Vector3d(0, 0, 0.6) - centre).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d world_from_camera;
  world_from_camera << right, down, forward;
  Scan s("cam", 120, 160);
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c) {
      const Eigen::Vector3d ray_cam((c - 79.5) / 140.0, (r - 59.5) / 140.0, 1.0);
      const Eigen::Vector3d ray = (world_from_camera * ray_cam).normalized();
      const double t = CastRay(centre, ray);
      s.Set(r, c, (frame * (t * ray_cam.normalized())).cast<float>(), 0.5f);
    }
  world_from_scan->linear() = world_from_camera * frame.transpose();
  world_from_scan->translation() = centre;
  return s;
}

TEST(FreeSpace, PerspectiveGridsSeeFreeSpaceInAnyAxesConvention) {
  const Eigen::Matrix3d z_up = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (const Eigen::Matrix3d& frame : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), z_up}) {
    Eigen::Isometry3d wa = Eigen::Isometry3d::Identity(), wb = Eigen::Isometry3d::Identity();
    const Scan a = Render(Eigen::Vector3d(-1.6, -1.2, 1.4), frame, &wa);
    const Scan b = Render(Eigen::Vector3d(-0.4, -1.9, 1.3), frame, &wb);
    const Eigen::Isometry3d truth = wa.inverse() * wb;
    const PairFreeSpace right = PairFreeSpaceCheck(a, b, truth, FreeSpaceOptions());
    Eigen::Isometry3d off = truth;
    off.pretranslate(Eigen::Vector3d(0.3, 0.0, 0.0));
    FreeSpaceOptions o;
    o.margin_m = 0.05;
    const PairFreeSpace wrong = PairFreeSpaceCheck(a, b, off, o);
    std::printf("perspective grid: tested %d / %d, violations at the truth %.2f %%, 0.3 m off %.1f %%\n",
                right.a_sees_b.tested, right.b_sees_a.tested, 100 * right.total(), 100 * wrong.total());
    EXPECT_GT(right.a_sees_b.tested, 1000);
    EXPECT_GT(right.b_sees_a.tested, 1000);
    EXPECT_LT(right.total(), 0.005);
    EXPECT_GT(wrong.total(), 0.05);
  }
}

TEST(FreeSpace, AGridWithoutAViewpointIsNotTested) {
  Eigen::Isometry3d wa = Eigen::Isometry3d::Identity(), wb = Eigen::Isometry3d::Identity();
  Scan a = Render(Eigen::Vector3d(-1.6, -1.2, 1.4), Eigen::Matrix3d::Identity(), &wa);
  const Scan b = Render(Eigen::Vector3d(-0.4, -1.9, 1.3), Eigen::Matrix3d::Identity(), &wb);
  EXPECT_GT(FreeSpaceViolations(a, b, wa.inverse() * wb, FreeSpaceOptions()).tested, 1000);
  std::mt19937 rng(5);
  std::shuffle(a.points.begin(), a.points.end(), rng);  // no projection maps directions to these cells
  EXPECT_EQ(FreeSpaceViolations(a, b, wa.inverse() * wb, FreeSpaceOptions()).tested, 0);
}

}  // namespace
}  // namespace scanreg
