#include "core/registration/plan_view.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

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

// Peak position between three neighbouring samples, in samples from the centre one (parabola).
double SubCell(double left, double centre, double right) {
  const double d = left - 2.0 * centre + right;
  return std::abs(d) < 1e-12 ? 0.0 : std::clamp(0.5 * (left - right) / d, -0.5, 0.5);
}

// Shifts of the child histogram (in bins, to a fraction of one: a tenth of a degree turns a wall
// 30 m away by 5 cm) that best match the parent's, strongest first.
std::vector<double> HeadingPeaks(const std::vector<double>& parent, const std::vector<double>& child, int count) {
  std::vector<double> corr(kHeadingBins, 0.0);
  for (int s = 0; s < kHeadingBins; ++s)
    for (int b = 0; b < kHeadingBins; ++b) corr[s] += parent[b] * child[(b - s + kHeadingBins) % kHeadingBins];
  std::vector<double> peaks;
  std::vector<char> taken(kHeadingBins, 0);
  for (int k = 0; k < count; ++k) {
    int best = -1;
    for (int s = 0; s < kHeadingBins; ++s)
      if (!taken[s] && (best < 0 || corr[s] > corr[best])) best = s;
    if (best < 0 || !(corr[best] > 0)) break;
    peaks.push_back(best + SubCell(corr[(best + kHeadingBins - 1) % kHeadingBins], corr[best], corr[(best + 1) % kHeadingBins]));
    for (int d = -8; d <= 8; ++d) taken[(best + d + kHeadingBins) % kHeadingBins] = 1;  // ±4°
  }
  return peaks;
}

// Occupancy map of the walls of `v` turned by `heading`, centred on the origin, padded to `size` x
// `size` (drawn within the first 2 x `half` cells), blurred by a cell so that neighbouring cells
// still correlate.
cv::Mat WallMap(const PlanView& v, double heading, double cell, int half, int size) {
  cv::Mat m = cv::Mat::zeros(size, size, CV_32F);
  const Eigen::Rotation2Dd rot(heading);
  const cv::Rect inside(0, 0, 2 * half, 2 * half);
  const auto to_cell = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d q = rot * p;
    return cv::Point(static_cast<int>(std::floor(q.x() / cell)) + half, static_cast<int>(std::floor(q.y() / cell)) + half);
  };
  for (const Eigen::Vector2d& p : v.wall_xy) {
    const cv::Point c = to_cell(p);
    if (inside.contains(c)) m.at<float>(c) = 1.0f;
  }
  for (const auto& [a, b] : v.wall_runs) {
    cv::Point from = to_cell(a), to = to_cell(b);
    if (cv::clipLine(inside, from, to)) cv::line(m, from, to, cv::Scalar(1.0));
  }
  cv::GaussianBlur(m, m, cv::Size(3, 3), 0.8);
  return m;
}

std::int64_t CellKey(const Eigen::Vector2d& p, double cell) {
  return (static_cast<std::int64_t>(std::floor(p.x() / cell)) << 32) ^
         (static_cast<std::int64_t>(std::floor(p.y() / cell)) & 0xffffffffLL);
}

// Whether b lies on the line through a and c (within `tolerance`) between them.
bool Between(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double tolerance) {
  const Eigen::Vector2d ac = c - a;
  const double len = ac.norm();
  if (!(len > 0.0)) return false;
  const double along = ac.dot(b - a) / len;
  const double across = std::abs(ac.x() * (b - a).y() - ac.y() * (b - a).x()) / len;
  return across <= tolerance && along > 0.0 && along < len;
}

// Rows of the scan's grid within `angle` of elevation; 0 when the grid's angles are unknown.
int RowsWithin(const Scan& scan, double angle) {
  const std::vector<float>& el = scan.angles.elevation;
  if (static_cast<int>(el.size()) != scan.rows || scan.rows < 2) return 0;
  const double step = std::abs(static_cast<double>(el.back()) - el.front()) / (scan.rows - 1);
  return step > 0.0 && std::isfinite(step) ? static_cast<int>(std::min(1000.0, std::ceil(angle / step))) : 0;
}

// The walls a scan seen from one spot shows, into `v` (levelled by `level`): a return is on a wall
// where the next one up its column stands above it (its plan position within the tangent of 15°
// of the height between them — the samples' own test on their normals); the returns of
// neighbouring columns on walls are joined by the wall between them when a third column's return
// lies on the same straight line (not across a door or a corner).
void AddScanWalls(const Scan& scan, const Eigen::Isometry3d& level, const PlanOptions& options, PlanView* v) {
  const double cell = v->cell_m;
  const Eigen::Isometry3f level_f = level.cast<float>();
  const float steep = static_cast<float>(std::tan(15.0 * M_PI / 180.0));
  const int rows = scan.rows, cols = scan.cols;
  std::vector<Eigen::Vector3f> levelled(scan.points.size(), Eigen::Vector3f::Constant(NAN));
  for (std::size_t i = 0; i < scan.points.size(); ++i)
    if (scan.valid[i]) {
      const Eigen::Vector3f p = level_f * scan.points[i];
      if (p.allFinite() && p.head<2>().norm() < options.radius_m) levelled[i] = p;
    }
  std::vector<char> wall(scan.points.size(), 0);
  const auto stands_above = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const float dz = std::abs(b.z() - a.z());
    return a.allFinite() && b.allFinite() && dz > 0.0f && dz <= options.max_wall_run_m &&
           (b.head<2>() - a.head<2>()).norm() <= steep * dz;
  };
  // Up the column to the first return a cell higher or lower (nearer ones differ by the noise),
  // within 2.8° of elevation (at least 8 rows), whatever the resolution: a wall seen level is found
  // from where a cell of height spans 2.8° (6.5 m away for a 0.32 m cell). A fixed 8 rows (2.9° at
  // 1000 x 250) found it at 3000 x 750 (0.12° a row) only from 19 m, and stations of a street 25 m
  // apart got wrong plan-view poses there.
  const int rows_up = std::max(8, RowsWithin(scan, 2.8 * M_PI / 180.0));
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = scan.Index(r, c);
      if (!levelled[i].allFinite()) continue;
      for (int k = r + 1; k < std::min(rows, r + 1 + rows_up); ++k) {
        const std::size_t j = scan.Index(k, c);
        if (!levelled[j].allFinite() || std::abs(levelled[j].z() - levelled[i].z()) < cell) continue;
        if (stands_above(levelled[i], levelled[j])) wall[i] = wall[j] = 1;
        break;
      }
    }
  std::unordered_set<std::int64_t> cells;  // a wall cell once, whatever number of returns it holds
  for (std::size_t i = 0; i < wall.size(); ++i)
    if (wall[i]) {
      const Eigen::Vector2d p = levelled[i].head<2>().cast<double>();
      if (cells.insert(CellKey(p, cell)).second) v->wall_xy.push_back(p);
    }
  const auto on_wall = [&](int r, int c) -> const Eigen::Vector3f* {
    if (c < 0 || c >= cols) return nullptr;
    const std::size_t i = scan.Index(r, c);
    return wall[i] ? &levelled[i] : nullptr;
  };
  std::unordered_set<std::int64_t> joined;  // a pair of cells once, for all the rows that join them
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c + 1 < cols; ++c) {
      const Eigen::Vector3f* a = on_wall(r, c);
      const Eigen::Vector3f* b = on_wall(r, c + 1);
      if (!a || !b) continue;
      const Eigen::Vector2d a2 = a->head<2>().cast<double>(), b2 = b->head<2>().cast<double>();
      const double gap = (b2 - a2).norm();
      if (gap <= 1.5 * cell || gap > options.max_wall_run_m) continue;
      const Eigen::Vector3f* before = on_wall(r, c - 1);
      const Eigen::Vector3f* after = on_wall(r, c + 2);
      const bool straight = (before && Between(before->head<2>().cast<double>(), a2, b2, cell)) ||
                            (after && Between(a2, b2, after->head<2>().cast<double>(), cell));
      if (!straight) continue;
      const std::int64_t key = CellKey(a2, cell) * 1000003 ^ CellKey(b2, cell);
      if (joined.insert(key).second) v->wall_runs.emplace_back(a2, b2);
    }
}

double Wrap(int k, int size) { return k > size / 2 ? k - size : k; }

}  // namespace

PlanView MakePlanView(const GeometricFeatures& features, const Scan& scan, const PlanOptions& options) {
  PlanView v = MakePlanView(features, options);
  // A cloud seen from several places has no columns to follow: its samples' walls serve.
  if (!v.usable || !scan.single_viewpoint || scan.rows < 2 || scan.points.size() != scan.valid.size()) return v;
  PlanView from_scan = v;
  from_scan.wall_xy.clear();
  AddScanWalls(scan, features.Levelling(), options, &from_scan);
  return from_scan.wall_xy.size() >= 50 ? from_scan : v;
}

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
  // kMaxMapCells cells across (streets: never reached): an office's 7 cm cells over a 60 m radius
  // would make maps 3456 cells across (issue 38), where the walls lie within 20 m.
  double reach = 0.0;
  for (const PlanView* v : {&parent, &child})
    for (const Eigen::Vector2d& p : v->wall_xy) reach = std::max(reach, p.norm());
  reach = std::min(reach, options.radius_m) + parent.cell_m;
  constexpr int kMaxMapCells = 2048;
  const double cell = std::max(parent.cell_m, 4.0 * reach / kMaxMapCells);
  const int half = static_cast<int>(std::ceil(reach / cell));
  // Coarse to fine: each heading's shift is found by FFT correlation on maps `factor` cells to a
  // cell (at most kCoarseHalf cells from the centre), then among the fine shifts around it by direct
  // correlation of the fine maps — the whole corridor in a map costs a 2160-point FFT a heading
  // at 7 cm, where the coarse maps take 540 (issue 38).
  constexpr int kCoarseHalf = 160;
  const int factor = std::max(1, (half + kCoarseHalf - 1) / kCoarseHalf);
  const int coarse_half = (half + factor - 1) / factor;
  const int size = cv::getOptimalDFTSize(4 * coarse_half);
  // Real-input transforms in OpenCV's packed (CCS) layout, told that only the rows a map can fill
  // are non-zero (its cells and the blur's one-cell spill): the same correlation as with complex
  // transforms of the whole square, for under half the work (issue 36).
  const int filled = std::min(size, 2 * coarse_half + 1);
  const cv::Mat pmap = WallMap(parent, 0.0, cell, half, 2 * half);
  const double pnorm = cv::norm(pmap);
  cv::Mat pspec;
  cv::dft(WallMap(parent, 0.0, cell * factor, coarse_half, size), pspec, 0, filled);
  const std::vector<double> peaks =
      HeadingPeaks(HeadingHistogram(parent.wall_azimuth), HeadingHistogram(child.wall_azimuth), options.max_headings);
  std::vector<PlanHypothesis> all;
  for (double peak : peaks) {
    for (double turn : {0.0, M_PI}) {
      const double heading = peak * kBin + turn;
      cv::Mat cspec, prod, corr;
      cv::dft(WallMap(child, heading, cell * factor, coarse_half, size), cspec, 0, filled);
      cv::mulSpectrums(pspec, cspec, prod, 0, /*conjB=*/true);
      cv::idft(prod, corr, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
      cv::Point at;
      double coarse_best = 0.0;
      cv::minMaxLoc(corr, nullptr, &coarse_best, nullptr, &at);
      if (!(coarse_best > 0.0)) continue;
      // The fine shifts within a coarse cell and one beyond, by direct correlation.
      const cv::Mat cmap = WallMap(child, heading, cell, half, 2 * half);
      const double norm = pnorm * cv::norm(cmap);
      if (!(norm > 0.0)) continue;
      const int cx = static_cast<int>(Wrap(at.x, size)) * factor, cy = static_cast<int>(Wrap(at.y, size)) * factor;
      const int reach_cells = factor + 1;
      const int w = 2 * reach_cells + 1;
      std::vector<double> local(static_cast<std::size_t>(w) * w, 0.0);
      for (int y = 0; y < cmap.rows; ++y) {
        const float* row = cmap.ptr<float>(y);
        for (int x = 0; x < cmap.cols; ++x) {
          if (row[x] <= 0.0f) continue;
          for (int j = 0; j < w; ++j) {
            const int py = y + cy + j - reach_cells;
            if (py < 0 || py >= pmap.rows) continue;
            const float* prow = pmap.ptr<float>(py);
            for (int i = 0; i < w; ++i) {
              const int px = x + cx + i - reach_cells;
              if (px >= 0 && px < pmap.cols) local[static_cast<std::size_t>(j) * w + i] += row[x] * prow[px];
            }
          }
        }
      }
      // The best inside the window (its border only gives the parabola its neighbours).
      int bi = reach_cells, bj = reach_cells;
      for (int j = 1; j + 1 < w; ++j)
        for (int i = 1; i + 1 < w; ++i)
          if (local[static_cast<std::size_t>(j) * w + i] > local[static_cast<std::size_t>(bj) * w + bi]) bi = i, bj = j;
      const auto value = [&](int j, int i) { return static_cast<float>(local[static_cast<std::size_t>(j) * w + i]); };
      const double best = value(bj, bi);
      if (!(best > 0.0)) continue;
      const double dx = cx + bi - reach_cells + SubCell(value(bj, bi - 1), value(bj, bi), value(bj, bi + 1));
      const double dy = cy + bj - reach_cells + SubCell(value(bj - 1, bi), value(bj, bi), value(bj + 1, bi));
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
