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

#include "core/merge/marching_cubes.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_io.h"
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

// Binary PLY: (vertices, faces) from the header, checking the body's size and indices.
std::pair<std::size_t, std::size_t> ReadPlyCounts(const std::filesystem::path& p, Eigen::Vector3d* origin) {
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
    if (a == "comment" && b == "scanreg_origin") l >> origin->x() >> origin->y() >> origin->z();
  }
  const std::size_t body = s.size() - end - 11;
  if (body != nv * 12 + nf * 13) return {0, 0};
  for (std::size_t f = 0; f < nf; ++f) {
    const char* rec = s.data() + end + 11 + nv * 12 + f * 13;
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
  ASSERT_TRUE(WriteMeshFile(dir / "m.ply", mesh));
  ASSERT_TRUE(WriteMeshFile(dir / "m.OBJ", mesh));
  ASSERT_TRUE(WriteMeshFile(dir / "m.stl", mesh));
  Eigen::Vector3d origin = Eigen::Vector3d::Zero(), first = Eigen::Vector3d::Zero();
  EXPECT_EQ(ReadPlyCounts(dir / "m.ply", &origin), std::make_pair(mesh.vertices.size(), mesh.triangles.size()));
  EXPECT_NEAR((origin - mesh.origin).norm(), 0.0, 1e-6);
  EXPECT_EQ(ReadObjCounts(dir / "m.OBJ", &first), std::make_pair(mesh.vertices.size(), mesh.triangles.size()));
  EXPECT_NEAR((first - (mesh.origin + mesh.vertices[0].cast<double>())).norm(), 0.0, 1e-5);  // absolute, UTM-sized
  EXPECT_EQ(ReadStlCounts(dir / "m.stl"), std::make_pair(distinct.size(), mesh.triangles.size()));
  ASSERT_TRUE(WritePointCloudPly(dir / "p.ply", mesh.origin, mesh.vertices));
  EXPECT_EQ(ReadPlyCounts(dir / "p.ply", &origin), std::make_pair(mesh.vertices.size(), std::size_t(0)));
  const Status bad = WriteMeshFile(dir / "m.xyz", mesh);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find(".ply, .obj or .stl"), std::string::npos);
  // Only the four requested files: no temporary left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
  EXPECT_EQ(files, 4);
}

}  // namespace
}  // namespace scanreg::merge
