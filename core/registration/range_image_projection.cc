#include "core/registration/range_image_projection.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

namespace scanreg {
namespace {

constexpr int kMinCells = 12;

struct Cell {
  Eigen::Vector3d p;
  double col, row;
};

// Normalised DLT (Hartley & Zisserman, Alg. 7.1): pixel ~ P [p; 1], P 3x4, rows (col, row, w).
bool FitProjective(const std::vector<Cell>& cells, Eigen::Matrix<double, 3, 4>* camera) {
  Eigen::Vector3d mp = Eigen::Vector3d::Zero();
  Eigen::Vector2d mq = Eigen::Vector2d::Zero();
  for (const Cell& c : cells) {
    mp += c.p;
    mq += Eigen::Vector2d(c.col, c.row);
  }
  mp /= double(cells.size());
  mq /= double(cells.size());
  double dp = 0, dq = 0;
  for (const Cell& c : cells) {
    dp += (c.p - mp).norm();
    dq += (Eigen::Vector2d(c.col, c.row) - mq).norm();
  }
  const double sp = std::sqrt(3.0) * cells.size() / std::max(dp, 1e-300);
  const double sq = std::sqrt(2.0) * cells.size() / std::max(dq, 1e-300);
  Eigen::Matrix<double, 12, 12> ata = Eigen::Matrix<double, 12, 12>::Zero();
  for (const Cell& c : cells) {
    Eigen::Vector4d x;
    x << sp * (c.p - mp), 1.0;
    const double u = sq * (c.col - mq.x()), v = sq * (c.row - mq.y());
    Eigen::Matrix<double, 12, 1> r1 = Eigen::Matrix<double, 12, 1>::Zero(), r2 = r1;
    r1.segment<4>(0) = x;
    r1.segment<4>(8) = -u * x;
    r2.segment<4>(4) = x;
    r2.segment<4>(8) = -v * x;
    ata.selfadjointView<Eigen::Lower>().rankUpdate(r1);
    ata.selfadjointView<Eigen::Lower>().rankUpdate(r2);
  }
  ata = ata.selfadjointView<Eigen::Lower>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eig(ata);
  if (eig.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, 12, 1> h = eig.eigenvectors().col(0);
  Eigen::Matrix<double, 3, 4> pn;
  pn << h.segment<4>(0).transpose(), h.segment<4>(4).transpose(), h.segment<4>(8).transpose();
  Eigen::Matrix4d tp = Eigen::Matrix4d::Identity();
  tp.topLeftCorner<3, 3>() *= sp;
  tp.topRightCorner<3, 1>() = -sp * mp;
  Eigen::Matrix3d tq_inv = Eigen::Matrix3d::Identity();
  tq_inv.topLeftCorner<2, 2>() /= sq;
  tq_inv.topRightCorner<2, 1>() = mq;
  *camera = tq_inv * pn * tp;
  // Points in front: w > 0.
  double wsum = 0;
  for (const Cell& c : cells) wsum += (*camera).row(2).dot(Eigen::Vector4d(c.p.x(), c.p.y(), c.p.z(), 1.0)) > 0 ? 1 : -1;
  if (wsum < 0) *camera = -*camera;
  return camera->allFinite();
}

// Least squares col = a . [p; 1], row = b . [p; 1].
bool FitAffine(const std::vector<Cell>& cells, Eigen::Matrix<double, 3, 4>* camera) {
  Eigen::Vector3d mp = Eigen::Vector3d::Zero();
  for (const Cell& c : cells) mp += c.p;
  mp /= double(cells.size());
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
  Eigen::Vector4d atu = Eigen::Vector4d::Zero(), atv = Eigen::Vector4d::Zero();
  for (const Cell& c : cells) {
    Eigen::Vector4d x;
    x << c.p - mp, 1.0;
    ata += x * x.transpose();
    atu += c.col * x;
    atv += c.row * x;
  }
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(ata);
  if (ldlt.info() != Eigen::Success) return false;
  Eigen::Vector4d a = ldlt.solve(atu), b = ldlt.solve(atv);
  // Undo the centring: a . [p - mp; 1] = a.head(3) . p + (a(3) - a.head(3) . mp).
  a(3) -= a.head<3>().dot(mp);
  b(3) -= b.head<3>().dot(mp);
  camera->row(0) = a.transpose();
  camera->row(1) = b.transpose();
  camera->row(2) << 0, 0, 0, 1;
  return camera->allFinite() && a.head<3>().cross(b.head<3>()).norm() > 0;
}

void Residuals(const std::vector<Cell>& cells, const Eigen::Matrix<double, 3, 4>& camera, double* rms, double* max) {
  double sum = 0, mx = 0;
  for (const Cell& c : cells) {
    const Eigen::Vector3d h = camera * Eigen::Vector4d(c.p.x(), c.p.y(), c.p.z(), 1.0);
    const double e2 = std::pow(h.x() / h.z() - c.col, 2) + std::pow(h.y() / h.z() - c.row, 2);
    sum += e2;
    mx = std::max(mx, e2);
  }
  *rms = std::sqrt(sum / cells.size());
  *max = std::sqrt(mx);
}

}  // namespace

const char* GridCameraModelName(GridCameraModel model) {
  switch (model) {
    case GridCameraModel::kAngular: return "angular";
    case GridCameraModel::kProjective: return "projective";
    case GridCameraModel::kAffine: return "affine";
  }
  return "?";
}

Status RangeImageOptions::Validate() const {
  if (!(edge_spacing_ratio > 1.0) || !std::isfinite(edge_spacing_ratio))
    return MakeError(ErrorCode::kInvalidArgument, "range image: edge_spacing_ratio must be > 1 (e.g. 8)");
  if (!(min_edge_break_m >= 0.0) || !std::isfinite(min_edge_break_m))
    return MakeError(ErrorCode::kInvalidArgument, "range image: min_edge_break_m must be >= 0 metres");
  if (!(prefer_projective_ratio > 0.0 && prefer_projective_ratio <= 1.0))
    return MakeError(ErrorCode::kInvalidArgument, "range image: prefer_projective_ratio must be in (0, 1]");
  return Status::Ok();
}

Expected<RangeImageProjection> RangeImageProjection::Create(const Scan& scan, const RangeImageOptions& options) {
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = scan.Validate(); !s) return s.error();
  if (scan.rows < 2 || scan.cols < 2)
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + scan.name + "': grid smaller than 2 x 2");
  RangeImageProjection proj;
  proj.scan_ = &scan;
  std::vector<Cell> cells;
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c)
      if (scan.IsValid(r, c)) cells.push_back({scan.Point(r, c).cast<double>(), double(c), double(r)});
  if (static_cast<int>(cells.size()) < kMinCells)
    return MakeError(ErrorCode::kInvalidArgument,
                     "scan '" + scan.name + "': fewer than 12 valid cells, cannot use it as a range image");
  proj.fit_.cells = static_cast<int>(cells.size());

  if (!scan.angles.empty()) {
    const auto& az = scan.angles.azimuth;
    const auto& el = scan.angles.elevation;
    proj.az0_ = az.front();
    // Mean step between neighbouring columns (each wrapped to (-pi, pi]): also right for a full
    // turn, whose first and last columns are neighbours.
    double span = 0;
    for (int c = 0; c + 1 < scan.cols; ++c) span += std::remainder(double(az[c + 1]) - az[c], 2 * M_PI);
    proj.daz_ = span / (scan.cols - 1);
    if (std::abs(proj.daz_) < 1e-12) return MakeError(ErrorCode::kInvalidArgument, "scan '" + scan.name + "': flat azimuth grid");
    proj.el0_ = el.front();
    proj.del_ = (double(el.back()) - el.front()) / (scan.rows - 1);
    if (std::abs(proj.del_) < 1e-12) return MakeError(ErrorCode::kInvalidArgument, "scan '" + scan.name + "': flat elevation grid");
    proj.wraps_ = std::abs(proj.daz_ * scan.cols) > 2 * M_PI * 0.97;
    proj.fit_.model = GridCameraModel::kAngular;
    double sum = 0, mx = 0;
    for (const Cell& c : cells) {
      double row = 0, col = 0;
      if (!proj.Project(c.p, &row, &col)) continue;
      double dc = std::abs(col - c.col);
      if (proj.wraps_) dc = std::min(dc, scan.cols - dc);
      const double e2 = dc * dc + (row - c.row) * (row - c.row);
      sum += e2;
      mx = std::max(mx, e2);
    }
    proj.fit_.rms_px = std::sqrt(sum / cells.size());
    proj.fit_.max_px = std::sqrt(mx);
  } else {
    Eigen::Matrix<double, 3, 4> projective, affine;
    double prms = -1, pmax = 0, arms = -1, amax = 0;
    bool pok = FitProjective(cells, &projective);
    if (pok) {
      const Eigen::Matrix3d m = projective.leftCols<3>();
      pok = std::abs(m.determinant()) > 1e-12 * std::pow(m.norm(), 3);
      if (pok) Residuals(cells, projective, &prms, &pmax);
      pok = pok && std::isfinite(prms);
    }
    const bool aok = FitAffine(cells, &affine);
    if (aok) Residuals(cells, affine, &arms, &amax);
    if (!pok && !aok)
      return MakeError(ErrorCode::kFailed, "scan '" + scan.name + "': no camera fits its grid (degenerate points)");
    proj.fit_.projective_rms_px = pok ? prms : -1;
    proj.fit_.affine_rms_px = aok ? arms : -1;
    const bool use_projective = pok && (!aok || prms < options.prefer_projective_ratio * arms);
    if (use_projective) {
      proj.fit_.model = GridCameraModel::kProjective;
      proj.camera_ = projective;
      proj.centre_ = -projective.leftCols<3>().inverse() * projective.col(3);
      proj.fit_.rms_px = prms;
      proj.fit_.max_px = pmax;
    } else {
      proj.fit_.model = GridCameraModel::kAffine;
      proj.camera_ = affine;
      Eigen::Vector3d d = affine.row(0).head<3>().transpose().cross(affine.row(1).head<3>().transpose()).normalized();
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const Cell& c : cells) mean += c.p;
      if (d.dot(mean) < 0) d = -d;  // away from the scan frame's origin
      proj.direction_ = d;
      proj.fit_.rms_px = arms;
      proj.fit_.max_px = amax;
    }
    // Median neighbour spacing: the discontinuity scale of fitted-camera grids.
    std::vector<double> d;
    for (int r = 0; r < scan.rows; ++r)
      for (int c = 0; c < scan.cols; ++c) {
        if (!scan.IsValid(r, c)) continue;
        if (c + 1 < scan.cols && scan.IsValid(r, c + 1)) d.push_back((scan.Point(r, c) - scan.Point(r, c + 1)).norm());
        if (r + 1 < scan.rows && scan.IsValid(r + 1, c)) d.push_back((scan.Point(r, c) - scan.Point(r + 1, c)).norm());
      }
    if (!d.empty()) {
      std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
      proj.median_spacing_m_ = d[d.size() / 2];
    }
  }
  proj.BuildMesh(options);
  return proj;
}

double RangeImageProjection::Spacing(const Eigen::Vector3f& a, const Eigen::Vector3f& b) const {
  if (fit_.model == GridCameraModel::kAngular)
    return 0.5 * (a.norm() + b.norm()) * std::max(std::abs(daz_), std::abs(del_));
  return median_spacing_m_;
}

void RangeImageProjection::BuildMesh(const RangeImageOptions& options) {
  const Scan& s = *scan_;
  quad_cols_ = wraps_ ? s.cols : s.cols - 1;
  triangles_.assign(static_cast<std::size_t>(s.rows - 1) * quad_cols_, 0);
  valid_triangles_ = 0;
  auto edge_ok = [&](int r0, int c0, int r1, int c1) {
    const Eigen::Vector3f& a = s.Point(r0, c0);
    const Eigen::Vector3f& b = s.Point(r1, c1);
    return (a - b).norm() <= std::max(options.edge_spacing_ratio * Spacing(a, b), options.min_edge_break_m);
  };
  for (int r = 0; r + 1 < s.rows; ++r) {
    for (int c = 0; c < quad_cols_; ++c) {
      const int c1 = (c + 1) % s.cols;
      const bool v00 = s.IsValid(r, c), v01 = s.IsValid(r, c1), v10 = s.IsValid(r + 1, c), v11 = s.IsValid(r + 1, c1);
      const bool diag = v01 && v10 && edge_ok(r, c1, r + 1, c);
      std::uint8_t bits = 0;
      if (diag && v00 && edge_ok(r, c, r, c1) && edge_ok(r, c, r + 1, c)) bits |= 1;
      if (diag && v11 && edge_ok(r + 1, c1, r + 1, c) && edge_ok(r + 1, c1, r, c1)) bits |= 2;
      triangles_[static_cast<std::size_t>(r) * quad_cols_ + c] = bits;
      valid_triangles_ += (bits & 1) + (bits >> 1);
    }
  }
}

bool RangeImageProjection::Project(const Eigen::Vector3d& p, double* row, double* col) const {
  const Scan& s = *scan_;
  double r = 0, c = 0;
  if (fit_.model == GridCameraModel::kAngular) {
    const double az = std::atan2(p.y(), p.x());
    const double el = std::atan2(p.z(), std::hypot(p.x(), p.y()));
    c = std::remainder(az - az0_, 2 * M_PI) / daz_;
    if (wraps_) c = std::fmod(c + 2.0 * s.cols, double(s.cols));
    r = (el - el0_) / del_;
  } else {
    const Eigen::Vector3d h = camera_ * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    if (!(h.z() > 0)) return false;
    c = h.x() / h.z();
    r = h.y() / h.z();
  }
  if (!(r >= 0 && r <= s.rows - 1)) return false;
  if (!(c >= 0 && c <= (wraps_ ? s.cols : s.cols - 1))) return false;
  *row = r;
  *col = c;
  return true;
}

Eigen::Vector3d RangeImageProjection::LineOfSight(const Eigen::Vector3d& p) const {
  switch (fit_.model) {
    case GridCameraModel::kAngular: return p.normalized();
    case GridCameraModel::kProjective: return (p - centre_).normalized();
    case GridCameraModel::kAffine: return direction_;
  }
  return p.normalized();
}

bool RangeImageProjection::Triangle(double row, double col, Eigen::Vector3d tri[3], double* a, double* b) const {
  const Scan& s = *scan_;
  if (!(row >= 0 && row <= s.rows - 1)) return false;
  const int r0 = std::min(static_cast<int>(row), s.rows - 2);
  const double v = row - r0;
  int c0 = 0;
  double u = 0;
  if (wraps_) {
    if (!(col >= 0 && col <= s.cols)) return false;
    const double fc = std::floor(col);
    u = col - fc;
    c0 = static_cast<int>(fc) % s.cols;
  } else {
    if (!(col >= 0 && col <= s.cols - 1)) return false;
    c0 = std::min(static_cast<int>(col), s.cols - 2);
    u = col - c0;
  }
  const int c1 = (c0 + 1) % s.cols;
  const std::uint8_t bits = triangles_[static_cast<std::size_t>(r0) * quad_cols_ + c0];
  if (u + v <= 1.0) {
    if (!(bits & 1)) return false;
    tri[0] = s.Point(r0, c0).cast<double>();
    tri[1] = s.Point(r0, c1).cast<double>();
    tri[2] = s.Point(r0 + 1, c0).cast<double>();
    *a = u;
    *b = v;
  } else {
    if (!(bits & 2)) return false;
    tri[0] = s.Point(r0 + 1, c1).cast<double>();
    tri[1] = s.Point(r0 + 1, c0).cast<double>();
    tri[2] = s.Point(r0, c1).cast<double>();
    *a = 1 - u;
    *b = 1 - v;
  }
  return true;
}

bool RangeImageProjection::SurfaceAt(double row, double col, Eigen::Vector3d* point) const {
  Eigen::Vector3d t[3];
  double a = 0, b = 0;
  if (!Triangle(row, col, t, &a, &b)) return false;
  *point = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
  return true;
}

bool RangeImageProjection::SurfaceAlongLineOfSight(const Eigen::Vector3d& p, Eigen::Vector3d* surface) const {
  double row = 0, col = 0, a = 0, b = 0;
  Eigen::Vector3d t[3];
  if (!Project(p, &row, &col) || !Triangle(row, col, t, &a, &b)) return false;
  // Intersect the line of sight through p with the triangle's plane: the measurement lies exactly
  // on that line (the grid's sub-pixel interpolation alone drifts off it by a fraction of the
  // spacing, a systematic tangential residual that projective ICP cannot correct).
  const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  const Eigen::Vector3d l = LineOfSight(p);
  const double den = n.dot(l);
  if (std::abs(den) > 1e-3 * n.norm()) {
    *surface = p + (n.dot(t[0] - p) / den) * l;
  } else {
    *surface = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);  // grazing: the interpolated point
  }
  return true;
}

}  // namespace scanreg
