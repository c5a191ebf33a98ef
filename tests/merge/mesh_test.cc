// Marching Cubes on analytic fields, mesh topology, small-piece removal, and export round trips
// (small readers for binary PLY, OBJ and binary STL).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "core/common/log.h"
#include "core/merge/marching_cubes.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_io.h"
#include "core/merge/mesh_preview.h"
#include "core/merge/sparse_grid.h"
#include "tests/support/test_paths.h"

namespace scanreg::merge {
namespace {

// Field of the union of spheres (centres relative to the grid origin), allocated near them.
SparseGrid SpheresGrid(const std::vector<std::pair<Eigen::Vector3f, float>>& spheres, double voxel) {
  SparseGrid grid(Eigen::Vector3d(500000.0, 4000000.0, 100.0), voxel);  // UTM-sized origin
  for (const auto& [c, r] : spheres) {
    for (float t = 0; t < 6.3f; t += 0.05f) {
      for (float u = -1.6f; u < 1.6f; u += 0.05f) {
        grid.AllocateAround(c + r * Eigen::Vector3f(std::cos(t) * std::cos(u), std::sin(t) * std::cos(u), std::sin(u)),
                            3 * voxel);
      }
    }
  }
  for (std::size_t b = 0; b < grid.num_blocks(); ++b) {
    auto& block = grid.block(b);
    for (int z = 0; z < 8; ++z) {
      for (int y = 0; y < 8; ++y) {
        for (int x = 0; x < 8; ++x) {
          const Eigen::Vector3f p = grid.Position(block.key, x, y, z);
          float d = 1e9f;
          for (const auto& [c, r] : spheres) d = std::min(d, (p - c).norm() - r);
          if (std::abs(d) > 3 * voxel) continue;
          block.distance[SparseGrid::Local(x, y, z)] = d;
          block.weight[SparseGrid::Local(x, y, z)] = 1.0f;
        }
      }
    }
  }
  return grid;
}

TEST(MarchingCubes, SphereIsWatertightAndAccurate) {
  const Eigen::Vector3f c(0.31f, -0.17f, 0.05f);
  const SparseGrid grid = SpheresGrid({{c, 0.4f}}, 0.02);
  EXPECT_GT(grid.num_blocks(), 8u);
  const Mesh mesh = ExtractMesh(grid);
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_TRUE(IsWatertight(mesh));
  EXPECT_EQ(PieceSizes(mesh).size(), 1u);
  double max_err = 0.0;
  for (const auto& v : mesh.vertices) max_err = std::max(max_err, double(std::abs((v - c).norm() - 0.4f)));
  EXPECT_LT(max_err, 0.004);  // linear interpolation of an exact distance: well below a voxel
  // Euler characteristic of a sphere: V - E + F = 2.
  const EdgeCounts e = CountEdges(mesh);
  EXPECT_EQ(long(mesh.vertices.size()) - long(e.manifold) + long(mesh.triangles.size()), 2);
}

// Area and enclosed volume (signed, about c) of a mesh: a preview with holes or flipped triangles
// loses both.
std::pair<double, double> AreaAndVolume(const Mesh& mesh, const Eigen::Vector3f& c) {
  double area = 0.0, volume = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = (mesh.vertices[t[0]] - c).cast<double>(), b = (mesh.vertices[t[1]] - c).cast<double>(),
                          d = (mesh.vertices[t[2]] - c).cast<double>();
    area += 0.5 * (b - a).cross(d - a).norm();
    volume += a.dot(b.cross(d)) / 6.0;
  }
  return {area, volume};
}

TEST(MeshPreview, AMeshWithinTheBudgetIsShownWholeALargerOneSimplifiedOnTheSameSurface) {
  const Eigen::Vector3f c(0.31f, -0.17f, 0.05f);
  const float r = 0.4f;
  const Mesh mesh = ExtractMesh(SpheresGrid({{c, r}}, 0.02));
  ASSERT_GT(mesh.triangles.size(), 5000u);
  CancelToken cancel;
  auto whole = PreviewMesh(InMemoryMesh(mesh), mesh.triangles.size(), 0.02, cancel);
  ASSERT_TRUE(whole) << whole.error().message;
  EXPECT_EQ(whole->cell_m, 0.0);
  EXPECT_EQ(whole->mesh.triangles, mesh.triangles);
  EXPECT_EQ(whole->mesh.vertices, mesh.vertices);
  EXPECT_EQ(whole->mesh.origin, mesh.origin);

  const double kPi = 3.14159265358979;
  for (const std::size_t budget : {std::size_t(2000), std::size_t(500)}) {
    auto preview = PreviewMesh(InMemoryMesh(mesh), budget, 0.02, cancel);
    ASSERT_TRUE(preview) << preview.error().message;
    const Mesh& p = preview->mesh;
    EXPECT_LE(p.triangles.size(), budget);
    EXPECT_GT(p.triangles.size(), budget / 8) << "cell " << preview->cell_m;
    EXPECT_GT(preview->cell_m, 0.02);
    EXPECT_EQ(p.origin, mesh.origin);
    for (const auto& t : p.triangles)
      for (int k = 0; k < 3; ++k) ASSERT_TRUE(t[k] >= 0 && t[k] < int(p.vertices.size()));
    double worst = 0.0;  // a cell's mean lies inside the sphere by about cell^2 / r
    for (const auto& v : p.vertices) worst = std::max(worst, double(std::abs((v - c).norm() - r)));
    EXPECT_LT(worst, preview->cell_m) << "cell " << preview->cell_m;
    // The same closed, outward surface: its area and volume within a few percent of the sphere's.
    const auto [area, volume] = AreaAndVolume(p, c);
    EXPECT_NEAR(area / (4 * kPi * r * r), 1.0, 0.12) << budget;
    EXPECT_NEAR(volume / (4.0 / 3.0 * kPi * r * r * r), 1.0, 0.15) << budget;
  }

  cancel.Cancel();
  auto cancelled = PreviewMesh(InMemoryMesh(mesh), 500, 0.02, cancel);
  ASSERT_FALSE(cancelled);
  EXPECT_EQ(cancelled.error().code, ErrorCode::kCancelled);
  EXPECT_FALSE(PreviewMesh(InMemoryMesh(mesh), 0, 0.02, CancelToken()));
}

TEST(MeshTest, RemoveSmallPiecesKeepsTheLargeOne) {
  const SparseGrid grid = SpheresGrid({{Eigen::Vector3f(0, 0, 0), 0.4f}, {Eigen::Vector3f(1.5f, 0, 0), 0.06f}}, 0.02);
  Mesh mesh = ExtractMesh(grid);
  ASSERT_EQ(PieceSizes(mesh).size(), 2u);
  const std::size_t small = PieceSizes(mesh)[1];
  EXPECT_EQ(RemoveSmallPieces(mesh, 0.05), small);
  EXPECT_EQ(PieceSizes(mesh).size(), 1u);
  EXPECT_TRUE(IsWatertight(mesh));  // vertex indices remapped consistently
}

// --- small readers -------------------------------------------------------------------------

std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Binary PLY of double vertices: (vertices, faces) from the header, checking the body's size and
// indices; *first is the first vertex.
std::pair<std::size_t, std::size_t> ReadPlyCounts(const std::filesystem::path& p, Eigen::Vector3d* first) {
  const std::string s = ReadAll(p);
  const std::size_t end = s.find("end_header\n");
  if (end == std::string::npos) return {0, 0};
  std::istringstream header(s.substr(0, end));
  std::string line;
  std::size_t nv = 0, nf = 0;
  while (std::getline(header, line)) {
    std::istringstream l(line);
    std::string a, b;
    l >> a >> b;
    if (a == "element" && b == "vertex") l >> nv;
    if (a == "element" && b == "face") l >> nf;
  }
  const std::size_t body = s.size() - end - 11;
  if (body != nv * 24 + nf * 13) return {0, 0};
  if (nv > 0) std::memcpy(first->data(), s.data() + end + 11, 24);
  for (std::size_t f = 0; f < nf; ++f) {
    const char* rec = s.data() + end + 11 + nv * 24 + f * 13;
    if (rec[0] != 3) return {0, 0};
    for (int k = 0; k < 3; ++k) {
      std::int32_t idx;
      std::memcpy(&idx, rec + 1 + 4 * k, 4);
      if (idx < 0 || std::size_t(idx) >= nv) return {0, 0};
    }
  }
  return {nv, nf};
}

std::pair<std::size_t, std::size_t> ReadObjCounts(const std::filesystem::path& p, Eigen::Vector3d* first) {
  std::ifstream in(p);
  std::string line;
  std::size_t nv = 0, nf = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      if (nv == 0) std::istringstream(line.substr(2)) >> first->x() >> first->y() >> first->z();
      ++nv;
    }
    if (line.rfind("f ", 0) == 0) ++nf;
  }
  return {nv, nf};
}

// Binary STL: triangles, and distinct vertex positions (STL does not share vertices).
std::pair<std::size_t, std::size_t> ReadStlCounts(const std::filesystem::path& p) {
  const std::string s = ReadAll(p);
  if (s.size() < 84) return {0, 0};
  std::uint32_t nf;
  std::memcpy(&nf, s.data() + 80, 4);
  if (s.size() != 84 + std::size_t(nf) * 50) return {0, 0};
  std::set<std::tuple<float, float, float>> distinct;
  for (std::size_t f = 0; f < nf; ++f) {
    for (int k = 1; k <= 3; ++k) {
      float v[3];
      std::memcpy(v, s.data() + 84 + f * 50 + 12 * k, 12);
      distinct.insert({v[0], v[1], v[2]});
    }
  }
  return {distinct.size(), nf};
}

TEST(MeshIo, ExportsReReadWithIdenticalCounts) {
  const SparseGrid grid = SpheresGrid({{Eigen::Vector3f(0.1f, 0.2f, 0.3f), 0.3f}}, 0.02);
  const Mesh mesh = ExtractMesh(grid);
  ASSERT_GT(mesh.triangles.size(), 500u);
  std::set<std::tuple<float, float, float>> distinct;
  for (const auto& v : mesh.vertices) distinct.insert({v.x(), v.y(), v.z()});
  test::TempDir dir;
  int stl_warnings = 0;
  SetLogHandler([&](LogLevel level, const std::string& message) {
    stl_warnings += level == LogLevel::kWarning && message.find("32-bit floats") != std::string::npos;
  });
  ASSERT_TRUE(WriteMeshFile(dir / "m.ply", mesh));
  ASSERT_TRUE(WriteMeshFile(dir / "m.OBJ", mesh));
  ASSERT_TRUE(WriteMeshFile(dir / "m.stl", mesh));
  const Eigen::Vector3d world0 = mesh.origin + mesh.vertices[0].cast<double>();
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  EXPECT_EQ(ReadPlyCounts(dir / "m.ply", &first), std::make_pair(mesh.vertices.size(), mesh.triangles.size()));
  EXPECT_NEAR((first - world0).norm(), 0.0, 1e-9);
  EXPECT_EQ(ReadObjCounts(dir / "m.OBJ", &first), std::make_pair(mesh.vertices.size(), mesh.triangles.size()));
  EXPECT_NEAR((first - world0).norm(), 0.0, 1e-5);  // absolute, UTM-sized
  // STL holds floats: 4,000 km from the origin the world coordinates round by decimetres, which a
  // warning says; the triangles are all there.
  EXPECT_EQ(ReadStlCounts(dir / "m.stl").second, mesh.triangles.size());
  EXPECT_EQ(stl_warnings, 1);
  Mesh near = mesh;
  near.origin = Eigen::Vector3d(24.0, -8.0, 0.0);  // demo-sized: no warning, every vertex distinct
  ASSERT_TRUE(WriteMeshFile(dir / "near.stl", near));
  const auto near_counts = ReadStlCounts(dir / "near.stl");
  EXPECT_EQ(near_counts.second, mesh.triangles.size());
  EXPECT_GE(near_counts.first, distinct.size() * 98 / 100);  // a few near-duplicate corners meet at float steps
  EXPECT_EQ(stl_warnings, 1);
  ASSERT_TRUE(WritePointCloudPly(dir / "p.ply", InMemoryMesh(mesh)));
  EXPECT_EQ(ReadPlyCounts(dir / "p.ply", &first), std::make_pair(mesh.vertices.size(), std::size_t(0)));
  EXPECT_NEAR((first - world0).norm(), 0.0, 1e-9);
  const Status bad = WriteMeshFile(dir / "m.xyz", mesh);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find(".ply, .obj or .stl"), std::string::npos);
  // Only the four requested files: no temporary left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
  EXPECT_EQ(files, 5);
  SetLogHandler({});
}

}  // namespace
}  // namespace scanreg::merge
