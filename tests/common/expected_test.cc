#include "core/common/expected.h"

#include <gtest/gtest.h>

namespace scanreg {
namespace {

Expected<int> ParsePositive(int v) {
  if (v <= 0) return MakeError(ErrorCode::kInvalidArgument, "value " + std::to_string(v) + " must be positive");
  return v;
}

TEST(ExpectedTest, CarriesValueOrError) {
  Expected<int> good = ParsePositive(3);
  ASSERT_TRUE(good.ok());
  EXPECT_EQ(*good, 3);
  Expected<int> bad = ParsePositive(-2);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().ToString().find("-2 must be positive"), std::string::npos);
}

TEST(StatusTest, DefaultIsOkAndErrorIsNot) {
  Status ok;
  EXPECT_TRUE(ok.ok());
  Status failed = MakeError(ErrorCode::kIoError, "cannot open x");
  EXPECT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::kIoError);
}

}  // namespace
}  // namespace scanreg
