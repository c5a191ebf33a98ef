#include "core/georef/checker_targets.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "core/georef/angular_steps.h"

namespace scanreg::georef {
namespace {

// The reflectance panorama with bilinear sampling (NaN where a cell has no return). Columns wrap
// round when the scan covers the full circle.
struct Panorama {
  const Scan& scan;
  bool wraps = false;

  float At(int r, int c) const {
    if (wraps) c = (c % scan.cols + scan.cols) % scan.cols;
    if (r < 0 || r >= scan.rows || c < 0 || c >= scan.cols || !scan.IsValid(r, c)) return NAN;
    return scan.Reflectance(r, c);
  }
  float Sample(double r, double c) const {
    const int r0 = static_cast<int>(std::floor(r)), c0 = static_cast<int>(std::floor(c));
    const double fr = r - r0, fc = c - c0;
    const float a = At(r0, c0), b = At(r0, c0 + 1), d = At(r0 + 1, c0), e = At(r0 + 1, c0 + 1);
    return static_cast<float>((a * (1 - fc) + b * fc) * (1 - fr) + (d * (1 - fc) + e * fc) * fr);
  }
};

// The scan with its angular steps: what the response and the fit need.
struct Grid {
  const Scan& scan;
  Panorama pano;
  double dc = 0, dr = 0;  // radians between neighbouring columns, rows
};

std::optional<Grid> MakeGrid(const Scan& scan) {
  double dc = 0, dr = 0;
  AngularSteps(scan, &dc, &dr);
  if (!(dc > 0) || !(dr > 0)) return std::nullopt;
  return Grid{scan, Panorama{scan, scan.cols * dc > 2 * M_PI * 0.99}, dc, dr};
}

// ChESS response of a ring of 16 samples about the centre value.
double ChessResponse(const std::array<float, 16>& s, float centre) {
  double sum = 0, diff = 0, mean = 0;
  for (int n = 0; n < 4; ++n) sum += std::abs((s[n] + s[n + 8]) - (s[n + 4] + s[n + 12]));
  for (int n = 0; n < 8; ++n) diff += std::abs(s[n] - s[n + 8]);
  for (float v : s) mean += v;
  return sum - diff - 16.0 * std::abs(mean / 16.0 - centre);
}

// The checker response at cell (r, c), 0 where it cannot be computed or fails the quick test.
float Response(const Grid& g, int r, int c, const CheckerTargetOptions& o) {
  const double size = o.size_m;
  const float quick = static_cast<float>(o.min_contrast);
    if (!g.scan.IsValid(r, c)) return 0.0f;
    const double range = g.scan.Point(r, c).norm();
    if (range > o.max_range_m || range < 0.5 * size) return 0.0f;
    const double ring = 0.3 * size / range, rc = ring / g.dc, rr = ring / g.dr;
    if (std::min(rc, rr) < 1.2) return 0.0f;  // too few cells across the pattern
    // Quick test: opposite quarters alike and unlike their neighbours along the axes or the
    // diagonals (one of the two sets lies inside the squares whatever the pattern's angle).
    const double ar = std::min(rr, 24.0), ac = std::min(rc, 24.0), dr2 = 0.7071 * ar, dc2 = 0.7071 * ac;
    const float axes = std::abs(g.pano.Sample(r, c + ac) + g.pano.Sample(r, c - ac) - g.pano.Sample(r + ar, c) - g.pano.Sample(r - ar, c));
    const float diagonals = std::abs(g.pano.Sample(r + dr2, c + dc2) + g.pano.Sample(r - dr2, c - dc2) -
                                     g.pano.Sample(r + dr2, c - dc2) - g.pano.Sample(r - dr2, c + dc2));
    if (!(axes >= quick) && !(diagonals >= quick)) return 0.0f;
    // The centre may fall between cells: the best of the response at the cell and at the
    // half-cell offsets (on a coarse grid an edge through the ring's centre decides it).
    double best = -INFINITY;
    for (const auto& [or_, oc] : {std::pair{0.0, 0.0}, {0.5, 0.0}, {0.0, 0.5}, {0.5, 0.5}}) {
      const double cr = r + or_, cc = c + oc;
      std::array<float, 16> ringv;
      bool ok = true;
      for (int k = 0; k < 16 && ok; ++k) {
        const double a = k * M_PI / 8;
        ringv[k] = g.pano.Sample(cr + ar * std::sin(a), cc + ac * std::cos(a));
        ok = std::isfinite(ringv[k]);
      }
      const float centre = 0.25f * (g.pano.Sample(cr - 0.5, cc - 0.5) + g.pano.Sample(cr - 0.5, cc + 0.5) +
                                    g.pano.Sample(cr + 0.5, cc - 0.5) + g.pano.Sample(cr + 0.5, cc + 0.5));
      if (ok && std::isfinite(centre)) best = std::max(best, ChessResponse(ringv, centre));
    }
  return std::isfinite(best) ? static_cast<float>(best) : 0.0f;
}

struct BoardSample {
  double u, v, value;  // board coordinates (metres) and reflectance
};

// The pattern model a + b erf(x'/s) erf(y'/s) with x', y' the board coordinates about (cx, cy)
// turned by theta; s = exp(q): a Gaussian beam's average over the sharp-edged squares.
// Parameters: cx, cy, theta, a, b, q.
using Params = Eigen::Matrix<double, 6, 1>;

double Model(const Params& p, double u, double v, Eigen::Matrix<double, 1, 6>* jac) {
  const double c = std::cos(p[2]), sn = std::sin(p[2]), s = std::exp(p[5]);
  const double du = u - p[0], dv = v - p[1];
  const double x = du * c + dv * sn, y = -du * sn + dv * c;
  const double tx = std::erf(x / s), ty = std::erf(y / s);
  if (jac) {
    constexpr double k = 1.1283791670955126;  // 2 / sqrt(pi): erf' = k exp(-t^2)
    const double fx = p[4] * ty * k * std::exp(-(x / s) * (x / s)) / s;
    const double fy = p[4] * tx * k * std::exp(-(y / s) * (y / s)) / s;
    (*jac)[0] = -fx * c + fy * sn;
    (*jac)[1] = -fx * sn - fy * c;
    (*jac)[2] = fx * y - fy * x;
    (*jac)[3] = 1;
    (*jac)[4] = tx * ty;
    (*jac)[5] = -fx * x - fy * y;
  }
  return p[3] + p[4] * tx * ty;
}

// Levenberg-Marquardt; returns the sum of squared residuals and the normal matrix at the end.
double FitPattern(const std::vector<BoardSample>& samples, Params* p, Eigen::Matrix<double, 6, 6>* normal) {
  auto cost = [&](const Params& q) {
    double ssr = 0;
    for (const BoardSample& b : samples) ssr += std::pow(Model(q, b.u, b.v, nullptr) - b.value, 2);
    return ssr;
  };
  double lambda = 1e-3, ssr = cost(*p);
  for (int it = 0; it < 60; ++it) {
    Eigen::Matrix<double, 6, 6> jtj = Eigen::Matrix<double, 6, 6>::Zero();
    Params jtr = Params::Zero();
    Eigen::Matrix<double, 1, 6> j;
    for (const BoardSample& b : samples) {
      const double r = Model(*p, b.u, b.v, &j) - b.value;
      jtj += j.transpose() * j;
      jtr += j.transpose() * r;
    }
    *normal = jtj;
    bool improved = false;
    for (int tries = 0; tries < 8 && !improved; ++tries) {
      Eigen::Matrix<double, 6, 6> a = jtj;
      a.diagonal() *= 1.0 + lambda;
      const Params step = a.ldlt().solve(-jtr);
      if (!step.allFinite()) break;
      const Params next = *p + step;
      const double c = cost(next);
      if (c < ssr) {
        improved = true;
        const bool converged = ssr - c < 1e-12 * (1 + ssr) && step.head<2>().norm() < 1e-7;
        *p = next;
        ssr = c;
        lambda = std::max(lambda * 0.3, 1e-9);
        if (converged) return ssr;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  return ssr;
}

// The board at cell (r0, c0): its plane from the cells on the pattern, then the pattern model
// fitted to the reflectance where their lines of sight meet the plane; none when a check fails.
std::optional<DetectedChecker> FitAt(const Grid& g, int r0, int c0, const CheckerTargetOptions& o) {
  const double size = o.size_m;
  const Eigen::Vector3d p0 = g.scan.Point(r0, c0).cast<double>();
  const double range = p0.norm();
  // The cells on the pattern (the square's inscribed circle, less the candidate's noise): the
  // plane from the board alone, not the wall it may stand a little in front of.
  const int wc = static_cast<int>(std::ceil(0.5 * size / (range * g.dc))), wr = static_cast<int>(std::ceil(0.5 * size / (range * g.dr)));
  std::vector<std::array<int, 2>> cells;
  for (int r = std::max(0, r0 - wr); r <= std::min(g.scan.rows - 1, r0 + wr); ++r)
    for (int dcol = -wc; dcol <= wc; ++dcol) {
      int c = c0 + dcol;
      if (g.pano.wraps) c = (c % g.scan.cols + g.scan.cols) % g.scan.cols;
      if (c < 0 || c >= g.scan.cols || !g.scan.IsValid(r, c)) continue;
      if ((g.scan.Point(r, c).cast<double>() - p0).norm() < 0.45 * size) cells.push_back({r, c});
    }
  if (static_cast<int>(cells.size()) < o.min_points) return std::nullopt;
  // The plane, twice refitted without the points beyond 3 RMS (a pole, a leaf, a mixed pixel).
  std::vector<char> in(cells.size(), 1);
  Eigen::Vector3d centroid, normal;
  double rms = 0;
  int used = 0;
  for (int pass = 0; pass < 3; ++pass) {
    centroid.setZero();
    used = 0;
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (in[i]) centroid += g.scan.Point(cells[i][0], cells[i][1]).cast<double>(), ++used;
    if (used < o.min_points) break;
    centroid /= used;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (in[i]) {
        const Eigen::Vector3d d = g.scan.Point(cells[i][0], cells[i][1]).cast<double>() - centroid;
        cov += d * d.transpose();
      }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / used);
    normal = eig.eigenvectors().col(0);
    rms = std::sqrt(std::max(eig.eigenvalues()[0], 0.0));
    for (std::size_t i = 0; i < cells.size(); ++i)
      in[i] = std::abs(normal.dot(g.scan.Point(cells[i][0], cells[i][1]).cast<double>() - centroid)) <=
              3.0 * std::max(rms, 1e-4);
  }
  if (used < o.min_points || rms > o.max_plane_rms_m) return std::nullopt;
  if (normal.dot(centroid) > 0) normal = -normal;  // towards the scanner
  const Eigen::Vector3d ray0 = p0.normalized();
  const double cos0 = -normal.dot(ray0);
  if (cos0 < 0.2) return std::nullopt;  // grazing: the board is too foreshortened to place
  const double offset = normal.dot(centroid);
  const Eigen::Vector3d q0 = ray0 * (offset / normal.dot(ray0));
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitZ().cross(normal);
  if (e1.norm() < 0.1) e1 = Eigen::Vector3d::UnitX().cross(normal);
  e1.normalize();
  const Eigen::Vector3d e2 = normal.cross(e1);
  // Board samples: each line of sight meets the plane; only cells inside the pattern and on the plane.
  std::vector<BoardSample> samples;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (!in[i]) continue;
    const Eigen::Vector3d d = g.scan.Point(cells[i][0], cells[i][1]).cast<double>().normalized();
    const Eigen::Vector3d x = d * (offset / normal.dot(d)) - q0;
    const double u = x.dot(e1), v = x.dot(e2);
    if (std::hypot(u, v) <= 0.4 * size) samples.push_back({u, v, g.scan.Reflectance(cells[i][0], cells[i][1])});
  }
  if (static_cast<int>(samples.size()) < o.min_points) return std::nullopt;
  double mean = 0;
  for (const BoardSample& b : samples) mean += b.value;
  mean /= samples.size();
  const double footprint = std::max(0.5 * range * g.dc / cos0, 0.01 * size);
  Params best;
  double best_ssr = INFINITY;
  Eigen::Matrix<double, 6, 6> best_normal;
  for (int k = 0; k < 4; ++k) {
    Params p;
    p << 0, 0, k * M_PI / 8, mean, 0, std::log(footprint);
    double b = 0;
    for (const BoardSample& s : samples) {
      const double c = std::cos(p[2]), sn = std::sin(p[2]);
      const double x = s.u * c + s.v * sn, y = -s.u * sn + s.v * c;
      b += (s.value - mean) * (x * y > 0 ? 1 : -1);
    }
    p[4] = b / samples.size();
    Eigen::Matrix<double, 6, 6> normal_matrix;
    const double ssr = FitPattern(samples, &p, &normal_matrix);
    if (ssr < best_ssr) best_ssr = ssr, best = p, best_normal = normal_matrix;
  }
  if (!std::isfinite(best_ssr)) return std::nullopt;
  const double contrast = 2 * std::abs(best[4]), s_edge = std::exp(best[5]);
  const int n = static_cast<int>(samples.size());
  const double fit_rms = std::sqrt(best_ssr / n);
  if (contrast < o.min_contrast || fit_rms > 0.15 * contrast) return std::nullopt;
  if (std::hypot(best[0], best[1]) > 0.15 * size || s_edge > 0.2 * size) return std::nullopt;
  // Four alternating quarters, each seen clear of the edges.
  std::array<int, 4> count{}, agree{};
  for (const BoardSample& s : samples) {
    const double c = std::cos(best[2]), sn = std::sin(best[2]);
    const double du = s.u - best[0], dv = s.v - best[1];
    const double x = du * c + dv * sn, y = -du * sn + dv * c;
    if (std::abs(x) < s_edge || std::abs(y) < s_edge) continue;
    const int q = (x > 0 ? 1 : 0) + (y > 0 ? 2 : 0);
    ++count[q];
    agree[q] += ((s.value - best[3]) * best[4] * (x * y > 0 ? 1 : -1)) > 0.5 * best[4] * best[4];
  }
  bool quarters = true;
  for (int q = 0; q < 4; ++q) quarters = quarters && count[q] >= 1 && agree[q] >= 0.8 * count[q];
  if (!quarters) return std::nullopt;
  const Eigen::Matrix<double, 6, 6> cov = best_normal.inverse() * (best_ssr / std::max(1, n - 6));
  if (!cov.allFinite()) return std::nullopt;
  const double sigma_in_plane = std::sqrt(std::max(cov.topLeftCorner<2, 2>().eigenvalues().real().maxCoeff(), 0.0));
  const double sigma_across = rms / std::sqrt(static_cast<double>(used)) / cos0;  // along the line of sight
  const double sigma = std::hypot(sigma_in_plane, sigma_across);
  if (!(sigma <= o.max_sigma_m)) return std::nullopt;
  DetectedChecker d;
  d.center = q0 + best[0] * e1 + best[1] * e2;
  if (!d.center.allFinite()) return std::nullopt;
  d.normal = normal;
  d.sigma_m = sigma;
  d.contrast = contrast;
  d.rms = fit_rms;
  d.points = n;
  return d;
}

}  // namespace

Status CheckerTargetOptions::Validate() const {
  auto bad = [](const std::string& w) { return MakeError(ErrorCode::kInvalidArgument, "checkerboard targets: " + w); };
  if (!(size_m >= 0.02 && size_m <= 2.0)) return bad("the pattern size must be in [0.02, 2] m");
  if (!(max_range_m > 0 && max_range_m <= 10000)) return bad("the maximum range must be in (0, 10000] m");
  if (!(min_contrast > 0 && min_contrast <= 1)) return bad("the minimum contrast must be in (0, 1]");
  if (min_points < 8) return bad("at least 8 cells are needed to fit the pattern");
  if (!(max_sigma_m > 0 && max_sigma_m <= 1)) return bad("the centre's sigma limit must be in (0, 1] m");
  if (!(max_plane_rms_m > 0 && max_plane_rms_m <= 1)) return bad("the plane RMS limit must be in (0, 1] m");
  return Status::Ok();
}

std::optional<DetectedChecker> FitCheckerTargetAt(const Scan& scan, int row, int col, int search_cells,
                                                  const CheckerTargetOptions& o) {
  if (!o.Validate() || scan.rows < 5 || scan.cols < 5) return std::nullopt;
  const std::optional<Grid> grid = MakeGrid(scan);
  if (!grid) return std::nullopt;
  // Start from the strongest response near the click (a click is rarely on the centre's cell).
  float best = 0;
  int br = row, bc = col;
  for (int r = std::max(0, row - search_cells); r <= std::min(scan.rows - 1, row + search_cells); ++r)
    for (int c = std::max(0, col - search_cells); c <= std::min(scan.cols - 1, col + search_cells); ++c) {
      const float v = Response(*grid, r, c, o);
      if (v > best) best = v, br = r, bc = c;
    }
  if (!(best > 0)) return std::nullopt;
  return FitAt(*grid, br, bc, o);
}

Expected<std::vector<DetectedChecker>> DetectCheckerTargets(const Scan& scan, const CheckerTargetOptions& o,
                                                            const CancelToken& cancel) {
  if (Status s = o.Validate(); !s) return s.error();
  if (scan.rows < 5 || scan.cols < 5) {
    return MakeError(ErrorCode::kInvalidArgument, "scan " + scan.name + ": finding checkerboard targets needs an "
                                                  "organized scan grid (rows x columns); this scan has " +
                                                      std::to_string(scan.rows) + " x " + std::to_string(scan.cols));
  }
  std::vector<DetectedChecker> found;
  const std::optional<Grid> grid = MakeGrid(scan);
  if (!grid) return found;
  const double size = o.size_m;

  // 1. ChESS response on a ring of 0.3 of the pattern's size; local maxima above the threshold.
  std::vector<float> response(scan.size(), 0.0f);
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < scan.rows; ++r) {
    if (cancel.IsCancelled()) continue;
    for (int c = 0; c < scan.cols; ++c) response[scan.Index(r, c)] = Response(*grid, r, c, o);
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "target search cancelled");
  const double threshold = 4.0 * o.min_contrast;
  std::vector<std::pair<float, std::size_t>> candidates;
  for (int r = 1; r + 1 < scan.rows; ++r) {
    for (int c = 1; c + 1 < scan.cols; ++c) {
      const float v = response[scan.Index(r, c)];
      if (v < threshold) continue;
      bool peak = true;
      for (int dy = -2; dy <= 2 && peak; ++dy)
        for (int dx = -2; dx <= 2 && peak; ++dx) {
          const int rr = r + dy, cc = c + dx;
          if ((dy || dx) && rr >= 0 && rr < scan.rows && cc >= 0 && cc < scan.cols)
            peak = response[scan.Index(rr, cc)] < v || (response[scan.Index(rr, cc)] == v && (dy > 0 || (dy == 0 && dx > 0)));
        }
      if (peak) candidates.push_back({v, scan.Index(r, c)});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  if (candidates.size() > 400) candidates.resize(400);

  // 2-3. Plane and pattern fit round each candidate.
  for (const auto& [score, index] : candidates) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "target search cancelled");
    const std::optional<DetectedChecker> fit =
        FitAt(*grid, static_cast<int>(index / scan.cols), static_cast<int>(index % scan.cols), o);
    if (!fit) continue;
    const DetectedChecker& d = *fit;
    bool duplicate = false;
    for (DetectedChecker& k : found) {
      if ((k.center - d.center).norm() < 0.5 * size) {
        if (d.sigma_m < k.sigma_m) k = d;
        duplicate = true;
        break;
      }
    }
    if (!duplicate) found.push_back(d);
  }
  std::sort(found.begin(), found.end(),
            [](const DetectedChecker& a, const DetectedChecker& b) { return a.center.norm() < b.center.norm(); });
  return found;
}

}  // namespace scanreg::georef
