// A full disk while writing (issue 16): every writer turns the failed write into a clear error
// naming the file, leaves no partial output and no temporary behind, and keeps the previous file.
// The disk fills by injection: a file-size limit (RLIMIT_FSIZE, with SIGXFSZ ignored) makes every
// write beyond 64 kB fail with EFBIG, as a full disk fails with ENOSPC.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <fstream>
#include <functional>

#include "core/io/e57_writer.h"
#include "core/io/las_writer.h"
#include "core/io/pcd.h"
#include "core/io/ply.h"
#include "core/io/pose_csv.h"
#include "core/io/pose_file.h"
#include "core/io/project.h"
#include "core/io/ptx.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

constexpr rlim_t kLimit = 64 * 1024;

// Runs `write` with files limited to kLimit bytes; the limit is lifted again before returning.
Status WithFullDisk(const std::function<Status()>& write) {
  rlimit old{};
  getrlimit(RLIMIT_FSIZE, &old);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit full = old;
  full.rlim_cur = kLimit;
  EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &full), 0);
  Status s = Status::Ok();
  try {
    s = write();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the writer threw: " << e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  return s;
}

std::vector<std::string> Entries(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(DiskFull, EveryWriterFailsCleanlyKeepsThePreviousFileAndLeavesNoTemporary) {
  test::TempDir dir;
  const Scan scan = test::MakeRoomScan(200, 400);  // 80,000 cells: every format exceeds 64 kB
  std::vector<NamedPose> poses;
  Project project;
  for (int i = 0; i < 3000; ++i) {
    const std::string name = "station_" + std::to_string(i);
    poses.emplace_back(name, Eigen::Isometry3d(Eigen::Translation3d(i, 0.5 * i, 1.0)));
    ProjectScan ps;
    ps.name = name;
    ps.path = dir / (name + ".ptx");
    ps.world_from_scan = poses.back().world_from_scan;
    project.scans.push_back(ps);
  }
  LasCloud las;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) las.points.push_back(scan.points[i].cast<double>());
  NullProgress progress;
  CancelToken cancel;
  const std::vector<std::pair<std::string, std::function<Status(const std::filesystem::path&)>>> writers = {
      {"scan.ptx", [&](const auto& p) { return WritePtx(p, {scan}, progress, cancel); }},
      {"scan.e57", [&](const auto& p) { return WriteE57(p, {scan}, progress, cancel); }},
      {"scan.ply", [&](const auto& p) { return WritePly(p, scan, progress, cancel); }},
      {"scan.pcd", [&](const auto& p) { return WritePcd(p, scan, progress, cancel); }},
      {"cloud.las", [&](const auto& p) { return WriteLas(p, las); }},
      {"p.scanreg.json", [&](const auto& p) { return SaveProject(project, p); }},
      {"poses.json", [&](const auto& p) { return WritePosesJson(p, poses); }},
      {"poses.csv", [&](const auto& p) { return WritePosesCsv(p, poses); }},
  };
  for (const auto& [name, write] : writers) {
    const std::filesystem::path path = dir / name;
    std::ofstream(path) << "the previous file";
    const Status s = WithFullDisk([&] { return write(path); });
    ASSERT_FALSE(s.ok()) << name << ": the write that could not fit reported success";
    EXPECT_NE(s.error().message.find(name), std::string::npos) << name << ": " << s.error().message;
    std::ifstream in(path);
    std::string kept((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(kept, "the previous file") << name;
    EXPECT_TRUE(write(path).ok()) << name << ": the same write with room must succeed";
    EXPECT_GT(std::filesystem::file_size(path), kLimit) << name;
  }
  std::vector<std::string> expected;
  for (const auto& w : writers) expected.push_back(w.first);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(Entries(dir.path()), expected);  // no temporary left by any failed write
}

}  // namespace
}  // namespace scanreg::io
