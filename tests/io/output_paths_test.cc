// Outputs never replace inputs: the same file by another name or through a link is refused.
#include "core/io/output_paths.h"

#include <gtest/gtest.h>

#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

TEST(OutputPaths, TheSameFileUnderAnyNameIsRefused) {
  test::TempDir dir;
  test::WriteBytes(dir / "scan.ptx", "x");
  std::filesystem::create_directories(dir / "sub");
  std::filesystem::create_symlink(dir / "scan.ptx", dir / "link.ptx");
  const std::vector<std::filesystem::path> inputs = {dir / "scan.ptx"};
  for (const std::filesystem::path& out : {dir / "scan.ptx", dir / "sub" / ".." / "scan.ptx", dir / "link.ptx"}) {
    const Status s = CheckNotAnInput(out, inputs, "--out");
    ASSERT_FALSE(s.ok()) << out;
    EXPECT_NE(s.error().message.find("is the input file"), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("--out"), std::string::npos);
  }
  EXPECT_TRUE(CheckNotAnInput(dir / "mesh.ply", inputs, "--out").ok());  // not yet existing, another name
  EXPECT_TRUE(CheckNotAnInput(dir / "sub" / "scan.ptx", inputs, "--out").ok());
}

TEST(OutputPaths, ProjectInputsAreTheProjectFileAndEveryScan) {
  Project p;
  p.file = "/data/p.scanreg.json";
  p.scans.resize(2);
  p.scans[0].path = "/data/a.ptx";
  p.scans[1].path = "/data/b.e57";
  const auto inputs = ProjectInputs(p);
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_FALSE(CheckNotAnInput("/data/b.e57", inputs, "--out").ok());
  EXPECT_FALSE(CheckNotAnInput("/data/p.scanreg.json", inputs, "--out").ok());
}

}  // namespace
}  // namespace scanreg::io
