// Organizing an unorganized cloud into a panoramic grid by spherical projection around the
// scanner origin (SPEC §1).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg {

struct OrganizeOptions {
  double azimuth_step_rad = 0.12 * M_PI / 180.0;    // column spacing (W: 0.12 deg)
  double elevation_step_rad = 0.12 * M_PI / 180.0;  // row spacing
  // Elevation range of the grid; when min >= max, it is taken from the data.
  double elevation_min_rad = 0.0;
  double elevation_max_rad = 0.0;
  // Azimuth of the left edge of column 0 and the azimuth range the columns cover (radians); a span
  // <= 0 means a full turn. Points outside a partial span are left out.
  double azimuth_start_rad = -M_PI;
  double azimuth_span_rad = 0.0;
  // When not empty: one row per entry (radians, strictly decreasing, so row 0 is the highest), as
  // for the laser rings of a multi-beam lidar; each point goes to the row of the nearest
  // elevation, and elevation_step_rad / elevation_min_rad / elevation_max_rad are unused.
  std::vector<double> row_elevations_rad;
  // When a point's cell is taken, the point may move up to this many columns along its row into a
  // free cell; the points of a row keep their azimuth order. 0: the nearer point wins the cell.
  int max_column_shift = 0;
  Status Validate() const;
};

// The directions of a cloud's usable points (finite, away from the origin), sorted by azimuth
// once, so that several candidate grids can be tried cheaply (O(n) each). `points` must outlive
// the projection.
class CloudProjection {
 public:
  explicit CloudProjection(const std::vector<Eigen::Vector3f>& points);

  std::size_t usable() const { return dirs_.size(); }
  double elevation_min() const { return el_min_; }  // radians; +inf/-inf without usable points
  double elevation_max() const { return el_max_; }
  // How many points Organize keeps with these options, without building the grid.
  Expected<std::size_t> CountKept(const OrganizeOptions& options) const;
  // The grid, as OrganizeCloud documents; reflectance, colour, time and sensor are empty or one per input point.
  Expected<Scan> Organize(const std::vector<float>& reflectance, const OrganizeOptions& options, std::string name,
                          const std::vector<Rgb>& colour = {}, const std::vector<double>& time = {},
                          const std::vector<Eigen::Vector3f>& sensor = {}) const;

 private:
  struct Dir {
    double az;            // radians, atan2(y, x)
    float el;             // radians, atan2(z, |xy|)
    float range;          // metres
    std::uint32_t index;  // into the points
  };
  // Places the points in the grid of `options`; returns how many are kept. Builds the grid into
  // *out (with reflectance, colour, time and sensor, which may be empty) unless out is null.
  Expected<std::size_t> Place(const OrganizeOptions& options, const std::vector<float>& reflectance,
                              const std::vector<Rgb>& colour, const std::vector<double>& time,
                              const std::vector<Eigen::Vector3f>& sensor, std::string name, Scan* out) const;

  const std::vector<Eigen::Vector3f>* points_;
  std::vector<Dir> dirs_;  // sorted by azimuth, then range
  double el_min_, el_max_;
};

// points are in the scanner frame (subtract the scanner origin first). When two points compete
// for one cell and no free cell is within max_column_shift columns (or they lie on one ray), the
// nearer one (the first return) takes the cell and the other joins the scan's list_points, as
// does every point outside a partial grid: no usable point is lost. Row 0 is the highest elevation; column 0 starts at
// azimuth_start_rad (column azimuths increase from there and may exceed pi for a partial span).
// Every point is an input point, unchanged. Non-finite points and points at the origin are
// skipped. reflectance may be empty (then 0.5); colour, time and sensor may be empty (then the scan has none).
Expected<Scan> OrganizeCloud(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                             const OrganizeOptions& options, std::string name, const std::vector<Rgb>& colour = {},
                             const std::vector<double>& time = {}, const std::vector<Eigen::Vector3f>& sensor = {});

}  // namespace scanreg
