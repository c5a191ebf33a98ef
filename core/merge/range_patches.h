// The range images as meshes (S §2.1): each organized scan's adjacent valid cells form triangles
// ("patches") in world coordinates relative to a common origin, with a spatial hash for radius
// queries (the role of S's k-d tree; a uniform hash answers fixed-radius queries more cheaply).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/merge/sparse_grid.h"

namespace scanreg::merge {

struct Patch {
  std::array<int, 3> v;    // indices into RangePatches::points
  Eigen::Vector3f normal;  // unit, facing the scanner that saw it
  int scan = 0;            // index into the input scans
};

// A scan's range image for Curless–Levoy projection (only for scans with an angular grid).
struct RangeView {
  Eigen::Matrix3f scan_from_world = Eigen::Matrix3f::Identity();  // rotation
  Eigen::Vector3f eye = Eigen::Vector3f::Zero();                  // scanner, world minus origin
  AngularGrid angles;
  std::shared_ptr<const std::vector<float>> range;  // rows*cols, metres; < 0 where the cell is empty
  int rows = 0, cols = 0;
  bool empty() const { return angles.empty(); }
  // Range of the scan's surface along the line of sight through x: bilinear over the 2x2 cells
  // around it when they agree within max_jump_m, else the nearest cell when another of the four
  // agrees with it (a lone return is no surface); false outside the grid or without a surface.
  bool RangeAlong(const Eigen::Vector3f& x, float max_jump_m, float* surface_range, float* voxel_range) const;
};

struct RangePatches {
  std::vector<RangeView> views;         // per scan (empty views for scans without angles)
  Eigen::Vector3d origin;               // world position of (0, 0, 0)
  std::vector<Eigen::Vector3f> points;  // world minus origin, scan by scan
  std::vector<std::size_t> scan_begin;  // per scan and one past the last: its first point
  std::vector<Patch> patches;
  std::vector<Eigen::Vector3f> scanner;  // per scan: scanner position, world minus origin
  double max_patch_radius = 0.0;         // metres: largest centroid-to-vertex distance

  // Indices of the patches that may lie within radius_m of x (bounding-sphere test), each once.
  // Patches spanning more than 16^3 hash cells are never returned. Thread-safe.
  void Candidates(const Eigen::Vector3f& x, double radius_m, std::vector<int>* out) const;
  // The patches of `from` whose bounding sphere reaches within radius_m of x, in their order: the
  // candidates of a point, from those of a larger ball around it (one hash query for many points).
  void Filter(const std::vector<int>& from, const Eigen::Vector3f& x, double radius_m, std::vector<int>* out) const;
  // Bounding-sphere test: patch p may lie within radius_m of x.
  bool Reaches(int p, const Eigen::Vector3f& x, float radius_m) const {
    const float reach = radius_m + radius[p];
    return (centroid[p] - x).squaredNorm() <= reach * reach;
  }
  void BuildHash(double cell_m);

  std::unordered_map<BlockKey, std::vector<int>, BlockKeyHash> hash;
  double cell = 1.0;
  std::vector<Eigen::Vector3f> centroid;
  std::vector<float> radius;  // per patch: centroid-to-vertex
};

// Triangulates the valid cells of every scan at its world_from_scan. Skips triangles with an edge
// over 8x the scan's median grid spacing (depth edges) or seen more obliquely than max_grazing_deg.
// Errors name the scan when no scan has a valid point.
// Range images much denser than the grid are thinned first: every s-th row and column with
// s = clamp(floor(0.5 voxel / median spacing), 1, 8) (0 voxel: no thinning).
// What the tiles of a tiled merge share, prepared once: each scan's range view and spacing, and the bounding box
// (relative to PatchOrigin) of each 16 x 16-cell block's valid points together with the 8 rows and
// columns after it (the farthest a triangle of the block reaches), so a tile visits only the blocks
// that may reach it.
struct TileInputs {
  static constexpr int kCellBlock = 16;
  std::vector<RangeView> views;
  std::vector<double> spacing;                            // per scan: median spacing of its cells
  std::vector<std::vector<Eigen::AlignedBox3f>> blocks;  // per scan, row-major over cell blocks
};
TileInputs PrepareTileInputs(const std::vector<const Scan*>& scans);

// `keep` (relative to the origin, which depends on the scans only): points outside it are left out,
// with the triangles they belong to (a tile of a tiled merge; `tiles` from PrepareTileInputs).
Expected<RangePatches> BuildRangePatches(const std::vector<const Scan*>& scans, double max_grazing_deg,
                                         const CancelToken& cancel, double voxel_m = 0.0,
                                         const Eigen::AlignedBox3f* keep = nullptr, const TileInputs* tiles = nullptr);

// The origin BuildRangePatches uses for these scans (the first scanner with a valid point, rounded).
Eigen::Vector3d PatchOrigin(const std::vector<const Scan*>& scans);
// The longest triangle edge BuildRangePatches may make for these scans at this voxel.
double MaxPatchEdge(const std::vector<const Scan*>& scans, double voxel_m);

// Nearest point to x on triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3f ClosestPointOnTriangle(const Eigen::Vector3f& x, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                       const Eigen::Vector3f& c);

}  // namespace scanreg::merge
