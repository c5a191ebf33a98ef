// Where tests find real data and scratch space.
#pragma once

#include <filesystem>
#include <string>

namespace scanreg::test {

// $SCANREG_REALDATA, defaulting to tests/data/realdata in the source tree. Empty path when the
// directory does not exist (a user's machine); tests then GTEST_SKIP with a message.
std::filesystem::path RealDataDir();

// A fresh, empty directory under the system temp dir, unique to this test; removed when the
// object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace scanreg::test

// Skips the current test when real data are missing.
#define SCANREG_REQUIRE_REALDATA(dir)                                                              \
  const std::filesystem::path dir = ::scanreg::test::RealDataDir();                               \
  if (dir.empty()) GTEST_SKIP() << "real data not found: set SCANREG_REALDATA to a folder laid out as tests/data/realdata"
