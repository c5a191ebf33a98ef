// Many scans at once (issue 33): a measure of how consistent a set of poses is that needs no ground
// truth, and the multi-view fine step that minimises it. Both work on every overlapping pair's
// point-to-plane residuals: the samples of one scan against the other's surface (the nearest sample
// and its normal from the surrounding samples), in both directions.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <utility>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/registration/point_index.h"

namespace scanreg {

// One scan's samples in its own frame, their normals (zero where the neighbourhood is no plane)
// and an index over them.
struct ViewSurface {
  std::vector<Eigen::Vector3d> points, normals;
  std::unique_ptr<PointIndex> index;
};
// Normals from the k nearest samples (a plane fit; edges and clutter get none).
ViewSurface MakeViewSurface(std::vector<Eigen::Vector3d> samples, int k = 12);

using Poses = std::vector<Eigen::Isometry3d>;  // world_from_scan, one per view

// The unordered pairs (i < j) whose overlap — the larger of both directions' share of samples
// within distance_m of the other's samples — reaches min_overlap at any of the pose sets.
// used[i] false: view i takes no part.
std::vector<std::pair<int, int>> OverlappingPairs(const std::vector<const ViewSurface*>& views,
                                                  const std::vector<Poses>& pose_sets, const std::vector<bool>& used,
                                                  double distance_m, double min_overlap);

// How consistent pose sets are, compared on the same samples. A sample of one scan meets the other
// scan's surface at the nearest of its 4 nearest samples there within cutoff_m whose normal is
// within 30° of its own and which lies within cutoff_m along that sample's tangent plane (beyond the
// other scan's border, or across a corner, it meets nothing); samples without a normal take no
// part. The samples compared are those of each pair that meet the other surface at any of the pose
// sets; each costs the bounded (Geman-McClure) loss r^2 / (r^2 + scale^2) of its point-to-plane
// residual r, or the loss's ceiling 1 where it meets nothing at that pose set — so a pose that
// pulls scans apart cannot look better by losing its overlap, and a few samples seen at one pose
// only (borders, occlusions) cannot outweigh the residuals of the rest. The mean loss m is reported
// as a robust RMS, scale x sqrt(m / (1 - m)) (the RMS of residuals that would all give it).
struct Consistency {
  double rms_m = 0;                // over every pair
  std::vector<double> scan_rms_m;  // each view's share: the pairs it is in (0: none)
  std::vector<long> scan_samples;
  std::vector<double> pair_rms_m;  // per pair: the plain RMS of the residuals of the samples met at this pose set (-1: none)
  long samples = 0;
};
std::vector<Consistency> MeasureConsistency(const std::vector<const ViewSurface*>& views,
                                            const std::vector<Poses>& pose_sets,
                                            const std::vector<std::pair<int, int>>& pairs, double cutoff_m,
                                            double scale_m);

// The multi-view fine step: every view's pose at once, Gauss-Newton on the point-to-plane residuals
// of every pair (both directions), correspondences found anew at each round, a Cauchy kernel, the
// cutoff halved twice down to floor_m. Fixed views keep their poses (at least one: the datum).
struct MultiViewOptions {
  double cutoff_m = 0.01;
  double floor_m = 0.0;            // lowest cutoff (e.g. 3 x the range noise)
  int rounds = 12;
  int samples_per_pair = 3000;     // of the child, evenly
  double converged_m = 1e-6;       // stop when no sample moves more than this (relative to the cutoff: x cutoff)
};
struct MultiViewResult {
  Poses world;
  int rounds = 0;
  bool converged = false;
  // Per view: the smallest over the largest eigenvalue of its own 6 x 6 information (rotation about
  // its samples' centre scaled by their spread); near 0 the overlaps leave a direction free.
  std::vector<double> conditioning;
};
Expected<MultiViewResult> AlignMultiView(const std::vector<const ViewSurface*>& views, const Poses& start,
                                         const std::vector<std::pair<int, int>>& pairs, const std::vector<bool>& fixed,
                                         const MultiViewOptions& options, const CancelToken& cancel);

}  // namespace scanreg
