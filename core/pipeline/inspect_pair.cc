#include "core/pipeline/inspect_pair.h"

#include "core/features/confusion.h"
#include "core/features/feature_cache.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/scale_defaults.h"
#include "core/registration/point_index.h"
#include "core/registration/surface_distance.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

Error Cancelled() { return MakeError(ErrorCode::kCancelled, "pair registration cancelled"); }

// Up to max_count valid points of the scan, evenly thinned, mapped by `to_frame`.
std::vector<Eigen::Vector3d> OverlayPoints(const Scan& scan, const Eigen::Isometry3d& to_frame, int max_count) {
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) pts.push_back(to_frame * scan.points[i].cast<double>());
  return ThinEvenly(std::move(pts), max_count);
}

// Distances of `points` to the surface sampled by `surface`; the points are kept as floats.
void Overlay(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& surface,
             double max_distance_m, std::vector<Eigen::Vector3f>* out, std::vector<float>* distances) {
  const std::vector<double> d = PointToSurfaceDistances(PointIndex(surface), surface, points, max_distance_m);
  out->reserve(points.size());
  distances->reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    out->push_back(points[i].cast<float>());
    distances->push_back(static_cast<float>(d[i]));
  }
}

}  // namespace

Expected<PairInspection> InspectPair(const Scan& parent, const Scan& child, const RegisterOptions& raw_options,
                                     const InspectOptions& inspect, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = raw_options.Validate(); !s) return s.error();
  for (const Scan* s : {&parent, &child}) {
    if (s->CountValid() == 0) {
      return MakeError(ErrorCode::kInvalidArgument, "scan '" + s->name + "' has no valid point; remove it");
    }
  }
  const Expected<RegisterOptions> resolved = ResolveLengths(raw_options, {&parent, &child});
  if (!resolved) return resolved.error();
  const RegisterOptions& options = *resolved;
  PairInspection out;
  PreparedScan prepared[2];
  const Scan* scans[2] = {&parent, &child};
  for (int k = 0; k < 2; ++k) {
    if (cancel.IsCancelled()) return Cancelled();
    progress.Report(0.25 * k, "features of " + scans[k]->name);
    bool cached = false;
    if (Status s = PrepareScanFeatures(*scans[k], options, &prepared[k], &cached, cancel); !s) return s.error();
  }
  progress.Report(0.5, "matching " + child.name + " with " + parent.name);
  SubProgress match_progress(progress, 0.5, 0.6);
  Expected<MatchTable> table =
      MatchAllPairs({prepared[0].features, prepared[1].features}, options.match, match_progress, cancel);
  if (!table) return table.error();
  out.matches = BothWays(*table, 0, 1);

  progress.Report(0.6, "registering " + child.name + " to " + parent.name);
  out.result = RegisterPair(prepared[0], prepared[1], out.matches,
                            MatchGeometric(prepared[0].geometric, prepared[1].geometric), options, cancel);
  if (cancel.IsCancelled()) return Cancelled();
  out.coarse_inlier.assign(out.matches.size(), 0);
  for (int m : out.result.coarse_inlier_matches) out.coarse_inlier[m] = 1;

  if (parent.reference_world_from_scan && child.reference_world_from_scan) {
    const Eigen::Isometry3d ref = parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan;
    if (out.result.link.status != io::LinkStatus::kFailed || out.result.link.ransac_inliers > 0) {
      out.reference_error = ComparePoses(out.result.link.parent_from_child, ref);
      out.coarse_reference_error = ComparePoses(out.result.coarse_parent_from_child, ref);
    }
  }

  if (inspect.overlay) {
    progress.Report(0.9, "distances between " + parent.name + " and " + child.name);
    const Eigen::Isometry3d& pfc = out.result.link.parent_from_child;
    const double max_d = options.overlap_distance_m;
    std::vector<Eigen::Vector3d> child_surface;
    child_surface.reserve(prepared[1].samples.size());
    for (const Eigen::Vector3f& p : prepared[1].samples) child_surface.push_back(pfc * p.cast<double>());
    Overlay(OverlayPoints(parent, Eigen::Isometry3d::Identity(), inspect.overlay_points), child_surface, max_d,
            &out.parent_points, &out.parent_distance_m);
    if (cancel.IsCancelled()) return Cancelled();
    Overlay(OverlayPoints(child, pfc, inspect.overlay_points), ToDouble(prepared[0].samples), max_d, &out.child_points,
            &out.child_distance_m);
  }
  out.parent_features = std::move(prepared[0].features);
  out.child_features = std::move(prepared[1].features);
  progress.Report(1.0, "pair done");
  return out;
}

}  // namespace scanreg::pipeline
