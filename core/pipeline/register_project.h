// Automatic registration of a whole project (W §2): features, confusion matrix, scan order,
// pairwise registration along the tree with failed links replaced by the next-best edge, and
// world poses chained from the root. The CLI's `register` and the GUI both run this.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/features/confusion.h"
#include "core/geometry/scan.h"
#include "core/geometry/transform.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_pair.h"

namespace scanreg::pipeline {

struct ScanRegistration {
  std::string name;
  bool registered = false;
  std::string reason;  // why not registered
  int parent = -1;     // index of the scan it was registered to; -1 for the root
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  // Not registered, but in a cluster of scans registered to each other (issue 14): the index of
  // the cluster's root scan and the pose in its frame; -1 when none.
  int cluster = -1;
  Eigen::Isometry3d cluster_from_scan = Eigen::Isometry3d::Identity();
  // Not registered: the tree placed it, but by a weak link that no loop confirmed (or through such
  // a scan), so its pose is not verified (issue 33); the reason says which link.
  bool unverified = false;
  bool has_coarse = false;  // world pose from the coarse links only (W fig. 6 "after coarse")
  Eigen::Isometry3d coarse_world_from_scan = Eigen::Isometry3d::Identity();
  // The scan's share of the project's consistency (verify_poses.h) at the start poses and at its
  // result, and how well its overlaps constrain its pose (1: every direction alike; near 0: one is
  // free); negative when not measured.
  double start_consistency_m = -1, consistency_m = -1, conditioning = -1;
};

struct ProjectRegistration {
  Eigen::MatrixXi confusion;  // C(i, j), W §2 step 3
  int root = -1;
  std::vector<ScanRegistration> scans;
  std::vector<io::LinkRecord> links;  // tree links first (in placement order), then failed attempts
  // Global registration, when run: each accepted link's residual before and after, and its weight.
  struct GlobalLink {
    std::string parent, child;
    double translation_before_m = 0, rotation_before_rad = 0, translation_after_m = 0, rotation_after_rad = 0;
    double weight = 1.0;
    bool down_weighted = false;
  };
  std::vector<GlobalLink> global_links;
  std::optional<io::ConsistencyRecord> consistency;  // refinement from current poses (verify_poses.h)
  // Georeferencing (issue 15), run when the project has control points: whether it placed the
  // project in the control frame, and why not. The residuals are in io::Project::georef.
  bool georeferenced = false;
  std::string georef_error;
  int features_from_cache = 0;
  // Candidate pairs (options.candidates): the unordered pairs whose features were matched up front,
  // of all n (n - 1) / 2; the others are kSkippedPair in the confusion matrix.
  int pairs_matched = 0, pairs_possible = 0;
  // The pairs found overlapping at the registered poses and refined from them for the global step
  // (parent, child), whether their features were matched or not.
  std::vector<std::pair<int, int>> pairs_by_overlap;
  // register --collect (pair_jobs.h): the pair registrations taken from the jobs' results.
  int pairs_from_jobs = 0;
  double seconds_features = 0, seconds_matching = 0, seconds_pairs = 0, seconds_total = 0;
};

// The matches of a pair in both directions (parent's features as query), without duplicates:
// the ratio test is asymmetric, so the union holds more true correspondences than either side.

// SIFT (or the feature cache) and FPFH as options.features asks (the geometric voxel resolved by
// ResolveLengths, scale_defaults.h),
// then PrepareScan. *cached: the SIFT features came from the cache.
Status PrepareScanFeatures(const Scan& scan, const RegisterOptions& options, PreparedScan* prepared, bool* cached,
                           const CancelToken& cancel);

std::vector<FeatureMatch> BothWays(const MatchTable& table, int parent, int child);

// The user's decisions a registration keeps, by scan name.
struct UserChoices {
  std::vector<std::optional<std::string>> parent_override;    // one per scan (empty: none)
  std::vector<std::pair<std::string, std::string>> rejected;  // (parent, child) links the user rejected
  // Links the user made or accepted (picked points, a pair result used, a weak link accepted): used
  // as they are, never re-registered or failed by a loop check; the link's parent becomes the
  // child's parent unless the child has another parent override (then the override wins).
  std::vector<io::LinkRecord> kept;
};

// The user's choices by scan index: root, parent overrides, rejected links and kept links (links
// and kept links naming a scan not in the list are dropped; a kept link to the root is dropped:
// the root keeps its pose). Errors name an unknown root or parent override, or a cycle.
struct ScanOrderChoices {
  std::optional<int> root;
  std::vector<std::optional<int>> overrides;  // one per scan
  std::vector<std::pair<int, int>> excluded;  // (parent, child)
  std::map<std::pair<int, int>, io::LinkRecord> kept;  // (parent, child)
};
Expected<ScanOrderChoices> ResolveScanOrderChoices(const std::vector<Scan>& scans, const UserChoices& user,
                                                   const std::optional<std::string>& root);

// scans: with their current world_from_scan (the root keeps its own). exchange: pair
// registrations planned as jobs, or collected from them (pair_jobs.h). From a store (scan_store.h)
// the scans are read when needed, within its memory budget: the same result as from memory.
struct PairExchange;
class ScanStore;
Expected<ProjectRegistration> RegisterScans(const std::vector<Scan>& scans, const UserChoices& user,
                                            const RegisterOptions& options, ProgressSink& progress,
                                            const CancelToken& cancel, const PairExchange* exchange = nullptr);
Expected<ProjectRegistration> RegisterScans(ScanStore& scans, const UserChoices& user, const RegisterOptions& options,
                                            ProgressSink& progress, const CancelToken& cancel,
                                            const PairExchange* exchange = nullptr);

// Writes the result into the project: poses, registered flags, links and root.
void ApplyRegistration(const ProjectRegistration& result, io::Project& project);

// Registers the project's (already loaded) scans with the project's root, parent overrides and
// rejected links, and writes the result into the project (not saved). When the project has control
// points it is then georeferenced (GeoreferenceProject); a georeferencing failure leaves the
// registration in the root scan's frame and is reported in georef_error, not as an error.
// With exchange->planned (register --plan) the project is left as it was.
Expected<ProjectRegistration> RegisterProjectScans(io::Project& project, const std::vector<Scan>& scans,
                                                   RegisterOptions options, ProgressSink& progress,
                                                   const CancelToken& cancel, const PairExchange* exchange = nullptr);
Expected<ProjectRegistration> RegisterProjectScans(io::Project& project, ScanStore& scans, RegisterOptions options,
                                                   ProgressSink& progress, const CancelToken& cancel,
                                                   const PairExchange* exchange = nullptr);

// options.keep_imported: the project's imported poses are anchors. Each other registered scan is
// placed from its nearest anchor up the scan order (its pose relative to that anchor as registered);
// the anchors keep their poses. RegisterProjectScans calls this.
void KeepImportedPoses(const io::Project& project, const std::vector<bool>& anchor, ProjectRegistration* result);

// Error of a registered pose against the reference, both taken relative to the root (so the
// datum of the registration does not matter).
struct ReferenceError {
  bool available = false;
  double position_m = 0, angle_rad = 0;  // after fine
  bool has_coarse = false;
  double coarse_position_m = 0, coarse_angle_rad = 0;  // after coarse
};
std::vector<ReferenceError> ReferenceErrors(const ProjectRegistration& result, const std::vector<Scan>& scans);
// The same for a saved project (its poses, coarse poses and reference poses); none without a root.
std::vector<ReferenceError> ReferenceErrors(const io::Project& project);
// Error of a link's parent_from_child against the reference poses of its two scans (found by name
// in `scans`); none when either scan or its reference pose is missing.
std::optional<PoseError> LinkReferenceError(const io::LinkRecord& link, const std::vector<Scan>& scans);

}  // namespace scanreg::pipeline
