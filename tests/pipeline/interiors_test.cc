// Issue 38: interiors. An office floor — a corridor with same-size rooms behind regularly spaced
// doors, ceiling lights every 3 m, painted walls — aliases: a room fits another room turned 180°, a
// corridor fits itself shifted. Whatever it registers, no scan may be placed wrong and no accepted
// link may be wrong; the data must contain such wrong poses for the test to mean anything.
#include <gtest/gtest.h>

#include <cmath>

#include "core/geometry/transform.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

std::vector<Scan> SimulateOffice(SceneOptions::Kind kind, std::uint64_t seed, double spacing_m, int cols = 1000,
                                 int rows = 250) {
  SimulatedProjectOptions o;
  o.scene.kind = kind;
  o.stations = 8;
  o.spacing_m = spacing_m;
  o.scanner.cols = cols;
  o.scanner.rows = rows;
  o.seed = o.scanner.seed = o.scene.seed = seed;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(scans.ok()) << scans.error().ToString();
  return scans.ok() ? std::move(*scans) : std::vector<Scan>{};
}

// Returns how many scans were registered (each checked against the truth).
int ExpectNothingWrong(SceneOptions::Kind kind, std::uint64_t seed, double spacing_m = 8.0, int cols = 1000,
                       int rows = 250) {
  const std::vector<Scan> scans = SimulateOffice(kind, seed, spacing_m, cols, rows);
  EXPECT_EQ(scans.size(), 8u);
  if (scans.size() != 8u) return 0;
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, RegisterOptions{}, progress, cancel);
  EXPECT_TRUE(r.ok()) << r.error().ToString();
  if (!r.ok()) return 0;
  const std::vector<ReferenceError> errors = ReferenceErrors(*r, scans);
  int registered = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    registered += r->scans[i].registered;
    if (!r->scans[i].registered) {
      EXPECT_FALSE(r->scans[i].reason.empty()) << scans[i].name << " left out without a reason";
      continue;
    }
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name << " registered wrong";
    EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << scans[i].name << " registered wrong";
  }
  int aliased = 0;  // pair poses a metre or more from the truth: the floor's aliasing
  for (const io::LinkRecord& l : r->links) {
    const PoseError e = *LinkReferenceError(l, scans);
    const bool wrong = e.position_m > 1.0 || e.angle_rad * kDeg > 5.0;
    aliased += wrong;
    if (l.status == io::LinkStatus::kFailed) continue;
    EXPECT_LE(e.position_m, 0.05) << l.parent << "-" << l.child << " accepted but wrong (" << l.method << ", "
                                  << l.reason << ")";
    EXPECT_LE(e.angle_rad * kDeg, 0.2) << l.parent << "-" << l.child;
  }
  EXPECT_GE(aliased, 1) << "the floor gave no wrong pair pose: the test would prove nothing";
  return registered;
}

// Same-size rooms with different furniture: a room fits another room turned 180° with 9-12
// consistent correspondences and 4.8 % free-space conflict, and a corridor station fits another
// with the scanners on top of each other. Seed 2: a plan-view pose put the corridor's end stations,
// 24.7 m apart, on each other turned 180° ("ok", 82 % overlap, no conflict).
TEST(Interiors, NoScanOfAnOfficeFloorIsPlacedWrong) {
  ExpectNothingWrong(SceneOptions::Kind::kOffice, 1);
  ExpectNothingWrong(SceneOptions::Kind::kOffice, 2);
}

// The same floor scanned at W's resolution (3000 x 750). More features give every pair of rooms
// more votes, so a room station had candidate neighbours for a loop — whose own links all failed:
// two rooms were placed by plan-view poses alone, 20.5 m and 31.3 m and 90° off ("ok", 18-21 %
// overlap, 1.7-1.8 % of their points in the other scanner's free space, where the true plan-view
// poses leave under 0.05 %), and nothing checked them. (Measured with full-size SIFT; with the
// half-size default, 3 scans were.)
TEST(Interiors, NoScanOfAnOfficeFloorScannedAtThePapersResolutionIsPlacedWrong) {
  ExpectNothingWrong(SceneOptions::Kind::kOffice, 1, 8.0, 3000, 750);
}

// Corridor stations 5 m apart. Once the plan view maps the whole corridor, it fits the corridor
// turned 180° about its middle as well as the truth (seed 2: a corridor station placed 15.7 m off
// and turned around, "ok", 47 % overlap against 21 % at the truth, no conflict at either): a
// plan-view pose without feature support fails when another pose fits the surfaces too.
//
// Free space then tells those look-alike poses apart (FreeSpaceRefutes): turned 180° or slid by
// rooms, a corridor station fits with up to twice the overlap of the truth, but leaves the far ends
// and the furniture seen through the doors where the other scanner saw through (seed 1: 739 of
// 49,475 samples against 15 at the truth). When the overlap ranked them, such links failed as
// ambiguous and 2 of 8 scans were registered on each floor; now 5.
TEST(Interiors, NoScanOfAnOfficeFloorWithStationsFiveMetresApartIsPlacedWrong) {
  EXPECT_GE(ExpectNothingWrong(SceneOptions::Kind::kOffice, 1, 5.0), 4);
  EXPECT_GE(ExpectNothingWrong(SceneOptions::Kind::kOffice, 2, 5.0), 4);
}

// Identical rooms and a mirror-symmetric corridor: from its twin's spot a station sees the same
// data, so the features put stations on each other (seed 2: all 8 on 2 spots, "ok", exit 0, before
// a pose with two tripod stations on one spot failed). What can be told apart is; the rest is
// left out with the reason.
TEST(Interiors, NoScanOfASymmetricFloorWithIdenticalRoomsIsPlacedWrong) {
  ExpectNothingWrong(SceneOptions::Kind::kOfficeIdentical, 1);
  ExpectNothingWrong(SceneOptions::Kind::kOfficeIdentical, 2);
}

// The same floor with corridor stations 5 m apart (the simulator's default spacing): a corridor
// station was placed by a room station it never saw (24 m apart), 16 m off, "ok" with 37 % overlap
// and no conflict — the room it does see is the twin of the room station's own (seed 1; seed 2 the
// same, 12 m off). A link needs a loop when either of its scans looks the same from another spot.
TEST(Interiors, NoScanOfASymmetricFloorIsPlacedByATwinRoom) {
  ExpectNothingWrong(SceneOptions::Kind::kOfficeIdentical, 1, 5.0);
  ExpectNothingWrong(SceneOptions::Kind::kOfficeIdentical, 2, 5.0);
}

// Two scans of the identical-room floor registered as a project of their own: a room station and
// a corridor station, or two of either. Nothing but their own link can place the second, and in a
// building of identical rooms the walls seen from above fit elsewhere as well as at the truth:
// s01-s04 was placed 10.0 m and 180° off ("ok", plan-view pose, 40 % overlap, 11.5 mm RMS at
// 12 mm noise, no free-space conflict), s06-s07 8.6 m off, s02-s07 24.7 m off. A pose the surfaces
// alone support and no loop can check is placed but not verified.
TEST(Interiors, TwoScansOfAFloorOfIdenticalRoomsAloneAreNeverRegisteredWrong) {
  const std::vector<Scan> floor = SimulateOffice(SceneOptions::Kind::kOfficeIdentical, 1, 8.0);
  ASSERT_EQ(floor.size(), 8u);
  int aliased = 0;
  for (const auto& [a, b] : std::vector<std::pair<int, int>>{{0, 3}, {5, 6}, {1, 6}, {0, 5}, {1, 2}}) {
    const std::vector<Scan> pair = {floor[a], floor[b]};
    NullProgress progress;
    CancelToken cancel;
    Expected<ProjectRegistration> r = RegisterScans(pair, {}, RegisterOptions{}, progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    const std::vector<ReferenceError> errors = ReferenceErrors(*r, pair);
    for (const io::LinkRecord& l : r->links) {
      const PoseError e = *LinkReferenceError(l, pair);
      aliased += e.position_m > 1.0 || e.angle_rad * kDeg > 5.0;
    }
    for (std::size_t i = 0; i < pair.size(); ++i) {
      if (!r->scans[i].registered) {
        EXPECT_FALSE(r->scans[i].reason.empty()) << pair[i].name << " left out without a reason";
        continue;
      }
      EXPECT_LE(errors[i].position_m, 0.02) << pair[0].name << "-" << pair[1].name << ": " << pair[i].name
                                            << " registered wrong";
      EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << pair[0].name << "-" << pair[1].name << ": " << pair[i].name;
    }
  }
  EXPECT_GE(aliased, 2) << "the pairs gave no wrong pose: the test would prove nothing";
}

}  // namespace
}  // namespace scanreg::pipeline
