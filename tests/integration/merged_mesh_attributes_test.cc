// Issues 34 and 35: a merged mesh carries the scanners' colour and marks the surface it only
// interpolated — read by readers that are not ours: VTK's PLY reader for the colour, PCL's for the
// vertex gap (scalar_gap: metres to the nearest scan point).
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "core/merge/merge.h"
#include "core/merge/mesh_io.h"
#include "core/merge/vertex_info.h"
#include "tests/merge/merge_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::merge {
namespace {

// A colour that varies slowly with position (1 level per 5 mm at most): a vertex a few millimetres
// from the point that coloured it has nearly that point's colour, and a wrong point's colour shows.
Rgb ColourAt(const Eigen::Vector3d& p) {
  auto channel = [](double v) { return 127.5 + 120.0 * std::sin(2.0 * M_PI * v / 4.0); };
  return ToRgb(channel(p.x()), channel(p.y() + 1.0), channel(p.z() + 2.0));
}

// A 1 m sphere seen from 14 places around it, 100 x 100 cells each; the scans in `plain` without colour.
std::vector<Scan> ColouredSphereScans(const std::vector<int>& plain) {
  const Eigen::Vector3d centre(2.0, -1.0, 0.5);
  std::vector<Scan> scans;
  int k = 0;
  for (const Eigen::Vector3d& eye : test::AllAroundEyes(centre, 4.0)) {
    Scan s = test::MakeWindowScan(test::SphereCaster(centre, 1.0), eye, centre, 100, 100, 0.3, 0.002, 10 + k,
                                  "s" + std::to_string(k));
    if (std::find(plain.begin(), plain.end(), k) == plain.end()) {
      s.AddColour();
      for (std::size_t i = 0; i < s.size(); ++i)
        if (s.valid[i]) s.colour[i] = ColourAt(s.world_from_scan * s.points[i].cast<double>());
    }
    scans.push_back(std::move(s));
    ++k;
  }
  return scans;
}

struct ReadMesh {
  std::vector<Eigen::Vector3d> points;
  std::vector<Rgb> colours;     // VTK's RGB point data
  std::vector<float> gap;       // PCL's "scalar_gap" field
};

ReadMesh ReadBack(const std::filesystem::path& path) {
  ReadMesh out;
  auto reader = vtkSmartPointer<vtkPLYReader>::New();
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  if (!poly || !poly->GetPoints()) return out;
  auto* rgb = vtkUnsignedCharArray::SafeDownCast(poly->GetPointData()->GetScalars());
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double p[3];
    poly->GetPoint(i, p);
    out.points.emplace_back(p[0], p[1], p[2]);
    if (rgb && rgb->GetNumberOfComponents() == 3) {
      out.colours.push_back(Rgb{rgb->GetValue(3 * i), rgb->GetValue(3 * i + 1), rgb->GetValue(3 * i + 2)});
    }
  }
  pcl::PCLPointCloud2 cloud;
  if (pcl::io::loadPLYFile(path.string(), cloud) != 0) return out;
  for (const auto& f : cloud.fields) {
    if (f.name != "scalar_gap" || f.datatype != pcl::PCLPointField::FLOAT32) continue;
    for (std::size_t i = 0; i < std::size_t(cloud.width) * cloud.height; ++i) {
      float q;
      std::memcpy(&q, cloud.data.data() + i * cloud.point_step + f.offset, 4);
      out.gap.push_back(q);
    }
  }
  return out;
}

int ColourError(const Rgb& a, const Rgb& b) {
  int worst = 0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(int(a[c]) - int(b[c])));
  return worst;
}

TEST(MergedMeshAttributes, TheScannersColourReachesTheMeshAndEveryVertexSaysHowFarItsMeasurementIs) {
  // Three of the fourteen scans have no colour: their points colour nothing.
  const std::vector<Scan> scans = ColouredSphereScans({3, 7, 11});
  MergeOptions options;
  options.voxel_m = 0.02;
  options.sigma_m = 0.002;
  NullProgress progress;
  CancelToken cancel;
  Expected<MergeResult> merged = MergeScanSet(scans, options, progress, cancel);
  ASSERT_TRUE(merged.ok()) << merged.error().ToString();
  ASSERT_TRUE(merged->mesh.coloured);
  const test::TempDir dir;
  ASSERT_TRUE(WriteMeshFile(dir / "sphere.ply", merged->mesh).ok());
  const ReadMesh read = ReadBack(dir / "sphere.ply");
  ASSERT_EQ(read.points.size(), merged->mesh.vertices.size());
  ASSERT_EQ(read.colours.size(), read.points.size()) << "VTK finds no red green blue on the vertices";
  ASSERT_EQ(read.gap.size(), read.points.size()) << "PCL finds no gap on the vertices";
  std::size_t wrong = 0, far = 0;
  double worst_gap = 0.0;
  for (std::size_t i = 0; i < read.points.size(); ++i) {
    // The reader puts every vertex on the sphere (within a voxel).
    ASSERT_NEAR((read.points[i] - Eigen::Vector3d(2.0, -1.0, 0.5)).norm(), 1.0, options.voxel_m);
    wrong += ColourError(read.colours[i], ColourAt(read.points[i])) > 8;
    far += read.gap[i] > FilledGap(options.voxel_m);
    worst_gap = std::max(worst_gap, double(read.gap[i]));
  }
  std::printf("%zu vertices: %zu with a colour more than 8 levels off the surface's, %zu beyond 1.5 voxels of a scan "
              "point (largest gap %.1f mm)\n",
              read.points.size(), wrong, far, 1e3 * worst_gap);
  EXPECT_GT(read.points.size(), 10000u);
  EXPECT_LE(wrong, read.points.size() / 200);  // 0.5 %
  EXPECT_EQ(far, 0u);
  EXPECT_EQ(merged->interpolated_vertices, 0u);
  std::vector<float> gaps = read.gap;
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  EXPECT_GT(gaps[gaps.size() / 2], 0.0f);  // a distance, not a flag
  EXPECT_LE(gaps[gaps.size() / 2], 0.5 * options.voxel_m);  // the points are 1.8 cm apart

  // No scan with colour: no colour written, the gap still.
  const std::vector<Scan> plain = ColouredSphereScans({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13});
  Expected<MergeResult> grey = MergeScanSet(plain, options, progress, cancel);
  ASSERT_TRUE(grey.ok()) << grey.error().ToString();
  EXPECT_FALSE(grey->mesh.coloured);
  ASSERT_TRUE(WriteMeshFile(dir / "grey.ply", grey->mesh).ok());
  const ReadMesh read_grey = ReadBack(dir / "grey.ply");
  EXPECT_TRUE(read_grey.colours.empty());
  EXPECT_EQ(read_grey.gap.size(), read_grey.points.size());
}

}  // namespace
}  // namespace scanreg::merge
