// Isolated pairs against the downloadable baseline (issues 36 and 37): every pair of a 10 m-spaced
// street (6 stations, 15 pairs, the near and the far ones) registered alone — each pair a 2-scan
// project through scanreg's whole pipeline, and through FPFH + mutual filter + RANSAC (100 k) +
// point-to-plane ICP as Open3D's tutorial sets it (fpfh_ransac_baseline.h). The issue asks that the
// baseline registers at least 10 of the 15 before any speed is compared with it. Then one pair at
// the paper's size (3000 x 750) from a PTX file, parsing included on both sides: the speed ratio.
// Right: the relative pose within 5 cm / 0.2° of the truth; wrong: a pose returned as a result that
// is not right (scanreg: both scans registered; the baseline returns a pose whenever RANSAC finds one).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

#include "core/geometry/transform.h"
#include "core/io/ptx.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/fpfh_ransac_baseline.h"

namespace scanreg::bench {
namespace {

constexpr const char* kSection = "pairs";
constexpr double kDeg = 180.0 / M_PI;

PoseError ErrorOf(const Eigen::Isometry3d& parent_from_child, const Scan& parent, const Scan& child) {
  return ComparePoses(parent_from_child, parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan);
}

bool Right(const PoseError& e) { return e.position_m <= 0.05 && e.angle_rad * kDeg <= 0.2; }

struct Outcome {
  bool returned = false;  // a pose was given as the result
  bool right = false;
  double seconds = 0;
  PoseError error;  // of the pose returned
};

Outcome Scanreg(const Scan& parent, const Scan& child) {
  NullProgress progress;
  CancelToken cancel;
  Expected<pipeline::ProjectRegistration> r = MakeError(ErrorCode::kFailed, "not run");
  Outcome out;
  out.seconds = Seconds([&] { r = pipeline::RegisterScans({parent, child}, {}, {}, progress, cancel); });
  if (!r || !r->scans[0].registered || !r->scans[1].registered) return out;
  out.returned = true;
  out.error = ErrorOf(r->scans[0].world_from_scan.inverse() * r->scans[1].world_from_scan, parent, child);
  out.right = Right(out.error);
  return out;
}

Outcome Baseline(const Scan& parent, const Scan& child) {
  const FpfhRansacResult r = FpfhRansacPair(parent, child, FpfhRansacOptions{});
  const PoseError e = ErrorOf(r.parent_from_child, parent, child);
  std::printf("[pairs] baseline %s-%s: %zu mutual correspondences, %zu inliers, %d iterations\n", parent.name.c_str(),
              child.name.c_str(), r.correspondences, r.inliers, r.iterations);
  return {r.accepted, r.accepted && Right(e), r.Seconds(), e};
}

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void AllPairs(Table& table, bool quick) {
  SimulatedProjectOptions o;
  o.stations = quick ? 3 : 6;
  o.spacing_m = 10.0;
  o.scanner.cols = 1000;
  o.scanner.rows = 250;
  NullProgress progress;
  CancelToken cancel;
  const Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
  if (!scans) {
    table.Add({kSection, "10 m street: simulate", 0.0, "", "failed: " + scans.error().ToString()});
    return;
  }
  struct Tally {
    int right = 0, wrong = 0;
    std::vector<double> seconds;
  } ours, theirs;
  int pairs = 0;
  for (std::size_t i = 0; i < scans->size(); ++i)
    for (std::size_t j = i + 1; j < scans->size(); ++j) {
      const Outcome a = Scanreg((*scans)[i], (*scans)[j]);
      const Outcome b = Baseline((*scans)[i], (*scans)[j]);
      ++pairs;
      for (auto [t, x] : {std::pair<Tally*, const Outcome*>{&ours, &a}, {&theirs, &b}}) {
        t->right += x->right;
        t->wrong += x->returned && !x->right;
        t->seconds.push_back(x->seconds);
      }
      std::printf("[pairs] %s-%s (%.0f m): scanreg %s %.1f s (%.3f m %.3f deg), baseline %s %.1f s (%.3f m %.3f deg)\n",
                  (*scans)[i].name.c_str(), (*scans)[j].name.c_str(), o.spacing_m * static_cast<double>(j - i),
                  a.right ? "right" : a.returned ? "WRONG" : "refused", a.seconds, a.error.position_m,
                  a.error.angle_rad * kDeg, b.right ? "right" : b.returned ? "WRONG" : "none", b.seconds,
                  b.error.position_m, b.error.angle_rad * kDeg);
      std::fflush(stdout);
    }
  const std::string size = Fmt("%.0f stations 10 m apart, 1000x250, %.0f pairs", o.stations, pairs);
  table.Add({kSection, "10 m street, every pair: FPFH+mutual+RANSAC+ICP right", static_cast<double>(theirs.right),
             "pairs",
             Fmt("%.0f wrong poses returned; %.1f s per pair (median); ", theirs.wrong, Median(theirs.seconds)) +
                 size + "; voxel 0.5 m, 100k it; the issue's street: 10 of 15"});
  table.Add({kSection, "10 m street, every pair: scanreg right", static_cast<double>(ours.right), "pairs",
             Fmt("%.0f wrong poses returned; %.1f s per pair (median), the rest refused with a reason",
                 ours.wrong, Median(ours.seconds))});
  table.Add({kSection, "10 m street: per-pair speed-up over the baseline", Median(theirs.seconds) / Median(ours.seconds),
             "x", "median times, scanreg's whole pipeline on a 2-scan project"});
}

// One pair from a PTX file, as a user starts: parse, then register.
void PaperSizePair(Table& table, bool quick) {
  SimulatedProjectOptions o;
  o.stations = 2;
  o.scanner.cols = quick ? 1000 : 3000;
  o.scanner.rows = quick ? 250 : 750;
  NullProgress progress;
  CancelToken cancel;
  const Expected<std::vector<Scan>> simulated = SimulateProject(o, progress, cancel);
  char dir_template[] = "/tmp/scanreg-pairs-XXXXXX";
  if (!simulated || !::mkdtemp(dir_template)) {
    table.Add({kSection, "isolated pair: simulate", 0.0, "", "failed"});
    return;
  }
  const std::filesystem::path file = std::filesystem::path(dir_template) / "pair.ptx";
  if (!io::WritePtx(file, *simulated, progress, cancel)) {
    table.Add({kSection, "isolated pair: write PTX", 0.0, "", "failed"});
    return;
  }
  auto parse = [&] {
    Expected<std::vector<Scan>> scans = io::ReadPtx(file, progress, cancel);
    if (scans) {  // the reader knows nothing of the truth; the simulator does
      for (std::size_t i = 0; i < scans->size(); ++i)
        (*scans)[i].reference_world_from_scan = (*simulated)[i].reference_world_from_scan;
    }
    return scans;
  };
  Outcome ours, theirs;
  ours.seconds = Seconds([&] {
    const Expected<std::vector<Scan>> scans = parse();
    if (scans) ours = Scanreg((*scans)[0], (*scans)[1]);
  });
  theirs.seconds = Seconds([&] {
    const Expected<std::vector<Scan>> scans = parse();
    if (scans) theirs = Baseline((*scans)[0], (*scans)[1]);
  });
  // (Scanreg and Baseline time themselves; the outer Seconds, parse included, is assigned last.)
  std::filesystem::remove_all(dir_template);
  const std::string size = Fmt("%.0fx%.0f, 5 m apart, PTX parse included", o.scanner.cols, o.scanner.rows);
  table.Add({kSection, "isolated pair: scanreg", ours.seconds, "s",
             std::string(ours.right ? "right" : ours.returned ? "WRONG" : "refused") + "; " + size});
  table.Add({kSection, "isolated pair: FPFH+mutual+RANSAC+ICP", theirs.seconds, "s",
             std::string(theirs.right ? "right" : theirs.returned ? "WRONG" : "none") + "; " + size});
  table.Add({kSection, "isolated pair: speed-up over the baseline", theirs.seconds / ours.seconds, "x",
             "issue 36 floor: 35x"});
}

}  // namespace

void RunPairsBench(Table& table, bool quick) {
  AllPairs(table, quick);
  PaperSizePair(table, quick);
}

}  // namespace scanreg::bench
