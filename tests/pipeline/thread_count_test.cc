// Issue 13, item 4: scans are prepared and pairs matched concurrently; the registration is the same
// whatever the thread count (poses and links to numerical noise, the same links and statuses).
#include <gtest/gtest.h>
#include <omp.h>

#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

ProjectRegistration RegisterWithThreads(const std::vector<Scan>& scans, int threads) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  NullProgress progress;
  auto r = RegisterScans(scans, UserChoices{}, RegisterOptions{}, progress, CancelToken());
  omp_set_num_threads(before);
  EXPECT_TRUE(r.ok()) << r.error().message;
  return r.ok() ? *r : ProjectRegistration{};
}

TEST(ThreadCount, OneThreadAndTwoGiveTheSameRegistration) {
  SimulatedProjectOptions o;
  o.stations = 4;
  o.scanner.cols = 1500;
  o.scanner.rows = 375;
  NullProgress progress;
  auto scans = SimulateProject(o, progress, CancelToken());
  ASSERT_TRUE(scans.ok());
  const ProjectRegistration one = RegisterWithThreads(*scans, 1), two = RegisterWithThreads(*scans, 2);
  ASSERT_EQ(one.scans.size(), scans->size());
  ASSERT_EQ(two.scans.size(), scans->size());
  int registered = 0;
  for (std::size_t i = 0; i < one.scans.size(); ++i) {
    EXPECT_EQ(one.scans[i].registered, two.scans[i].registered) << one.scans[i].name;
    EXPECT_EQ(one.scans[i].parent, two.scans[i].parent) << one.scans[i].name;
    registered += one.scans[i].registered;
    const Eigen::Isometry3d d = one.scans[i].world_from_scan.inverse() * two.scans[i].world_from_scan;
    EXPECT_LT(d.translation().norm(), 1e-6) << one.scans[i].name;
    EXPECT_LT(Eigen::AngleAxisd(d.linear()).angle(), 1e-7) << one.scans[i].name;
  }
  EXPECT_EQ(registered, 4) << "a test that passes when every link fails is not a test";
  EXPECT_EQ(one.confusion, two.confusion);
  ASSERT_EQ(one.links.size(), two.links.size());
  for (std::size_t k = 0; k < one.links.size(); ++k) {
    EXPECT_EQ(one.links[k].parent, two.links[k].parent);
    EXPECT_EQ(one.links[k].child, two.links[k].child);
    EXPECT_EQ(one.links[k].status, two.links[k].status);
    EXPECT_NEAR(one.links[k].rms_m, two.links[k].rms_m, 1e-7);
  }
}

}  // namespace
}  // namespace scanreg::pipeline
