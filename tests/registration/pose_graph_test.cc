#include "core/registration/pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace scanreg {
namespace {

// n poses on a circle of radius 5 m, facing the centre.
std::vector<Eigen::Isometry3d> Ring(int n) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.translation() = Eigen::Vector3d(5 * std::cos(a), 5 * std::sin(a), 0.1 * i);
    poses.push_back(p);
  }
  return poses;
}

double WorstPosition(const std::vector<Eigen::Isometry3d>& a, const std::vector<Eigen::Isometry3d>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i].translation() - b[i].translation()).norm());
  return worst;
}

Eigen::Isometry3d Drift(double deg, const Eigen::Vector3d& t) {
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  d.translation() = t;
  return d;
}

TEST(PoseGraph, LoopClosureReducesInjectedDrift) {
  const int n = 8;
  const auto truth = Ring(n);
  std::vector<PoseGraphLink> links;
  // Chain links each carry a small bias (0.3 deg, 1 cm): chaining them drifts.
  for (int i = 0; i + 1 < n; ++i)
    links.push_back({i, i + 1, truth[i].inverse() * truth[i + 1] * Drift(0.3, Eigen::Vector3d(0.01, 0.005, 0))});
  std::vector<Eigen::Isometry3d> chained = {truth[0]};
  for (int i = 0; i + 1 < n; ++i) chained.push_back(chained.back() * links[i].parent_from_child);
  links.push_back({n - 1, 0, truth[n - 1].inverse() * truth[0]});  // loop closure, unbiased
  NullProgress progress;
  CancelToken cancel;
  PoseGraphOptions o;
  o.kernel = PoseGraphOptions::Kernel::kNone;
  auto r = OptimizePoseGraph(chained, links, o, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const double before = WorstPosition(chained, truth), after = WorstPosition(r->world_from_scan, truth);
  std::printf("worst position error: chained %.1f mm, after the pose graph %.1f mm (%d iterations); loop link residual %.1f -> %.1f mm\n",
              before * 1e3, after * 1e3, r->iterations, r->links.back().translation_before_m * 1e3,
              r->links.back().translation_after_m * 1e3);
  EXPECT_TRUE(r->converged);
  EXPECT_LT(after, 0.5 * before);
  EXPECT_LT(r->links.back().translation_after_m, r->links.back().translation_before_m);
  EXPECT_EQ((r->world_from_scan[0].matrix() - truth[0].matrix()).norm(), 0.0);  // root fixed
}

TEST(PoseGraph, WrongLinkIsDownWeighted) {
  const int n = 5;
  const auto truth = Ring(n);
  std::vector<PoseGraphLink> links;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) links.push_back({i, j, truth[i].inverse() * truth[j]});
  const std::size_t wrong = 4;  // 1 -> 2
  links[wrong].parent_from_child = links[wrong].parent_from_child * Drift(10.0, Eigen::Vector3d(1.0, -0.5, 0.2));
  std::vector<Eigen::Isometry3d> start = truth;
  for (int i = 1; i < n; ++i) start[i] = start[i] * Drift(0.5, Eigen::Vector3d(0.02, 0.01, -0.01));
  NullProgress progress;
  CancelToken cancel;
  auto r = OptimizePoseGraph(start, links, PoseGraphOptions(), progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  for (std::size_t k = 0; k < links.size(); ++k) {
    const auto& l = r->links[k];
    std::printf("link %d->%d: %.1f mm / %.3f deg before, %.1f mm / %.3f deg after, weight %.3g%s\n", l.parent, l.child,
                l.translation_before_m * 1e3, l.rotation_before_rad * 180 / M_PI, l.translation_after_m * 1e3,
                l.rotation_after_rad * 180 / M_PI, l.weight, l.down_weighted ? " DOWN-WEIGHTED" : "");
    EXPECT_EQ(l.down_weighted, k == wrong) << k;
  }
  EXPECT_LT(WorstPosition(r->world_from_scan, truth), 0.002);
}

TEST(PoseGraph, OneLinkProjectIsUnchanged) {
  const auto truth = Ring(2);
  const std::vector<PoseGraphLink> links = {{0, 1, truth[0].inverse() * truth[1]}};
  NullProgress progress;
  CancelToken cancel;
  auto r = OptimizePoseGraph(truth, links, PoseGraphOptions(), progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  EXPECT_LT(WorstPosition(r->world_from_scan, truth), 1e-9);
  EXPECT_FALSE(r->links[0].down_weighted);
}

TEST(PoseGraph, RejectsBadInput) {
  const auto truth = Ring(3);
  NullProgress progress;
  CancelToken cancel;
  EXPECT_FALSE(OptimizePoseGraph(truth, {{0, 5, Eigen::Isometry3d::Identity()}}, PoseGraphOptions(), progress, cancel).ok());
  EXPECT_FALSE(OptimizePoseGraph(truth, {{0, 1, Eigen::Isometry3d::Identity()}}, PoseGraphOptions(), progress, cancel).ok());  // 2 unlinked
  PoseGraphOptions o;
  o.translation_sigma_m = 0;
  EXPECT_FALSE(o.Validate().ok());
  o = PoseGraphOptions();
  o.kernel_scale = -1;
  EXPECT_FALSE(o.Validate().ok());
}

}  // namespace
}  // namespace scanreg
