// Options of the automatic registration (W §2 with the alternatives measured in issue 3).
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/features/matching.h"
#include "core/features/sift.h"
#include "core/georef/georeference.h"
#include "core/georef/checker_targets.h"
#include "core/georef/sphere_targets.h"
#include "core/registration/coarse.h"
#include "core/registration/geometric_features.h"
#include "core/registration/icp.h"
#include "core/registration/reliable_points.h"

namespace scanreg::pipeline {

enum class FineMethod {
  kKeypoints,      // W §2 step 9: ICP on the consistent keypoint 3D points
  kDense,          // point-to-plane ICP on voxel-downsampled full scans, robust kernel
  kEm,             // S §3.2 on the range images (point-to-plane M-step, core/registration/em_align.h)
  kProjectiveIcp,  // S's baseline [15]: correspondences along the parent's lines of sight
};
// Where the correspondences of the coarse step come from (issue 11, item 2): W's SIFT on the
// reflectance panorama, FPFH on the geometry (scans without reflectance, unorganized clouds,
// low resolution), or both into one estimator.
enum class FeatureSources { kSift, kGeometric, kBoth };
const char* FeatureSourcesName(FeatureSources sources);
const std::vector<FeatureSources>& AllFeatureSources();
inline bool UsesSift(FeatureSources s) { return s != FeatureSources::kGeometric; }
inline bool UsesGeometric(FeatureSources s) { return s != FeatureSources::kSift; }

const char* FineMethodName(FineMethod method);
const char* CoarseMethodName(CoarseMethod method);
// Every method, in the order the GUI lists them (add new methods here too).
const std::vector<FineMethod>& AllFineMethods();
const std::vector<CoarseMethod>& AllCoarseMethods();

// When a link is ok, weak or failed. A failed link is not chained; a weak one is chained but
// reported (the user may accept or reject it).
struct LinkThresholds {
  // Fewer consistent correspondences than the coarse step's computed requirement
  // (CoarseOptions::max_false_pose_probability): failed; fewer than this: weak.
  int weak_inliers = 15;
  double min_overlap = 0.05;    // fraction of the child's samples near the parent; less: failed
  double weak_overlap = 0.15;   // less: weak
  // Lengths: 0 = from the data (scale_defaults.h): the overlap distance d and 0.4 d (street: 0.10, 0.04 m).
  double max_rms_m = 0.0;   // RMS of the overlap distances above this: failed
  double weak_rms_m = 0.0;  // above this: weak
  double max_conflict = 0.05;   // free-space violations (visibility.h) above this: failed
  double weak_conflict = 0.02;  // above this: weak
  // A plan-view pose (no feature support) above this: weak, a loop confirms it. Its surfaces are its
  // only evidence, and the truth leaves almost nothing in the other scanner's free space (measured
  // on 60 true plan-view links of streets and offices at 1000 x 250 and 3000 x 750: under 0.05 %;
  // an office's rooms at 3000 x 750 fitted 20-31 m and 90° off with 1.7-1.8 %).
  double plan_view_conflict = 0.005;
  Status Validate() const;
};

// Every length below left at 0 is taken from the scans when a registration starts
// (core/pipeline/scale_defaults.h): the range noise, the overlap distance d, and the others as
// multiples of d (coarse inlier threshold d and ambiguity 5 d, dense ICP voxel d and schedule
// 10/4/2 d, keypoint ICP 2 d, W's t_std d, loop tolerance d, RMS thresholds d and 0.4 d).
struct RegisterOptions {
  RegisterOptions();  // the sub-options' lengths unset (0)
  FeatureSources features = FeatureSources::kBoth;
  SiftOptions sift;
  GeometricOptions geometric;  // voxel_m 0: the median of SuggestVoxel over the project's scans (scale_defaults.h)
  MatchOptions match;              // ratio t_des = 0.66 (W)
  ReliabilityOptions reliability;  // t_std = 0.1 m (W)
  CoarseOptions coarse;            // method: kEpnp (W) or k3d
  FineMethod fine = FineMethod::kDense;
  IcpOptions keypoint_icp;
  DenseIcpOptions dense_icp;
  LinkThresholds thresholds;
  double range_sigma_m = 0.0;       // scanner range noise; sets the consistency threshold
  double overlap_distance_m = 0.0;  // a child sample within this of the parent surface overlaps
  // Loop check (beyond W): each scan is also registered to its best other neighbour; a loop that
  // does not close within these tolerances fails both links (wrong links on repeated façades).
  bool verify_loops = true;
  bool verify_all_links = false;  // false: only weak links are checked (global registration checks all)
  int min_check_matches = 20;     // a neighbour needs this many matches to serve as a check
  double loop_tolerance_m = 0.0;
  double loop_tolerance_rad = 0.5 * M_PI / 180.0;
  // Global registration (issue 4): a pose graph over every accepted link (tree + loop checks),
  // Cauchy kernel, root fixed; it implies a loop check of every link (the graph's extra links).
  // On by default: measured (scanreg-bench --section global) never worse than the tree: 11 simulated
  // stations 1.86 -> 1.82 mm worst; one tree link off by 5 cm / 0.3 deg: 117 -> 13 mm; one wrong
  // extra link (1 m, 5 deg): down-weighted, 1.863 -> 1.866 mm; the 10 bunny scans with --coarse
  // none: 0.91 -> 0.57 mm (0.55 before its links were loop-checked). Costs about one more pair
  // registration per scan.
  bool global = true;
  // Refinement from the current poses (issue 33): after the pose graph, the multi-view fine step
  // (all scans at once over every overlapping pair, core/registration/multiview.h) — its poses are
  // taken when they are more consistent than the graph's (core/pipeline/verify_poses.h).
  bool multiview = true;
  // --coarse none: no features; refine from the scans' current world_from_scan (a .conf file, a
  // previous run). Links: the pairs whose surfaces overlap at those poses (core/pipeline/refine_project.h;
  // both paths run the one driver of core/pipeline/registration_driver.h).
  bool from_current_poses = false;
  // Scans whose pose was imported (io::ProjectScan::imported_pose) keep it: they anchor the
  // registration and the other scans are placed relative to them. Otherwise imported poses are
  // re-estimated (with from_current_poses, refined from where they are).
  bool keep_imported = false;
  // A run's scope, not a setting (`register --only-unregistered`, the GUI's Register unregistered
  // scans and parent overrides): only these scans are placed; every other registered scan keeps its
  // pose and its links and anchors the run. Empty: every scan.
  std::vector<std::string> only_scans;
  // Candidate pairs (issue 13, item 3): each scan's features are matched only with its `candidates`
  // most similar scans by a global descriptor (VLAD over SIFT and FPFH, core/pipeline/candidate_pairs.h),
  // its neighbours in capture order and the user's pairs; 0 matches every pair (W). Pairs left out
  // show as skipped in the confusion matrix; the driver matches one on demand when it needs it.
  int candidates = 10;
  // The global step's extra links (issue 13): besides the tree and its loop checks, each scan's
  // `global_partners` largest overlaps at the registered poses are refined and join the pose graph;
  // 0 (the default) refines every pair overlapping by thresholds.weak_overlap. Fewer is faster on big
  // projects (each pair is a dense ICP) and less accurate: on the 28-station city (1000x250) 4 refines
  // 61 of 131 pairs, the pairs stage takes 92 s instead of 114 s, and the worst scan is 6.9 mm off
  // instead of 4.0 mm (median 1.9 vs 1.2 mm).
  int global_partners = 0;
  std::optional<std::string> root;          // scan name; default: tail of the heaviest edge
  std::filesystem::path feature_cache_dir;  // empty: no cache
  // Georeferencing (issue 15), when the project has control points: the sphere and checkerboard
  // targets sought in every registered scan (checkers.size_m 0: no checkerboards) and the
  // adjustment onto control (core/pipeline/georeference_project.h).
  georef::SphereTargetOptions spheres;
  georef::CheckerTargetOptions checkers;
  georef::GeorefOptions georef;
  Status Validate() const;
};

}  // namespace scanreg::pipeline
