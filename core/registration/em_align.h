// Probabilistic alignment of two range images with the line-of-sight error model (Sagawa et al.,
// S §3.2, SPEC §3), and behind the same interface its baselines: projective ("along the line of
// sight") ICP, S's reference [15] (Oishi et al. 2003), and projective point-to-plane ICP.
//
// Every vertex x_i of the child (S's range image A, the one moved) is a noisy measurement of a
// surface point s on its own line of sight v_i. EM samples s_ij = x_i + t_j v_i with the Gaussian
// bin weights (S eq. 15)
//     P(s_ij) = 1/2 [erf((t_j + t_{j+1}) / (2 sqrt2 sigma)) - erf((t_j + t_{j-1}) / (2 sqrt2 sigma))]
// (t_0 = -inf, t_{m+1} = +inf); each sample's correspondence y_ij is the parent's (B's) measured
// surface on the parent's line of sight through s_ij (RangeImageProjection); the M-step is the
// weighted rigid fit argmin sum P(s_ij) |y_ij - s_ij(theta)|^2 (S eq. 14, FitRigid). E and M
// alternate until the pose stops moving.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/registration/range_image_projection.h"

namespace scanreg {

struct EmOptions {
  enum class Method {
    kEm,             // S §3.2: samples along the child's line of sight, erf bin weights
    kProjectiveIcp,  // S's [15]: the single sample t = 0, weight 1
    kPointToPlane,   // projective correspondences (t = 0), point-to-plane linearised fit
  };
  Method method = Method::kEm;
  // kEm's M-step residual. kPointToPoint is S eq. 14, |y_ij - s_ij|^2: its residuals all lie on the
  // parent's lines of sight, so it exerts (almost) no torque about the parent's centre and stalls
  // on a wrong pose (measured on the Stanford bunny: 5 deg / 5 mm starts end at 3 deg / 5 mm).
  // kPointToPlane (ours, default: it measured better, see tests/bench/bench_em.cc): the same
  // samples, correspondences and weights, but the vertex x_i is pulled onto the parent's tangent
  // plane at each y_ij, sum_j P(s_ij) ((x_i(theta) - y_ij) . n(y_ij))^2. Pulling the sample s_ij
  // itself would add sum_j P t_j^2 (v_i . n)^2, a term that turns the child's lines of sight
  // towards the parent's surface (measured: noisy pyramid 20.6 mm vs 16.1 mm).
  enum class Residual { kPointToPlane, kPointToPoint };
  Residual residual = Residual::kPointToPlane;
  // Range noise along the line of sight, metres (S §3.1: Canesta DP200, 8 mm at 1 m).
  double sigma_m = 0.008;
  // Sample offsets t_j in units of sigma, strictly increasing (S §3.2: "given by the user";
  // SPEC §3: m = 5..9 over +-3 sigma). Only kEm uses them.
  std::vector<double> sample_offsets_sigma = {-3, -2, -1, 0, 1, 2, 3};
  int max_iterations = 50;
  double convergence_translation_m = 1e-5;  // stop when an update moves less than this...
  double convergence_rotation_rad = 1e-5;   // ...and rotates less than this
  int subsample = 1;  // every k-th valid vertex of the child
  // Pairs farther apart than this are dropped (self-occlusion, non-overlap); 0 = keep all (S).
  double max_correspondence_m = 0.0;
  // Robust rejection (not in S, whose synthetic scenes have no occlusions; real ones do: a vertex
  // the parent does not see projects onto the occluder): a child vertex is dropped when its
  // central sample's pair is farther apart than max(outlier_mad_factor x 1.4826 x median over
  // vertices, outlier_floor_sigma x sigma). 0 = off (default: measured on a rotated room, the
  // median is set by the floor and ceiling, which slide in their planes, and the walls that carry
  // the rotation get rejected).
  double outlier_mad_factor = 0.0;
  double outlier_floor_sigma = 3.0;
  int min_correspondences = 30;  // fewer: kFailed at the start, not converged later
  // Mesh of both range images: depth-discontinuity test (RangeImageOptions), with the break
  // length at least mesh_break_sigma x sigma so that range noise does not tear the mesh.
  RangeImageOptions mesh;
  double mesh_break_sigma = 6.0;
  // kPointToPlane: parent normals by PCA over a (2k+1)^2 window of grid neighbours.
  int normal_window = 2;

  Status Validate() const;
};

const char* EmMethodName(EmOptions::Method method);
// The method with kEm's residual spelled out: "EM (S, point-to-point)" or "EM (point-to-plane)".
std::string EmMethodName(const EmOptions& options);

struct EmResult {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  int iterations = 0;
  double rms_m = 0.0;       // last E-step: weighted RMS of |y - s| (of the point-to-plane residual when used)
  int correspondences = 0;  // sample pairs in the last E-step
  int vertices = 0;         // child vertices sampled (after subsampling)
  double overlap = 0.0;     // fraction of those whose t = 0 sample found the parent's surface
  bool converged = false;
  CameraFitReport parent_camera, child_camera;
};

// The bin weights P(s_ij) of S eq. 15 for offsets t_j (metres) and sigma (metres). They sum to 1.
std::vector<double> EmSampleWeights(const std::vector<double>& offsets_m, double sigma_m);

// Aligns child to parent (both organized scans in their own frames). Errors: invalid options or
// scans (kInvalidArgument), fewer than min_correspondences pairs at the initial pose (kFailed:
// the scans do not overlap there), cancel (kCancelled, checked per iteration).
Expected<EmResult> AlignEm(const Scan& parent, const Scan& child, Eigen::Isometry3d initial_parent_from_child,
                           const EmOptions& options, ProgressSink& progress, const CancelToken& cancel);

// The mesh options AlignEm(Scan, ...) builds both range images with: options.mesh with the
// break length raised to mesh_break_sigma x sigma_m.
RangeImageOptions EmMeshOptions(const EmOptions& options);

// Same, with the range-image projections already built (reuse across many pairs; build them with
// EmMeshOptions).
Expected<EmResult> AlignEm(const RangeImageProjection& parent, const RangeImageProjection& child,
                           Eigen::Isometry3d initial_parent_from_child, const EmOptions& options,
                           ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg
