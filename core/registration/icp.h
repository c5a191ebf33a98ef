// Fine registration (W §4.4, SPEC §2 step 9): ICP on the consistent keypoints (the paper), and
// dense point-to-plane ICP on voxel-downsampled full scans (alternative).
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg {

class PointIndex;

struct IcpResult {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  double rms_m = 0.0;       // RMS residual over the final correspondences (point-to-point or point-to-plane)
  int iterations = 0;       // total, all stages
  int correspondences = 0;  // pairs used in the last iteration
  double overlap = 0.0;     // fraction of child samples with a parent point within the final max distance
  bool converged = false;   // the last stage met the convergence test with >= the minimum correspondences
};

// Keypoint ICP (W §4.4): point-to-point, nearest neighbour among the keypoint sets.
struct IcpOptions {
  double max_correspondence_m = 0.2;  // pairs farther apart are ignored, metres (a few inlier thresholds)
  int max_iterations = 50;
  double convergence_translation_m = 1e-6;  // stop when an update moves less than this...
  double convergence_rotation_rad = 1e-7;   // ...and rotates less than this
  int min_correspondences = 3;              // FitRigid's minimum

  Status Validate() const;
};

// parent_pts / child_pts: keypoints in each scanner frame (not necessarily paired). Each iteration
// pairs every child point with its nearest parent point within max_correspondence_m and refits
// (FitRigid). Errors: invalid options, empty sets, fewer than min_correspondences pairs at the
// start (kFailed), cancel (kCancelled, checked per iteration).
Expected<IcpResult> KeypointIcp(const std::vector<Eigen::Vector3d>& parent_pts,
                                const std::vector<Eigen::Vector3d>& child_pts,
                                Eigen::Isometry3d initial_parent_from_child, const IcpOptions& options,
                                const CancelToken& cancel);

// Dense point-to-plane ICP on the valid points of two organized scans.
struct DenseIcpOptions {
  double voxel_m = 0.1;  // voxel size of the centroid downsampling of both scans, metres
  // The child's voxel samples are thinned to at most this many (evenly, deterministic). Measured
  // on the 1500x375 demo (6 stations): 20k samples 0.2-0.8 mm error, 8k 0.2-1.4 mm at ~2/3 of
  // the time per pair; W's errors are 9-32 mm.
  int max_samples = 8000;
  int normal_neighbours = 12;  // k of the k-nn PCA normals on the parent samples
  // Parent samples whose PCA neighbourhood is not planar (surface variation l0 / (l0+l1+l2) above
  // this; edges, corners, vegetation) get no normal and are not used.
  double max_surface_variation = 0.05;
  // Correspondence distance schedule, coarse to fine, metres: one stage per entry, each run to
  // convergence or max_iterations_per_stage. The last entry is also the overlap radius.
  std::vector<double> max_correspondence_schedule_m = {1.0, 0.4, 0.2};
  int max_iterations_per_stage = 30;
  double convergence_translation_m = 1e-4;
  double convergence_rotation_rad = 1e-5;
  // Tukey biweight, c = 4.685 * scale, scale = 1.4826 * MAD of the point-to-plane residuals, but at
  // least robust_scale_floor_m (noise-free data would otherwise give scale 0).
  double robust_scale_floor_m = 0.01;
  int min_correspondences = 30;  // fewer: the stage stops, the result is not converged

  Status Validate() const;
};

// Errors: invalid options or scans, a scan without valid points (kInvalidArgument), cancel
// (kCancelled, checked per iteration). No overlap is not an error: the result then has
// converged = false and overlap ~ 0, and callers mark the link failed.
Expected<IcpResult> DenseIcp(const Scan& parent, const Scan& child, Eigen::Isometry3d initial_parent_from_child,
                             const DenseIcpOptions& options, ProgressSink& progress, const CancelToken& cancel);

// A parent's voxel samples prepared for dense ICP once (k-d tree and PCA normals), for every pair
// and every start pose it takes part in. A sample's normal is computed the first time a pair
// meets it and kept: a pair meets a small part of a scan (8-station street, 3000x750: the normals
// of every sample were 15 % of a first registration's CPU time; issue 36).
class IcpSurface {
 public:
  IcpSurface(std::vector<Eigen::Vector3d> samples, const DenseIcpOptions& options);
  ~IcpSurface();
  std::size_t Bytes() const;  // memory held
  // PCA normal over the sample's k nearest samples; zero where the neighbourhood is not planar.
  // Safe to call from several threads at once.
  Eigen::Vector3d Normal(int sample) const;

  std::vector<Eigen::Vector3d> points;
  std::unique_ptr<PointIndex> index;

 private:
  int normal_neighbours_;
  double max_surface_variation_;
  mutable std::vector<Eigen::Vector3d> normals_;
  mutable std::unique_ptr<std::atomic<std::uint8_t>[]> normal_state_;  // 0 not computed, 1 being stored, 2 stored
};

Expected<IcpResult> DenseIcpSurface(const IcpSurface& parent, const std::vector<Eigen::Vector3d>& child_samples,
                                    Eigen::Isometry3d initial_parent_from_child, const DenseIcpOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel);

// The same on samples already voxel-downsampled at options.voxel_m (each scan's samples computed
// once and reused for every pair it takes part in).
Expected<IcpResult> DenseIcpSamples(const std::vector<Eigen::Vector3d>& parent_samples,
                                    const std::vector<Eigen::Vector3d>& child_samples,
                                    Eigen::Isometry3d initial_parent_from_child, const DenseIcpOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg
