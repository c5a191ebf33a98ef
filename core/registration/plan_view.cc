#include "core/registration/plan_view.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace scanreg {
namespace {

constexpr int kHeadingBins = 360;  // 0.5° over [0, 180°): walls' normals are axial
constexpr double kBin = M_PI / kHeadingBins;

std::vector<double> HeadingHistogram(const std::vector<double>& azimuth) {
  std::vector<double> h(kHeadingBins, 0.0);
  for (double a : azimuth) {
    double x = std::fmod(a, M_PI);
    if (x < 0) x += M_PI;
    h[std::min(kHeadingBins - 1, static_cast<int>(x / kBin))] += 1.0;
  }
  std::vector<double> s(kHeadingBins, 0.0);  // smoothed: [1 2 3 2 1]
  for (int b = 0; b < kHeadingBins; ++b)
    for (int k = -2; k <= 2; ++k) s[b] += (3 - std::abs(k)) * h[(b + k + kHeadingBins) % kHeadingBins];
  return s;
}

// Shifts of the child histogram (in bins) that best match the parent's, strongest first.
std::vector<int> HeadingPeaks(const std::vector<double>& parent, const std::vector<double>& child, int count) {
  std::vector<double> corr(kHeadingBins, 0.0);
  for (int s = 0; s < kHeadingBins; ++s)
    for (int b = 0; b < kHeadingBins; ++b) corr[s] += parent[b] * child[(b - s + kHeadingBins) % kHeadingBins];
  std::vector<int> peaks;
  std::vector<char> taken(kHeadingBins, 0);
  for (int k = 0; k < count; ++k) {
    int best = -1;
    for (int s = 0; s < kHeadingBins; ++s)
      if (!taken[s] && (best < 0 || corr[s] > corr[best])) best = s;
    if (best < 0 || !(corr[best] > 0)) break;
    peaks.push_back(best);
    for (int d = -8; d <= 8; ++d) taken[(best + d + kHeadingBins) % kHeadingBins] = 1;  // ±4°
  }
  return peaks;
}

// Occupancy map of points (already in the frame of the map) centred on the origin, padded to
// `size` x `size`, blurred by a cell so that neighbouring cells still correlate.
cv::Mat WallMap(const std::vector<Eigen::Vector2d>& xy, double cell, int half, int size) {
  cv::Mat m = cv::Mat::zeros(size, size, CV_32F);
  for (const Eigen::Vector2d& p : xy) {
    const int cx = static_cast<int>(std::floor(p.x() / cell)) + half;
    const int cy = static_cast<int>(std::floor(p.y() / cell)) + half;
    if (cx < 0 || cy < 0 || cx >= 2 * half || cy >= 2 * half) continue;
    m.at<float>(cy, cx) = 1.0f;
  }
  cv::GaussianBlur(m, m, cv::Size(3, 3), 0.8);
  return m;
}

double Wrap(int k, int size) { return k > size / 2 ? k - size : k; }

// Sub-cell peak position along one axis from three samples (parabola).
double SubCell(float left, float centre, float right) {
  const double d = left - 2.0 * centre + right;
  return std::abs(d) < 1e-12 ? 0.0 : std::clamp(0.5 * (left - right) / d, -0.5, 0.5);
}

}  // namespace

PlanView MakePlanView(const GeometricFeatures& features, const PlanOptions& options) {
  PlanView v;
  if (!features.levelled || features.normals.size() != features.points.size()) return v;
  v.cell_m = options.cell_voxels * features.voxel_m;
  const Eigen::Isometry3d level = features.Levelling();
  const double s15 = std::sin(15.0 * M_PI / 180.0), c15 = std::cos(15.0 * M_PI / 180.0);
  std::vector<double> ground;
  for (int i = 0; i < features.FinestEnd(); ++i) {  // the finest scale's samples
    const Eigen::Vector3d p = level * features.points[i];
    const Eigen::Vector3d n = level.linear() * features.normals[i];
    const double r = p.head<2>().norm();
    if (std::abs(n.z()) < s15 && r < options.radius_m) {
      v.wall_xy.push_back(p.head<2>());
      v.wall_azimuth.push_back(std::atan2(n.y(), n.x()));
    } else if (std::abs(n.z()) > c15 && r < 15.0 && p.z() < 0.0) {
      ground.push_back(p.z());
    }
  }
  if (!ground.empty()) {
    std::nth_element(ground.begin(), ground.begin() + ground.size() / 2, ground.end());
    v.ground_z = ground[ground.size() / 2];
  }
  v.usable = v.wall_xy.size() >= 50 && !ground.empty();
  return v;
}

std::vector<PlanHypothesis> PlanHypotheses(const PlanView& parent, const PlanView& child, const PlanOptions& options) {
  std::vector<PlanHypothesis> out;
  if (!parent.usable || !child.usable || !(parent.cell_m > 0.0)) return out;
  // The map reaches the farthest wall of either scan (not beyond the radius), and has at most
  // kMaxMapCells cells across (streets: never reached): an office's 7 cm cells over a 60 m radius would make every pair's
  // correlation a 3456 x 3456 FFT (issue 38), where the walls lie within 20 m.
  double reach = 0.0;
  for (const PlanView* v : {&parent, &child})
    for (const Eigen::Vector2d& p : v->wall_xy) reach = std::max(reach, p.norm());
  reach = std::min(reach, options.radius_m) + parent.cell_m;
  constexpr int kMaxMapCells = 2048;
  const double cell = std::max(parent.cell_m, 4.0 * reach / kMaxMapCells);
  const int half = static_cast<int>(std::ceil(reach / cell));
  const int size = cv::getOptimalDFTSize(4 * half);
  // Real-input transforms in OpenCV's packed (CCS) layout, told that only the rows a map can fill
  // are non-zero (its cells and the blur's one-cell spill): the same correlation as with complex
  // transforms of the whole square, for under half the work (issue 36).
  const int filled = std::min(size, 2 * half + 1);
  const cv::Mat pmap = WallMap(parent.wall_xy, cell, half, size);
  cv::Mat pspec;
  cv::dft(pmap, pspec, 0, filled);
  const double pnorm = cv::norm(pmap);
  const std::vector<int> peaks =
      HeadingPeaks(HeadingHistogram(parent.wall_azimuth), HeadingHistogram(child.wall_azimuth), options.max_headings);
  std::vector<PlanHypothesis> all;
  for (int peak : peaks) {
    for (double turn : {0.0, M_PI}) {
      const double heading = peak * kBin + turn;
      const Eigen::Rotation2Dd rot(heading);
      std::vector<Eigen::Vector2d> rotated;
      rotated.reserve(child.wall_xy.size());
      for (const Eigen::Vector2d& q : child.wall_xy) rotated.push_back(rot * q);
      const cv::Mat cmap = WallMap(rotated, cell, half, size);
      cv::Mat cspec, prod, corr;
      cv::dft(cmap, cspec, 0, filled);
      cv::mulSpectrums(pspec, cspec, prod, 0, /*conjB=*/true);
      cv::idft(prod, corr, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
      cv::Point at;
      double best = 0.0;
      cv::minMaxLoc(corr, nullptr, &best, nullptr, &at);
      const double norm = pnorm * cv::norm(cmap);
      if (!(best > 0.0) || !(norm > 0.0)) continue;
      const auto value = [&](int y, int x) { return corr.at<float>((y + size) % size, (x + size) % size); };
      const double dx = Wrap(at.x, size) + SubCell(value(at.y, at.x - 1), value(at.y, at.x), value(at.y, at.x + 1));
      const double dy = Wrap(at.y, size) + SubCell(value(at.y - 1, at.x), value(at.y, at.x), value(at.y + 1, at.x));
      PlanHypothesis h;
      h.parent_from_child.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      h.parent_from_child.translation() = Eigen::Vector3d(dx * cell, dy * cell, parent.ground_z - child.ground_z);
      h.score = best / norm;
      all.push_back(h);
    }
  }
  std::sort(all.begin(), all.end(), [](const PlanHypothesis& a, const PlanHypothesis& b) { return a.score > b.score; });
  for (const PlanHypothesis& h : all) {
    if (h.score < options.min_relative_score * all.front().score) break;
    bool distinct = true;
    for (const PlanHypothesis& o : out)
      distinct &= (h.parent_from_child.translation() - o.parent_from_child.translation()).norm() > 2 * cell ||
                  Eigen::AngleAxisd(h.parent_from_child.linear().transpose() * o.parent_from_child.linear()).angle() >
                      2 * M_PI / 180;
    if (distinct) out.push_back(h);
    if (static_cast<int>(out.size()) >= options.max_hypotheses) break;
  }
  return out;
}

}  // namespace scanreg
