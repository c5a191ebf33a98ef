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

// A triangle of adjacent cells, or a disc (v[0] == v[1] == v[2]; issue 34, item 2) around a point
// without grid neighbours — a listed point, or any point of a cloud seen from several places — on
// the plane of its nearest neighbours, with its scan's disc radius (RangePatches::disc_radius).
struct Patch {
  std::array<int, 3> v;    // indices into RangePatches::points
  Eigen::Vector3f normal;  // unit, facing the scanner that saw it (a cloud without one: point_normals.h)
  int scan = 0;            // index into the input scans
  bool disc() const { return v[0] == v[1]; }
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
  // Per scan: 1 when its points were seen from its scanner (Scan::single_viewpoint). A cloud seen
  // from several places has no range view, and its distances run along its discs' normals, not
  // along lines of sight from a scanner it does not have.
  std::vector<char> viewpoint;
  std::vector<float> disc_radius;  // per scan: radius of its discs (0: none)
  // Per point its colour, once a scan with colour has come (empty before and without); `coloured`
  // per scan: 1 when its points' colours are the scanner's (0: black, no colour).
  std::vector<Rgb> colour;
  std::vector<char> coloured;
  double max_patch_radius = 0.0;         // metres: largest centroid-to-vertex distance

  // Indices of the patches that may lie within radius_m of x (bounding-sphere test), each once.
  // Patches spanning more than 16^3 hash cells are never returned. Thread-safe.
  void Candidates(const Eigen::Vector3f& x, double radius_m, std::vector<int>* out) const;
  // Bounding-sphere test: patch p may lie within radius_m of x.
  bool Reaches(int p, const Eigen::Vector3f& x, float radius_m) const {
    const float reach = radius_m + radius[p];
    return (centroid[p] - x).squaredNorm() <= reach * reach;
  }
  void BuildHash(double cell_m);
  // The point of patch `id` nearest x.
  Eigen::Vector3f Closest(int id, const Eigen::Vector3f& x) const;
  // Cosine between patch p's line of sight through `at` and `dir`, at least 0.2 (S's guard near 90
  // degrees); 1 for a scan without a viewpoint, whose noise is taken along the normal.
  float SightCosine(const Patch& p, const Eigen::Vector3f& at, const Eigen::Vector3f& dir) const;

  std::unordered_map<BlockKey, std::vector<int>, BlockKeyHash> hash;
  double cell = 1.0;
  std::vector<Eigen::Vector3f> centroid;
  std::vector<float> radius;  // per patch: centroid-to-vertex
};

// The bounding spheres of a set of patches side by side, one array per coordinate: the candidates of
// a point, from those of a larger ball around it (one hash query for a group of grid points, then
// this filter per point). The copies keep the per-point pass in cache and vectorised; reading the
// spheres from the patches' arrays at each point was a fifth of a consensus merge (issue 35).
class PatchSpheres {
 public:
  void Load(const RangePatches& patches, const std::vector<int>& ids);
  // The loaded patches whose bounding sphere reaches within radius_m of x (RangePatches::Reaches),
  // in their order.
  void Filter(const Eigen::Vector3f& x, float radius_m, std::vector<int>* out) const;

 private:
  std::vector<int> ids_;
  std::vector<float> x_, y_, z_, r_;
  mutable std::vector<unsigned char> hit_;
};

// What a tiled merge keeps of a scan between tiles, from one pass over it (issue 13, item 5): its
// grid, its median spacing (the thinning stride), its valid points and, with blocks, the bounding
// box (relative to the patches' origin) of each 16 x 16-cell block's valid points together with the
// 8 rows and columns after it (the farthest a triangle of the block reaches), so that a tile reads
// only the cells that may reach it.
//
// A scan's discs (issue 34, item 2) are made once, here, and shared by the tiles: its listed points,
// and for a cloud seen from several places every point — its grid, built around an origin no scanner
// stood at, is no range image (adjacent cells need not be neighbours on a surface), so its cells are
// not triangulated and `valid` is 0. Measured on two stations merged into one cloud (consensus,
// 8 cm voxel): its cells triangulated 7.4 % spurious and 44 % holes; discs 0.1 % and 21 %, the two
// stations' own merge 0.1 % and 17 %. Normals from the 12 nearest points (point_normals.h); a list
// denser than half a voxel is replaced by the centroid of each half-voxel cube.
struct ScanLayout {
  static constexpr int kCellBlock = 16;
  int rows = 0, cols = 0;
  double spacing = 0.0;
  std::size_t valid = 0;  // cells triangulated
  struct Discs {
    std::vector<Eigen::Vector3f> points;  // relative to the origin
    std::vector<Eigen::Vector3f> normals;
    std::vector<Rgb> colours;  // per point when the scan has colour (a cube's mean)
    float radius = 0.0f;
    Eigen::AlignedBox3f box;
  };
  std::shared_ptr<const Discs> discs;       // null: none
  std::vector<Eigen::AlignedBox3f> blocks;  // row-major over cell blocks; empty: not computed
  int block_rows() const { return (rows + kCellBlock - 1) / kCellBlock; }
  int block_cols() const { return (cols + kCellBlock - 1) / kCellBlock; }
};
ScanLayout LayoutScan(const Scan& scan, const Eigen::Vector3d& origin, bool with_blocks, double voxel_m,
                      const CancelToken& cancel);

// A window of a scan's cells — rows [row0, row0 + cells->rows), columns [col0, col0 + cells->cols)
// of the scan `layout` describes, with their angles — as a Scan of its own: a tile's share of a
// scan (or the whole scan, at 0, 0).
struct ScanPiece {
  std::shared_ptr<const Scan> cells;
  int row0 = 0, col0 = 0;
  const ScanLayout* layout = nullptr;
};
// The cells of `scan` in rows [r0, r1) and columns [c0, c1), with their angles and pose.
Scan CropScan(const Scan& scan, int r0, int r1, int c0, int c1);
// The cells a tile reads of a scan: the blocks that may reach `keep` (layout.blocks), widened by one
// block each way (the neighbours a TSDF projection reads), as rows [*r0, *r1) and columns [*c0, *c1);
// false when no block reaches it.
bool PieceWindow(const ScanLayout& layout, const Eigen::AlignedBox3f& keep, int* r0, int* r1, int* c0, int* c1);

// Triangulates the valid cells of every piece at its scan's world_from_scan, relative to `origin`,
// and adds its layout's discs.
// Skips triangles with an edge over 8x the scan's median grid spacing (depth edges) or seen more
// obliquely than max_grazing_deg. Range images much denser than the grid are thinned first: every
// s-th row and column of the whole scan with s = clamp(floor(0.5 voxel / median spacing), 1, 8)
// (0 voxel: no thinning). `keep` (relative to the origin): points outside it are left out, with
// the triangles they belong to, and only the blocks that may reach it are visited (a tile of a
// tiled merge: the pieces' layouts must hold blocks). Patch::scan indexes the pieces.
Expected<RangePatches> BuildRangePatches(const std::vector<ScanPiece>& pieces, const Eigen::Vector3d& origin,
                                         double max_grazing_deg, const CancelToken& cancel, double voxel_m,
                                         const Eigen::AlignedBox3f* keep = nullptr);
// Whole scans, around PatchOrigin(scans). Errors name the scans when none has a valid point.
Expected<RangePatches> BuildRangePatches(const std::vector<const Scan*>& scans, double max_grazing_deg,
                                         const CancelToken& cancel, double voxel_m = 0.0);

// The origin BuildRangePatches uses for these scans (the first scanner with a valid point, rounded).
Eigen::Vector3d PatchOrigin(const std::vector<const Scan*>& scans);
// The longest triangle edge BuildRangePatches may make of a scan with this spacing at this voxel.
double MaxPatchEdge(double spacing, double voxel_m);

// Nearest point to x on triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3f ClosestPointOnTriangle(const Eigen::Vector3f& x, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                       const Eigen::Vector3f& c);

}  // namespace scanreg::merge
