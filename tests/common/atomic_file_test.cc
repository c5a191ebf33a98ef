#include "core/common/atomic_file.h"

#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <cerrno>
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

// A process killed mid-write leaves its temporary; the next write into the same folder removes it
// (whichever file it was for), but never one of a process that still runs, nor a file that only
// looks similar. Temporaries are hidden from listings and globs.
TEST(AtomicFileTest, StaleTemporariesOfDeadProcessesAreRemoved) {
  test::TempDir dir;
  const auto path = dir / "a.txt";
  pid_t dead = 0;
  for (pid_t p = 4000000; p > 300000; p -= 9973) {
    if (::kill(p, 0) != 0 && errno == ESRCH) {
      dead = p;
      break;
    }
  }
  ASSERT_GT(dead, 0);
  const auto stale = dir / (".a.txt.tmp-" + std::to_string(dead) + "-0");
  const auto live = dir / (".a.txt.tmp-" + std::to_string(::getpid()) + "-99999");
  const auto other = dir / (".b.txt.tmp-" + std::to_string(dead) + "-0");
  const auto user = dir / (".b.txt.tmp-" + std::to_string(dead) + "-notes");
  for (const auto& f : {stale, live, other, user}) std::ofstream(f) << "partial";
  AtomicFile file(path);
  EXPECT_EQ(file.temp_path().filename().string().rfind(".a.txt.tmp-", 0), 0u) << file.temp_path();
  ASSERT_TRUE(file.Open().ok());
  ASSERT_TRUE(file.Write("x").ok());
  ASSERT_TRUE(file.Commit().ok());
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(live)) << "a running process's temporary stays";
  EXPECT_FALSE(std::filesystem::exists(other)) << "a dead process's temporary of another file in the folder";
  EXPECT_TRUE(std::filesystem::exists(user)) << "only names of the form .<name>.tmp-<pid>-<n>";
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
