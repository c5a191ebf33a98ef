// Which free-space conflicts count as moving objects (visibility.h): two scans from one spot of
// scenes that differ by one object-sized thing. A van that stands in one scan and is gone in the
// other stands out of its range image (a jump to what lies behind it): moving, not against the
// pose. A corridor's end wall, just as small, that one scan sees 5 m away and the other 9 m away
// (what a pose slid along a corridor looks like) meets the side walls, floor and ceiling the other
// scanner sees too: static, against the pose.
#include <gtest/gtest.h>

#include "core/registration/visibility.h"
#include "core/simulate/scanner.h"
#include "core/simulate/scene.h"

namespace scanreg {
namespace {

using Vec3 = Eigen::Vector3d;

Scan ScanOf(Scene scene) {
  scene.Build();
  ScannerOptions o;
  o.cols = 1000;
  o.rows = 250;
  o.range_noise_m = 0.005;
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan =
      SimulateScan(scene, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1.5)), o, "scan", progress, cancel);
  EXPECT_TRUE(scan.ok()) << scan.error().ToString();
  return scan ? *scan : Scan();
}

// A corridor 2 m wide and 2.7 m high along x, the scanner at x = 0; its ends at x = -west and x = 40
// (long enough for a 2 x 2.7 m wall to be object-sized against the scene).
Scan Corridor(double west) {
  Scene s;
  const int paint = s.AddTexture(SurfaceTexture::Uniform(0.7f));
  const double length = west + 40.0, centre = 0.5 * (40.0 - west);
  s.AddRectangle(Vec3(centre, 0, 0), Vec3::UnitX(), Vec3::UnitY(), 0.5 * length, 1.0, paint);    // floor
  s.AddRectangle(Vec3(centre, 0, 2.7), Vec3::UnitX(), Vec3::UnitY(), 0.5 * length, 1.0, paint);  // ceiling
  for (double y : {-1.0, 1.0})
    s.AddRectangle(Vec3(centre, y, 1.35), Vec3::UnitX(), Vec3::UnitZ(), 0.5 * length, 1.35, paint);
  for (double x : {-west, 40.0}) s.AddRectangle(Vec3(x, 0, 1.35), Vec3::UnitY(), Vec3::UnitZ(), 1.0, 1.35, paint);
  return ScanOf(s);
}

// A street: the road and a façade 12 m away, and a van (5 x 2 x 2.4 m) 7 m away when `van`.
Scan Street(bool van) {
  Scene s;
  const int road = s.AddTexture(SurfaceTexture::Uniform(0.3f));
  const int wall = s.AddTexture(SurfaceTexture::Uniform(0.6f));
  s.AddRectangle(Vec3(0, 0, 0), Vec3::UnitX(), Vec3::UnitY(), 40.0, 40.0, road);
  s.AddRectangle(Vec3(0, 12, 8), Vec3::UnitX(), Vec3::UnitZ(), 40.0, 8.0, wall);
  if (van) s.AddBox(Vec3(2, 7, 1.2), Vec3(2.5, 1.0, 1.2), 0.0, wall);
  return ScanOf(s);
}

TEST(FreeSpaceClusters, AVanThatLeftIsMovingButAWallOfTheSameSizeIsNot) {
  FreeSpaceOptions o;
  o.margin_m = 0.1;
  const Eigen::Isometry3d same_spot = Eigen::Isometry3d::Identity();

  // The van is in `other` only: its points lie in the observer's free space, and they are moving.
  const FreeSpaceResult van = FreeSpaceViolations(Street(false), Street(true), same_spot, o);
  ASSERT_GT(van.tested, 0);
  EXPECT_GT(van.fraction(), 0.005) << van.violations << " of " << van.tested;
  EXPECT_GE(van.moving, 0.9 * van.violations) << van.moving << " of " << van.violations;

  // The end wall 5 m away in `other` and 9 m away in the observer: as small as the van (2 x 2.7 m),
  // but it runs on into the walls, floor and ceiling the observer sees too: static.
  const FreeSpaceResult wall = FreeSpaceViolations(Corridor(9.0), Corridor(5.0), same_spot, o);
  ASSERT_GT(wall.tested, 0);
  EXPECT_GT(wall.fraction(), 0.005) << wall.violations << " of " << wall.tested;
  EXPECT_LE(wall.moving, 0.1 * wall.violations) << wall.moving << " of " << wall.violations;
  EXPECT_GT(wall.static_fraction(), 0.005);

  // The same corridors the other way round: the observer's nearer wall hides the other's farther
  // one, so nothing lies in free space.
  const FreeSpaceResult hidden = FreeSpaceViolations(Corridor(5.0), Corridor(9.0), same_spot, o);
  EXPECT_LT(hidden.fraction(), 0.001);
}

}  // namespace
}  // namespace scanreg
