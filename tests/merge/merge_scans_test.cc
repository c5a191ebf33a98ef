// pipeline::MergeScans / WriteMesh: selection of registered scans, errors, cancel writes nothing.
#include "core/pipeline/merge_scans.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/merge/merge_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

std::vector<Scan> TwoSpheres() {
  // Scan 0 sees a sphere at the origin, scan 1 one 5 m away (unregistered in the test).
  std::vector<Scan> scans;
  scans.push_back(
      test::MakeWindowScan(test::SphereCaster({0, 0, 0}, 0.3), {2, 0, 0}, {0, 0, 0}, 60, 60, 0.2, 0.005, 1, "near"));
  scans.push_back(
      test::MakeWindowScan(test::SphereCaster({5, 5, 0}, 0.3), {7, 5, 0}, {5, 5, 0}, 60, 60, 0.2, 0.005, 2, "far"));
  return scans;
}

TEST(MergeScansPipeline, MergesOnlySelectedScansAndWrites) {
  const auto scans = TwoSpheres();
  MergeOptions options;
  options.voxel_m = 0.02;
  options.sigma_m = 0.005;
  options.method = MergeMethod::kTsdf;
  NullProgress progress;
  CancelToken cancel;
  auto result = MergeScans(scans, {true, false}, options, progress, cancel);
  ASSERT_TRUE(result) << result.error().ToString();
  EXPECT_EQ(result->scans, 1u);
  for (const auto& v : result->mesh.vertices) {
    EXPECT_LT((result->mesh.origin + v.cast<double>()).norm(), 0.4);  // nothing from the far sphere
  }
  test::TempDir dir;
  ASSERT_TRUE(WriteMesh(dir / "mesh.ply", result->mesh));
  EXPECT_TRUE(std::filesystem::exists(dir / "mesh.ply"));
  EXPECT_FALSE(WriteMesh(dir / "mesh.vtk", result->mesh));
  // The merged point cloud: one point per mesh vertex, re-read from the PLY header.
  ASSERT_TRUE(WritePoints(dir / "points.ply", result->mesh));
  std::ifstream in(dir / "points.ply", std::ios::binary);
  std::string line;
  long vertices = -1;
  while (std::getline(in, line) && line != "end_header") {
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stol(line.substr(15));
  }
  EXPECT_EQ(vertices, long(result->mesh.vertices.size()));
  // double x y z, float quality (the scans have no colour)
  EXPECT_EQ(std::filesystem::file_size(dir / "points.ply"), std::size_t(in.tellg()) + 28 * vertices);
  const Status xyz = WritePoints(dir / "points.xyz", result->mesh);
  ASSERT_FALSE(xyz);
  EXPECT_NE(xyz.error().message.find(".ply"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "points.xyz"));
}

TEST(MergeScansPipeline, CancelledMergeWritesNoFile) {
  const auto scans = TwoSpheres();
  MergeOptions options;
  NullProgress progress;
  CancelToken cancel;
  // Cancel from the progress callback once the field is under way.
  CallbackProgress cancelling([&](double f, const std::string&) {
    if (f > 0.1) cancel.Cancel();
  });
  test::TempDir dir;
  auto result = MergeScans(scans, {}, options, cancelling, cancel);
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().code, ErrorCode::kCancelled);
  // The caller writes only on success: the directory stays empty.
  if (result) {
    ASSERT_TRUE(WriteMesh(dir / "mesh.ply", result->mesh));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MergeScansPipeline, ErrorsNameTheProblem) {
  const auto scans = TwoSpheres();
  NullProgress progress;
  CancelToken cancel;
  MergeOptions options;
  options.voxel_m = -0.01;
  auto bad = MergeScans(scans, {}, options, progress, cancel);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("voxel size"), std::string::npos) << bad.error().message;
  options.voxel_m = 0.02;
  auto none = MergeScans(scans, {false, false}, options, progress, cancel);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("register"), std::string::npos) << none.error().message;
  auto empty = MergeScans({}, {}, options, progress, cancel);
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("no scan"), std::string::npos) << empty.error().message;
  EXPECT_FALSE(MergeScans(scans, {true}, options, progress, cancel));  // flags do not match the scans
}

}  // namespace
}  // namespace scanreg::pipeline
