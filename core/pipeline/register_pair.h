// Registering one child scan to its parent from their feature matches: reliable 3D points,
// coarse (EPnP or 3D RANSAC), consistency filter, fine (keypoint or dense ICP), evidence and
// status. The unit of work of the project registration and of the GUI's pair panel.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/features/matching.h"
#include "core/features/sift.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include "core/registration/geometric_features.h"
#include "core/registration/icp.h"
#include "core/registration/plan_view.h"
#include "core/registration/ray_free_space.h"

namespace scanreg::pipeline {

class ScanStore;  // scan_store.h

// A scan with what the registration derives from it once: all its pairs need, except the free-space
// test and EM fine alignment, which read the full scan (Full()).
struct PreparedScan {
  std::string name;
  // The full scan: the caller's (it outlives this), or else scan `index` of `store` (read again when
  // the store dropped it under its memory budget).
  const Scan* scan = nullptr;
  ScanStore* store = nullptr;
  int index = -1;
  ScanFeatures features;        // SIFT (empty when not used)
  std::vector<Eigen::Vector3f> keypoint_points;  // per SIFT keypoint: its reliable 3D point (W §2 step 5), NaN if none
  double angular_step = 0.0;    // the grid's angular spacing (radians; 0 when unknown)
  GeometricFeatures geometric;  // FPFH (empty when not used)
  PlanView plan;                // walls seen from above (levelled scans with geometric features)
  bool panoramic = false;       // a full-circle grid from its file: a tripod station that sees all round
  double median_range_m = 0.0;  // of the samples, from the scanner
  // Free space seen along the scan's per-point rays (a cloud with sensor positions and no one
  // viewpoint: ray_free_space.h), in cubes of the overlap distance; null otherwise.
  std::shared_ptr<const RayFreeSpace> rays;
  // Valid points voxel-downsampled at the dense ICP voxel, scanner frame, in single precision (kept
  // for the whole run: 12 bytes a sample; ToDouble for use).
  std::vector<Eigen::Vector3f> samples;
  DenseIcpOptions surface_options;  // how Surface() prepares them (normals)
  // The samples prepared as a dense ICP parent and for point-to-surface distances (k-d tree and
  // normals, ~75 bytes a sample): built when first asked for, then kept by the store under its
  // memory budget, or else for the life of this scan (HoldScan). Null without samples.
  std::shared_ptr<const IcpSurface> Surface() const;
  struct SurfaceMemo {
    std::once_flag once;
    std::shared_ptr<const IcpSurface> surface;
  };
  std::shared_ptr<SurfaceMemo> memo;  // set by HoldScan

  // The full scan; an error when the store cannot read it again.
  Expected<std::shared_ptr<const Scan>> Full() const;
};

// Sets name, scan and angular step from a scan the caller keeps (and forgets any surface).
void HoldScan(const Scan& scan, PreparedScan* prepared);

// The free space along the scan's per-point rays (PreparedScan::rays) in cubes of `evidence_m` (the
// distance EvaluateAlignment is asked with: half its margin), for a scan with sensor positions and
// no grid viewpoint; none otherwise.
void PrepareRays(const Scan& scan, double evidence_m, PreparedScan* prepared);

// Features are detected by the caller; this holds the scan (HoldScan) and fills the keypoints' 3D
// points, the samples, the plan view and the rays (PrepareRays).
void PrepareScan(const Scan& scan, const RegisterOptions& options, PreparedScan* prepared);

struct PairResult {
  io::LinkRecord link;  // evidence, status, reason, parent_from_child (after fine)
  Eigen::Isometry3d coarse_parent_from_child = Eigen::Isometry3d::Identity();
  bool coarse_ok = false;
  std::vector<int> coarse_inlier_matches;  // indices into `matches` of the coarse RANSAC inliers, ascending
  // Evidence too weak to chain on its own (a plan-view pose with object-sized conflicts): the link
  // is failed unless a loop through another scan closes on it (tree_walk.h).
  bool needs_loop = false;
  // Evidence against the pose (a weak link with static free-space conflicts): the same, but only
  // when the child has another neighbour to close a loop through — a lone pair stays weak.
  bool needs_loop_if_checkable = false;
  // The pose puts both scanners on one spot (SameSpot): the two scans look alike from there.
  bool same_spot = false;
  // The pose rests on the surfaces alone (a plan-view pose that too few correspondences confirm).
  bool surfaces_only = false;
  double violation_rate = 0.0;  // the pose's free-space violation rate (AlignmentEvidence::ViolationRate)
  // The pose's support is near the chance model's floor (few consistent correspondences, or
  // ambiguous features): its child is "registered" only when a loop through another scan closes on
  // it (tree_walk.h; issue 33: "registered" means verified), else placed but not verified.
  bool weak_support = false;
  // Set by the tree walk: failed only because no loop confirmed it when it was a tree link (its
  // other scans then hung below its child). It still serves as a check that needs a loop itself,
  // whatever made it need one (its evidence, or a twin: tree_walk.cc).
  bool unconfirmed = false;
  bool NeedsLoop() const { return needs_loop || needs_loop_if_checkable || unconfirmed; }
};

// matches: parent's SIFT descriptors (query) matched in the child (train); geometric: FPFH matches
// (MatchGeometric(parent.geometric, child.geometric)). Both feed one coarse estimator, levelled
// (4-DoF) when both scans are (GeometricFeatures::levelled) and the coarse method is 3D.
PairResult RegisterPair(const PreparedScan& parent, const PreparedScan& child, const std::vector<FeatureMatch>& matches,
                        const std::vector<GeometricMatch>& geometric, const RegisterOptions& options,
                        const CancelToken& cancel);

// Link weights beyond SIFT (issue 11): the support of the FPFH matches alone beyond chance (a short
// RANSAC; 0 when it does not pass the chance test) and, for levelled scans, the plan-view
// correlation of the best hypothesis above that of unrelated scans (at least 1: every levelled pair
// stays a candidate link).
int GeometricWeight(const PreparedScan& parent, const PreparedScan& child, const std::vector<GeometricMatch>& geometric,
                    const RegisterOptions& options);

// Overlap and RMS (point-to-plane) of the child's samples against the parent's, and free-space
// conflicts, at a pose: the evidence shared by every method.
struct AlignmentEvidence {
  double overlap = 0.0;   // fraction of child samples with a parent sample within max_distance_m
  double rms_m = 0.0;     // RMS distance of those samples
  double conflict = 0.0;  // free-space violations on static surfaces, the larger of both directions (visibility.h)
  double moving = 0.0;    // free-space violations in object-sized clusters (moving objects), the larger of both
  int violations = 0;     // every free-space violation, static or object-sized, both directions (samples)
  int tested = 0;         // samples tested for them, both directions
  std::string unavailable;  // why the free-space test could not run (a full scan could not be read again)
  double ViolationRate() const { return tested ? double(violations) / double(tested) : 0.0; }
};

// Free space tells apart poses that the overlap cannot (issue 38): a pose that fits a repeated
// corridor or a symmetric room leaves what differs there — the corridor's far ends, the furniture
// seen through the doors — where the other scanner saw through, in clusters small enough to pass
// for moving objects; the true pose leaves almost nothing. Measured on office floors' corridor
// pairs: 4-24 of ~47,000 samples at the truth, 85-1475 at the poses turned 180° or slid by rooms,
// whose overlap was up to twice the truth's. A pose with violation rate `rate_other` is refuted
// against one with `rate_kept` when it is at least 3 times as high and kClearViolationRate more:
// moving traffic, which both poses see, does not decide.
constexpr double kClearViolationRate = 0.001;
bool FreeSpaceRefutes(double rate_kept, double rate_other);
AlignmentEvidence EvaluateAlignment(const PreparedScan& parent, const PreparedScan& child,
                                    const Eigen::Isometry3d& parent_from_child, double max_distance_m);

// The surface checks of a link's evidence (link.overlap, link.conflict, link.rms_m) against the
// thresholds, shared by every way of registering a pair: the reason the link fails, or is weak;
// empty when the surfaces give no cause.
std::string SurfaceFailure(const LinkThresholds& t, const io::LinkRecord& link);
std::string SurfaceWeakness(const LinkThresholds& t, const io::LinkRecord& link);

}  // namespace scanreg::pipeline
