#include "core/georef/sphere_targets.h"

#include "core/georef/angular_steps.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace scanreg::georef {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Key {
  long x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return static_cast<std::size_t>(k.x * 73856093L ^ k.y * 19349663L ^ k.z * 83492791L);
  }
};

}  // namespace

Status SphereTargetOptions::Validate() const {
  auto bad = [](const std::string& w) { return MakeError(ErrorCode::kInvalidArgument, "sphere targets: " + w); };
  if (!(radius_m >= 0.005 && radius_m <= 2.0)) return bad("the radius must be in [0.005, 2] m");
  if (!(max_range_m > 0 && max_range_m <= 10000)) return bad("the maximum range must be in (0, 10000] m");
  if (min_points < 4) return bad("at least 4 points are needed to fit a sphere");
  if (!(min_coverage >= 0 && min_coverage <= 1)) return bad("the coverage must be in [0, 1]");
  if (!(min_cap_deg >= 0 && min_cap_deg < 90)) return bad("the cap angle must be in [0, 90) degrees");
  if (!(max_rms_fraction > 0 && max_rms_fraction <= 1)) return bad("the RMS fraction must be in (0, 1]");
  if (!(max_sigma_fraction > 0 && max_sigma_fraction <= 1)) return bad("the sigma fraction must be in (0, 1]");
  return Status::Ok();
}

Eigen::Vector3d FitSphereCenter(const std::vector<Eigen::Vector3d>& points, double radius, const Eigen::Vector3d& start,
                                double* rms_m) {
  Eigen::Vector3d c = start;
  for (int it = 0; it < 20 && points.size() >= 3; ++it) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtf = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d d = p - c;
      const double n = d.norm();
      if (n < 1e-12) continue;
      const Eigen::Vector3d j = -d / n;
      jtj += j * j.transpose();
      jtf += j * (n - radius);
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtf);
    if (!step.allFinite()) break;
    c += step;
    if (step.norm() < 1e-9) break;
  }
  if (rms_m) {
    double s = 0;
    for (const Eigen::Vector3d& p : points) s += std::pow((p - c).norm() - radius, 2);
    *rms_m = points.empty() ? 0.0 : std::sqrt(s / points.size());
  }
  return c;
}

Expected<std::vector<DetectedSphere>> DetectSphereTargets(const Scan& scan, const SphereTargetOptions& o,
                                                          const CancelToken& cancel) {
  if (Status s = o.Validate(); !s) return s.error();
  if (scan.rows < 5 || scan.cols < 5) {
    return MakeError(ErrorCode::kInvalidArgument, "scan " + scan.name + ": finding sphere targets needs an organized "
                                                  "scan grid (rows x columns); this scan has " +
                                                      std::to_string(scan.rows) + " x " + std::to_string(scan.cols));
  }
  const double r = o.radius_m;
  double dc = 0, dr = 0;
  AngularSteps(scan, &dc, &dr);
  std::vector<DetectedSphere> found;
  if (!(dc > 0) || !(dr > 0)) return found;
  const double step_angle = std::sqrt(dc * dr);

  // Pass 1: each cell's centre candidate p - r n, n from neighbours about r/2 apart.
  const std::size_t n_cells = scan.size();
  std::vector<Eigen::Vector3f> cand(n_cells);
  std::vector<std::uint8_t> has(n_cells, 0), step(n_cells, 1);
  for (int row = 0; row < scan.rows; ++row) {
    if (row % 64 == 0 && cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "target search cancelled");
    for (int col = 0; col < scan.cols; ++col) {
      if (!scan.IsValid(row, col)) continue;
      const Eigen::Vector3d p = scan.Point(row, col).cast<double>();
      const double d = p.norm();
      if (d > o.max_range_m || d < 2 * r) continue;
      const int s = std::clamp(static_cast<int>(std::lround(0.3 * r / (d * step_angle))), 1, 8);
      if (row < s || row + s >= scan.rows || col < s || col + s >= scan.cols) continue;
      if (!scan.IsValid(row, col - s) || !scan.IsValid(row, col + s) || !scan.IsValid(row - s, col) ||
          !scan.IsValid(row + s, col))
        continue;
      const Eigen::Vector3d a = (scan.Point(row, col + s) - scan.Point(row, col - s)).cast<double>();
      const Eigen::Vector3d b = (scan.Point(row + s, col) - scan.Point(row - s, col)).cast<double>();
      const double limit = 4.0 * s * d * step_angle + 2 * r;  // no depth jump inside the stencil
      if (a.norm() > limit || b.norm() > limit) continue;
      Eigen::Vector3d n = a.cross(b);
      const double nn = n.norm();
      if (nn < 1e-12) continue;
      n /= nn;
      if (n.dot(p) > 0) n = -n;  // towards the scanner
      if (-n.dot(p) / d < 0.2) continue;  // grazing
      const std::size_t i = scan.Index(row, col);
      cand[i] = (p - r * n).cast<float>();
      has[i] = 1;
      step[i] = static_cast<std::uint8_t>(s);
    }
  }
  // Pass 2: a cell votes when its grid neighbours agree on the centre (a sphere's do, a plane's
  // are r/2 apart, a pole's differ along its axis).
  const float agree = static_cast<float>(0.25 * r);
  std::unordered_map<Key, std::vector<std::size_t>, KeyHash> votes;
  const double cell = 0.5 * r;
  for (int row = 0; row < scan.rows; ++row) {
    for (int col = 0; col < scan.cols; ++col) {
      const std::size_t i = scan.Index(row, col);
      if (!has[i]) continue;
      const int s = step[i];
      int agreeing = 0;
      for (const auto& [dy, dx] : {std::pair{0, s}, {0, -s}, {s, 0}, {-s, 0}}) {
        const int rr = row + dy, cc = col + dx;
        if (rr < 0 || rr >= scan.rows || cc < 0 || cc >= scan.cols) continue;
        const std::size_t j = scan.Index(rr, cc);
        if (has[j] && (cand[j] - cand[i]).norm() < agree) ++agreeing;
      }
      if (agreeing < 2) continue;
      const Eigen::Vector3f& c = cand[i];
      votes[{static_cast<long>(std::floor(c.x() / cell)), static_cast<long>(std::floor(c.y() / cell)),
             static_cast<long>(std::floor(c.z() / cell))}]
          .push_back(i);
    }
  }
  // Clusters of vote cells (26-connected).
  std::unordered_map<Key, int, KeyHash> label;
  std::vector<std::vector<std::size_t>> clusters;
  for (const auto& [key, cells] : votes) {
    if (label.count(key)) continue;
    const int id = static_cast<int>(clusters.size());
    clusters.emplace_back();
    std::vector<Key> stack{key};
    label[key] = id;
    while (!stack.empty()) {
      const Key k = stack.back();
      stack.pop_back();
      const auto& members = votes.at(k);
      clusters[id].insert(clusters[id].end(), members.begin(), members.end());
      for (long x = -1; x <= 1; ++x)
        for (long y = -1; y <= 1; ++y)
          for (long z = -1; z <= 1; ++z) {
            const Key nk{k.x + x, k.y + y, k.z + z};
            if (votes.count(nk) && !label.count(nk)) {
              label[nk] = id;
              stack.push_back(nk);
            }
          }
    }
  }
  // Fit and verify each cluster.
  for (const std::vector<std::size_t>& members : clusters) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "target search cancelled");
    if (members.size() < 2) continue;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    int r0 = scan.rows, r1 = -1, c0 = scan.cols, c1 = -1;
    for (std::size_t i : members) {
      c += cand[i].cast<double>();
      const int row = static_cast<int>(i / scan.cols), col = static_cast<int>(i % scan.cols);
      r0 = std::min(r0, row), r1 = std::max(r1, row), c0 = std::min(c0, col), c1 = std::max(c1, col);
    }
    c /= static_cast<double>(members.size());
    const double d = c.norm();
    if (d < 2 * r) continue;
    // A sphere's votes gather within noise of its centre; a plane's or a pole's spread out.
    double spread = 0;
    for (std::size_t i : members) spread += (cand[i].cast<double>() - c).squaredNorm();
    if (std::sqrt(spread / members.size()) > 0.3 * r) continue;
    // The sphere's cells: the window the whole sphere covers at this range.
    const int half_rows = static_cast<int>(std::ceil(1.5 * r / (d * dr))) + 2;
    const int half_cols = static_cast<int>(std::ceil(1.5 * r / (d * dc))) + 2;
    const int mid_row = (r0 + r1) / 2, mid_col = (c0 + c1) / 2;
    std::vector<Eigen::Vector3d> window;
    for (int row = std::max(0, mid_row - half_rows); row <= std::min(scan.rows - 1, mid_row + half_rows); ++row)
      for (int col = std::max(0, mid_col - half_cols); col <= std::min(scan.cols - 1, mid_col + half_cols); ++col)
        if (scan.IsValid(row, col)) window.push_back(scan.Point(row, col).cast<double>());
    std::vector<Eigen::Vector3d> fit;
    double tol = 0.25 * r, rms = 0;
    for (int round = 0; round < 4; ++round) {
      fit.clear();
      for (const Eigen::Vector3d& p : window)
        if (std::abs((p - c).norm() - r) < tol) fit.push_back(p);
      if (static_cast<int>(fit.size()) < o.min_points) break;
      c = FitSphereCenter(fit, r, c, &rms);
      tol = std::max(3.0 * rms, 0.002);
    }
    if (static_cast<int>(fit.size()) < o.min_points || rms > o.max_rms_fraction * r) continue;
    const double range = c.norm();
    const double expected = M_PI * r * r / (range * dc * range * dr);
    const double coverage = fit.size() / expected;
    if (coverage < o.min_coverage) continue;
    const Eigen::Vector3d towards = -c / range;
    std::vector<double> angles;
    int inside = 0;
    for (const Eigen::Vector3d& p : fit) angles.push_back(std::acos(std::clamp((p - c).normalized().dot(towards), -1.0, 1.0)));
    for (const Eigen::Vector3d& p : window)
      if ((p - c).norm() < r - std::max(3.0 * rms, 0.002)) ++inside;
    std::nth_element(angles.begin(), angles.begin() + angles.size() * 9 / 10, angles.end());
    if (angles[angles.size() * 9 / 10] < o.min_cap_deg * kDeg) continue;
    if (inside > 0.1 * fit.size()) continue;
    // Seen from the scanner a sphere is a disk the points fill evenly: their centroid near its
    // centre and their mean squared distance from it r^2 / 2. The round top of a pole, an edge or
    // an arc of a larger curve fills it unevenly.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double second = 0;
    for (const Eigen::Vector3d& p : fit) {
      const Eigen::Vector3d across = (p - c) - towards * (p - c).dot(towards);
      mean += across;
      second += across.squaredNorm();
    }
    mean /= static_cast<double>(fit.size());
    second /= static_cast<double>(fit.size()) * r * r;
    if (mean.norm() > 0.25 * r || second < 0.3 || second > 0.7) continue;
    // Centre covariance: s^2 (J^T J)^-1.
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& p : fit) {
      const Eigen::Vector3d j = (p - c).normalized();
      jtj += j * j.transpose();
    }
    const double dof = std::max<double>(1.0, static_cast<double>(fit.size()) - 3.0);
    const double s2 = rms * rms * fit.size() / dof;
    DetectedSphere sphere;
    sphere.center = c;
    sphere.rms_m = rms;
    sphere.points = static_cast<int>(fit.size());
    sphere.coverage = coverage;
    sphere.sigma_m = std::sqrt(std::max(0.0, (s2 * jtj.inverse()).trace()));
    if (!std::isfinite(sphere.sigma_m) || sphere.sigma_m > o.max_sigma_fraction * r) continue;
    found.push_back(sphere);
  }
  // One sphere per place: clusters of one sphere split by noise keep the best-supported fit.
  std::sort(found.begin(), found.end(), [](const DetectedSphere& a, const DetectedSphere& b) { return a.points > b.points; });
  std::vector<DetectedSphere> unique;
  for (const DetectedSphere& s : found) {
    bool dup = false;
    for (const DetectedSphere& u : unique) dup = dup || (u.center - s.center).norm() < r;
    if (!dup) unique.push_back(s);
  }
  std::sort(unique.begin(), unique.end(),
            [](const DetectedSphere& a, const DetectedSphere& b) { return a.center.norm() < b.center.norm(); });
  return unique;
}

}  // namespace scanreg::georef

