#include "core/simulate/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/simulate/project_sim.h"

#include "core/simulate/random.h"

namespace scanreg {
namespace {

TEST(SceneTest, RectangleHitIsExact) {
  Scene scene;
  const int tex = scene.AddTexture(SurfaceTexture::Uniform(0.4f));
  scene.AddRectangle({10, 0, 1}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 2.0, 1.0, tex);
  scene.Build();
  const auto hit = scene.Intersect(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 10.0, 1e-12);
  EXPECT_NEAR(hit->normal.x(), -1.0, 1e-12);  // faces the ray origin
  EXPECT_NEAR(hit->albedo, 0.4, 1e-6);
  EXPECT_EQ(hit->primitive, 0);
  EXPECT_FALSE(scene.Intersect(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 9.0).has_value());  // max range
  EXPECT_FALSE(scene.Intersect({0, 0, 2.5}, Eigen::Vector3d::UnitX(), 100.0).has_value());  // above the rectangle
}

TEST(SceneTest, BoxFacesAndNormals) {
  Scene scene;
  scene.AddBox({20, 0, 5}, {2, 3, 5}, 0.0, scene.AddTexture(SurfaceTexture::Uniform(0.5f)));
  scene.Build();
  auto hit = scene.Intersect({0, 0, 1}, Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 18.0, 1e-12);
  EXPECT_NEAR(hit->normal.x(), -1.0, 1e-12);
  hit = scene.Intersect({20, 1, 30}, -Eigen::Vector3d::UnitZ(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 20.0, 1e-12);
  EXPECT_NEAR(hit->normal.z(), 1.0, 1e-12);
  EXPECT_FALSE(scene.Intersect({0, 5, 1}, Eigen::Vector3d::UnitX(), 100.0).has_value());
  // A yawed box: rotated 90°, its x half-extent lies along world y.
  Scene yawed;
  yawed.AddBox({20, 0, 5}, {3, 1, 5}, M_PI / 2, yawed.AddTexture(SurfaceTexture::Uniform(0.5f)));
  yawed.Build();
  hit = yawed.Intersect({0, 0, 1}, Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 19.0, 1e-9);
}

TEST(SceneTest, CylinderSideAndCap) {
  Scene scene;
  scene.AddCylinder({10, 0}, 1.0, 0.0, 3.0, scene.AddTexture(SurfaceTexture::Uniform(0.5f)));
  scene.Build();
  auto hit = scene.Intersect({0, 0, 1}, Eigen::Vector3d::UnitX(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 9.0, 1e-12);
  EXPECT_NEAR(hit->normal.x(), -1.0, 1e-12);
  EXPECT_FALSE(scene.Intersect({0, 0, 3.5}, Eigen::Vector3d::UnitX(), 100.0).has_value());
  hit = scene.Intersect({10.5, 0, 10}, -Eigen::Vector3d::UnitZ(), 100.0);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range, 7.0, 1e-12);
  EXPECT_NEAR(hit->normal.z(), 1.0, 1e-12);
}

TEST(SceneTest, WindowsAreDarkerThanTheWall) {
  SurfaceTexture t = SurfaceTexture::Uniform(0.6f);
  t.windows.enabled = true;
  t.windows.u_min = 0;
  t.windows.u_max = 30;
  t.windows.v_min = 4;
  t.windows.v_max = 20;
  // First window: u in [0.9, 2.1], v in [4.9, 6.5] (defaults: 1.2 x 1.6 m, offsets 0.9 m).
  EXPECT_NEAR(t.Albedo(1.5, 5.7), t.windows.glass_albedo, 1e-6);
  EXPECT_NEAR(t.Albedo(1.5 + t.windows.spacing_u, 5.7 + t.windows.spacing_v), t.windows.glass_albedo, 1e-6);
  EXPECT_NEAR(t.Albedo(0.3, 5.7), 0.6, 1e-6);   // wall between windows
  EXPECT_NEAR(t.Albedo(1.5, 2.0), 0.6, 1e-6);   // ground floor: no window grid
  EXPECT_NEAR(t.Albedo(0.86, 5.7), t.windows.frame_albedo, 1e-6);
}

// A checkerboard: light where u v > 0, dark where u v < 0, and at an edge the beam's average: the
// Gaussian footprint straddling a sharp edge returns the mean, half a sigma in a known erf share.
TEST(SceneTest, CheckerboardEdgesAreAveragedOverTheFootprint) {
  SurfaceTexture t = SurfaceTexture::Uniform(0.9f);
  t.checker_half_m = 0.1;
  const double mid = 0.5 * (t.checker_light + t.checker_dark), half = 0.5 * (t.checker_light - t.checker_dark);
  EXPECT_NEAR(t.Albedo(0.05, 0.05, 0.002), t.checker_light, 1e-6);
  EXPECT_NEAR(t.Albedo(-0.05, 0.05, 0.002), t.checker_dark, 1e-6);
  EXPECT_NEAR(t.Albedo(0.0, 0.05, 0.002), mid, 1e-6);  // on the edge: half light, half dark
  EXPECT_NEAR(t.Albedo(0.002, 0.05, 0.002), mid + half * std::erf(1 / std::sqrt(2.0)), 1e-6);  // one sigma in
  EXPECT_NEAR(t.Albedo(0.2, 0.05, 0.002), 0.9, 1e-6);  // the board's margin
}

// Simulated checkerboards are stuck on flat façades, facing the street, 2 mm proud of the wall.
TEST(SceneTest, SimulatedCheckerboardsAreOnWalls) {
  SimulatedProjectOptions o;
  o.stations = 4;
  o.checker_targets = 6;
  const std::vector<SimulatedTarget> targets = SimulatedTargets(o);
  ASSERT_GE(targets.size(), 5u);
  SceneOptions bare = o.scene;
  bare.street_length_m = std::max(bare.street_length_m, 3 * o.spacing_m + 60.0);
  const Scene walls = MakeScene(bare);
  for (const SimulatedTarget& t : targets) {
    EXPECT_EQ(t.kind, "checker");
    EXPECT_NEAR(std::abs(t.normal.z()), 0.0, 0.02) << t.name;
    EXPECT_LT(t.normal.y() * t.world.y(), 0.0) << t.name << " faces the street";
    const auto hit = walls.Intersect(t.world + 0.1 * t.normal, -t.normal, 1.0);
    ASSERT_TRUE(hit.has_value()) << t.name;
    EXPECT_NEAR(hit->range, 0.102, 1e-6) << t.name;
  }
}

TEST(SceneTest, HierarchyAgreesWithBruteForce) {
  SceneOptions options;
  options.far_site = true;
  const Scene scene = MakeScene(options);
  ASSERT_GT(scene.num_primitives(), 60);
  sim::Rng rng(7);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d origin(rng.Uniform(-40, 40), rng.Uniform(-3, 3), rng.Uniform(0.5, 3));
    const Eigen::Vector3d dir = Eigen::Vector3d(rng.Gaussian(), rng.Gaussian(), rng.Gaussian()).normalized();
    const auto fast = scene.Intersect(origin, dir, 200.0);
    const auto slow = scene.IntersectBruteForce(origin, dir, 200.0);
    ASSERT_EQ(fast.has_value(), slow.has_value()) << "ray " << i;
    if (!fast) continue;
    ++hits;
    EXPECT_EQ(fast->primitive, slow->primitive);
    EXPECT_NEAR(fast->range, slow->range, 1e-9);
  }
  EXPECT_GT(hits, 10000);
}

TEST(SceneTest, SameSeedSameSceneDifferentSeedDifferent) {
  SceneOptions options;
  const Scene a = MakeScene(options), b = MakeScene(options);
  options.seed = 2;
  const Scene c = MakeScene(options);
  ASSERT_EQ(a.num_primitives(), b.num_primitives());
  for (int i = 0; i < a.num_primitives(); ++i)
    EXPECT_TRUE(a.primitive_bounds(i).isApprox(b.primitive_bounds(i), 0.0)) << i;
  bool differs = a.num_primitives() != c.num_primitives();
  for (int i = 0; !differs && i < a.num_primitives(); ++i)
    differs = !a.primitive_bounds(i).isApprox(c.primitive_bounds(i), 1e-9);
  EXPECT_TRUE(differs);
}

TEST(SceneTest, RepeatedWindowsFacadesAreIdentical) {
  SceneOptions options;
  options.kind = SceneOptions::Kind::kRepeatedWindows;
  const Scene scene = MakeScene(options);
  // Rays at the same height toward two façades 20 m apart along the street hit equal albedo
  // (where no street furniture stands in front).
  int equal = 0, total = 0;
  for (double z = 2.0; z < 14.0; z += 0.37) {
    for (double x = -9.9; x < 10; x += 0.53) {
      const auto a = scene.Intersect({x, 0, z}, Eigen::Vector3d::UnitY(), 100.0);
      const auto b = scene.Intersect({x + 20.0, 0, z}, Eigen::Vector3d::UnitY(), 100.0);
      ASSERT_TRUE(a && b);
      if (a->range < 8.5 || b->range < 8.5) continue;  // street furniture in front of the façade
      ++total;
      equal += std::abs(a->albedo - b->albedo) < 1e-6;
    }
  }
  EXPECT_GT(total, 300);
  EXPECT_EQ(equal, total);
}

TEST(SceneTest, OptionsValidateRejectsNonsense) {
  SceneOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.street_length_m = 0.0;
  EXPECT_FALSE(o.Validate().ok());
  o = SceneOptions();
  o.street_half_width_m = std::nan("");
  EXPECT_FALSE(o.Validate().ok());
}

}  // namespace
}  // namespace scanreg
