// CellSearch (core/registration/cell_search.h) against PCL's own k-d tree search on the same clouds:
// the same neighbours, distances and order, so FPFH descriptors computed with either are identical.
#include "core/registration/cell_search.h"

#include <gtest/gtest.h>

#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/search/kdtree.h>

#include <cmath>
#include <random>

namespace scanreg {
namespace {

// Samples of two walls, a floor and a pole with noise, plus a few scattered points: voxel-like
// spacing (5 cm) as the geometric features see a scan.
pcl::PointCloud<pcl::PointXYZ>::Ptr StreetCorner(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.004f);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (float a = -3; a < 3; a += 0.05f)
    for (float b = 0; b < 3; b += 0.05f) {
      cloud->push_back(pcl::PointXYZ(a + noise(rng), 2.0f + noise(rng), b));    // wall
      cloud->push_back(pcl::PointXYZ(-3.0f + noise(rng), a, b + noise(rng)));   // wall
      cloud->push_back(pcl::PointXYZ(a, b - 1.0f, noise(rng)));                 // floor
    }
  for (float z = 0; z < 3; z += 0.05f)
    for (float t = 0; t < 2 * float(M_PI); t += 0.5f)
      cloud->push_back(pcl::PointXYZ(1.0f + 0.06f * std::cos(t), 0.5f + 0.06f * std::sin(t), z));  // pole
  for (int i = 0; i < 200; ++i) cloud->push_back(pcl::PointXYZ(u(rng), u(rng), u(rng) + 3.0f));
  return cloud;
}

TEST(CellSearch, RadiusSearchGivesTheKdTreesNeighboursInItsOrder) {
  const auto cloud = StreetCorner(1);
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  for (double radius : {0.125, 0.5, 0.3}) {
    CellSearch cells(radius * (1 + 1e-4));
    cells.setInputCloud(cloud);
    pcl::Indices a, b;
    std::vector<float> da, db;
    long total = 0;
    for (std::size_t i = 0; i < cloud->size(); i += 7) {
      tree.radiusSearch((*cloud)[i], radius, a, da);
      cells.radiusSearch((*cloud)[i], radius, b, db);
      ASSERT_EQ(a, b) << "point " << i << ", radius " << radius;
      ASSERT_EQ(da, db) << "point " << i << ", radius " << radius;
      total += static_cast<long>(b.size());
    }
    EXPECT_GT(total, 5 * static_cast<long>(cloud->size() / 7)) << "too few neighbours to compare at " << radius;
    // At most max_nn: the nearest ones.
    tree.radiusSearch((*cloud)[0], radius, a, da, 5);
    cells.radiusSearch((*cloud)[0], radius, b, db, 5);
    EXPECT_EQ(a, b);
    EXPECT_EQ(b.size(), 5u);
  }
  // A query far from every point finds none.
  pcl::Indices none;
  std::vector<float> d;
  CellSearch cells(0.2);
  cells.setInputCloud(cloud);
  EXPECT_EQ(cells.radiusSearch(pcl::PointXYZ(100, 100, 100), 0.2, none, d), 0);
}

TEST(CellSearch, NearestKSearchFindsTheKdTreesNeighbours) {
  const auto cloud = StreetCorner(2);
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  CellSearch cells(0.1);
  cells.setInputCloud(cloud);
  pcl::Indices a(8), b;
  std::vector<float> da(8), db;
  for (const pcl::PointXYZ& q : {(*cloud)[10], (*cloud)[5000], pcl::PointXYZ(0.3f, 0.2f, 1.0f), pcl::PointXYZ(40, -3, 2)}) {
    ASSERT_EQ(tree.nearestKSearch(q, 8, a, da), 8);
    ASSERT_EQ(cells.nearestKSearch(q, 8, b, db), 8);
    EXPECT_EQ(da, db);  // the same distances; equal ones may come in another order
  }
}

TEST(CellSearch, FpfhDescriptorsAreBitIdenticalToTheKdTrees) {
  const auto cloud = StreetCorner(3);
  const double normal_radius = 0.125, feature_radius = 0.3;
  auto describe = [&](pcl::search::Search<pcl::PointXYZ>::Ptr ns, pcl::search::Search<pcl::PointXYZ>::Ptr fs) {
    auto normals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
    pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cloud);
    ne.setSearchMethod(ns);
    ne.setRadiusSearch(normal_radius);
    ne.compute(*normals);
    pcl::FPFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fe;
    fe.setInputCloud(cloud);
    fe.setInputNormals(normals);
    fe.setSearchMethod(fs);
    fe.setRadiusSearch(feature_radius);
    pcl::PointCloud<pcl::FPFHSignature33> out;
    fe.compute(out);
    return out;
  };
  const auto kd = describe(pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>(),
                           pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
  const auto cells = describe(pcl::make_shared<CellSearch>(normal_radius * (1 + 1e-4)),
                              pcl::make_shared<CellSearch>(feature_radius * (1 + 1e-4)));
  ASSERT_EQ(kd.size(), cells.size());
  int described = 0;
  for (std::size_t i = 0; i < kd.size(); ++i) {
    float sum = 0;
    for (int k = 0; k < 33; ++k) {
      const float x = kd[i].histogram[k], y = cells[i].histogram[k];
      ASSERT_TRUE((std::isnan(x) && std::isnan(y)) || x == y) << "point " << i << " bin " << k;
      if (std::isfinite(x)) sum += x;
    }
    described += sum > 0;
  }
  EXPECT_GT(described, static_cast<int>(kd.size()) / 2);
}

}  // namespace
}  // namespace scanreg
