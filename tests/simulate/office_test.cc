// The simulated office floor (issue 38): rooms behind doors off a corridor; the identical floor is
// symmetric under a 180° turn about its centre, the furnished one is not.
#include <gtest/gtest.h>

#include <cmath>

#include "core/simulate/project_sim.h"
#include "core/simulate/random.h"
#include "core/simulate/scene.h"

namespace scanreg {
namespace {

Scene Office(SceneOptions::Kind kind) {
  SceneOptions o;
  o.kind = kind;
  o.street_length_m = 36.0;
  return MakeScene(o);
}

double Range(const Scene& s, const Eigen::Vector3d& from, const Eigen::Vector3d& dir) {
  const auto hit = s.Intersect(from, dir.normalized(), 100.0);
  return hit ? hit->range : -1.0;
}

// Rays across the corridor at door height: through a door they reach a room (several metres),
// elsewhere the corridor wall 1 m away; the doors repeat every room.
TEST(OfficeScene, DoorsOpenIntoRoomsAtEveryRoom) {
  const Scene s = Office(SceneOptions::Kind::kOfficeIdentical);
  int doors = 0, walls = 0;
  for (double x = -17.9; x < 18.0; x += 0.1) {
    const double r = Range(s, {x, 0.0, 1.0}, {0.0, 1.0, 0.0});
    ASSERT_GT(r, 0.0) << "the floor is closed";
    if (r > 2.0) ++doors;
    else if (std::abs(r - 1.0) < 0.01) ++walls;
  }
  // Nine rooms a side, a 0.9 m door each (less the leaf's 4 cm): about 9 x 9 rays of 360.
  EXPECT_NEAR(doors, 9 * 9, 12);
  EXPECT_GT(walls, 250);
}

// A 180° turn about the floor's centre maps the identical floor onto itself: the same rays from
// turned origins in turned directions meet surfaces at the same ranges. The furnished floor differs.
TEST(OfficeScene, TheIdenticalFloorIsSymmetricAndTheFurnishedOneIsNot) {
  const Scene same = Office(SceneOptions::Kind::kOfficeIdentical), varied = Office(SceneOptions::Kind::kOffice);
  sim::Rng rng(7);
  int agree_same = 0, agree_varied = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(rng.Uniform(-17, 17), rng.Uniform(-0.9, 0.9), rng.Uniform(0.3, 2.4));
    const double a = rng.Uniform(-M_PI, M_PI), e = rng.Uniform(-0.6, 0.6);
    const Eigen::Vector3d d(std::cos(a) * std::cos(e), std::sin(a) * std::cos(e), std::sin(e));
    const Eigen::Vector3d tp(-p.x(), -p.y(), p.z()), td(-d.x(), -d.y(), d.z());
    agree_same += std::abs(Range(same, p, d) - Range(same, tp, td)) < 1e-6;
    agree_varied += std::abs(Range(varied, p, d) - Range(varied, tp, td)) < 1e-6;
  }
  EXPECT_EQ(agree_same, n);
  EXPECT_LT(agree_varied, n);
  EXPECT_GT(agree_varied, n / 2) << "the walls, doors and lights are laid out alike";
}

// Half the stations in the corridor, each other one in a room, 1.2-1.7 m behind its door.
TEST(OfficeScene, StationsStandInTheCorridorAndInRooms) {
  SimulatedProjectOptions o;
  o.scene.kind = SceneOptions::Kind::kOffice;
  o.stations = 8;
  o.spacing_m = 8.0;
  ASSERT_TRUE(o.Validate().ok());
  const std::vector<Eigen::Isometry3d> poses = SimulatedStationPoses(o);
  ASSERT_EQ(poses.size(), 8u);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double y = std::abs(poses[i].translation().y());
    if (i % 2 == 0) EXPECT_LT(y, 0.35) << "corridor station " << i;
    else EXPECT_GT(y, 2.3) << "room station " << i;
  }
  EXPECT_NEAR(poses[6].translation().x() - poses[0].translation().x(), 24.0, 1.0);
  o.sphere_targets = 2;
  EXPECT_FALSE(o.Validate().ok()) << "targets are simulated on the street only";
}

}  // namespace
}  // namespace scanreg
