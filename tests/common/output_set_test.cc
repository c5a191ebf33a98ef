#include "core/common/output_set.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

TEST(OutputSet, AnAbandonedSetRemovesOnlyTheFilesItCreated) {
  test::TempDir dir;
  std::ofstream(dir / "old.txt") << "before";
  {
    OutputSet set;
    for (const char* name : {"old.txt", "new1.txt", "new2.txt"}) {
      set.Track(dir / name);
      std::ofstream(dir / name) << "this run";
    }
    const Error e = set.Failed(MakeError(ErrorCode::kIoError, "disk full"));
    EXPECT_NE(e.message.find("removed the 2 new file(s)"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("1 file(s) that existed before"), std::string::npos) << e.message;
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "old.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir / "new1.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir / "new2.txt"));
}

TEST(OutputSet, ACompleteSetStaysAndAnUnfinishedOneIsRemovedWhenDropped) {
  test::TempDir dir;
  {
    OutputSet set;
    set.Track(dir / "a.txt");
    std::ofstream(dir / "a.txt") << "x";
    set.Complete();
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "a.txt"));
  {
    OutputSet set;  // an early return without Failed(): the destructor cleans up
    set.Track(dir / "b.txt");
    std::ofstream(dir / "b.txt") << "x";
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "b.txt"));
}

}  // namespace
}  // namespace scanreg
