// The desktop's previews (issue 13, item 1): every stride-th row and column of a scan, within a
// global cell budget, with the full scan's grid and point count; read one scan at a time.
#include "core/pipeline/scan_previews.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"

namespace scanreg::pipeline {
namespace {

// A 90 x 200 scan with a hole pattern and an angular grid; points encode their cell.
Scan Patterned() {
  Scan s("p", 90, 200);
  for (int r = 0; r < s.rows; ++r) {
    s.angles.elevation.push_back(0.01f * r);
    for (int c = 0; c < s.cols; ++c)
      if ((r * 7 + c) % 5 != 0) s.Set(r, c, Eigen::Vector3f(float(r), float(c), 1.f), 0.001f * c);
  }
  for (int c = 0; c < s.cols; ++c) s.angles.azimuth.push_back(0.02f * c);
  s.world_from_scan.translation() = Eigen::Vector3d(5, 6, 7);
  return s;
}

TEST(ScanPreviews, APreviewIsTheScansOwnCellsWithinItsBudget) {
  const Scan full = Patterned();
  const ScanPreview p = MakePreview(full, 5000);  // 18 000 cells: every second row and column (4 500)
  EXPECT_EQ(p.stride, 2);
  EXPECT_LE(p.scan.size(), 5000u);
  EXPECT_EQ(p.scan.rows, 45);
  EXPECT_EQ(p.scan.cols, 100);
  EXPECT_EQ(p.full_rows, 90);
  EXPECT_EQ(p.full_cols, 200);
  EXPECT_EQ(p.full_valid, full.CountValid());
  EXPECT_TRUE(p.scan.Validate().ok());
  for (int r = 0; r < p.scan.rows; ++r) {
    for (int c = 0; c < p.scan.cols; ++c) {
      ASSERT_EQ(p.scan.IsValid(r, c), full.IsValid(2 * r, 2 * c)) << r << "," << c;
      if (!p.scan.IsValid(r, c)) continue;
      ASSERT_EQ(p.scan.Point(r, c), full.Point(2 * r, 2 * c));
      ASSERT_EQ(p.scan.Reflectance(r, c), full.Reflectance(2 * r, 2 * c));
    }
  }
  EXPECT_EQ(p.scan.angles.azimuth[7], full.angles.azimuth[14]);
  EXPECT_EQ(p.scan.angles.elevation[7], full.angles.elevation[14]);
  EXPECT_TRUE(p.scan.world_from_scan.isApprox(full.world_from_scan));
  EXPECT_EQ(p.scan.name, "p");

  // A budget the scan fits: the scan itself.
  const ScanPreview whole = MakePreview(full, 18000);
  EXPECT_EQ(whole.stride, 1);
  EXPECT_EQ(whole.scan.size(), full.size());
  EXPECT_EQ(whole.scan.points, full.points);
  // The smallest stride that fits, whatever the budget.
  for (std::size_t budget : {1u, 100u, 4499u, 4500u, 8000u})
    EXPECT_LE(MakePreview(full, budget).scan.size(), std::max<std::size_t>(budget, 1)) << budget;
  EXPECT_EQ(PreviewStride(90, 200, 4499), 3);
  EXPECT_EQ(PreviewStride(750, 3000, kPreviewCells / 100), 4);  // 100 stations of the paper's scans
}

TEST(ScanPreviews, TheBudgetIsSharedByTheProjectsScans) {
  EXPECT_EQ(PreviewCellsPerScan(1), kPreviewCells);
  EXPECT_LE(PreviewCellsPerScan(100) * 100, kPreviewCells);
  EXPECT_GE(PreviewCellsPerScan(1'000'000), 10'000u);  // never nothing to draw
}

TEST(ScanPreviews, AProjectsPreviewsAreReadFromItsFilesNamedAndPosed) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "scan_previews_project";
  std::filesystem::remove_all(dir);
  SimulatedProjectOptions o;
  o.stations = 3;
  o.scanner.cols = 400;
  o.scanner.rows = 100;
  NullProgress progress;
  Expected<io::Project> project = WriteSimulatedProject(o, dir, progress, CancelToken());
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  project->scans[1].world_from_scan.translation() = Eigen::Vector3d(1, 2, 3);
  Expected<std::vector<Scan>> full = LoadProjectScans(*project, progress, CancelToken());
  ASSERT_TRUE(full.ok());

  Expected<std::vector<ScanPreview>> previews = LoadScanPreviews(*project, 10'000, progress, CancelToken());
  ASSERT_TRUE(previews.ok()) << previews.error().ToString();
  ASSERT_EQ(previews->size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const ScanPreview& p = (*previews)[i];
    EXPECT_EQ(p.scan.name, project->scans[i].name);
    EXPECT_EQ(p.stride, 2);  // 40 000 cells in 10 000: every second row and column (50 x 200)
    EXPECT_LE(p.scan.size(), 10'000u);
    EXPECT_EQ(p.full_valid, (*full)[i].CountValid());
    EXPECT_EQ(p.full_rows, 100);
    EXPECT_EQ(p.full_cols, 400);
    EXPECT_TRUE(p.scan.world_from_scan.isApprox(project->scans[i].world_from_scan));
    EXPECT_EQ(p.scan.Point(10, 20), (*full)[i].Point(20, 40));
    EXPECT_EQ(p.scan.IsValid(30, 150), (*full)[i].IsValid(60, 300));
  }
  // Some scans only, in the order asked.
  Expected<std::vector<ScanPreview>> some = LoadScanPreviews(*project, 10'000, progress, CancelToken(), {2, 0});
  ASSERT_TRUE(some.ok());
  ASSERT_EQ(some->size(), 2u);
  EXPECT_EQ((*some)[0].scan.name, project->scans[2].name);
  EXPECT_EQ((*some)[1].scan.name, project->scans[0].name);

  // Read again: from the preview cache beside the scan cache, the same previews.
  int entries = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / ".scanreg-cache"))
    entries += e.path().filename().string().rfind("preview_", 0) == 0;
  EXPECT_EQ(entries, 3);
  Expected<std::vector<ScanPreview>> again = LoadScanPreviews(*project, 10'000, progress, CancelToken());
  ASSERT_TRUE(again.ok());
  for (std::size_t i = 0; i < 3; ++i) {
    const ScanPreview &a = (*previews)[i], &b = (*again)[i];
    EXPECT_EQ(b.stride, a.stride);
    EXPECT_EQ(b.full_valid, a.full_valid);
    EXPECT_EQ(b.full_rows, a.full_rows);
    EXPECT_EQ(b.scan.points, a.scan.points);
    EXPECT_EQ(b.scan.valid, a.scan.valid);
    EXPECT_TRUE(b.scan.world_from_scan.isApprox(project->scans[i].world_from_scan));
  }
  // A corrupt preview entry is made again from the scan.
  for (const auto& e : std::filesystem::directory_iterator(dir / ".scanreg-cache")) {
    if (e.path().filename().string().rfind("preview_", 0) != 0) continue;
    std::filesystem::resize_file(e.path(), std::filesystem::file_size(e.path()) / 2);
  }
  Expected<std::vector<ScanPreview>> rebuilt = LoadScanPreviews(*project, 10'000, progress, CancelToken());
  ASSERT_TRUE(rebuilt.ok());
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ((*rebuilt)[i].scan.points, (*previews)[i].scan.points);

  // A scan asked for twice comes back whole both times (its last use takes it, the first a copy).
  Expected<std::vector<Scan>> twice = LoadProjectScans(*project, progress, CancelToken(), {1, 0, 1});
  ASSERT_TRUE(twice.ok());
  ASSERT_EQ(twice->size(), 3u);
  EXPECT_EQ((*twice)[0].points, (*full)[1].points);
  EXPECT_EQ((*twice)[2].points, (*full)[1].points);
  EXPECT_EQ((*twice)[1].points, (*full)[0].points);

  // A missing file: the error names the scan and the file.
  std::filesystem::remove(project->scans[1].path);
  Expected<std::vector<ScanPreview>> missing = LoadScanPreviews(*project, 10'000, progress, CancelToken());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find(project->scans[1].name), std::string::npos) << missing.error().message;
  EXPECT_NE(missing.error().message.find(project->scans[1].path.filename().string()), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace scanreg::pipeline
