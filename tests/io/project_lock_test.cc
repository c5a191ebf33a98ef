// Runs that cannot trample each other (issue 16, item 4): the project lock and the refusal to save
// over a project that changed on disk since it was read.
#include "core/io/project_lock.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "core/io/project.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(ProjectLock, ASecondWriterRefusesUntilTheFirstIsDone) {
  test::TempDir dir;
  const std::filesystem::path project = dir / "p.scanreg.json";
  {
    Expected<ProjectLock> first = ProjectLock::Acquire(project, "scanreg-cli register");
    ASSERT_TRUE(first.ok()) << first.error().ToString();
    EXPECT_TRUE(std::filesystem::exists(ProjectLockPath(project)));
    Expected<ProjectLock> second = ProjectLock::Acquire(project, "scanreg-cli register");
    ASSERT_FALSE(second.ok());
    EXPECT_NE(second.error().message.find("being written by another run"), std::string::npos) << second.error().message;
    EXPECT_NE(second.error().message.find(std::to_string(::getpid())), std::string::npos) << "names the process";
    EXPECT_NE(second.error().message.find("scanreg-cli register"), std::string::npos) << "and what it does";
  }
  EXPECT_FALSE(std::filesystem::exists(ProjectLockPath(project))) << "released with its holder";
  EXPECT_TRUE(ProjectLock::Acquire(project, "again").ok());
}

TEST(ProjectLock, ALockOfAProcessThatNoLongerRunsIsTakenOver) {
  test::TempDir dir;
  const std::filesystem::path project = dir / "p.scanreg.json";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);  // the pid no longer runs
  std::ofstream(ProjectLockPath(project)) << child << " scanreg-cli register (killed)\n";
  Expected<ProjectLock> lock = ProjectLock::Acquire(project, "scanreg-cli register");
  ASSERT_TRUE(lock.ok()) << lock.error().ToString();
  EXPECT_NE(ReadText(ProjectLockPath(project)).find(std::to_string(::getpid())), std::string::npos);
}

TEST(ProjectLock, RunsRacingForAStaleLockNeverHoldItTogether) {
  // Eight processes start at once on a project whose lock was left by a killed run; each that gets
  // the lock marks "I hold it" with an exclusive file for a moment. Two holders at a time would
  // find the mark taken.
  test::TempDir dir;
  const std::filesystem::path project = dir / "p.scanreg.json";
  const std::filesystem::path mark = dir / "holder";
  for (int round = 0; round < 5; ++round) {
    std::ofstream(ProjectLockPath(project)) << "999999 scanreg-cli register (killed)\n";
    std::vector<pid_t> children;
    for (int k = 0; k < 8; ++k) {
      const pid_t child = ::fork();
      ASSERT_GE(child, 0);
      if (child == 0) {
        Expected<ProjectLock> lock = ProjectLock::Acquire(project, "racer");
        if (!lock.ok()) ::_exit(lock.error().code == ErrorCode::kConflict ? 1 : 3);
        const int fd = ::open(mark.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
        if (fd < 0) ::_exit(2);  // someone else holds it too
        ::usleep(20000);
        ::close(fd);
        std::filesystem::remove(mark);
        ::_exit(0);
      }
      children.push_back(child);
    }
    int holders = 0;
    for (pid_t child : children) {
      int status = 0;
      ASSERT_EQ(::waitpid(child, &status, 0), child);
      ASSERT_TRUE(WIFEXITED(status));
      const int code = WEXITSTATUS(status);
      EXPECT_NE(code, 2) << "two runs held the lock at once";
      EXPECT_NE(code, 3) << "a run failed for another reason than the lock";
      holders += code == 0;
    }
    EXPECT_GE(holders, 1) << "the stale lock was never taken over";
  }
}

TEST(ProjectLock, ASaveOverAProjectChangedOnDiskIsRefusedAndWritesNothing) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "p.scanreg.json";
  Project p;
  p.settings["note"] = "original";
  ASSERT_TRUE(SaveProject(p, path).ok());
  Expected<Project> mine = LoadProject(path);
  Expected<Project> theirs = LoadProject(path);
  ASSERT_TRUE(mine.ok() && theirs.ok());
  EXPECT_NE(mine->disk_digest, 0u);
  // Another run saves first...
  theirs->settings["note"] = "theirs";
  ASSERT_TRUE(SaveProject(*theirs, path).ok());
  // ...so ours, read before, is refused and their result stays.
  mine->settings["note"] = "mine";
  const Status s = SaveProject(*mine, path);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("changed on disk"), std::string::npos) << s.error().message;
  EXPECT_NE(ReadText(path).find("theirs"), std::string::npos);
  // Saving elsewhere is allowed; saving after a save of one's own is too (the digest follows).
  std::uint64_t digest = 0;
  ASSERT_TRUE(SaveProject(*mine, dir / "mine.scanreg.json", &digest).ok());
  Expected<Project> again = LoadProject(path);
  ASSERT_TRUE(again.ok());
  again->settings["note"] = "first save";
  ASSERT_TRUE(SaveProject(*again, path, &again->disk_digest).ok());
  again->settings["note"] = "second save";
  EXPECT_TRUE(SaveProject(*again, path, &again->disk_digest).ok());
  EXPECT_NE(ReadText(path).find("second save"), std::string::npos);
}

}  // namespace
}  // namespace scanreg::io
