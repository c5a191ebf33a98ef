// Free-space consistency of two scans at a relative pose (after Huber & Hebert 2003, "Fully
// automatic registration of multiple 3D data sets"): a scanner's ray that returned from range R
// passed through everything nearer. A point of the other scan that lands in that free space
// contradicts the pose. Correct poses have almost no such points; wrong poses that still overlap
// well geometrically (a street shifted by one building on repeated façades) have many, because
// the unique objects (cars, posts, trees) end up where the observer saw through.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/geometry/scan.h"
#include "core/registration/ray_free_space.h"

namespace scanreg {

//
// Moving objects (vehicles, people) are where one scanner saw a surface and the other saw through:
// at the correct pose they violate too. They are told apart by shape: the violations are grouped
// into connected clusters, and a cluster no larger than a vehicle (and small against the scene) that
// stands out of `other`'s range image — its boundary mostly a jump to something farther, or to no
// return — is counted as `moving`, not against the pose. A wrong pose moves static surfaces (façades,
// the street's ends, every object at once) into free space: large clusters, clusters attached to
// surfaces the observer confirms (a corridor's end wall, object-sized, meets the side walls without a
// depth jump), or more than a street's worth of traffic. Limitation: a pose shifted along a street of identical flat façades, where
// only object-sized things (posts, parked cars) conflict, looks like traffic here; it still
// conflicts more than the true pose (PairFreeSpace::total), which ranks the candidate poses, and
// the correspondences, rival poses and loop checks must catch it.
struct FreeSpaceOptions {
  double margin_m = 0.2;         // a violation is nearer than the observer's surface by more than this
  int max_samples = 50000;       // samples of `other`, on a regular sub-grid of its cells
  double cluster_cell_m = 1.0;   // violations within about 2 cells of each other form one cluster
  double max_object_m = 15.0;    // bounding-box diagonal of the largest moving object (a bus: ~13 m)
  double max_object_share = 0.1;  // ... and at most this share of the other scan's extent
  double max_moving = 0.3;       // more than this share of samples "moving": not traffic, all count
  // Returns this near their own scanner are not samples: the tripod, the operator, a robot's body
  // travel with the scanner and lie in every other scanner's free space at the true pose (measured:
  // the PCL room scans, a pan-tilt lidar on a robot: 20 % of the points within 0.5 m of the
  // scanner, 24 % "conflict" at the right pose, 70 % of it within 0.43 m). The radius is
  // min(near_field_m, near_field_fraction x the scan's median range), so an object scanned at
  // centimetres keeps its points.
  double near_field_m = 0.5;
  double near_field_fraction = 0.1;
};

struct FreeSpaceResult {
  int tested = 0;      // samples of `other` that project onto a valid cell of `observer`
  int violations = 0;  // of those, samples nearer than the observer's surface by more than the margin
  int moving = 0;      // of the violations, those in object-sized clusters
  double fraction() const { return tested ? double(violations) / tested : 0.0; }
  double static_fraction() const { return tested ? double(violations - moving) / tested : 0.0; }
  double moving_fraction() const { return tested ? double(moving) / tested : 0.0; }
};

// Samples `other`'s valid points (a regular sub-grid of an organized scan, evenly spaced indices
// otherwise), maps them into the observer's frame and its grid: panoramic (observer.angles) or
// perspective (a depth camera's pixel grid, fitted to the observer's own points). A sample is a
// violation when even the nearest return in the 3x3 cells around its projection is farther than
// the sample's range + margin (the 3x3 minimum spares depth edges and mixed pixels). A grid that is
// neither (no viewpoint: HasViewpoint) sees free space only along the observer's per-point rays
// (`observer_rays`, built from Scan::sensor with cells of half the margin): a sample in a free cube
// is a violation, one beside a return is tested; tested = 0 without them.
FreeSpaceResult FreeSpaceViolations(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                                    const FreeSpaceOptions& options, const RayFreeSpace* observer_rays = nullptr);

// True when free space can be seen from the observer's grid (panoramic or perspective).
bool HasViewpoint(const Scan& observer);

// Both directions of a pair at a pose: a's free space against b's samples and the reverse.
struct PairFreeSpace {
  FreeSpaceResult a_sees_b, b_sees_a;
  double conflict() const { return std::max(a_sees_b.static_fraction(), b_sees_a.static_fraction()); }
  double moving() const { return std::max(a_sees_b.moving_fraction(), b_sees_a.moving_fraction()); }
  double total() const { return std::max(a_sees_b.fraction(), b_sees_a.fraction()); }
};
PairFreeSpace PairFreeSpaceCheck(const Scan& a, const Scan& b, const Eigen::Isometry3d& a_from_b,
                                 const FreeSpaceOptions& options, const RayFreeSpace* a_rays = nullptr,
                                 const RayFreeSpace* b_rays = nullptr);

// Marks (sets to 1) every valid point of `other` that lies in the observer's free space, without
// sampling or clustering: after registration these are moving objects (or stray returns). `mask`
// has other.size() entries; points already marked stay marked. An observer without a grid
// viewpoint sees free space along `observer_rays` when given (cubes of half the margin), else none.
void MarkFreeSpacePoints(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                         double margin_m, std::vector<std::uint8_t>* mask, const RayFreeSpace* observer_rays = nullptr);

}  // namespace scanreg
