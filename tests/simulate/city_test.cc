// The simulated city (issue 13, item 7): stations along streets that close loops, façades on both
// sides of every street.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/simulate/project_sim.h"
#include "core/simulate/scene.h"

namespace scanreg {
namespace {

SimulatedProjectOptions City(int stations, double spacing) {
  SimulatedProjectOptions o;
  o.scene.kind = SceneOptions::Kind::kCity;
  o.stations = stations;
  o.spacing_m = spacing;
  return o;
}

// Distance in plan from p to the nearest street centre line of the city.
double OffStreet(const Eigen::Vector3d& p, const std::vector<StreetLeg>& legs) {
  double best = INFINITY;
  for (const StreetLeg& l : legs) {
    const Eigen::Vector2d a = l.from.head<2>(), b = l.to.head<2>(), q = p.head<2>();
    const double t = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * (b - a) - q).norm());
  }
  return best;
}

TEST(City, StationsWalkTheStreetsAndCloseLoops) {
  const SimulatedProjectOptions o = City(60, 10.0);
  ASSERT_TRUE(o.Validate().ok()) << o.Validate().error().message;
  const std::vector<Eigen::Isometry3d> poses = SimulatedStationPoses(o);
  ASSERT_EQ(poses.size(), 60u);
  SceneOptions grown = o.scene;  // the city grows to hold the stations: find the size it took
  for (grown.city_blocks_x = 1; grown.city_blocks_x <= 10; ++grown.city_blocks_x) {
    grown.city_blocks_y = grown.city_blocks_x;
    double off = 0;
    for (const Eigen::Isometry3d& p : poses) off = std::max(off, OffStreet(p.translation(), CityStreets(grown)));
    if (off <= 2.0) break;
  }
  ASSERT_LE(grown.city_blocks_x, 10) << "every station stands within 2 m of a street's centre line";
  int loops = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const double d = (poses[i].translation() - poses[j].translation()).head<2>().norm();
      EXPECT_GT(d, 0.3 * o.spacing_m) << "stations " << j + 1 << " and " << i + 1 << " stand on each other";
      loops += i - j > 5 && d < 1.5 * o.spacing_m;  // far apart in capture order, close in space
    }
  }
  EXPECT_GE(loops, 3) << "the streets cross: the campaign comes back to where it was";
}

TEST(City, TheCampaignWalksARingThroughEveryCrossing) {
  const SimulatedProjectOptions o = City(28, 10.0);  // one block: 4 sides of 66 m in 7 steps each
  ASSERT_TRUE(o.Validate().ok()) << o.Validate().error().message;
  const std::vector<Eigen::Isometry3d> poses = SimulatedStationPoses(o);
  ASSERT_EQ(poses.size(), 28u);
  const double pitch = CityPitch(o.scene);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const std::size_t next = (i + 1) % poses.size();  // the last station closes the ring with the first
    const double d = (poses[next].translation() - poses[i].translation()).head<2>().norm();
    EXPECT_LT(d, 1.5 * o.spacing_m) << "stations " << i + 1 << " and " << next + 1 << " are not neighbours";
  }
  for (const Eigen::Vector2d crossing : {Eigen::Vector2d(0, 0), Eigen::Vector2d(pitch, 0),
                                         Eigen::Vector2d(pitch, pitch), Eigen::Vector2d(0, pitch)}) {
    double nearest = INFINITY;
    for (const Eigen::Isometry3d& p : poses) nearest = std::min(nearest, (p.translation().head<2>() - crossing).norm());
    EXPECT_LT(nearest, 2.5) << "a station at the crossing (" << crossing.transpose() << ")";
  }
}

TEST(City, EveryStreetHasFacadesOnBothSides) {
  SceneOptions o;
  o.kind = SceneOptions::Kind::kCity;
  o.city_blocks_x = 2;
  o.city_blocks_y = 2;
  ASSERT_TRUE(o.Validate().ok());
  const Scene scene = MakeScene(o);
  int probes = 0, facades = 0;
  const double pitch = o.city_block_m + 2 * o.street_half_width_m;
  for (const StreetLeg& leg : CityStreets(o)) {
    const Eigen::Vector3d a = (leg.to - leg.from).normalized(), left = Eigen::Vector3d::UnitZ().cross(a);
    const double length = (leg.to - leg.from).norm();
    for (const Eigen::Vector3d& dir : {left, Eigen::Vector3d(-left)}) {
      int side_facades = 0;
      // Beside the middle of each block along the street (crossings every pitch metres), 6 m up
      // (above cars and kiosks).
      for (double u = 0.5 * pitch; u < length; u += pitch)
        for (double du : {-10.0, 0.0, 10.0}) {
          const auto hit = scene.Intersect(leg.from + (u + du) * a + Eigen::Vector3d(0, 0, 6.0), dir, 150.0);
          ++probes;
          ASSERT_TRUE(hit.has_value()) << "nothing beside the street at u = " << u + du;
          EXPECT_GE(hit->range, o.street_half_width_m - 1.0);
          const bool facade = hit->range <= o.street_half_width_m + 2.0 && std::abs(hit->normal.z()) < 0.1;
          side_facades += facade;
          if (!facade) std::printf("no façade at u = %.1f: %.1f m (an alley?)\n", u + du, hit->range);
        }
      EXPECT_GE(side_facades, 3) << "façades along this side of the street";
      facades += side_facades;
    }
  }
  EXPECT_EQ(probes, 6 * 2 * 2 * 3) << "3 streets each way, 2 blocks along each, both sides, 3 probes";
  EXPECT_GE(facades, 0.85 * probes) << "façades line the streets (alleys open between some)";
}

TEST(City, StreetOnlyOptionsAreRefusedClearly) {
  SimulatedProjectOptions o = City(10, 10.0);
  o.sphere_targets = 4;
  ASSERT_FALSE(o.Validate().ok());
  EXPECT_NE(o.Validate().error().message.find("street scene only"), std::string::npos);
}

TEST(City, AHundredStationsAreNamedInOrder) {
  SimulatedProjectOptions o = City(100, 10.0);
  o.scanner.cols = 60;
  o.scanner.rows = 15;
  NullProgress progress;
  std::vector<std::string> names;
  const Status s = SimulateProjectScans(
      o, [&](Scan&& scan, std::vector<std::uint8_t>&&) { names.push_back(scan.name); return Status::Ok(); }, progress,
      CancelToken());
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(names.size(), 100u);
  EXPECT_EQ(names.front(), "s001");
  EXPECT_EQ(names.back(), "s100");
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
}

}  // namespace
}  // namespace scanreg
