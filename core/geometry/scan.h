// The organized scan: an H x W panorama (rows = elevation, columns = azimuth) in the scanner's
// own frame, with its pose. SPEC §1.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg {

// Angular geometry of a panoramic grid: the azimuth of each column and the elevation of each
// row, in radians, in the scanner frame (azimuth = atan2(y, x), elevation = atan2(z, |xy|)).
// Empty when unknown (e.g. a triangulation range grid); then the line of sight of a valid cell
// is the direction to its point.
struct AngularGrid {
  std::vector<float> azimuth;    // one per column
  std::vector<float> elevation;  // one per row
  bool empty() const { return azimuth.empty() || elevation.empty(); }
};

// A point's colour, 8 bits a channel (red, green, blue), as a scanner's camera gives it.
using Rgb = std::array<std::uint8_t, 3>;

// A colour from channels already on the 0..255 scale: rounded, clamped, and 0 where a channel is not finite.
Rgb ToRgb(double red, double green, double blue);

// 17 bytes per cell: 12 (xyz float) + 4 (reflectance) + 1 (valid), 3 more with colour, 8 more with time,
// 12 more with sensor positions. Points stay local to the
// scanner (float is plenty within a few km); the pose is double, so UTM-sized coordinates keep
// their precision.
struct Scan {
  std::string name;
  int rows = 0;  // elevation
  int cols = 0;  // azimuth
  std::vector<Eigen::Vector3f> points;  // rows*cols, row-major, metres, scanner frame
  std::vector<float> reflectance;       // rows*cols, nominally [0, 1]
  std::vector<std::uint8_t> valid;      // rows*cols, 1 where the cell holds a return
  AngularGrid angles;
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  std::optional<Eigen::Isometry3d> reference_world_from_scan;  // ground truth / survey control
  // The grid came with the file (a scanner's own range image: PTX, structured E57, an organized PCD);
  // false when it was organized here from a list of points (mobile lidar, merged clouds).
  bool grid_from_file = true;
  // Points the grid has no cell for, kept as a list in the scanner frame: a cloud seen from more
  // than one place (a merged or mobile-mapping cloud) organized around its origin leaves out the
  // points that share a cell with a nearer one. Never dropped: they are counted, exported and drawn
  // with the grid's points (ForEachPoint); the steps that need a range image use the grid.
  std::vector<Eigen::Vector3f> list_points;
  std::vector<float> list_reflectance;  // one per list point
  // Colour where the file gave one (PTX r g b, PLY red green blue, PCD rgb, E57 colorRed..., LAS RGB):
  // then one per cell (empty cells black) and one per listed point; both empty otherwise.
  std::vector<Rgb> colour;
  std::vector<Rgb> list_colour;
  // Time of each return where the file gave one (LAS GPS time, PLY gps_time / time / timestamp, E57
  // timeStamp), in seconds of the file's own time base (time_base): then one per cell (empty cells 0)
  // and one per listed point; both empty otherwise. Kept and exported, never used to move a point.
  std::vector<double> time;
  std::vector<double> list_time;
  std::string time_base;  // what the times count from, as the file said ("" when it did not)
  // Where the sensor was when it measured each point, where the file gave it (a mobile mapper's or
  // a merged cloud's per-point origin: PLY x_origin y_origin z_origin), scanner frame: then one per
  // cell (empty cells 0) and one per listed point; both empty otherwise. A cloud seen from several
  // places sees free space along these rays (registration/ray_free_space.h).
  std::vector<Eigen::Vector3f> sensor;
  std::vector<Eigen::Vector3f> list_sensor;
  // The grid's points were all seen from the scanner origin. False for a cloud seen from several
  // places: its grid is only an index, and no evidence is drawn from free space "seen" from it.
  bool single_viewpoint = true;

  Scan() = default;
  Scan(std::string scan_name, int num_rows, int num_cols);

  std::size_t size() const { return points.size(); }
  std::size_t Index(int row, int col) const { return static_cast<std::size_t>(row) * cols + col; }
  bool IsValid(int row, int col) const { return valid[Index(row, col)] != 0; }
  const Eigen::Vector3f& Point(int row, int col) const { return points[Index(row, col)]; }
  float Reflectance(int row, int col) const { return reflectance[Index(row, col)]; }
  void Set(int row, int col, const Eigen::Vector3f& p, float refl);
  void Clear(int row, int col);

  bool HasColour() const { return !colour.empty() || !list_colour.empty(); }
  // Gives the scan colour: every cell and listed point black until set.
  void AddColour();
  bool HasTime() const { return !time.empty() || !list_time.empty(); }
  // time_base for messages: quoted, or "an unknown base".
  std::string TimeBaseText() const { return time_base.empty() ? "an unknown base" : "'" + time_base + "'"; }
  // Gives the scan times: every cell and listed point 0 until set.
  void AddTime();
  bool HasSensor() const { return !sensor.empty() || !list_sensor.empty(); }
  // Gives the scan sensor positions: every cell and listed point at the origin until set.
  void AddSensor();

  std::size_t CountValid() const;  // the grid's points
  std::size_t CountPoints() const { return CountValid() + list_points.size(); }  // every point
  // Visits every point, the grid's valid cells first (row-major), then the list: f(point, reflectance).
  template <typename F>
  void ForEachPoint(F&& f) const {
    for (std::size_t i = 0; i < points.size(); ++i)
      if (valid[i]) f(points[i], reflectance[i]);
    for (std::size_t i = 0; i < list_points.size(); ++i) f(list_points[i], list_reflectance[i]);
  }
  // Unit line of sight of a cell, scanner frame: from the angular grid when known, else the
  // direction to the cell's point (zero vector for an empty cell without angles).
  Eigen::Vector3f LineOfSight(int row, int col) const;
  // Checks that the arrays agree with rows x cols (the colour too, when there is one) and that every
  // valid point is finite.
  Status Validate() const;
};

// True when the sensor positions (Scan::sensor, list_sensor, or any such list) lie further apart than
// `tolerance_m`: the points were seen from several places, whatever the grid says.
bool SensorsSpread(const std::vector<Eigen::Vector3f>& sensor, double tolerance_m = 0.01);

// Fills scan.angles from the valid points: the median azimuth of each column and the median
// elevation of each row; columns/rows without a valid point are interpolated from neighbours.
// Does nothing (returns false) for grids that are not panoramic (too few valid cells).
bool EstimateAngularGrid(Scan& scan);

}  // namespace scanreg
