// Free space seen along per-point rays (issue 34): a cloud seen from several places (a mobile
// mapper's, or stations merged by another program) has no one viewpoint, but where its file gives
// each point's sensor position (Scan::sensor) every return says the space from the sensor to it was
// empty. The rays are traced through a grid of cubes: a cube a ray passed through, short of its
// return by the margin, is free; a cube beside any return is surface. visibility.h tests another
// scan's samples against it as it tests them against a scanner's range image.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg {

class RayFreeSpace {
 public:
  // cell_m: the cubes' edge; rays stop 2 cells short of their return, so the margin of the free
  // space is 2-3.5 cells (the range-image test's margin is 2 cells of the same size). At most
  // `max_cells` cubes are traced: the rays are taken evenly over the points until their lengths
  // add up to that. Empty (known() false) for a scan without sensor positions or a cell <= 0.
  RayFreeSpace(const Scan& scan, double cell_m, std::size_t max_cells = 8000000);

  bool known() const { return !free_.empty(); }
  double cell_m() const { return cell_; }
  int rays() const { return rays_; }
  enum class Seen { kUnseen, kSurface, kFree };
  // The state of the cube holding p (scan frame): kSurface when a return lies in it or a cube beside
  // it (26-neighbourhood), else kFree when a ray passed through it, else kUnseen.
  Seen At(const Eigen::Vector3d& p) const;
  bool Free(const Eigen::Vector3d& p) const;  // At(p) == kFree, the free cubes looked up first
  std::size_t Bytes() const { return (free_.capacity() + surface_.capacity()) * sizeof(std::uint64_t); }

 private:
  bool Has(const std::vector<std::uint64_t>& set, std::int64_t x, std::int64_t y, std::int64_t z) const;
  bool NearSurface(std::int64_t x, std::int64_t y, std::int64_t z) const;  // a return in the cube or beside it

  double cell_ = 0.0;
  int rays_ = 0;
  std::vector<std::uint64_t> free_, surface_;  // packed cube keys, sorted, unique
};

}  // namespace scanreg
