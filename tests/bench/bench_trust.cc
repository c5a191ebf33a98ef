// Trust section (issue 33): refinement from imported poses on real scans. The ten Stanford bunny
// scans start from bun.conf moved by 5 deg / 5 mm (three seeds); per run: scans called registered,
// pairs of registered scans within 2 mm / 0.5 deg of the reference and beyond 1 cm / 2 deg, the
// consistency measure (no ground truth) before and after, and the time — for scanreg with the
// multi-view step (default), without it (the pose graph alone), and PCL's LUM (Lu & Milios
// multiview, correspondences found anew at each of a shrinking schedule of distances) as the
// in-run baseline. The same for twelve real RGB-D keyframes (TUM fr3_cabinet) at their set's
// tolerances.
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/registration/lum.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/io/pose_file.h"
#include "core/pipeline/register_project.h"
#include "tests/bench/bench_table.h"
#include "tests/support/real_sets.h"

namespace scanreg::bench {
namespace {

constexpr double kDeg = 180.0 / M_PI;
const char* kSection = "trust";

struct PairCounts {
  int registered = 0, pairs = 0, within = 0, wrong = 0;
};

PairCounts CountPairs(const std::vector<Scan>& scans, const std::vector<Eigen::Isometry3d>& world,
                      const std::vector<bool>& registered, double within_m = 0.002, double within_deg = 0.5,
                      double wrong_m = 0.01, double wrong_deg = 2.0, const test::RealSet* set = nullptr) {
  PairCounts c;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    c.registered += registered[i];
    for (std::size_t j = i + 1; j < scans.size(); ++j) {
      if (!registered[i] || !registered[j]) continue;
      const PoseError e = ComparePoses(world[i].inverse() * world[j], scans[i].reference_world_from_scan->inverse() *
                                                                         *scans[j].reference_world_from_scan);
      ++c.pairs;
      c.within += e.position_m <= (set ? set->WithinM(i, j) : within_m) && e.angle_rad <= within_deg / kDeg;
      c.wrong += e.position_m > wrong_m || e.angle_rad > wrong_deg / kDeg;
    }
  }
  return c;
}

Eigen::Isometry3d Moved(const Eigen::Isometry3d& pose, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(5.0 / kDeg, Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
  d.translation() = 0.005 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  return pose * d;
}

// PCL's LUM from the start poses, as PCL's lum tool runs it: the clouds (1 mm voxel samples) in the
// world at their start poses, LUM's own poses the corrections from there (its linearisation holds
// for small angles only: given the scans' full poses it walked 1 cm away even from bun.conf), every
// pair's nearest neighbours within each distance of the schedule (8, 4, 2, 1 mm; 5 LUM iterations
// each), the first scan fixed. In millimetres (LUM works in single precision); `unit` 100 runs the same
// schedule in centimetres (1 cm samples, 8-4-2-1 cm) for room-sized scenes.
std::vector<Eigen::Isometry3d> Lum(const std::vector<Scan>& scans, double unit = 1000.0) {
  const double kUnit = unit;  // LUM's coordinates
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  pcl::registration::LUM<pcl::PointXYZ> lum;
  for (const Scan& s : scans) {
    Cloud::Ptr raw(new Cloud), sampled(new Cloud);
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (!s.valid[k]) continue;
      const Eigen::Vector3d w = kUnit * (s.world_from_scan * s.points[k].cast<double>());
      raw->push_back(pcl::PointXYZ(w.x(), w.y(), w.z()));
    }
    pcl::VoxelGrid<pcl::PointXYZ> grid;
    grid.setInputCloud(raw);
    grid.setLeafSize(1.0f, 1.0f, 1.0f);
    grid.filter(*sampled);
    lum.addPointCloud(sampled);
  }
  const int n = static_cast<int>(scans.size());
  for (double distance : {8.0, 4.0, 2.0, 1.0}) {
    std::vector<Cloud::Ptr> world(n);
    std::vector<pcl::KdTreeFLANN<pcl::PointXYZ>> trees(n);
    for (int i = 0; i < n; ++i) {
      world[i] = lum.getTransformedCloud(i);
      trees[i].setInputCloud(world[i]);
    }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        pcl::CorrespondencesPtr corr(new pcl::Correspondences);
        std::vector<int> idx(1);
        std::vector<float> d2(1);
        for (std::size_t k = 0; k < world[i]->size(); k += 4)
          if (trees[j].nearestKSearch((*world[i])[k], 1, idx, d2) > 0 && d2[0] < distance * distance)
            corr->emplace_back(static_cast<int>(k), idx[0], d2[0]);
        if (corr->size() >= 50) lum.setCorrespondences(i, j, corr);
      }
    lum.setMaxIterations(5);
    lum.compute();
  }
  std::vector<Eigen::Isometry3d> out;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d correction(lum.getTransformation(i).matrix().cast<double>());
    correction.translation() /= kUnit;
    out.push_back(correction * scans[i].world_from_scan);
  }
  return out;
}

// scanreg's refinement from the scans' current poses (what `register` does on imported poses).
struct Refined {
  Expected<pipeline::ProjectRegistration> result = MakeError(ErrorCode::kCancelled, "not run");
  double seconds = 0.0;
  std::vector<Eigen::Isometry3d> world;
  std::vector<bool> registered;
};

Refined Refine(const std::vector<Scan>& scans, bool multiview) {
  NullProgress progress;
  CancelToken cancel;
  pipeline::RegisterOptions o;
  o.from_current_poses = true;
  o.multiview = multiview;
  Refined out;
  out.seconds = Seconds([&] { out.result = pipeline::RegisterScans(scans, {}, o, progress, cancel); });
  if (out.result)
    for (const pipeline::ScanRegistration& s : out.result->scans)
      out.world.push_back(s.world_from_scan), out.registered.push_back(s.registered);
  return out;
}

// A real multi-view set (tests/support/real_sets.h) from its reference moved by 5 deg / 5 mm:
// scanreg and LUM (centimetre schedule), judged at the set's tolerances (its reference's own
// precision: TUM's keyframes a few cm, KITTI's GPS/INS 0.17 m a frame, 3DTK's registration ~5-12 cm).
void RunTrustBenchSet(Table& table, const std::string& name, Expected<test::RealSet> set, bool quick) {
  if (!set) return table.Add({kSection, name, 0.0, "", "skipped: " + set.error().ToString()});
  const int n = static_cast<int>(set->scans.size());
  const auto count = [&](const std::vector<Scan>& scans, const std::vector<Eigen::Isometry3d>& world,
                         const std::vector<bool>& registered) {
    return CountPairs(scans, world, registered, set->within_m, set->within_deg, set->wrong_m, set->wrong_deg, &*set);
  };
  auto describe = [&](const PairCounts& c) {
    return Fmt("of %.0f pairs within ", c.pairs) + Fmt("%.0f mm", 1e3 * set->within_m) +
           (set->within_m_per_step > 0 ? Fmt(" (+%.0f a step)", 1e3 * set->within_m_per_step) : std::string()) +
           Fmt(" / %.1f deg; ", set->within_deg) + Fmt("%.0f beyond ", c.wrong) + Fmt("%.0f mm / ", 1e3 * set->wrong_m) +
           Fmt("%.0f deg", set->wrong_deg);
  };
  for (unsigned seed = 1; seed <= (quick ? 1u : 2u); ++seed) {
    std::vector<Scan> scans = set->scans;
    std::mt19937 rng(seed);
    for (Scan& s : scans) s.world_from_scan = Moved(*s.reference_world_from_scan, rng);
    std::vector<Eigen::Isometry3d> start;
    for (const Scan& s : scans) start.push_back(s.world_from_scan);
    const std::string run = name + Fmt(" %.0f scans 5 deg / 5 mm, seed ", n) + std::to_string(seed);
    const PairCounts at_start = count(scans, start, std::vector<bool>(n, true));
    table.Add({kSection, run + ": start", static_cast<double>(at_start.within), "pairs ok", describe(at_start)});
    const Refined f = Refine(scans, true);
    const Expected<pipeline::ProjectRegistration>& r = f.result;
    if (!r) return table.Add({kSection, run, 0.0, "", "failed: " + r.error().ToString()});
    const PairCounts c = count(scans, f.world, f.registered);
    table.Add({kSection, run + ": scanreg", static_cast<double>(c.within), "pairs ok",
               describe(c) + Fmt("; %.0f of ", c.registered) + Fmt("%.0f registered; ", n) +
                   Fmt("consistency %.2f -> ", r->consistency ? 1e3 * r->consistency->start_rms_m : -1.0) +
                   Fmt("%.2f mm; ", r->consistency ? 1e3 * r->consistency->result_rms_m : -1.0) + Fmt("%.1f s", f.seconds)});
    std::vector<Eigen::Isometry3d> lum;
    const double lum_seconds = Seconds([&] { lum = Lum(scans, 100.0); });
    const PairCounts l = count(scans, lum, std::vector<bool>(n, true));
    table.Add({kSection, run + ": PCL LUM", static_cast<double>(l.within), "pairs ok",
               describe(l) + Fmt("; %.1f s (1 cm samples, 8-4-2-1 cm correspondences)", lum_seconds)});
  }
}

void RunTrustBenchRealSets(Table& table, bool quick) {
  const char* env = std::getenv("SCANREG_REALDATA");
  const std::filesystem::path data = env ? env : SCANREG_BENCH_REALDATA;
  RunTrustBenchSet(table, "tum_fr3_cabinet", test::LoadTumCabinet(data), quick);
  RunTrustBenchSet(table, "kitti00_velodyne", test::LoadKittiVelodyne(data), quick);
  RunTrustBenchSet(table, "3dtk_robot_scans", test::Load3dtkCorridor(data), quick);
}

}  // namespace

void RunTrustBench(Table& table, bool quick) {
  const char* env = std::getenv("SCANREG_REALDATA");
  const std::filesystem::path dir = std::filesystem::path(env ? env : SCANREG_BENCH_REALDATA) / "stanford_bunny";
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(dir / "bun.conf");
  if (!poses) return table.Add({kSection, "bunny", 0.0, "", "skipped: " + poses.error().ToString()});
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> reference;
  for (const io::NamedPose& p : *poses) {
    Expected<Scan> s = io::ReadPly(dir / p.scan, progress, cancel);
    if (!s) return table.Add({kSection, "bunny", 0.0, "", "failed: " + s.error().ToString()});
    s->name = std::filesystem::path(p.scan).stem().string();
    s->reference_world_from_scan = p.world_from_scan;
    reference.push_back(std::move(*s));
  }
  const int n = static_cast<int>(reference.size());
  for (unsigned seed = 1; seed <= (quick ? 1u : 3u); ++seed) {
    std::vector<Scan> scans = reference;
    std::mt19937 rng(seed);
    for (Scan& s : scans) s.world_from_scan = Moved(*s.reference_world_from_scan, rng);
    std::vector<Eigen::Isometry3d> start;
    for (const Scan& s : scans) start.push_back(s.world_from_scan);
    const PairCounts at_start = CountPairs(scans, start, std::vector<bool>(n, true));
    const std::string run = "bunny 10 scans 5 deg / 5 mm, seed " + std::to_string(seed);
    table.Add({kSection, run + ": start", static_cast<double>(at_start.within), "pairs ok",
               Fmt("of %.0f within 2 mm / 0.5 deg; %.0f beyond 1 cm / 2 deg", at_start.pairs, at_start.wrong)});
    for (bool multiview : {true, false}) {
      const Refined f = Refine(scans, multiview);
      const Expected<pipeline::ProjectRegistration>& r = f.result;
      if (!r) return table.Add({kSection, run, 0.0, "", "failed: " + r.error().ToString()});
      const double seconds = f.seconds;
      const PairCounts c = CountPairs(scans, f.world, f.registered);
      const double before = r->consistency ? 1e3 * r->consistency->start_rms_m : -1;
      const double after = r->consistency ? 1e3 * r->consistency->result_rms_m : -1;
      table.Add({kSection, run + (multiview ? ": scanreg" : ": scanreg --no-multiview"), static_cast<double>(c.within),
                 "pairs ok",
                 Fmt("of %.0f registered pairs within 2 mm / 0.5 deg; %.0f beyond 1 cm / 2 deg; ", c.pairs, c.wrong) +
                     Fmt("%.0f of 10 registered; consistency %.3f -> %.3f mm; ", c.registered, before, after) +
                     Fmt("%.1f s", seconds)});
    }
    if (seed == 1) {  // LUM's own sanity: from the reference poses it should stay there
      std::vector<Scan> at_reference = reference;
      for (Scan& s : at_reference) s.world_from_scan = *s.reference_world_from_scan;
      const PairCounts c = CountPairs(at_reference, Lum(at_reference), std::vector<bool>(n, true));
      table.Add({kSection, "bunny from bun.conf: PCL LUM", static_cast<double>(c.within), "pairs ok",
                 Fmt("of %.0f pairs within 2 mm / 0.5 deg; %.0f beyond 1 cm / 2 deg", c.pairs, c.wrong)});
    }
    std::vector<Eigen::Isometry3d> lum;
    const double seconds = Seconds([&] { lum = Lum(scans); });
    // LUM has no notion of a scan it could not place: every scan counts as registered.
    const std::vector<Eigen::Isometry3d> relative = lum;
    const PairCounts c = CountPairs(scans, relative, std::vector<bool>(n, true));
    table.Add({kSection, run + ": PCL LUM", static_cast<double>(c.within), "pairs ok",
               Fmt("of %.0f pairs within 2 mm / 0.5 deg; %.0f beyond 1 cm / 2 deg; ", c.pairs, c.wrong) +
                   Fmt("%.1f s (1 mm samples, 8-4-2-1 mm correspondences)", seconds)});
  }
  RunTrustBenchRealSets(table, quick);
}

}  // namespace scanreg::bench
