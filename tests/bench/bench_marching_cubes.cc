// Marching Cubes comparison (issue 5): our sparse-grid ExtractMesh against VTK's vtkFlyingEdges3D
// and vtkMarchingCubes on the same field (a torus SDF sampled on a grid, truncated at 3 voxels):
// time, triangles, boundary and non-manifold edges, RMS of the vertices to the true surface.
// VTK is linked only here (core/ never includes it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/merge/marching_cubes.h"
#include "core/merge/mesh.h"
#include "core/merge/sparse_grid.h"
#include "tests/bench/bench_table.h"

#ifdef SCANREG_BENCH_VTK
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkMarchingCubes.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#endif

namespace scanreg::bench {

namespace {

constexpr double kMajor = 0.5, kMinor = 0.2;  // torus radii, metres

double TorusSdf(const Eigen::Vector3d& p) {
  const double q = std::hypot(p.x(), p.y()) - kMajor;
  return std::hypot(q, p.z()) - kMinor;
}

double SurfaceRms(const merge::Mesh& mesh) {
  double s2 = 0.0;
  for (const auto& v : mesh.vertices) s2 += std::pow(TorusSdf(mesh.origin + v.cast<double>()), 2);
  return std::sqrt(s2 / std::max<std::size_t>(mesh.vertices.size(), 1));
}

void AddRows(Table& table, const std::string& who, const merge::Mesh& mesh, double seconds, const std::string& size) {
  const merge::EdgeCounts edges = merge::CountEdges(mesh);
  char note[256];
  std::snprintf(note, sizeof note, "%s; %zu vertices, %zu boundary / %zu non-manifold edges, RMS %.1f um", size.c_str(),
                mesh.vertices.size(), edges.boundary, edges.non_manifold, SurfaceRms(mesh) * 1e6);
  table.Add({"merge", "marching cubes, torus (" + who + "): time", seconds, "s", note});
  table.Add({"merge", "marching cubes, torus (" + who + "): triangles", double(mesh.triangles.size()), "",
             merge::IsWatertight(mesh) ? "watertight" : "NOT watertight"});
}

#ifdef SCANREG_BENCH_VTK
merge::Mesh FromVtk(vtkPolyData* poly, const Eigen::Vector3d& origin) {
  merge::Mesh mesh;
  mesh.origin = origin;
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {  // relative to the image origin already
    double p[3];
    poly->GetPoint(i, p);
    mesh.vertices.push_back(Eigen::Vector3d(p[0], p[1], p[2]).cast<float>());
  }
  vtkCellArray* polys = poly->GetPolys();
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);) {
    if (n == 3) mesh.triangles.emplace_back(int(ids[0]), int(ids[1]), int(ids[2]));
  }
  return mesh;
}
#endif

}  // namespace

void RunMarchingCubesComparison(Table& table, bool quick) {
  const double h = quick ? 0.01 : 0.004, band = 3.0 * h;
  const Eigen::Vector3d lo(-0.8, -0.8, -0.3);
  const int nx = int(std::ceil(1.6 / h)) + 1, ny = nx, nz = int(std::ceil(0.6 / h)) + 1;
  const std::string size = std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) + " grid";
  // The sparse grid: blocks within the band of the surface, grid points within it known (as a merge leaves them).
  merge::SparseGrid grid(lo, h);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Eigen::Vector3f p(float(i * h), float(j * h), float(k * h));
        if (std::abs(TorusSdf(lo + p.cast<double>())) <= band) grid.AllocateAround(p, 0.5 * h);
      }
  for (std::size_t b = 0; b < grid.num_blocks(); ++b) {
    merge::SparseGrid::Block& block = grid.block(b);
    for (int l = 0; l < merge::SparseGrid::kVoxels; ++l) {
      const Eigen::Vector3f p = grid.Position(block.key, l % 8, (l / 8) % 8, l / 64);
      const double d = TorusSdf(lo + p.cast<double>());
      if (std::abs(d) <= band) block.distance[l] = float(d), block.weight[l] = 1.0f;
    }
  }
  merge::Mesh ours;
  const double ours_s = Seconds([&] { ours = merge::ExtractMesh(grid); });
  char memory[128];
  std::snprintf(memory, sizeof memory, ", field %.1f MiB sparse (%.1f MiB dense)", grid.MemoryBytes() / 1048576.0,
                4.0 * nx * ny * nz / 1048576.0);
  AddRows(table, "ours, sparse, 1 thread", ours, ours_s, size + memory);
#ifdef SCANREG_BENCH_VTK
  // The same values on a dense image, truncated to +-band where the sparse grid has none.
  vtkNew<vtkImageData> image;
  image->SetDimensions(nx, ny, nz);
  image->SetSpacing(h, h, h);
  image->SetOrigin(0.0, 0.0, 0.0);
  vtkNew<vtkFloatArray> values;
  values->SetNumberOfValues(vtkIdType(nx) * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double d = TorusSdf(lo + h * Eigen::Vector3d(i, j, k));
        values->SetValue((vtkIdType(k) * ny + j) * nx + i, float(std::clamp(d, -band, band)));
      }
  image->GetPointData()->SetScalars(values);
  auto run = [&](auto& filter, const std::string& who) {
    filter->SetInputData(image);
    filter->SetValue(0, 0.0);
    filter->ComputeNormalsOff(), filter->ComputeGradientsOff(), filter->ComputeScalarsOff();
    const double seconds = Seconds([&] { filter->Update(); });
    AddRows(table, who, FromVtk(filter->GetOutput(), lo), seconds, size);
  };
  vtkNew<vtkFlyingEdges3D> flying_edges;
  run(flying_edges, "vtkFlyingEdges3D, dense, SMP");
  vtkNew<vtkMarchingCubes> marching_cubes;
  run(marching_cubes, "vtkMarchingCubes, dense");
#else
  table.Add({"merge", "marching cubes, torus (VTK)", 0.0, "", "skipped: VTK not found at configure time"});
#endif
}

}  // namespace scanreg::bench
