#include "tests/support/test_paths.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <random>

namespace scanreg::test {

std::filesystem::path RealDataDir() {
  const char* env = std::getenv("SCANREG_REALDATA");
  std::filesystem::path dir = env && *env ? std::filesystem::path(env) : std::filesystem::path(SCANREG_DEFAULT_REALDATA);
  std::error_code ec;
  return std::filesystem::is_directory(dir, ec) ? dir : std::filesystem::path();
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "scanreg";
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() /
          ("scanreg_" + name + "_" + std::to_string(rd()) + "_" + std::to_string(counter++));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

}  // namespace scanreg::test
