#include "core/common/progress.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace scanreg {
namespace {

TEST(ProgressTest, SubProgressMapsOntoParentRange) {
  std::vector<double> seen;
  CallbackProgress parent([&](double f, const std::string&) { seen.push_back(f); });
  SubProgress sub(parent, 0.5, 0.75);
  sub.Report(0.0, "a");
  sub.Report(1.0, "a");
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_DOUBLE_EQ(seen[0], 0.5);
  EXPECT_DOUBLE_EQ(seen[1], 0.75);
}

TEST(ProgressTest, CancelFromAnotherThreadIsSeen) {
  CancelToken token;
  EXPECT_FALSE(token.IsCancelled());
  std::thread t([&] { token.Cancel(); });
  t.join();
  EXPECT_TRUE(token.IsCancelled());
}

}  // namespace
}  // namespace scanreg
