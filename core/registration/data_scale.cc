#include "core/registration/data_scale.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/registration/point_index.h"
#include "core/registration/voxel_filter.h"

namespace scanreg {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

constexpr int kMaxPoints = 100000;
constexpr int kSeeds = 2000;
constexpr int kNeighbours = 16;

}  // namespace

DataScale MeasureDataScale(const Scan& scan) {
  DataScale s;
  // The grid's points: spacing and noise are those of one scanner's sampling (a merged cloud's list
  // interleaves other stations' samples, a file's exact repeats would read as zero spacing).
  std::vector<Eigen::Vector3d> all;
  all.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) all.push_back(scan.points[i].cast<double>());
  const std::vector<Eigen::Vector3d> pts = ThinEvenly(all, kMaxPoints);
  if (pts.size() < 20) return s;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= double(pts.size());
  std::vector<double> spread;
  spread.reserve(pts.size());
  for (const auto& p : pts) spread.push_back((p - c).norm());
  s.extent_m = Median(spread);

  const PointIndex index(pts);
  const std::size_t step = std::max<std::size_t>(1, pts.size() / kSeeds);
  std::vector<double> nn, noise;
  for (std::size_t i = 0; i < pts.size(); i += step) {
    const std::vector<int> k = index.KNearest(pts[i], kNeighbours);
    if (k.size() < 2) continue;
    nn.push_back((pts[k[1]] - pts[i]).norm());
    if (static_cast<int>(k.size()) < kNeighbours) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int j : k) mean += pts[j];
    mean /= double(k.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int j : k) cov += (pts[j] - mean) * (pts[j] - mean).transpose();
    cov /= double(k.size());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov, Eigen::EigenvaluesOnly);
    // A line (an edge, a wire) has no plane to measure noise against.
    if (!(eig.eigenvalues()(1) > 4.0 * eig.eigenvalues()(0))) continue;
    const double dof = double(k.size()) / double(k.size() - 3);
    noise.push_back(std::sqrt(std::max(0.0, eig.eigenvalues()(0)) * dof));
  }
  // Spacing of the full scan: nearest-neighbour distances among thinned points on a surface grow
  // with the square root of the thinning.
  const double thinning = double(all.size()) / double(pts.size());
  s.spacing_m = Median(nn) / std::sqrt(std::max(1.0, thinning));
  s.noise_m = Median(noise);
  return s;
}

}  // namespace scanreg
