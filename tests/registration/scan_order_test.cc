#include "core/registration/scan_order.h"

#include <gtest/gtest.h>

namespace scanreg {
namespace {

// Root (default) = 1 (heaviest edge 1->2 = 80); tree 1->2, 2->3, 1->0; scan 4 has no edges.
Eigen::MatrixXi Confusion() {
  Eigen::MatrixXi c(5, 5);
  c << 1000, 50, 10, 5, 0,  //
      45, 900, 80, 20, 0,   //
      12, 70, 800, 60, 0,   //
      4, 25, 65, 700, 0,    //
      0, 0, 0, 0, 600;
  return c;
}

TEST(ScanOrder, MaximumSpanningTreeFromTailOfHeaviestEdge) {
  auto order = ComputeScanOrder(Confusion(), std::nullopt, {}, {});
  ASSERT_TRUE(order.ok()) << order.error().ToString();
  EXPECT_EQ(order->root, 1);
  EXPECT_EQ(order->parent, (std::vector<int>{1, -1, 1, 2, -1}));
  EXPECT_EQ(order->order, (std::vector<int>{1, 2, 3, 0}));
  EXPECT_EQ(order->unplaced, (std::vector<int>{4}));
}

TEST(ScanOrder, GivenRoot) {
  auto order = ComputeScanOrder(Confusion(), 0, {}, {});
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->root, 0);
  EXPECT_EQ(order->parent, (std::vector<int>{-1, 0, 1, 2, -1}));
  EXPECT_EQ(order->order, (std::vector<int>{0, 1, 2, 3}));
}

TEST(ScanOrder, OverrideBeatsWeights) {
  std::vector<std::optional<int>> overrides(5);
  overrides[3] = 0;  // C(0, 3) = 5 only
  auto order = ComputeScanOrder(Confusion(), std::nullopt, overrides, {});
  ASSERT_TRUE(order.ok()) << order.error().ToString();
  EXPECT_EQ(order->parent, (std::vector<int>{1, -1, 1, 0, -1}));
  EXPECT_EQ(order->order, (std::vector<int>{1, 2, 0, 3}));
  // Overrides even reach a scan with no usable edge.
  overrides[4] = 3;
  order = ComputeScanOrder(Confusion(), std::nullopt, overrides, {});
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->parent[4], 3);
  EXPECT_TRUE(order->unplaced.empty());
}

TEST(ScanOrder, ExcludedEdgeUsesNextBest) {
  auto order = ComputeScanOrder(Confusion(), std::nullopt, {}, {{2, 3}});
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->parent, (std::vector<int>{1, -1, 1, 1, -1}));  // 3 now hangs on 1 (C(1,3) = 20)
  EXPECT_EQ(order->order, (std::vector<int>{1, 2, 0, 3}));
  // Excluding the heaviest edge also moves the default root's choice of first child.
  order = ComputeScanOrder(Confusion(), std::nullopt, {}, {{1, 2}, {2, 1}});
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->root, 3);  // next heaviest usable edge: 3 -> 2 = 65
}

TEST(ScanOrder, OverrideCycleAndSelfAreErrors) {
  std::vector<std::optional<int>> overrides(5);
  overrides[0] = 1;
  overrides[1] = 0;
  auto order = ComputeScanOrder(Confusion(), std::nullopt, overrides, {});
  ASSERT_FALSE(order.ok());
  EXPECT_EQ(order.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(order.error().message.find("0 -> 1 -> 0"), std::string::npos) << order.error().message;

  std::vector<std::optional<int>> self(5);
  self[2] = 2;
  order = ComputeScanOrder(Confusion(), std::nullopt, self, {});
  ASSERT_FALSE(order.ok());
  EXPECT_NE(order.error().message.find("scan 2"), std::string::npos);

  std::vector<std::optional<int>> on_root(5);
  on_root[0] = 3;
  EXPECT_FALSE(ComputeScanOrder(Confusion(), 0, on_root, {}).ok());
}

TEST(ScanOrder, BadInputs) {
  EXPECT_FALSE(ComputeScanOrder(Eigen::MatrixXi(2, 3), std::nullopt, {}, {}).ok());
  EXPECT_FALSE(ComputeScanOrder(Confusion(), 7, {}, {}).ok());
  EXPECT_FALSE(ComputeScanOrder(Confusion(), std::nullopt, std::vector<std::optional<int>>(3), {}).ok());
  EXPECT_FALSE(ComputeScanOrder(Confusion(), std::nullopt, {}, {{0, 9}}).ok());
}

TEST(ScanOrder, MinWeight) {
  auto order = ComputeScanOrder(Confusion(), 0, {}, {}, 30);
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->parent, (std::vector<int>{-1, 0, 1, 2, -1}));
  order = ComputeScanOrder(Confusion(), 0, {}, {}, 70);
  ASSERT_TRUE(order.ok());
  EXPECT_EQ(order->order, (std::vector<int>{0}));  // 0 -> 1 is only 50
  EXPECT_EQ(order->unplaced, (std::vector<int>{1, 2, 3, 4}));
}

}  // namespace
}  // namespace scanreg
