#include "core/pipeline/georeference_project.h"

#include <algorithm>
#include <map>

#include "core/common/log.h"
#include "core/georef/checker_targets.h"
#include "core/georef/sphere_targets.h"
#include "core/pipeline/scan_store.h"

namespace scanreg::pipeline {

std::string ControlGrade(const io::ControlResidualRecord& row, double tolerance_m) {
  if (row.role == georef::ControlRoleName(georef::ControlRole::kNotFound) || !(tolerance_m > 0)) return "-";
  return georef::GradeName(georef::GradeOf(row.delta.norm(), tolerance_m));
}

Expected<georef::GeorefResult> GeoreferenceProject(io::Project& project, const std::vector<Scan>& scans,
                                                   const RegisterOptions& options, ProgressSink& progress,
                                                   const CancelToken& cancel) {
  ScanStore store(scans);
  return GeoreferenceProject(project, store, options, progress, cancel);
}

Expected<georef::GeorefResult> GeoreferenceProject(io::Project& project, ScanStore& scans,
                                                   const RegisterOptions& options, ProgressSink& progress,
                                                   const CancelToken& cancel) {
  project.georef.reset();
  if (scans.size() != static_cast<int>(project.scans.size())) {
    return MakeError(ErrorCode::kInvalidArgument, "georeferencing: the scans do not match the project's");
  }
  if (project.control.empty()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "georeferencing needs control points: import a control file (register --control FILE)");
  }
  // The registered scans take part; index maps between the project and the adjustment.
  std::vector<int> index_of(project.scans.size(), -1);
  std::vector<int> scan_of;
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < project.scans.size(); ++i) {
    if (!project.scans[i].registered) continue;
    index_of[i] = static_cast<int>(poses.size());
    scan_of.push_back(static_cast<int>(i));
    poses.push_back(project.scans[i].world_from_scan);
  }
  // Targets: the user's picked ones and names stay; spheres and checkerboards are found anew in
  // every registered scan.
  std::vector<io::TargetRecord> targets;
  for (const io::TargetRecord& t : project.targets)
    if (t.kind == "picked") targets.push_back(t);
  for (std::size_t k = 0; k < scan_of.size(); ++k) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "georeferencing cancelled");
    progress.Report(0.8 * k / scan_of.size(), "finding targets in " + project.scans[scan_of[k]].name);
    const Expected<std::shared_ptr<const Scan>> read = scans.Get(scan_of[k]);
    if (!read) return read.error();
    const Scan& scan = **read;
    auto spheres = georef::DetectSphereTargets(scan, options.spheres, cancel);
    if (!spheres) return spheres.error();
    std::vector<io::TargetRecord> found;
    for (const georef::DetectedSphere& s : *spheres) {
      io::TargetRecord t;
      t.kind = "sphere";
      t.center = s.center;
      t.sigma_m = s.sigma_m;
      t.rms_m = s.rms_m;
      t.points = s.points;
      found.push_back(t);
    }
    if (options.checkers.size_m > 0) {
      auto boards = georef::DetectCheckerTargets(scan, options.checkers, cancel);
      if (!boards) return boards.error();
      for (const georef::DetectedChecker& b : *boards) {
        io::TargetRecord t;
        t.kind = "checker";
        t.center = b.center;
        t.sigma_m = b.sigma_m;
        t.points = b.points;  // its quality is the centre's sigma (rms_m is a sphere's fit in metres)
        found.push_back(t);
      }
    }
    for (io::TargetRecord& t : found) {
      t.scan = scan.name;
      // The user picked this one: the pick stands for it (one observation, the user's name).
      const bool picked = std::any_of(targets.begin(), targets.end(), [&](const io::TargetRecord& p) {
        return p.kind == "picked" && p.scan == t.scan && (p.center - t.center).norm() < 0.05;
      });
      if (picked) continue;
      // A name the user gave a target of this scan before stays with it.
      for (const io::TargetRecord& old : project.targets)
        if (old.named_by_user && old.kind == t.kind && old.scan == t.scan && (old.center - t.center).norm() < 0.02)
          t.name = old.name, t.named_by_user = true;
      targets.push_back(t);
    }
  }
  std::vector<georef::TargetObservation> observations;
  std::vector<int> record_of;  // observation -> index into targets
  for (std::size_t r = 0; r < targets.size(); ++r) {
    const int p = project.FindScan(targets[r].scan);
    if (p < 0 || index_of[p] < 0) continue;  // the scan is not registered
    if (project.scans[p].manual_pose) continue;  // held as placed (below): its targets pull nothing
    georef::TargetObservation ob;
    ob.scan = index_of[p];
    ob.center = targets[r].center;
    ob.sigma_m = targets[r].sigma_m;
    if (targets[r].named_by_user) ob.name = targets[r].name;
    observations.push_back(ob);
    record_of.push_back(static_cast<int>(r));
  }
  std::vector<georef::ScanLink> links;
  for (const io::LinkRecord& l : project.links) {
    if (l.status == io::LinkStatus::kFailed || l.user_rejected) continue;
    const int a = project.FindScan(l.parent), b = project.FindScan(l.child);
    if (a < 0 || b < 0 || index_of[a] < 0 || index_of[b] < 0) continue;
    if (project.scans[b].manual_pose) continue;  // the hand placement overrides that link
    links.push_back({index_of[a], index_of[b], l.parent_from_child});
  }
  progress.Report(0.85, "adjusting onto control");
  // A scan the user placed by hand keeps that placement relative to the others: it moves with the
  // project into the control frame and nothing else.
  std::vector<bool> held;
  std::vector<Eigen::Vector3d> up;  // levelled scans: the file's vertical where it gave one
  for (int p : scan_of) {
    held.push_back(project.scans[p].manual_pose);
    up.push_back(project.scans[p].file_up.value_or(Eigen::Vector3d::UnitZ()));
  }
  auto result = georef::Georeference(poses, links, observations, project.control, options.georef, cancel, held, up);
  if (!result) {
    project.targets = targets;  // what was found is worth showing even when it cannot place the project
    return result.error();
  }
  // Poses: the control frame. Coarse poses (in the registration's frame) move with the root.
  const Eigen::Isometry3d moved = result->world_from_scan[0] * poses[0].inverse();
  for (std::size_t k = 0; k < scan_of.size(); ++k) {
    io::ProjectScan& s = project.scans[scan_of[k]];
    s.world_from_scan = result->world_from_scan[k];
    if (s.coarse_world_from_scan) s.coarse_world_from_scan = moved * *s.coarse_world_from_scan;
  }
  for (io::ProjectScan& s : project.scans)  // unregistered scans' cluster frames move with the project
    if (!s.registered && !s.cluster.empty()) s.world_from_scan = moved * s.world_from_scan;
  for (std::size_t j = 0; j < observations.size(); ++j) {
    io::TargetRecord& t = targets[record_of[j]];
    t.name = result->observation_target[j];
    t.residual_m = result->observation_residual_m[j];
  }
  project.targets = std::move(targets);
  io::GeorefRecord record;
  record.rms_m = result->rms_m;
  record.used = result->used;
  record.targets = result->targets;
  record.tolerance_m = options.georef.tolerance_m;
  for (const georef::ControlResidual& c : result->control) {
    io::ControlResidualRecord row;
    row.name = c.name;
    row.role = georef::ControlRoleName(c.role);
    row.delta = c.delta;
    row.leave_one_out_m = c.leave_one_out_m;
    row.observations = c.observations;
    if (c.role == georef::ControlRole::kBlunder)
      LogWarning("control point '" + c.name + "' is left out: " + std::to_string(c.residual_m() * 1000).substr(0, 6) +
                 " mm from where the other control points place its target (a blunder? check its coordinates)");
    record.control.push_back(row);
  }
  project.georef = std::move(record);
  progress.Report(1.0, "georeferenced");
  return result;
}

}  // namespace scanreg::pipeline
