// Geometric correspondences beside SIFT (issue 11, item 2): FPFH descriptors (Rusu et al. 2009,
// PCL's FPFHEstimationOMP) on voxel samples with normals, for scans with or without reflectance,
// organized or not, and the scan's "up" direction estimated from its normals (ground and walls), so
// that levelled scans can be registered with the 4-DoF solver (coarse.h).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/registration/data_scale.h"

namespace scanreg {

struct GeometricOptions {
  // Sample spacing, metres; both scans of a pair must use the same. 0: derived from the data
  // (SuggestVoxel; the caller resolves it before DetectGeometricFeatures).
  double voxel_m = 0.0;
  int max_samples = 15000;   // samples kept for normals and descriptors (thinned evenly beyond)
  int max_keypoints = 3000;  // samples of the child that look for a partner (thinned evenly)
  // Keypoints are the most curved samples, this fraction of them: planes (ground, façades) give
  // every sample the same descriptor and only add false matches.
  double distinctive_fraction = 0.5;
  double normal_radius_voxels = 2.5;
  double feature_radius_voxels = 10.0;  // measured: scanreg-bench --section geometric
  // A second, coarser set of descriptors at this many voxels (issue 37, item 2), matched only with
  // the same scale of the other scan: stations far apart see each other's surfaces at different
  // densities, which a coarse sampling evens out (a busy street 12 m apart: ~0 fine matches agree,
  // tens of coarse ones do; 3 is measured there). 0: the fine scale only, the default — on an office
  // floor the coarse descriptors, a metre across, match a corridor turned 180° (110 of 118
  // consistent correspondences, 8.7 m off), which only issue 38's alias search can refute.
  double coarse_scale = 0.0;
  Status Validate() const;
};

using Fpfh = std::array<float, 33>;

struct GeometricFeatures {
  double voxel_m = 0.0;  // the finest scale's voxel
  // Every scale's samples, finest first: scale s owns points [scales[s].begin, scales[s].end).
  std::vector<Eigen::Vector3d> points;  // voxel samples with a descriptor, scanner frame
  std::vector<Eigen::Vector3d> normals;  // unit, facing the scanner, one per point
  std::vector<Fpfh> descriptors;        // one per point
  std::vector<int> keypoints;           // indices into points: the evenly thinned subset used as queries
  // Nearest-descriptor search over one scale's descriptors (PCL's FLANN k-d tree), built once per scan.
  struct DescriptorIndex;
  struct Scale {
    double voxel_m = 0.0;
    int begin = 0, end = 0;
    std::shared_ptr<const DescriptorIndex> index;  // over descriptors [begin, end), local indices
  };
  std::vector<Scale> scales;
  // The end of the finest scale's points (what the levelling and the plan view use).
  int FinestEnd() const { return scales.empty() ? 0 : scales.front().end; }
  // The voxel of the scale that owns `point`.
  double VoxelOf(int point) const;
  // Levelling (issue 11, item 3): the scanner-frame direction of world up estimated from the normals
  // of the ground (near vertical) and the walls (near horizontal); `levelled` when the scan holds
  // enough of both and the estimate is within max tilt of the scanner's z axis.
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  bool levelled = false;
  double tilt_rad = 0.0;  // angle between `up` and the scanner's z axis
  // The rotation that takes `up` to +z (identity when not levelled): levelled frame from scan frame.
  Eigen::Isometry3d Levelling() const;
};

// A voxel size for a scan: a few times its point spacing and a fraction of its extent (a 20 cm
// object gets millimetres, a street tens of centimetres).
double SuggestVoxel(const Scan& scan);
// The same from an already measured scale.
double SuggestVoxel(const DataScale& scale);

Expected<GeometricFeatures> DetectGeometricFeatures(const Scan& scan, const GeometricOptions& options,
                                                    const CancelToken& cancel);

struct GeometricMatch {
  int parent = 0;  // index into parent.points
  int child = 0;   // index into child.points
};

// Each child keypoint's nearest parent descriptor of the same scale, kept when the parent point's
// nearest child descriptor lies within two of that scale's voxels of the keypoint (a mutual match up
// to the sampling) and it passes the ratio test against the second nearest parent descriptor.
std::vector<GeometricMatch> MatchGeometric(const GeometricFeatures& parent, const GeometricFeatures& child,
                                           double ratio = 0.9);

}  // namespace scanreg
