#include "core/common/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(AtomicFileTest, ReplacesContentAndLeavesNoTemporary) {
  test::TempDir dir;
  const auto path = dir / "a.txt";
  ASSERT_TRUE(WriteFileAtomically(path, "first").ok());
  ASSERT_TRUE(WriteFileAtomically(path, "second").ok());
  EXPECT_EQ(ReadAll(path), "second");
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);
}

TEST(AtomicFileTest, FailedWriteKeepsTheOldFile) {
  test::TempDir dir;
  const auto path = dir / "a.txt";
  ASSERT_TRUE(WriteFileAtomically(path, "original").ok());
  Status s = WriteFileAtomically(path, [](std::FILE* f) -> Status {
    std::fputs("partial", f);
    return MakeError(ErrorCode::kCancelled, "cancelled by the user");
  });
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(ReadAll(path), "original");
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);
}

TEST(AtomicFileTest, MissingFolderIsAClearError) {
  test::TempDir dir;
  Status s = WriteFileAtomically(dir / "no" / "such" / "a.txt", "x");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("does not exist"), std::string::npos);
}

}  // namespace
}  // namespace scanreg
