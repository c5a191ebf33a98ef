// Lists section (issue 34): a cloud merged from several stations — no single range image — through
// import, registration and merge. The merged cloud (world coordinates, shuffled, binary PLY of
// doubles as other programs export it) holds every valid point of 11 stations at 3000 x 750 (about
// 21 M points; 2 at 1000 x 250 with --quick); per step: time, points kept, peak memory of the step.
// Registration: the cloud with two tripod stations of the same street between its stations, default
// options; errors against the truth. Merge: TSDF at 5 cm of the registered scans (the cloud as discs,
// every point: range_patches.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "core/common/atomic_file.h"
#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {
namespace {

const char* kSection = "lists";

// x y z (double) intensity (float), binary little endian, as CloudCompare or PDAL export a cloud.
Status WriteMergedPly(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points,
                      const std::vector<float>& intensity) {
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  std::string chunk = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(points.size()) +
                      "\nproperty double x\nproperty double y\nproperty double z\nproperty float intensity\nend_header\n";
  for (std::size_t k = 0; k < points.size(); ++k) {
    chunk.append(reinterpret_cast<const char*>(points[k].data()), 24);
    chunk.append(reinterpret_cast<const char*>(&intensity[k]), 4);
    if (chunk.size() > (1 << 22)) {
      if (Status s = file.Write(chunk); !s) return s;
      chunk.clear();
    }
  }
  if (Status s = file.Write(chunk); !s) return s;
  return file.Commit();
}

}  // namespace

void RunListsBench(Table& table, bool quick) {
  NullProgress progress;
  CancelToken cancel;
  SimulatedProjectOptions o;
  o.stations = quick ? 4 : 13;  // every station merged but two kept as tripod scans
  o.spacing_m = 8;
  o.scanner.cols = quick ? 1000 : 3000;
  o.scanner.rows = quick ? 250 : 750;
  o.seed = o.scanner.seed = o.scene.seed = 34;
  Expected<std::vector<Scan>> sim = SimulateProject(o, progress, cancel);
  if (!sim) return table.Add({kSection, "simulate", 0.0, "", "failed: " + sim.error().ToString()});
  std::vector<Scan> tripods;
  std::vector<Eigen::Vector3d> merged;
  std::vector<float> intensity;
  const std::size_t tripod_a = 1, tripod_b = quick ? 3 : 5;
  for (std::size_t i = 0; i < sim->size(); ++i) {
    Scan& s = (*sim)[i];
    if (i == tripod_a || i == tripod_b) {
      tripods.push_back(std::move(s));
      continue;
    }
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (!s.valid[k]) continue;
      merged.push_back(*s.reference_world_from_scan * s.points[k].cast<double>());
      intensity.push_back(s.reflectance[k]);
    }
    s = Scan();  // only the merged copy stays
  }
  const int merged_stations = static_cast<int>(sim->size()) - 2;
  sim->clear();
  std::vector<std::size_t> order(merged.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), std::mt19937(34));
  {
    std::vector<Eigen::Vector3d> p(merged.size());
    std::vector<float> r(merged.size());
    for (std::size_t k = 0; k < order.size(); ++k) p[k] = merged[order[k]], r[k] = intensity[order[k]];
    merged.swap(p), intensity.swap(r);
  }
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "scanreg_bench_merged_cloud.ply";
  if (Status s = WriteMergedPly(file, merged, intensity); !s)
    return table.Add({kSection, "write", 0.0, "", "failed: " + s.error().ToString()});
  const std::size_t n = merged.size();
  merged = {}, intensity = {};
  const std::string what = Fmt("cloud of %.0f stations ", merged_stations) + Fmt("(%.2f M points)", n / 1e6);

  ResetPeakMemory();
  Expected<Scan> cloud = MakeError(ErrorCode::kFailed, "not run");
  const double read_s = Seconds([&] { cloud = io::ReadPly(file, progress, cancel); });
  std::filesystem::remove(file);
  if (!cloud) return table.Add({kSection, "import " + what, 0.0, "", "failed: " + cloud.error().ToString()});
  table.Add({kSection, "import " + what, read_s, "s",
             Fmt("%.0f points kept of %.0f (", double(cloud->CountPoints()), double(n)) +
                 Fmt("%.0f in a grid, %.0f as a list); ", double(cloud->CountValid()), double(cloud->list_points.size())) +
                 Fmt("peak %.0f MiB", PeakMemoryMiB())});
  cloud->name = "merged";
  cloud->reference_world_from_scan = Eigen::Isometry3d::Identity();
  std::vector<Scan> scans = std::move(tripods);
  scans.push_back(std::move(*cloud));

  ResetPeakMemory();
  Expected<pipeline::ProjectRegistration> r = MakeError(ErrorCode::kFailed, "not run");
  const double reg_s = Seconds([&] { r = pipeline::RegisterScans(scans, {}, pipeline::RegisterOptions(), progress, cancel); });
  if (!r) return table.Add({kSection, "register " + what, 0.0, "", "failed: " + r.error().ToString()});
  int registered = 0;
  double worst_m = 0, worst_deg = 0;
  const int root = r->root;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!r->scans[i].registered || root < 0) continue;
    ++registered;
    const PoseError e = ComparePoses(r->scans[root].world_from_scan.inverse() * r->scans[i].world_from_scan,
                                     scans[root].reference_world_from_scan->inverse() * *scans[i].reference_world_from_scan);
    worst_m = std::max(worst_m, e.position_m), worst_deg = std::max(worst_deg, e.angle_rad * 180.0 / M_PI);
  }
  table.Add({kSection, "register " + what + " + 2 tripod scans", reg_s, "s",
             Fmt("%.0f of 3 registered, worst %.1f mm / %.3f deg; ", registered, 1e3 * worst_m, worst_deg) +
                 Fmt("peak %.0f MiB", PeakMemoryMiB())});

  for (std::size_t i = 0; i < scans.size(); ++i) scans[i].world_from_scan = r->scans[i].world_from_scan;
  ResetPeakMemory();
  pipeline::MergeOptions mo;
  mo.method = pipeline::MergeMethod::kTsdf;
  mo.voxel_m = 0.05;
  mo.max_range_m = 25;
  Expected<pipeline::MergeResult> m = MakeError(ErrorCode::kFailed, "not run");
  const double merge_s = Seconds([&] { m = pipeline::MergeScans(scans, {}, mo, progress, cancel); });
  if (!m) return table.Add({kSection, "merge " + what, 0.0, "", "failed: " + m.error().ToString()});
  table.Add({kSection, "merge (TSDF 5 cm) " + what + " + 2 tripod scans", merge_s, "s",
             Fmt("%.0f vertices, every point of the cloud as a disc; peak %.0f MiB", double(m->mesh.vertices.size()),
                 PeakMemoryMiB())});
}

}  // namespace scanreg::bench
