// Two registrations of the same simulated street compared (issue 13): the same poses, links and
// evidence whichever way the work was split (pair jobs, memory budget).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>

#include "core/geometry/transform.h"
#include "core/io/project.h"
#include "tests/integration/cli_run.h"
#include "tests/support/test_paths.h"

namespace scanreg::test {

namespace fs = std::filesystem;

// A street of 6 stations whose candidate selection leaves pairs out (3 partners each).
inline fs::path Street(const test::TempDir& dir, const std::string& name) {
  const fs::path out = dir / name;
  EXPECT_EQ(RunCli("simulate --stations 6 --spacing 5 --size 600x150 --seed 4 --out " + Quote(out)).status, 0);
  return out / "project.scanreg.json";
}

// The registration of `other` (collected from pair jobs, or registered under a small memory budget)
// is the one of `single` (one process, default budget), and that one is right (within 2 cm of the
// simulation's truth).
inline void ExpectSameRegistration(const fs::path& single, const fs::path& other) {
  Expected<io::Project> a = io::LoadProject(single), b = io::LoadProject(other);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->scans.size(), b->scans.size());
  const Eigen::Isometry3d root_a = a->scans[0].world_from_scan, root_b = b->scans[0].world_from_scan;
  for (std::size_t i = 0; i < a->scans.size(); ++i) {
    const io::ProjectScan &sa = a->scans[i], &sb = b->scans[i];
    ASSERT_TRUE(sa.registered) << sa.name;
    EXPECT_EQ(sb.registered, sa.registered) << sa.name;
    // Against the truth: the registration works (relative to the first scan, as the datum is free).
    const Eigen::Isometry3d truth = a->scans[0].reference_world_from_scan->inverse() * *sa.reference_world_from_scan;
    const PoseError error = ComparePoses(root_a.inverse() * sa.world_from_scan, truth);
    EXPECT_LT(error.position_m, 0.02) << sa.name;
    // And the other run is the single one.
    // (Matrices compared directly: an angle from acos is only good to ~2e-8 rad near identity.)
    const Eigen::Matrix4d da = (root_a.inverse() * sa.world_from_scan).matrix();
    const Eigen::Matrix4d db = (root_b.inverse() * sb.world_from_scan).matrix();
    EXPECT_LT((da - db).cwiseAbs().maxCoeff(), 1e-9) << sa.name;
  }
  ASSERT_EQ(a->links.size(), b->links.size());
  for (std::size_t k = 0; k < a->links.size(); ++k) {
    const io::LinkRecord &la = a->links[k], &lb = b->links[k];
    EXPECT_EQ(la.parent + ">" + la.child, lb.parent + ">" + lb.child) << "link " << k;
    EXPECT_EQ(la.status, lb.status) << la.parent << ">" << la.child;
    EXPECT_EQ(la.loop_check, lb.loop_check) << la.parent << ">" << la.child;
    EXPECT_EQ(la.consistent, lb.consistent) << la.parent << ">" << la.child;
    EXPECT_NEAR(la.rms_m, lb.rms_m, 1e-12) << la.parent << ">" << la.child;
  }
}

}  // namespace scanreg::test
