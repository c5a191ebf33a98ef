// A range image as a projection and a mesh (S §2.1, §3.2; SPEC §3): where a 3D point falls in a
// scan's grid along that scan's line of sight, and the scan's measured surface at a sub-pixel cell
// (linear interpolation inside the grid triangle holding it; triangles across depth
// discontinuities are skipped).
//
// Panoramic scans project through their angular grid (azimuth per column, elevation per row, a
// regular step from the first to the last entry). Range grids without angles (the Stanford
// Cyberware scans) get a camera fitted to their valid cells by least squares on
// (col, row) <-> point: a general 3x4 projective camera (normalised DLT) and an affine
// (orthographic-like) camera; the one with the smaller RMS reprojection residual in pixels is kept
// (the projective one only when clearly better, see RangeImageOptions).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg {

enum class GridCameraModel { kAngular, kProjective, kAffine };
const char* GridCameraModelName(GridCameraModel model);

struct RangeImageOptions {
  // A mesh edge is a depth discontinuity when it is longer than
  // max(edge_spacing_ratio x the grid's sample spacing there, min_edge_break_m); triangles using
  // it are skipped. The spacing is range x angular step for panoramic grids, the median
  // neighbour distance for fitted cameras.
  double edge_spacing_ratio = 8.0;
  double min_edge_break_m = 0.0;  // metres; noisy data need a few sigma here
  // Grids without angles: the projective camera is kept only when its RMS reprojection residual
  // is below this fraction of the affine camera's (it has 3 more degrees of freedom).
  double prefer_projective_ratio = 0.8;

  Status Validate() const;
};

struct CameraFitReport {
  GridCameraModel model = GridCameraModel::kAngular;
  double rms_px = 0.0;             // chosen model, over the valid cells
  double max_px = 0.0;             // chosen model
  double projective_rms_px = -1;   // -1 when not fitted (angular grids)
  double affine_rms_px = -1;
  int cells = 0;                   // valid cells used
};

class RangeImageProjection {
 public:
  // The scan must outlive the projection (it is referenced, not copied). Errors: invalid options,
  // a grid smaller than 2 x 2, fewer than 12 valid cells or a degenerate camera fit.
  static Expected<RangeImageProjection> Create(const Scan& scan, const RangeImageOptions& options = {});

  const Scan& scan() const { return *scan_; }
  const CameraFitReport& fit() const { return fit_; }
  int valid_triangles() const { return valid_triangles_; }

  // Sub-pixel cell of a point in the scan frame (row, col as continuous indices: cell centres at
  // integers). False outside the grid or behind a projective camera.
  bool Project(const Eigen::Vector3d& p, double* row, double* col) const;
  // Unit line of sight through a point in the scan frame, pointing away from the sensor.
  Eigen::Vector3d LineOfSight(const Eigen::Vector3d& p) const;
  // The measured surface at a sub-pixel cell: linear interpolation in the valid mesh triangle
  // containing it. False when that triangle is missing (empty cell or depth discontinuity).
  bool SurfaceAt(double row, double col, Eigen::Vector3d* point) const;
  // The measured surface on the scan's line of sight through p (scan frame): the line's
  // intersection with the mesh triangle p projects into. False when p projects outside the grid or
  // onto a missing triangle.
  bool SurfaceAlongLineOfSight(const Eigen::Vector3d& p, Eigen::Vector3d* surface) const;

 private:
  RangeImageProjection() = default;
  bool Triangle(double row, double col, Eigen::Vector3d tri[3], double* a, double* b) const;
  double Spacing(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const;
  void BuildMesh(const RangeImageOptions& options);

  const Scan* scan_ = nullptr;
  CameraFitReport fit_;
  // Angular model.
  double az0_ = 0, daz_ = 1, el0_ = 0, del_ = 1;
  bool wraps_ = false;
  // Fitted models: pixel = P [p; 1] (projective, homogeneous) or A [p; 1] (affine, rows 0-1).
  Eigen::Matrix<double, 3, 4> camera_ = Eigen::Matrix<double, 3, 4>::Zero();  // rows: col, row, w
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();     // projective camera centre
  Eigen::Vector3d direction_ = Eigen::Vector3d::UnitZ();  // affine line of sight
  double median_spacing_m_ = 0.0;
  // Per quad (r, c) -> (r+1, c+1), bit 0: triangle (r,c)(r,c+1)(r+1,c); bit 1: (r+1,c+1)(r+1,c)(r,c+1).
  std::vector<std::uint8_t> triangles_;
  int quad_cols_ = 0;
  int valid_triangles_ = 0;
};

}  // namespace scanreg
