// What scanreg writes, read back by readers that are not ours (VTK, PCL): every merged mesh and
// merged point cloud lands on the registered scans, in world coordinates, also 500 km from the
// origin (UTM-sized).
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

#include "core/pipeline/create_project.h"
#include "core/pipeline/export_clouds.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/project_scans.h"
#include "core/simulate/project_sim.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

// Two simulated stations registered at their true poses, the world shifted by `offset`.
std::vector<Scan> RegisteredScans(const Eigen::Vector3d& offset) {
  SimulatedProjectOptions o;
  o.stations = 2;
  o.scanner.cols = 900;
  o.scanner.rows = 225;
  o.seed = o.scanner.seed = o.scene.seed = 7;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(scans.ok());
  if (!scans.ok()) return {};
  for (Scan& s : *scans) s.world_from_scan = Eigen::Translation3d(offset) * *s.reference_world_from_scan;
  return *scans;
}

pipeline::MergeResult Merge(const std::vector<Scan>& scans, double voxel) {
  pipeline::MergeOptions options;
  options.method = pipeline::MergeMethod::kTsdf;
  options.voxel_m = voxel;
  options.max_range_m = 15;
  NullProgress progress;
  CancelToken cancel;
  Expected<pipeline::MergeResult> r = pipeline::MergeScans(scans, {}, options, progress, cancel);
  EXPECT_TRUE(r.ok()) << r.error().ToString();
  return r.ok() ? *r : pipeline::MergeResult{};
}

std::vector<Eigen::Vector3d> WorldVertices(const merge::Mesh& mesh) {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : mesh.vertices) v.push_back(mesh.origin + p.cast<double>());
  return v;
}

template <typename Reader>
std::vector<Eigen::Vector3d> ReadWithVtk(const std::filesystem::path& path) {
  auto reader = vtkSmartPointer<Reader>::New();
  reader->SetFileName(path.c_str());
  reader->Update();
  std::vector<Eigen::Vector3d> out;
  vtkPoints* points = reader->GetOutput()->GetPoints();
  if (!points) return out;
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i) {
    double p[3];
    points->GetPoint(i, p);
    out.emplace_back(p[0], p[1], p[2]);
  }
  return out;
}

// Through PCL's PLY parser, in the file's own precision (FLOAT64 fields stay double).
std::vector<Eigen::Vector3d> ReadPlyWithPcl(const std::filesystem::path& path) {
  pcl::PCLPointCloud2 cloud;
  std::vector<Eigen::Vector3d> out;
  if (pcl::io::loadPLYFile(path.string(), cloud) != 0) return out;
  int offset[3] = {-1, -1, -1};
  for (const auto& f : cloud.fields) {
    for (int d = 0; d < 3; ++d)
      if (f.name == std::string(1, char('x' + d)) && f.datatype == pcl::PCLPointField::FLOAT64) offset[d] = f.offset;
  }
  if (offset[0] < 0 || offset[1] < 0 || offset[2] < 0) return out;  // not doubles: fails the size check
  for (std::size_t i = 0; i < std::size_t(cloud.width) * cloud.height; ++i) {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) std::memcpy(&p[d], cloud.data.data() + i * cloud.point_step + offset[d], 8);
    if (p.allFinite()) out.push_back(p);  // PCL reads a range_grid as an organized cloud, NaN where empty
  }
  return out;
}

// Largest distance from each read point to the nearest expected point (a voxel hash of `expected`).
double WorstDistance(const std::vector<Eigen::Vector3d>& read, const std::vector<Eigen::Vector3d>& expected,
                     double cell) {
  auto key = [cell](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = (p / cell).array().floor();
    return (std::int64_t(q.x()) * 73856093) ^ (std::int64_t(q.y()) * 19349663) ^ (std::int64_t(q.z()) * 83492791);
  };
  std::unordered_multimap<std::int64_t, Eigen::Vector3d> grid;
  for (const auto& p : expected) grid.emplace(key(p), p);
  double worst = 0;
  for (const auto& p : read) {
    double best = 1e300;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto range = grid.equal_range(key(p + cell * Eigen::Vector3d(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) best = std::min(best, (it->second - p).norm());
        }
    worst = std::max(worst, best);
  }
  return worst;
}

// Median distance from mesh vertices to the registered scan points (world coordinates).
double MedianDistanceToScans(const std::vector<Eigen::Vector3d>& vertices, const std::vector<Scan>& scans) {
  std::vector<Eigen::Vector3d> points;
  for (const Scan& s : scans)
    for (std::size_t i = 0; i < s.size(); i += 3)
      if (s.valid[i]) points.push_back(s.world_from_scan * s.points[i].cast<double>());
  std::vector<double> d;
  for (std::size_t i = 0; i < vertices.size(); i += std::max<std::size_t>(1, vertices.size() / 400)) {
    d.push_back(WorstDistance({vertices[i]}, points, 0.5));
  }
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d.empty() ? 1e9 : d[d.size() / 2];
}

TEST(ThirdPartyReaders, VtkPlacesMeshesAndPointsOnTheRegisteredScans) {
  const Eigen::Vector3d offset(24.0, -8.0, 0.0);  // the demo's frame: not at the origin
  const std::vector<Scan> scans = RegisteredScans(offset);
  ASSERT_EQ(scans.size(), 2u);
  const double voxel = 0.1;
  const merge::Mesh mesh = Merge(scans, voxel).mesh;
  ASSERT_GT(mesh.triangles.size(), 1000u);
  ASSERT_GT(mesh.origin.norm(), 1.0);  // the mesh is stored relative to an origin of its own
  test::TempDir dir;
  for (const char* name : {"m.ply", "m.obj", "m.stl"}) ASSERT_TRUE(pipeline::WriteMesh(dir / name, mesh)) << name;
  ASSERT_TRUE(pipeline::WritePoints(dir / "p.ply", mesh));
  const std::vector<Eigen::Vector3d> world = WorldVertices(mesh);
  const std::vector<std::pair<std::string, std::vector<Eigen::Vector3d>>> read = {
      {"m.ply", ReadWithVtk<vtkPLYReader>(dir / "m.ply")},
      {"m.obj", ReadWithVtk<vtkOBJReader>(dir / "m.obj")},
      {"m.stl", ReadWithVtk<vtkSTLReader>(dir / "m.stl")},
      {"p.ply", ReadWithVtk<vtkPLYReader>(dir / "p.ply")}};
  for (const auto& [name, points] : read) {
    SCOPED_TRACE(name);
    ASSERT_GT(points.size(), mesh.vertices.size() / 2);  // STL merges shared corners; the others keep all
    // Every vertex VTK reads is one of the mesh's world vertices (VTK keeps floats: 10 µm here) ...
    EXPECT_LT(WorstDistance(points, world, 0.05), 1e-4);
    // ... and the mesh lies on the registered scans (within half a voxel).
    EXPECT_LT(MedianDistanceToScans(points, scans), voxel / 2);
  }
}

TEST(ThirdPartyReaders, PclReadsUtmSizedPlyExactly) {
  const Eigen::Vector3d offset(500000.0, 5000000.0, 120.0);  // UTM-sized
  const std::vector<Scan> scans = RegisteredScans(offset);
  ASSERT_EQ(scans.size(), 2u);
  const merge::Mesh mesh = Merge(scans, 0.1).mesh;
  ASSERT_GT(mesh.triangles.size(), 1000u);
  test::TempDir dir;
  ASSERT_TRUE(pipeline::WriteMesh(dir / "m.ply", mesh));
  ASSERT_TRUE(pipeline::WritePoints(dir / "p.ply", mesh));
  const std::vector<Eigen::Vector3d> world = WorldVertices(mesh);
  for (const char* name : {"m.ply", "p.ply"}) {
    SCOPED_TRACE(name);
    const std::vector<Eigen::Vector3d> read = ReadPlyWithPcl(dir / name);
    ASSERT_EQ(read.size(), world.size());
    double worst = 0;
    for (std::size_t i = 0; i < read.size(); ++i) worst = std::max(worst, (read[i] - world[i]).norm());
    EXPECT_LT(worst, 1e-6);  // 1 µm 5,000 km from the origin: no float on the way
    EXPECT_LT(MedianDistanceToScans(read, scans), 0.05);
  }
}

TEST(ThirdPartyReaders, PclPlacesExportedPlyCloudsAtTheirRegisteredWorldPoints) {
  test::TempDir dir;
  SimulatedProjectOptions o;
  o.stations = 2;
  o.scanner.cols = 300;
  o.scanner.rows = 80;
  o.seed = o.scanner.seed = o.scene.seed = 5;
  NullProgress progress;
  CancelToken cancel;
  Expected<io::Project> project = pipeline::WriteSimulatedProject(o, dir / "p", progress, cancel);
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  const Eigen::Translation3d utm(500000.0, 5000000.0, 120.0);
  for (io::ProjectScan& s : project->scans) {
    s.world_from_scan = utm * *s.reference_world_from_scan;
    s.registered = true;
  }
  pipeline::ExportCloudsOptions options;
  options.dir = dir / "out";
  options.format = "ply";
  auto exported = pipeline::ExportClouds(*project, options, progress, cancel);
  ASSERT_TRUE(exported.ok()) << exported.error().ToString();
  auto scans = pipeline::LoadProjectScans(*project, progress, cancel);
  ASSERT_TRUE(scans.ok());
  for (std::size_t i = 0; i < scans->size(); ++i) {
    const Scan& scan = (*scans)[i];
    std::vector<Eigen::Vector3d> world;
    for (std::size_t k = 0; k < scan.size(); ++k)
      if (scan.valid[k]) world.push_back(project->scans[i].world_from_scan * scan.points[k].cast<double>());
    const std::vector<Eigen::Vector3d> read = ReadPlyWithPcl((*exported)[i].file);
    ASSERT_EQ(read.size(), world.size()) << scan.name;
    EXPECT_LT(WorstDistance(read, world, 0.01), 1e-5) << scan.name;  // 5,000 km out: exact to 10 µm
  }
}

}  // namespace
}  // namespace scanreg
