// Geometric correspondences (issue 11, item 2): how many FPFH matches of neighbouring scans are
// true (within 1.5 voxels of their partner at the reference poses), per keypoint selection, on
// sparse and low-resolution simulated streets. The coarse step can only find what is here.
#include <cstdio>
#include <string>
#include <vector>

#include "core/registration/geometric_features.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {
namespace {

constexpr const char* kSection = "geometric";

struct Project {
  std::string name;
  int stations, cols, rows;
  double spacing;
};

}  // namespace

void RunGeometricBench(Table& table, bool quick) {
  std::vector<Project> projects = {{"10 m, 1000x250", 4, 1000, 250, 10.0},
                                   {"15 m, 1500x375", 3, 1500, 375, 15.0},
                                   {"5 m, 600x150", 4, 600, 150, 5.0}};
  if (quick) projects.resize(1);
  for (const Project& p : projects) {
    SimulatedProjectOptions sim;
    sim.stations = p.stations;
    sim.spacing_m = p.spacing;
    sim.scanner.cols = p.cols;
    sim.scanner.rows = p.rows;
    NullProgress progress;
    CancelToken cancel;
    Expected<std::vector<Scan>> scans = SimulateProject(sim, progress, cancel);
    if (!scans) continue;
    std::vector<double> voxels;
    for (const Scan& s : *scans) voxels.push_back(SuggestVoxel(s));
    std::sort(voxels.begin(), voxels.end());
    GeometricOptions options;
    options.voxel_m = voxels[voxels.size() / 2];
    for (double radius : {4.0, 6.0, 10.0}) {
      options.feature_radius_voxels = radius;
      const double keep = options.distinctive_fraction;
      std::vector<GeometricFeatures> f;
      int levelled = 0;
      for (const Scan& s : *scans) {
        f.push_back(*DetectGeometricFeatures(s, options, cancel));
        levelled += f.back().levelled;
      }
      long total = 0, good = 0, near = 0;
      for (std::size_t i = 0; i + 1 < scans->size(); ++i) {
        const Eigen::Isometry3d truth =
            scans->at(i).reference_world_from_scan->inverse() * *scans->at(i + 1).reference_world_from_scan;
        for (const GeometricMatch& m : MatchGeometric(f[i], f[i + 1])) {
          ++total;
          const double d = (f[i].points[m.parent] - truth * f[i + 1].points[m.child]).norm();
          good += d < 1.5 * options.voxel_m;
          near += d < 4 * options.voxel_m;
        }
      }
      char note[160];
      std::snprintf(note, sizeof note, "voxel %.3f m, radius %.0f vox, %ld of %ld matches true (%ld within 4 vox), %d/%zu levelled",
                    options.voxel_m, radius, good, total, near, levelled, scans->size());
      table.Add({kSection, p.name + ": true matches per pair, keep " + std::to_string(keep).substr(0, 4) + " r " + std::to_string(int(radius)),
                 double(good) / (scans->size() - 1), "matches", note});
    }
  }
}

}  // namespace scanreg::bench
