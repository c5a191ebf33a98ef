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
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <unordered_map>

#include "core/io/pose_file.h"
#include "core/io/ply.h"
#include "core/io/scan_file.h"
#include "core/io/text_parse.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/export_clouds.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/scan_store.h"
#include "core/simulate/project_sim.h"
#include "tests/integration/import_file.h"
#include "tests/io/e57_test_util.h"
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

// Distance from each read point to the nearest expected point within `cell` (a voxel hash of
// `expected`; the neighbouring cells by their integer coordinates: cell * floor(p / cell) moved by one
// cell in floating point can skip a cell); 1e300 where none is that near.
std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& read, const std::vector<Eigen::Vector3d>& expected,
                                     double cell) {
  auto cell_of = [cell](const Eigen::Vector3d& p) -> Eigen::Array3d { return (p / cell).array().floor(); };
  auto key = [](const Eigen::Array3d& q) {
    return (std::int64_t(q.x()) * 73856093) ^ (std::int64_t(q.y()) * 19349663) ^ (std::int64_t(q.z()) * 83492791);
  };
  std::unordered_multimap<std::int64_t, Eigen::Vector3d> grid;
  for (const auto& p : expected) grid.emplace(key(cell_of(p)), p);
  std::vector<double> nearest;
  nearest.reserve(read.size());
  for (const auto& p : read) {
    double best = 1e300;
    const Eigen::Array3d c = cell_of(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto range = grid.equal_range(key(c + Eigen::Array3d(dx, dy, dz)));
          for (auto it = range.first; it != range.second; ++it) best = std::min(best, (it->second - p).norm());
        }
    nearest.push_back(best);
  }
  return nearest;
}

// Largest distance from each read point to the nearest expected point.
double WorstDistance(const std::vector<Eigen::Vector3d>& read, const std::vector<Eigen::Vector3d>& expected,
                     double cell) {
  const std::vector<double> nearest = NearestDistances(read, expected, cell);
  return nearest.empty() ? 0.0 : *std::max_element(nearest.begin(), nearest.end());
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


// The points of a LAS 1.4 file decoded here from the specification (R15 §2.4: offset to point data
// at byte 96, record length at 105, point count (uint64) at 247, scale and offset doubles at 131 and
// 155; X, Y, Z int32 first in every record), not by scanreg's reader.
std::vector<Eigen::Vector3d> ReadLasBySpecification(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<Eigen::Vector3d> out;
  if (b.size() < 375 || b.compare(0, 4, "LASF") != 0) return out;
  auto get = [&](std::size_t at, auto value) {
    std::memcpy(&value, b.data() + at, sizeof value);
    return value;
  };
  const std::uint32_t first = get(96, std::uint32_t{});
  const std::uint16_t length = get(105, std::uint16_t{});
  const std::uint64_t count = get(247, std::uint64_t{});
  if (first + count * length > b.size()) return out;
  double scale[3], offset[3];
  for (int d = 0; d < 3; ++d) scale[d] = get(131 + 8 * d, double{}), offset[d] = get(155 + 8 * d, double{});
  for (std::uint64_t k = 0; k < count; ++k) {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) p[d] = offset[d] + scale[d] * get(first + k * length + 4 * d, std::int32_t{});
    out.push_back(p);
  }
  return out;
}

// A cloud merged from two stations by another program (an ASCII PLY of x y z intensity in world
// coordinates, the points shuffled) is imported with every point — not one range image seen from
// its origin: the points that crowd each other's cells are kept as a list, and the scan is marked as
// seen from several places — and exported with every point: PCL reads the PLY, the LAS decoded by
// the specification and the E57's record count give them all back, to 0.1 mm. PTX, which holds a
// grid only, is refused with the formats that work.
TEST(ThirdPartyReaders, AMergedCloudIsImportedAndExportedWithEveryPoint) {
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> stations = TwoStreetStations();
  ASSERT_TRUE(stations.ok()) << stations.error().ToString();
  std::vector<Eigen::Vector3d> merged;
  for (const Scan& s : *stations)
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k]) merged.push_back(*s.reference_world_from_scan * s.points[k].cast<double>());
  std::shuffle(merged.begin(), merged.end(), std::mt19937(3));
  const std::filesystem::path file = dir / "merged.ply";
  {
    std::FILE* f = std::fopen(file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\n"
                 "property double z\nproperty float intensity\nend_header\n", merged.size());
    for (const Eigen::Vector3d& p : merged) std::fprintf(f, "%.5f %.5f %.5f 0.5\n", p.x(), p.y(), p.z());
    std::fclose(f);
  }
  std::optional<Imported> in = ImportFile(file, dir.path());
  ASSERT_TRUE(in);
  io::Project& project = in->project;
  const std::vector<Scan>& scans = in->scans;
  ASSERT_EQ(scans.size(), 1u);
  const Scan& scan = scans.front();
  std::printf("merged cloud: %zu points, %zu in the grid, %zu as a list\n", merged.size(), scan.CountValid(),
              scan.list_points.size());
  EXPECT_EQ(scan.CountPoints(), merged.size());
  EXPECT_GT(scan.list_points.size(), merged.size() / 20);  // two stations crowd each other's cells
  EXPECT_FALSE(scan.single_viewpoint);

  project.scans[0].registered = true;
  for (const char* format : {"ply", "las", "e57"}) {
    SCOPED_TRACE(format);
    pipeline::ExportCloudsOptions options;
    options.dir = dir / format;
    options.format = format;
    auto exported = pipeline::ExportClouds(project, options, progress, cancel);
    ASSERT_TRUE(exported.ok()) << exported.error().ToString();
    ASSERT_EQ(exported->size(), 1u);
    EXPECT_EQ((*exported)[0].points, merged.size());
    const std::filesystem::path out = (*exported)[0].file;
    std::vector<Eigen::Vector3d> read;
    if (std::string(format) == "e57") {  // decoded by the standard, not by our reader
      std::ifstream in(out, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const test::E57BySpecification e57 = test::DecodeE57BySpecification(bytes);
      EXPECT_TRUE(e57.Field("rowIndex").empty());  // unstructured: the list has no cells
      ASSERT_EQ(e57.Field("cartesianZ").size(), e57.records);
      for (std::size_t r = 0; r < e57.records; ++r) read.push_back(e57.World(r));
    } else {
      read = std::string(format) == "ply" ? ReadPlyWithPcl(out) : ReadLasBySpecification(out);
    }
    ASSERT_EQ(read.size(), merged.size());
    EXPECT_LT(WorstDistance(read, merged, 0.01), 1e-4);  // 0.1 mm
    EXPECT_LT(WorstDistance(merged, read, 0.01), 1e-4);  // and every input point is there
  }
  pipeline::ExportCloudsOptions ptx;
  ptx.dir = dir / "ptx";
  ptx.format = "ptx";
  auto refused = pipeline::ExportClouds(project, ptx, progress, cancel);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("e57, ply or las"), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("merged"), std::string::npos) << refused.error().message;
}

// The libE57 reference file bunnyDouble.e57 (written by another program: one unstructured list of
// 30,571 points, no grid): every point kept on import and on export, where PCL's reader finds them
// again; the points are where the file's own cartesianBounds and the Stanford range scans at their
// bun.conf poses (the same bunny, another scanner's data) say they are.
TEST(ThirdPartyReaders, AnUnstructuredE57FromAnotherProgramKeepsEveryPoint) {
  SCANREG_REQUIRE_REALDATA(data);
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::filesystem::path file = data / "e57_libe57format" / "bunnyDouble.e57";
  std::optional<Imported> in = ImportFile(file, dir.path());
  ASSERT_TRUE(in);
  io::Project& project = in->project;
  const std::vector<Scan>& scans = in->scans;
  ASSERT_EQ(scans.size(), 1u);
  const Scan& scan = scans.front();
  EXPECT_EQ(scan.CountPoints(), 30571u);  // the file's recordCount
  std::vector<Eigen::Vector3d> imported;
  scan.ForEachPoint([&](const Eigen::Vector3f& p, float) { imported.push_back(scan.world_from_scan * p.cast<double>()); });
  ASSERT_EQ(imported.size(), 30571u);
  // The file's cartesianBounds, as its writer put them in its XML section.
  Eigen::Vector3d lo = imported[0], hi = imported[0];
  for (const Eigen::Vector3d& p : imported) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  EXPECT_LT((lo - Eigen::Vector3d(-9.4689e-2, 4.0011e-2, -6.1873e-2)).cwiseAbs().maxCoeff(), 1e-6) << lo.transpose();
  EXPECT_LT((hi - Eigen::Vector3d(6.1009e-2, 1.87321e-1, 5.8799e-2)).cwiseAbs().maxCoeff(), 1e-6) << hi.transpose();
  // On the bunny's surface as the ten Stanford range scans saw it.
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(data / "stanford_bunny" / "bun.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  std::vector<Eigen::Vector3d> surface;
  for (const io::NamedPose& pose : *poses) {
    Expected<Scan> s = io::ReadPly(data / "stanford_bunny" / pose.scan, progress, cancel);
    ASSERT_TRUE(s.ok()) << s.error().ToString();
    s->ForEachPoint([&](const Eigen::Vector3f& p, float) { surface.push_back(pose.world_from_scan * p.cast<double>()); });
  }
  std::vector<double> to_surface = NearestDistances(imported, surface, 0.005);
  std::nth_element(to_surface.begin(), to_surface.begin() + to_surface.size() / 2, to_surface.end());
  const double median = to_surface[to_surface.size() / 2];
  std::printf("bunnyDouble.e57: %zu points kept; median distance to the range scans %.3f mm\n", imported.size(),
              median * 1e3);
  EXPECT_LT(median, 1e-3);

  project.scans[0].registered = true;
  pipeline::ExportCloudsOptions options;
  options.dir = dir / "ply";
  options.format = "ply";
  auto exported = pipeline::ExportClouds(project, options, progress, cancel);
  ASSERT_TRUE(exported.ok()) << exported.error().ToString();
  ASSERT_EQ(exported->size(), 1u);
  EXPECT_EQ((*exported)[0].points, 30571u);
  const std::vector<Eigen::Vector3d> read = ReadPlyWithPcl((*exported)[0].file);
  ASSERT_EQ(read.size(), imported.size());
  EXPECT_LT(WorstDistance(read, imported, 0.005), 1e-4);  // 0.1 mm
  EXPECT_LT(WorstDistance(imported, read, 0.005), 1e-4);
}

// A 20 cm object merged with the default options (as `scanreg-cli merge` without --voxel or
// --sigma): the voxel and the range noise are sized to the data, so the mesh VTK reads follows the
// ten Stanford range scans at their bun.conf poses; the street-sized 2 cm / 12 mm defaults would
// give a blob of a few hundred vertices on which almost no scan point lies.
TEST(ThirdPartyReaders, ASmallObjectMergedWithDefaultOptionsFollowsItsScans) {
  SCANREG_REQUIRE_REALDATA(data);
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::filesystem::path bunny = data / "stanford_bunny";
  pipeline::CreateProjectOptions create;
  for (const char* name : {"bun000", "bun045", "bun090", "bun180", "bun270", "bun315", "chin", "ear_back", "top2", "top3"})
    create.scan_files.push_back(bunny / (std::string(name) + ".ply"));
  create.poses = bunny / "bun.conf";
  Expected<pipeline::CreatedProject> created = pipeline::CreateProject(dir / "p.scanreg.json", create, progress, cancel);
  ASSERT_TRUE(created.ok()) << created.error().ToString();
  const io::Project& project = created->project;
  std::vector<int> all;
  for (std::size_t i = 0; i < project.scans.size(); ++i) all.push_back(int(i));
  Expected<pipeline::MergeOptions> sized =
      pipeline::SizeMergeToProject(project, all, pipeline::MergeOptions(), true, true, progress, cancel);
  ASSERT_TRUE(sized.ok()) << sized.error().ToString();
  std::printf("bunny: voxel %.4g m, range noise %.4g m\n", sized->voxel_m, sized->sigma_m);
  EXPECT_LE(sized->voxel_m, 0.002);  // the bunny is ~15 cm across, its scans ~0.5 mm apart
  EXPECT_LE(sized->sigma_m, 0.002);
  const pipeline::MergeOptions street;  // the defaults a street keeps
  Expected<pipeline::MergeOptions> kept =
      pipeline::SizeMergeToProject(project, all, street, false, false, progress, cancel);
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->voxel_m, street.voxel_m);
  Expected<pipeline::MergeResult> merged =
      pipeline::MergeProjectScans(project, all, *sized, pipeline::DefaultMemoryBudget(), progress, cancel);
  ASSERT_TRUE(merged.ok()) << merged.error().ToString();
  ASSERT_TRUE(pipeline::WriteMesh(dir / "bunny.ply", merged->mesh));
  const std::vector<Eigen::Vector3d> vertices = ReadWithVtk<vtkPLYReader>(dir / "bunny.ply");
  ASSERT_GT(vertices.size(), 10000u);
  std::vector<Eigen::Vector3d> scanned;
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(bunny / "bun.conf");
  ASSERT_TRUE(poses.ok());
  for (const io::NamedPose& pose : *poses) {
    Expected<Scan> s = io::ReadPly(bunny / pose.scan, progress, cancel);
    ASSERT_TRUE(s.ok()) << s.error().ToString();
    s->ForEachPoint([&](const Eigen::Vector3f& p, float) { scanned.push_back(pose.world_from_scan * p.cast<double>()); });
  }
  const auto share_within = [](const std::vector<double>& d, double limit) {
    return double(std::count_if(d.begin(), d.end(), [limit](double x) { return x <= limit; })) / d.size();
  };
  const double vertices_on_scans = share_within(NearestDistances(vertices, scanned, 0.002), 0.001);
  std::vector<Eigen::Vector3d> sample;  // every 10th scan point
  for (std::size_t i = 0; i < scanned.size(); i += 10) sample.push_back(scanned[i]);
  const double scans_covered = share_within(NearestDistances(sample, vertices, 0.002), 0.001);
  std::printf("bunny merged with the defaults: %zu vertices, %.1f %% within 1 mm of a scan point, %.1f %% of the "
              "scan points within 1 mm of a vertex\n", vertices.size(), 100 * vertices_on_scans, 100 * scans_covered);
  EXPECT_GT(vertices_on_scans, 0.75);
  EXPECT_GT(scans_covered, 0.95);
}

// A colour for each point of the coloured scan below, from its position (so any reordering of the
// points by a writer or reader can be followed).
Rgb ColourAt(const Eigen::Vector3d& p) {
  const long k = std::lround(p.x() * 1000) * 7 + std::lround(p.y() * 1000) * 13 + std::lround(p.z() * 1000) * 3;
  return Rgb{std::uint8_t(k % 251), std::uint8_t((k / 3) % 256), std::uint8_t((k / 7) % 253)};
}

// A scan with colour, as a scanner with a camera writes it (a Leica-style PTX of `x y z i r g b`
// lines), keeps its colour on import and in every export: PCL's PLY reader, the LAS records
// decoded by the specification (point format 7, RGB at byte 30, 16 bits a channel), the E57 decoded
// by the standard (test::DecodeE57BySpecification: colorRed/Green/Blue bit-packed integers) and our
// PTX reader give back each point's own colour.
TEST(ThirdPartyReaders, AScansColourIsKeptOnImportAndInEveryExport) {
  test::TempDir dir;
  const int rows = 20, cols = 30;
  std::vector<Eigen::Vector3d> points;  // scanner frame = world (identity pose)
  const std::filesystem::path file = dir / "coloured.ptx";
  {
    std::FILE* f = std::fopen(file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "%d\n%d\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", cols, rows);
    for (int c = 0; c < cols; ++c) {
      for (int r = 0; r < rows; ++r) {
        if ((r * cols + c) % 11 == 0) {  // an empty cell
          std::fprintf(f, "0 0 0 0.5 0 0 0\n");
          continue;
        }
        const double az = -0.6 + 0.04 * c, el = 0.4 - 0.04 * r, range = 5.0 + 0.1 * ((r * 7 + c * 3) % 10);
        const Eigen::Vector3d p(std::round(1000 * range * std::cos(el) * std::cos(az)) / 1000,
                                std::round(1000 * range * std::cos(el) * std::sin(az)) / 1000,
                                std::round(1000 * range * std::sin(el)) / 1000);
        const Rgb rgb = ColourAt(p);
        std::fprintf(f, "%.3f %.3f %.3f 0.5 %d %d %d\n", p.x(), p.y(), p.z(), rgb[0], rgb[1], rgb[2]);
        points.push_back(p);
      }
    }
    std::fclose(f);
  }
  NullProgress progress;
  CancelToken cancel;
  std::optional<Imported> in = ImportFile(file, dir.path());
  ASSERT_TRUE(in);
  io::Project& project = in->project;
  const std::vector<Scan>& scans = in->scans;
  ASSERT_TRUE(scans.front().HasColour());
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < scans.front().size(); ++k)
    if (scans.front().valid[k]) wrong += scans.front().colour[k] != ColourAt(scans.front().points[k].cast<double>());
  EXPECT_EQ(wrong, 0u);

  project.scans[0].registered = true;
  for (const char* format : {"ply", "las", "e57", "ptx"}) {
    SCOPED_TRACE(format);
    pipeline::ExportCloudsOptions options;
    options.dir = dir / format;
    options.format = format;
    auto exported = pipeline::ExportClouds(project, options, progress, cancel);
    ASSERT_TRUE(exported.ok()) << exported.error().ToString();
    const std::filesystem::path out = (*exported)[0].file;
    std::vector<std::pair<Eigen::Vector3d, Rgb>> read;
    if (std::string(format) == "ply") {
      pcl::PCLPointCloud2 cloud;
      ASSERT_EQ(pcl::io::loadPLYFile(out.string(), cloud), 0);
      int xyz[3] = {-1, -1, -1}, rgb = -1;
      for (const auto& f : cloud.fields) {
        for (int d = 0; d < 3; ++d)
          if (f.name == std::string(1, char('x' + d))) xyz[d] = f.offset;
        if (f.name == "rgb" || f.name == "rgba") rgb = f.offset;  // PCL packs red, green, blue
      }
      ASSERT_GE(rgb, 0) << "PCL found no colour";
      for (std::size_t i = 0; i < std::size_t(cloud.width) * cloud.height; ++i) {
        Eigen::Vector3d p;
        for (int d = 0; d < 3; ++d) std::memcpy(&p[d], cloud.data.data() + i * cloud.point_step + xyz[d], 8);
        if (!p.allFinite()) continue;
        std::uint32_t packed = 0;
        std::memcpy(&packed, cloud.data.data() + i * cloud.point_step + rgb, 4);
        read.push_back({p, Rgb{std::uint8_t(packed >> 16), std::uint8_t(packed >> 8), std::uint8_t(packed)}});
      }
    } else if (std::string(format) == "las") {
      std::ifstream in(out, std::ios::binary);
      const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      ASSERT_GT(b.size(), 375u);
      EXPECT_EQ(static_cast<int>(static_cast<unsigned char>(b[104])), 7);  // point data format 7: RGB
      const std::vector<Eigen::Vector3d> xyz = ReadLasBySpecification(out);
      std::uint32_t first = 0;
      std::uint16_t length = 0;
      std::memcpy(&first, b.data() + 96, 4);
      std::memcpy(&length, b.data() + 105, 2);
      for (std::size_t k = 0; k < xyz.size(); ++k) {
        Rgb c;
        for (int ch = 0; ch < 3; ++ch) {
          std::uint16_t v = 0;
          std::memcpy(&v, b.data() + first + k * length + 30 + 2 * ch, 2);
          c[ch] = std::uint8_t(v >> 8);
        }
        read.push_back({xyz[k], c});
      }
    } else if (std::string(format) == "e57") {  // decoded by the standard, not by our reader
      std::ifstream in(out, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const test::E57BySpecification e57 = test::DecodeE57BySpecification(bytes);
      const auto &x = e57.Field("cartesianX"), &y = e57.Field("cartesianY"), &z = e57.Field("cartesianZ");
      const auto &red = e57.Field("colorRed"), &green = e57.Field("colorGreen"), &blue = e57.Field("colorBlue");
      ASSERT_EQ(red.size(), e57.records) << "no colorRed, colorGreen, colorBlue for every record";
      ASSERT_EQ(blue.size(), e57.records);
      ASSERT_EQ(x.size(), e57.records);
      for (std::size_t k = 0; k < e57.records; ++k)  // the pose is the identity: scanner frame = world
        read.push_back({Eigen::Vector3d(x[k], y[k], z[k]), Rgb{std::uint8_t(red[k]), std::uint8_t(green[k]), std::uint8_t(blue[k])}});
    } else {
      Expected<std::vector<Scan>> back = io::ReadScanFile(out, progress, cancel);
      ASSERT_TRUE(back.ok()) << back.error().ToString();
      const Scan& s = back->front();
      ASSERT_TRUE(s.HasColour());
      for (std::size_t k = 0; k < s.size(); ++k)
        if (s.valid[k]) read.push_back({s.world_from_scan * s.points[k].cast<double>(), s.colour[k]});
    }
    ASSERT_EQ(read.size(), points.size());
    std::size_t mismatched = 0;
    for (const auto& [p, c] : read) mismatched += c != ColourAt(p);
    EXPECT_EQ(mismatched, 0u);
  }
}

}  // namespace
}  // namespace scanreg

