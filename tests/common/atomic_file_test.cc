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

int CountFiles(const std::filesystem::path& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST(AtomicFileTest, CommitReplacesTheTargetAndLeavesNoTemporary) {
  test::TempDir dir;
  const auto path = dir / "a.txt";
  std::ofstream(path) << "old";
  AtomicFile file(path);
  ASSERT_TRUE(file.Open().ok());
  ASSERT_TRUE(file.Write("new content").ok());
  EXPECT_EQ(ReadAll(path), "old") << "readers see the old file until the commit";
  ASSERT_TRUE(file.Commit().ok());
  EXPECT_EQ(ReadAll(path), "new content");
  EXPECT_EQ(CountFiles(dir.path()), 1);
}

TEST(AtomicFileTest, AbandonedWriteKeepsTheOldFile) {
  test::TempDir dir;
  const auto path = dir / "a.txt";
  std::ofstream(path) << "original";
  {
    AtomicFile file(path);
    ASSERT_TRUE(file.Open().ok());
    ASSERT_TRUE(file.Write("partial").ok());
  }  // no commit: cancelled or failed
  EXPECT_EQ(ReadAll(path), "original");
  EXPECT_EQ(CountFiles(dir.path()), 1);
}

TEST(AtomicFileTest, MissingFolderIsAClearError) {
  test::TempDir dir;
  AtomicFile file(dir / "no" / "such" / "a.txt");
  Status s = file.Open();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("a.txt"), std::string::npos) << s.error().message;
}

}  // namespace
}  // namespace scanreg
