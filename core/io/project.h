// The project file `*.scanreg.json`: which scans belong to a project (paths relative to the
// project file), their estimated and reference poses, scan-order overrides, link results and
// settings. Saved atomically; versioned.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "core/common/expected.h"
#include "core/io/georef_records.h"

namespace scanreg::io {

enum class LinkStatus { kOk, kWeak, kFailed };
const char* LinkStatusName(LinkStatus status);

// The evidence of one pairwise registration (child registered to parent). Stored in the project
// so that a report or the GUI can show it without re-running.
// A point the user picked in both scans of a link (manual alignment), each in its scan's own frame.
struct PickedPoint {
  Eigen::Vector3d parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d child = Eigen::Vector3d::Zero();
};

struct LinkRecord {
  std::string parent;  // scan names
  std::string child;
  std::string method;  // e.g. "epnp+keypoints"
  LinkStatus status = LinkStatus::kFailed;
  std::string reason;  // why weak / failed; empty when ok
  int matches = 0;            // SIFT matches
  int geometric_matches = 0;  // FPFH matches (issue 11, item 2)
  int reliable = 0;           // correspondences with reliable 3D points (SIFT) plus the FPFH ones
  int ransac_inliers = 0;
  int geometric_inliers = 0;  // of ransac_inliers, how many came from FPFH (the rest from SIFT)
  int consistent = 0;
  double rms_m = 0.0;
  double overlap = 0.0;   // fraction [0, 1]
  double conflict = 0.0;  // fraction of points in the other scan's free space on static surfaces [0, 1]
  double moving = 0.0;    // fraction in the other's free space on object-sized clusters: moving objects [0, 1]
  int iterations = 0;
  double seconds = 0.0;
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  bool loop_check = false;     // a redundant link that verified a loop of the tree (not chained)
  bool user_accepted = false;  // the user accepted a weak link
  bool user_rejected = false;  // the user rejected the link
  std::vector<PickedPoint> picked;  // the points the user picked (manual alignment); empty otherwise
};

// A pose as the project file holds it (16 numbers, row-major), and back; errors name `what`.
nlohmann::json PoseToJson(const Eigen::Isometry3d& pose);
Expected<Eigen::Isometry3d> PoseFromJson(const nlohmann::json& j, const std::string& what);
// One link as the project file holds it (also a pair job's result, pair_jobs.h), and back; errors
// name `where`.
nlohmann::json LinkToJson(const LinkRecord& link);
Expected<LinkRecord> LinkFromJson(const nlohmann::json& j, const std::string& where);

// How consistent the poses of the last refinement from current poses are, without ground truth
// (pipeline/verify_poses.h): the robust RMS of the point-to-plane residuals over every overlapping
// pair, at the start poses and as returned.
struct ConsistencyRecord {
  double start_rms_m = 0, result_rms_m = 0;
  double cutoff_m = 0;  // a sample meets the other surface within this
  int pairs = 0;
  bool multiview = false;  // the multi-view fine step's poses were taken
  bool refused = false;    // the result was less consistent than the start: the start poses were kept
};

struct ProjectScan {
  std::string name;            // unique within the project
  std::filesystem::path path;  // absolute while in memory; relative to the project on disk
  int index_in_file = 0;       // for multi-scan files (PTX)
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  bool registered = false;  // world_from_scan is a registration result (or the root)
  std::optional<Eigen::Isometry3d> reference_world_from_scan;
  std::optional<std::string> parent_override;  // scan-order override: register to this scan
  // From the last registration (optional in the file): the pose after the coarse step only
  // (W fig. 6 "after coarse") and why the scan could not be registered.
  std::optional<Eigen::Isometry3d> coarse_world_from_scan;
  std::string unregistered_reason;
  // The user placed the scan by hand (Registration → Edit scan pose): its pose carries no link
  // evidence; the report and the scan list say so. Cleared when a registration places the scan.
  bool manual_pose = false;
  // The pose was read from a file (a pose file given to `new --poses`, or the scan file's own
  // registered pose: PTX/E57 header) and is used as it is: `registered` is true, merge and export
  // accept it. Cleared when a registration re-estimates the scan (kept with --keep-imported).
  bool imported_pose = false;
  // The vertical in the scan's own frame as its file's pose gives it (the tilt compensator's pitch
  // and roll), when the file (or a pose file) carried a pose; levelled scans are levelled through
  // it (issue 15, item 3). Kept when a registration re-estimates the pose: it is the file's fact.
  std::optional<Eigen::Vector3d> file_up;
  // Not registered to the root, but registered to other scans that are not either: the name of the
  // root of that cluster (the scan itself for its root); empty when none. world_from_scan then holds
  // the cluster's own frame (the cluster root's pose), so one link to a registered scan places the
  // whole cluster (pipeline::ApplyPairResult). Cleared when the scan is registered.
  std::string cluster;
  // The last registration placed the scan but could not verify the pose (issue 33): a weak link no
  // loop confirms, or overlaps that disagree or leave a direction free. It is not registered (it
  // stays at its start pose, out of merge and export); unregistered_reason says why. Cleared when
  // the scan is registered or placed by hand.
  bool unverified = false;
  // From the last refinement from current poses (ConsistencyRecord): the median RMS of the residuals
  // of the scan's overlapping pairs at its start pose and at its result, and how well its overlaps
  // constrain its pose (1: every direction alike; near 0: one is free).
  std::optional<double> start_consistency_m, consistency_m, conditioning;
};

// Where a scan's pose comes from, for every front end and the report (one wording).
enum class PoseState { kUnregistered, kNotVerified, kRegistered, kImported, kManual };
PoseState ScanPoseState(const ProjectScan& scan);
const char* PoseStateName(PoseState state);  // "unregistered", "not verified", "registered", "imported", "manual pose"

struct Project {
  static constexpr int kSchemaVersion = 1;

  std::filesystem::path file;  // where it was loaded from / saved to; empty when new
  std::vector<ProjectScan> scans;
  std::vector<LinkRecord> links;
  std::optional<std::string> root;              // root scan of the scan order
  std::map<std::string, std::string> settings;  // option name -> value, as the user set them
  // Confusion matrix C(i, j) of the last registration (W §2 step 3) and the names of the scans of
  // its rows and columns; empty when the project has not been registered. Optional in the file.
  Eigen::MatrixXi confusion;
  std::optional<ConsistencyRecord> consistency;  // of the last registration, when it measured one
  std::vector<std::string> confusion_scans;
  // A digest of the file's bytes as last read or saved (0: none): SaveProject onto the same file
  // refuses when the file no longer has them — another run or an editor changed it meanwhile.
  std::uint64_t disk_digest = 0;
  // Georeferencing (issue 15): survey control, the targets in the scans, the last adjustment.
  std::vector<ControlPoint> control;
  std::vector<TargetRecord> targets;
  std::optional<GeorefRecord> georef;

  // Index of the scan with this name, or -1.
  int FindScan(const std::string& name) const;
  // The confusion matrix while it still describes the project's scans in order; nullptr when there
  // is none or scans were added, removed or reordered since (register again).
  const Eigen::MatrixXi* CurrentConfusion() const;
};

// Reads and checks a project file: schema version, unique scan names, every scan file present
// (an error names the missing file and the project), poses finite and rigid.
Expected<Project> LoadProject(const std::filesystem::path& path);

// Writes the project atomically (temp, fsync, rename); scan paths are stored relative to the
// project's folder. Does not touch the scan files. Onto project.file with a disk_digest: refuses
// (nothing written) when the file changed since it was read. *saved_digest: the new file's digest
// (keep it in project.disk_digest for the next save).
Status SaveProject(const Project& project, const std::filesystem::path& path, std::uint64_t* saved_digest = nullptr);

// FNV-1a, 64 bits, of the bytes.
std::uint64_t Digest(const std::string& bytes);

}  // namespace scanreg::io
