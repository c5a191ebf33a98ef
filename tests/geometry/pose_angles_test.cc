#include "core/geometry/pose_angles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace scanreg {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(PoseAngles, HeadingTurnsTheScannerAxisCounterClockwiseFromWorldX) {
  const Eigen::Matrix3d r = RotationFromHeadingPitchRoll({90 * kDeg, 0, 0});
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // Pitch turns +x down (right-handed about y), roll turns +y up (about x).
  EXPECT_NEAR((RotationFromHeadingPitchRoll({0, 10 * kDeg, 0}) * Eigen::Vector3d::UnitX()).z(), -std::sin(10 * kDeg),
              1e-12);
  EXPECT_NEAR((RotationFromHeadingPitchRoll({0, 0, 10 * kDeg}) * Eigen::Vector3d::UnitY()).z(), std::sin(10 * kDeg),
              1e-12);
}

TEST(PoseAngles, RandomRotationsRoundTrip) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> heading(-179, 179), pitch(-89, 89), roll(-179, 179);
  for (int k = 0; k < 200; ++k) {
    const HeadingPitchRoll a{heading(rng) * kDeg, pitch(rng) * kDeg, roll(rng) * kDeg};
    const HeadingPitchRoll b = HeadingPitchRollFromRotation(RotationFromHeadingPitchRoll(a));
    EXPECT_NEAR(b.heading, a.heading, 1e-9);
    EXPECT_NEAR(b.pitch, a.pitch, 1e-9);
    EXPECT_NEAR(b.roll, a.roll, 1e-9);
  }
}

TEST(PoseAngles, GimbalLockKeepsTheRotation) {
  for (double pitch : {90.0, -90.0}) {
    const Eigen::Matrix3d r = RotationFromHeadingPitchRoll({30 * kDeg, pitch * kDeg, 20 * kDeg});
    const Eigen::Matrix3d back = RotationFromHeadingPitchRoll(HeadingPitchRollFromRotation(r));
    EXPECT_TRUE(back.isApprox(r, 1e-9)) << pitch;
  }
}

TEST(PoseAngles, TiltIsTheAngleOfTheScannerZAxisFromVertical) {
  EXPECT_NEAR(TiltAngle(RotationFromHeadingPitchRoll({123 * kDeg, 0, 0})), 0.0, 1e-12);
  EXPECT_NEAR(TiltAngle(RotationFromHeadingPitchRoll({40 * kDeg, 0, 3 * kDeg})), 3 * kDeg, 1e-12);
  EXPECT_NEAR(TiltAngle(RotationFromHeadingPitchRoll({0, 4 * kDeg, 0})), 4 * kDeg, 1e-12);
}

}  // namespace
}  // namespace scanreg
