#include "core/pipeline/scale_defaults.h"

#include <algorithm>
#include <cstdio>
#include <memory>

#include "core/common/log.h"
#include "core/registration/data_scale.h"
#include "core/registration/geometric_features.h"
#include "core/registration/point_index.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

void SetIfUnset(double* value, double resolved) {
  if (*value == 0.0) *value = resolved;
}

bool AnyUnset(const RegisterOptions& o) {
  return o.range_sigma_m == 0 || o.overlap_distance_m == 0 || o.thresholds.max_rms_m == 0 ||
         o.thresholds.weak_rms_m == 0 || o.loop_tolerance_m == 0 || o.coarse.inlier_threshold_m == 0 ||
         o.coarse.ambiguity_distance_m == 0 || o.dense_icp.voxel_m == 0 ||
         o.dense_icp.max_correspondence_schedule_m.empty() || o.dense_icp.robust_scale_floor_m == 0 ||
         o.keypoint_icp.max_correspondence_m == 0 || o.reliability.max_range_std_m == 0 ||
         (UsesGeometric(o.features) && o.geometric.voxel_m == 0);
}

}  // namespace

ProjectScale MeasureProjectScale(const std::vector<const Scan*>& scans) {
  std::vector<DataScale> scales;
  for (const Scan* s : scans) scales.push_back(MeasureDataScale(*s));
  return MeasureProjectScale(scales);
}

ProjectScale MeasureProjectScale(const std::vector<DataScale>& scales) {
  std::vector<double> spacing, extent, noise, voxel;
  for (const DataScale& d : scales) {
    if (!d.ok()) continue;
    spacing.push_back(d.spacing_m);
    extent.push_back(d.extent_m);
    voxel.push_back(SuggestVoxel(d));
    if (d.noise_m > 0) noise.push_back(d.noise_m);
  }
  return {Median(spacing), Median(extent), Median(noise), Median(voxel)};
}

double DataOverlapDistance(const ProjectScale& scale) {
  return std::max({8.0 * scale.noise_m, 2.0 * scale.spacing_m, scale.extent_m / 100.0});
}

RegisterOptions WithLengths(RegisterOptions o, double noise_m, double overlap_distance_m) {
  SetIfUnset(&o.range_sigma_m, noise_m);
  SetIfUnset(&o.overlap_distance_m, overlap_distance_m);
  const double d = o.overlap_distance_m;
  SetIfUnset(&o.thresholds.max_rms_m, d);
  SetIfUnset(&o.thresholds.weak_rms_m, 0.4 * d);
  SetIfUnset(&o.loop_tolerance_m, d);
  SetIfUnset(&o.coarse.inlier_threshold_m, d);
  SetIfUnset(&o.coarse.ambiguity_distance_m, 5 * d);
  SetIfUnset(&o.dense_icp.voxel_m, d);
  if (o.dense_icp.max_correspondence_schedule_m.empty()) o.dense_icp.max_correspondence_schedule_m = {10 * d, 4 * d, 2 * d};
  SetIfUnset(&o.dense_icp.robust_scale_floor_m, 0.1 * d);
  SetIfUnset(&o.keypoint_icp.max_correspondence_m, 2 * d);
  SetIfUnset(&o.reliability.max_range_std_m, d);
  return o;
}

bool NeedsScale(const RegisterOptions& o) { return AnyUnset(o); }

Expected<RegisterOptions> ResolveLengths(const RegisterOptions& o, const std::vector<const Scan*>& scans,
                                         ProjectScale* measured) {
  if (!AnyUnset(o)) return o;
  std::vector<DataScale> scales;
  for (const Scan* s : scans) scales.push_back(MeasureDataScale(*s));
  return ResolveLengthsFromScales(o, scales, measured);
}

Expected<RegisterOptions> ResolveLengthsFromScales(const RegisterOptions& o, const std::vector<DataScale>& scales,
                                         ProjectScale* measured) {
  if (!AnyUnset(o)) return o;
  const ProjectScale scale = MeasureProjectScale(scales);
  if (measured) *measured = scale;
  if (!(scale.spacing_m > 0)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "the scans give no scale (too few valid points); set the range noise and the overlap distance");
  }
  // Noise-free data (a synthetic model) measures 0: then a tenth of the spacing stands in.
  const double noise = o.range_sigma_m > 0 ? o.range_sigma_m : std::max(scale.noise_m, 0.1 * scale.spacing_m);
  const double d = o.overlap_distance_m > 0 ? o.overlap_distance_m
                                            : DataOverlapDistance({scale.spacing_m, scale.extent_m, noise});
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "scale from the data: spacing %.3g m, extent %.3g m, noise %.3g m -> range noise %.3g m%s, "
                "overlap distance %.3g m%s",
                scale.spacing_m, scale.extent_m, scale.noise_m, noise, o.range_sigma_m > 0 ? " (set)" : "", d,
                o.overlap_distance_m > 0 ? " (set)" : "");
  LogInfo(buf);
  RegisterOptions out = WithLengths(o, noise, d);
  if (UsesGeometric(o.features) && o.geometric.voxel_m == 0) {
    out.geometric.voxel_m = scale.geometric_voxel_m;
    std::snprintf(buf, sizeof buf, "geometric features: voxel %.4g m (from the scans' spacing and extent)",
                  out.geometric.voxel_m);
    LogInfo(buf);
  }
  return out;
}

double StartDistance(const std::vector<const Scan*>& scans, double d, double extent_m) {
  const double reach = std::max(d, extent_m / 3.0);
  const int n = static_cast<int>(scans.size());
  std::vector<std::unique_ptr<PointIndex>> surface(n);
  std::vector<std::vector<Eigen::Vector3d>> probes(n);
  for (int i = 0; i < n; ++i) {
    const std::vector<Eigen::Vector3d> pts = ValidPoints(*scans[i]);
    surface[i] = std::make_unique<PointIndex>(ThinEvenly(VoxelDownsample(pts, 0.5 * d), 200000));
    for (const Eigen::Vector3d& p : ThinEvenly(pts, 1000)) probes[i].push_back(scans[i]->world_from_scan * p);
  }
  double out = d;
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d parent_from_world = scans[i]->world_from_scan.inverse();
    for (int j = 0; j < n; ++j) {
      if (i == j || probes[j].empty()) continue;
      std::vector<double> near;
      for (const Eigen::Vector3d& p : probes[j]) {
        double d2 = 0;
        if (surface[i]->Nearest(parent_from_world * p, reach, &d2) >= 0) near.push_back(std::sqrt(d2));
      }
      if (2 * near.size() < probes[j].size()) continue;
      out = std::max(out, std::min(reach, 2.0 * Median(near)));
    }
  }
  return out;
}

}  // namespace scanreg::pipeline
