#include "core/registration/consistency.h"

#include <gtest/gtest.h>

namespace scanreg {
namespace {

TEST(Consistency, DropsPairsThatDoNotMeetIn3d) {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  parent_from_child.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  parent_from_child.translation() = Eigen::Vector3d(4.0, -1.0, 0.2);
  const double thr = ConsistencyThreshold(0.012);  // W's scanner noise
  EXPECT_NEAR(thr, 3.0 * std::sqrt(2.0) * 0.012, 1e-12);
  EXPECT_NEAR(ConsistencyThreshold(0.001), 0.03, 1e-12);  // floor
  std::vector<Correspondence3d> c;
  for (int i = 0; i < 10; ++i) {
    Correspondence3d x;
    x.child = Eigen::Vector3d(i, 10.0 - i, 0.5 * i);
    x.parent = parent_from_child * x.child + Eigen::Vector3d(0.02, 0.0, 0.0);  // within threshold
    c.push_back(x);
  }
  c[2].parent.x() += 0.2;  // periodic-façade style mismatch
  c[7].parent.z() -= 3.0;
  c[5].parent.y() += 0.06;  // just outside 51 mm
  EXPECT_EQ(ConsistentIndices(c, parent_from_child, thr), (std::vector<int>{0, 1, 3, 4, 6, 8, 9}));
}

}  // namespace
}  // namespace scanreg
