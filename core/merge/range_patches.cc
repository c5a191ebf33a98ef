#include "core/merge/range_patches.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/merge/point_normals.h"

namespace scanreg::merge {

namespace {

// Median distance between horizontally adjacent valid cells (a sample of them).
double MedianSpacing(const Scan& scan) {
  std::vector<float> d;
  const int step = std::max(1, int(scan.size() / 20000));
  for (std::size_t i = 0; i + 1 < scan.size(); i += step) {
    if ((i + 1) % scan.cols == 0 || !scan.valid[i] || !scan.valid[i + 1]) continue;
    d.push_back((scan.points[i + 1] - scan.points[i]).norm());
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// A scan's pose relative to the patches' origin.
Eigen::Isometry3f Shifted(const Scan& s, const Eigen::Vector3d& origin) {
  Eigen::Isometry3d shifted = s.world_from_scan;
  shifted.translation() -= origin;
  return shifted.cast<float>();
}

// The scan's range image for Curless–Levoy projection (empty without an angular grid).
RangeView MakeView(const Scan& s, const Eigen::Isometry3f& t) {
  RangeView view;
  if (!s.single_viewpoint || s.angles.empty() || int(s.angles.azimuth.size()) != s.cols || int(s.angles.elevation.size()) != s.rows) return view;
  view.scan_from_world = t.linear().transpose();
  view.eye = t.translation();
  view.angles = s.angles;
  view.rows = s.rows, view.cols = s.cols;
  auto range = std::make_shared<std::vector<float>>(s.size(), -1.0f);
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.valid[i]) (*range)[i] = s.points[i].norm();
  view.range = std::move(range);
  return view;
}

// Rows and columns kept of a range image much denser than the grid (every s-th).
int Stride(double spacing, double voxel_m) { return spacing > 0 ? std::clamp(int(0.5 * voxel_m / spacing), 1, 8) : 1; }

// atan2 within 1e-7 rad of std::atan2, several times faster: Abramowitz & Stegun 4.4.49 on
// [0, 1] (error 2e-8) with the octant symmetries.
inline float FastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float hi = std::max(ax, ay);
  if (hi == 0.0f) return 0.0f;
  const float a = std::min(ax, ay) / hi, s = a * a;
  float r = a * (0.9999993329f +
                 s * (-0.3332985605f +
                      s * (0.1994653599f +
                           s * (-0.1390853351f +
                                s * (0.0964200441f + s * (-0.0559098861f + s * (0.0218612288f - 0.0040540580f * s)))))));
  if (ay > ax) r = 1.57079632679f - r;
  if (x < 0.0f) r = 3.14159265359f - r;
  return y < 0.0f ? -r : r;
}

// Index i0 and fraction t with v between a[i0] and a[i0 + 1] (a monotonic, either direction);
// within half a step beyond the ends counts as the end cell. The search starts where v would be on
// an evenly spaced grid (scanners' angular steps are nearly even), so it takes a step or two.
bool Locate(const std::vector<float>& a, float v, int* i0, float* t) {
  const int n = int(a.size());
  if (n < 2) return false;
  const bool inc = a.back() > a.front();
  const float step = (a.back() - a.front()) / float(n - 1);
  const float guess = (v - a.front()) / step;
  int i = !(guess > 0.0f) ? 0 : (guess >= float(n) ? n : int(guess));  // NaN: from the start
  // lower_bound: the first i with a[i] not before v.
  auto before = [&](int k) { return inc ? a[k] < v : a[k] > v; };
  while (i > 0 && !before(i - 1)) --i;
  while (i < n && before(i)) ++i;
  if (i == 0) {
    if (std::abs(v - a[0]) > 0.5f * std::abs(a[1] - a[0])) return false;
    *i0 = 0, *t = 0.0f;
    return true;
  }
  if (i == n) {
    if (std::abs(v - a[n - 1]) > 0.5f * std::abs(a[n - 1] - a[n - 2])) return false;
    *i0 = n - 2, *t = 1.0f;
    return true;
  }
  *i0 = i - 1;
  *t = (v - a[i - 1]) / (a[i] - a[i - 1]);
  return true;
}

// The points of `s` that become discs, at t: its listed points, and every point of a cloud seen
// from several places; where they lie denser than half a voxel, the centroid of each half-voxel
// cube instead: a merged or mobile-mapping cloud holds hundreds of points per voxel near its
// stations. Measured (`scanreg-bench --section lists`: 21.6 M points, 5 cm voxel) against keeping
// every m-th point by the median spacing: 260 s against 249 s, 7.39 M vertices against 5.54 M (fewer
// holes where the cloud is sparse), peak 5.7 GB against 6.9 GB; quarter-voxel cubes: 475 s.
struct DiscSource {
  std::vector<Eigen::Vector3f> points;
  std::vector<Rgb> colours;              // per point when the scan has colour
  std::vector<Eigen::Vector3f> sensors;  // per point when the scan has sensor positions (at t)
};
DiscSource DiscPoints(const Scan& s, const Eigen::Isometry3f& t, double voxel_m) {
  DiscSource out;
  std::vector<Eigen::Vector3f>& points = out.points;
  const bool every_point = !s.single_viewpoint, coloured = s.HasColour(), sensed = s.HasSensor();
  points.reserve(s.list_points.size() + (every_point ? s.CountValid() : 0));
  if (every_point) {
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (!s.valid[i]) continue;
      points.push_back(t * s.points[i]);
      if (coloured) out.colours.push_back(s.colour[i]);
      if (sensed) out.sensors.push_back(t * s.sensor[i]);
    }
  }
  for (const Eigen::Vector3f& p : s.list_points) points.push_back(t * p);
  if (coloured) out.colours.insert(out.colours.end(), s.list_colour.begin(), s.list_colour.end());
  if (sensed)
    for (const Eigen::Vector3f& e : s.list_sensor) out.sensors.push_back(t * e);
  if (!(voxel_m > 0.0)) return out;
  const double cell = 0.5 * voxel_m;
  std::unordered_map<BlockKey, std::uint32_t, BlockKeyHash> index;  // cube -> its centroid's slot
  std::vector<Eigen::Vector3d> sum;
  std::vector<Eigen::Vector3d> colour_sum, sensor_sum;
  std::vector<std::uint32_t> count;
  index.reserve(points.size() / 4);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    const BlockKey key{int(std::floor(p.x() / cell)), int(std::floor(p.y() / cell)), int(std::floor(p.z() / cell))};
    const auto [it, added] = index.try_emplace(key, std::uint32_t(sum.size()));
    if (added) {
      sum.emplace_back(Eigen::Vector3d::Zero()), count.push_back(0);
      if (coloured) colour_sum.emplace_back(Eigen::Vector3d::Zero());
      if (sensed) sensor_sum.emplace_back(Eigen::Vector3d::Zero());
    }
    sum[it->second] += p.cast<double>();
    if (sensed) sensor_sum[it->second] += out.sensors[i].cast<double>();
    if (coloured) colour_sum[it->second] += Eigen::Vector3d(out.colours[i][0], out.colours[i][1], out.colours[i][2]);
    ++count[it->second];
  }
  if (sum.size() == points.size()) return out;  // no cube holds two: as they are
  points.clear();
  out.colours.clear();
  out.sensors.clear();
  for (std::size_t k = 0; k < sum.size(); ++k) {
    points.push_back((sum[k] / double(count[k])).cast<float>());
    if (sensed) out.sensors.push_back((sensor_sum[k] / double(count[k])).cast<float>());
    if (coloured) {
      const Eigen::Vector3d c = colour_sum[k] / double(count[k]);
      out.colours.push_back(ToRgb(c.x(), c.y(), c.z()));
    }
  }
  points.shrink_to_fit();
  out.colours.shrink_to_fit();
  return out;
}

// The discs of a scan at t (ScanLayout::Discs), or null.
std::shared_ptr<const ScanLayout::Discs> MakeDiscs(const Scan& s, const Eigen::Isometry3f& t, double voxel_m,
                                                   const CancelToken& cancel) {
  if (s.list_points.empty() && s.single_viewpoint) return nullptr;
  const DiscSource source = DiscPoints(s, t, voxel_m);
  const std::vector<Eigen::Vector3f>& points = source.points;
  const Eigen::Vector3f eye = t.translation();
  // Each point faces the sensor that saw it: the scanner of a scan seen from one place, its own
  // sensor position where the file gave one, else the orientation grows from the origin.
  const std::vector<Eigen::Vector3f> eyes = s.single_viewpoint ? std::vector<Eigen::Vector3f>{eye} : source.sensors;
  const PointNormals normals = EstimatePointNormals(points, eyes, eye, 12, cancel);
  if (cancel.IsCancelled() || !(normals.spacing > 0.0f)) return nullptr;
  auto discs = std::make_shared<ScanLayout::Discs>();
  discs->radius = normals.spacing;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (normals.normal[i].isZero()) continue;
    discs->points.push_back(points[i]);
    discs->normals.push_back(normals.normal[i]);
    if (!source.colours.empty()) discs->colours.push_back(source.colours[i]);
    discs->box.extend(points[i]);
  }
  return discs;
}

}  // namespace

bool RangeView::RangeAlong(const Eigen::Vector3f& x, float max_jump_m, float* surface_range, float* voxel_range) const {
  if (empty()) return false;
  const Eigen::Vector3f q = scan_from_world * (x - eye);
  const float r = q.norm();
  if (!(r > 0.0f)) return false;
  int c0, r0;
  float tc, tr;
  if (!Locate(angles.azimuth, FastAtan2(q.y(), q.x()), &c0, &tc)) return false;
  if (!Locate(angles.elevation, FastAtan2(q.z(), std::sqrt(q.x() * q.x() + q.y() * q.y())), &r0, &tr)) return false;
  const std::vector<float>& range = *this->range;
  const float v00 = range[r0 * cols + c0], v01 = range[r0 * cols + c0 + 1];
  const float v10 = range[(r0 + 1) * cols + c0], v11 = range[(r0 + 1) * cols + c0 + 1];
  *voxel_range = r;
  const float lo = std::min({v00, v01, v10, v11}), hi = std::max({v00, v01, v10, v11});
  if (lo > 0.0f && hi - lo <= max_jump_m) {
    *surface_range = (1 - tr) * ((1 - tc) * v00 + tc * v01) + tr * ((1 - tc) * v10 + tc * v11);
    return true;
  }
  const float nearest = tr < 0.5f ? (tc < 0.5f ? v00 : v01) : (tc < 0.5f ? v10 : v11);
  if (nearest <= 0.0f) return false;
  int agree = 0;  // the nearest cell itself, and the others of the four on its surface
  for (const float v : {v00, v01, v10, v11}) agree += v > 0.0f && std::abs(v - nearest) <= max_jump_m;
  if (agree < 2) return false;
  *surface_range = nearest;
  return true;
}

ScanLayout LayoutScan(const Scan& s, const Eigen::Vector3d& origin, bool with_blocks, double voxel_m,
                      const CancelToken& cancel) {
  constexpr int kB = ScanLayout::kCellBlock, kReach = 8;  // the largest stride
  ScanLayout out;
  out.rows = s.rows, out.cols = s.cols;
  out.spacing = MedianSpacing(s);
  out.valid = s.single_viewpoint ? s.CountValid() : 0;
  const Eigen::Isometry3f t = Shifted(s, origin);
  out.discs = MakeDiscs(s, t, voxel_m, cancel);
  if (!with_blocks || out.valid == 0) return out;
  const int block_cols = out.block_cols();
  out.blocks.assign(std::size_t(out.block_rows()) * block_cols, Eigen::AlignedBox3f());  // empty boxes
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      const std::size_t i = s.Index(r, c);
      if (!s.valid[i]) continue;
      const Eigen::Vector3f p = t * s.points[i];
      // The cell belongs to its own block and, within kReach, to the blocks before it.
      for (int br = std::max(0, (r - kReach) / kB); br <= r / kB; ++br)
        for (int bc = std::max(0, (c - kReach) / kB); bc <= c / kB; ++bc) out.blocks[std::size_t(br) * block_cols + bc].extend(p);
    }
  }
  return out;
}

Scan CropScan(const Scan& scan, int r0, int r1, int c0, int c1) {
  Scan out;
  out.name = scan.name;
  out.single_viewpoint = scan.single_viewpoint;
  out.rows = r1 - r0, out.cols = c1 - c0;
  out.world_from_scan = scan.world_from_scan;
  out.reference_world_from_scan = scan.reference_world_from_scan;
  const std::size_t n = std::size_t(out.rows) * out.cols;
  out.points.resize(n);
  out.reflectance.resize(n);
  out.valid.resize(n);
  if (scan.HasColour()) out.colour.resize(n);  // the listed points are the layout's discs, not the piece's
  for (int r = r0; r < r1; ++r) {
    const std::size_t from = scan.Index(r, c0), to = std::size_t(r - r0) * out.cols;
    std::copy_n(scan.points.begin() + from, out.cols, out.points.begin() + to);
    std::copy_n(scan.reflectance.begin() + from, out.cols, out.reflectance.begin() + to);
    std::copy_n(scan.valid.begin() + from, out.cols, out.valid.begin() + to);
    if (scan.HasColour()) std::copy_n(scan.colour.begin() + from, out.cols, out.colour.begin() + to);
  }
  if (!scan.angles.empty()) {
    out.angles.azimuth.assign(scan.angles.azimuth.begin() + c0, scan.angles.azimuth.begin() + c1);
    out.angles.elevation.assign(scan.angles.elevation.begin() + r0, scan.angles.elevation.begin() + r1);
  }
  return out;
}

bool PieceWindow(const ScanLayout& layout, const Eigen::AlignedBox3f& keep, int* r0, int* r1, int* c0, int* c1) {
  constexpr int kB = ScanLayout::kCellBlock;
  const int block_rows = layout.block_rows(), block_cols = layout.block_cols();
  int lo_r = block_rows, hi_r = -1, lo_c = block_cols, hi_c = -1;
  for (int br = 0; br < block_rows; ++br) {
    for (int bc = 0; bc < block_cols; ++bc) {
      const Eigen::AlignedBox3f& b = layout.blocks[std::size_t(br) * block_cols + bc];
      if (b.isEmpty() || !b.intersects(keep)) continue;
      lo_r = std::min(lo_r, br), hi_r = std::max(hi_r, br);
      lo_c = std::min(lo_c, bc), hi_c = std::max(hi_c, bc);
    }
  }
  if (hi_r < 0) return false;
  *r0 = std::max(0, lo_r - 1) * kB, *r1 = std::min(layout.rows, (hi_r + 2) * kB);
  *c0 = std::max(0, lo_c - 1) * kB, *c1 = std::min(layout.cols, (hi_c + 2) * kB);
  return true;
}

Eigen::Vector3d PatchOrigin(const std::vector<const Scan*>& scans) {
  // The first scanner position, rounded to a metre (keeps UTM offsets out of the floats).
  for (const Scan* s : scans)
    if (s->CountValid()) return s->world_from_scan.translation().array().round();
  return Eigen::Vector3d::Zero();
}

double MaxPatchEdge(double spacing, double voxel_m) { return 8.0 * spacing * Stride(spacing, voxel_m); }

Eigen::Vector3f ClosestPointOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                                       const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1.0f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

Expected<RangePatches> BuildRangePatches(const std::vector<const Scan*>& scans, double max_grazing_deg,
                                         const CancelToken& cancel, double voxel_m) {
  std::size_t total = 0;
  for (const Scan* s : scans) total += s->CountPoints();
  if (total == 0) {
    std::string names;
    for (const Scan* s : scans) names += (names.empty() ? "" : ", ") + s->name;
    return MakeError(ErrorCode::kInvalidArgument,
                     scans.empty() ? "merge: no scan to merge (mark scans registered first)"
                                   : "merge: the scans to merge (" + names + ") have no valid point");
  }
  const Eigen::Vector3d origin = PatchOrigin(scans);
  std::vector<ScanLayout> layouts(scans.size());
  std::vector<ScanPiece> pieces(scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    layouts[i] = LayoutScan(*scans[i], origin, false, voxel_m, cancel);
    pieces[i].cells = std::shared_ptr<const Scan>(scans[i], [](const Scan*) {});  // not owned
    pieces[i].layout = &layouts[i];
  }
  return BuildRangePatches(pieces, origin, max_grazing_deg, cancel, voxel_m);
}

Expected<RangePatches> BuildRangePatches(const std::vector<ScanPiece>& pieces, const Eigen::Vector3d& origin,
                                         double max_grazing_deg, const CancelToken& cancel, double voxel_m,
                                         const Eigen::AlignedBox3f* keep) {
  RangePatches out;
  out.origin = origin;
  if (!keep) {
    std::size_t total = 0;
    for (const ScanPiece& piece : pieces)
      total += piece.layout->valid + (piece.layout->discs ? piece.layout->discs->points.size() : 0);
    out.points.reserve(total);
  }
  const float cos_grazing = float(std::cos(max_grazing_deg * M_PI / 180.0));
  std::vector<int> id;               // per cell of the current piece: its point, or -1
  std::vector<std::size_t> touched;  // the cells given a point
  for (std::size_t si = 0; si < pieces.size(); ++si) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled while meshing the scans");
    const Scan& s = *pieces[si].cells;
    const ScanLayout& layout = *pieces[si].layout;
    const int row0 = pieces[si].row0, col0 = pieces[si].col0;
    const int row_end = row0 + s.rows, col_end = col0 + s.cols;  // of the whole scan's grid
    const Eigen::Isometry3f t = Shifted(s, origin);
    const Eigen::Vector3f eye = t.translation();
    out.scanner.push_back(eye);
    out.viewpoint.push_back(s.single_viewpoint);
    out.disc_radius.push_back(layout.discs ? layout.discs->radius : 0.0f);
    out.scan_begin.push_back(out.points.size());
    // Colour per point once any piece has it (the points before it black, their scan not coloured).
    const bool coloured = !s.colour.empty() || (layout.discs && !layout.discs->colours.empty());
    out.coloured.push_back(coloured);
    const bool keep_colour = std::any_of(out.coloured.begin(), out.coloured.end(), [](char c) { return c != 0; });
    if (keep_colour) out.colour.resize(out.points.size(), Rgb{0, 0, 0});
    out.views.push_back(MakeView(s, t));
    if (layout.discs) {
      const ScanLayout::Discs& discs = *layout.discs;
      for (std::size_t k = 0; k < discs.points.size(); ++k) {
        if (keep && !keep->contains(discs.points[k])) continue;
        const int v = int(out.points.size());
        out.points.push_back(discs.points[k]);
        if (keep_colour) out.colour.push_back(discs.colours.empty() ? Rgb{0, 0, 0} : discs.colours[k]);
        out.patches.push_back({{v, v, v}, discs.normals[k], int(si)});
      }
      out.max_patch_radius = std::max(out.max_patch_radius, double(discs.radius));
    }
    if (layout.valid == 0) continue;  // no cell triangulated (ScanLayout)
    const double spacing = layout.spacing;
    const int stride = Stride(spacing, voxel_m);
    const float max_edge2 = float(std::pow(8.0 * spacing * stride, 2));
    // The columns to visit in each row of cell blocks: the blocks that may reach `keep` (all
    // without a tile), within the piece. Cells are visited in row-major order either way, so a
    // tile's points and patches keep the whole merge's order.
    constexpr int kB = ScanLayout::kCellBlock;
    const int block_cols = layout.block_cols();
    std::vector<std::vector<std::pair<int, int>>> spans(layout.block_rows());  // [first, end) columns
    for (int br = row0 / kB; br * kB < row_end; ++br) {
      for (int bc = col0 / kB; bc * kB < col_end; ++bc) {
        if (keep) {
          const Eigen::AlignedBox3f& b = layout.blocks[std::size_t(br) * block_cols + bc];
          if (b.isEmpty() || !b.intersects(*keep)) continue;
        }
        const int first = std::max(col0, bc * kB), end = std::min(col_end, (bc + 1) * kB);
        if (!spans[br].empty() && spans[br].back().second == first) {
          spans[br].back().second = end;
        } else {
          spans[br].emplace_back(first, end);
        }
      }
    }
    // Calls f(c) for every stride-th column of row r in the visited blocks (whole-scan columns).
    auto for_columns = [&](int r, auto&& f) {
      for (const auto& [first, end] : spans[r / kB])
        for (int c = (first + stride - 1) / stride * stride; c < end; c += stride) f(c);
    };
    // A cell of the whole scan's grid in the piece.
    auto index = [&](int r, int c) { return std::size_t(r - row0) * s.cols + std::size_t(c - col0); };
    if (id.size() < s.size()) id.resize(s.size(), -1);
    touched.clear();
    const int first_row = (row0 + stride - 1) / stride * stride;
    for (int r = first_row; r < row_end; r += stride) {
      for_columns(r, [&](int c) {
        const std::size_t i = index(r, c);
        if (!s.valid[i]) return;
        const Eigen::Vector3f p = t * s.points[i];
        if (keep && !keep->contains(p)) return;
        id[i] = int(out.points.size());
        touched.push_back(i);
        out.points.push_back(p);
        if (keep_colour) out.colour.push_back(s.colour.empty() ? Rgb{0, 0, 0} : s.colour[i]);
      });
    }
    auto add = [&](int a, int b, int c) {
      if (a < 0 || b < 0 || c < 0) return;
      const Eigen::Vector3f &pa = out.points[a], &pb = out.points[b], &pc = out.points[c];
      if ((pb - pa).squaredNorm() > max_edge2 || (pc - pb).squaredNorm() > max_edge2 ||
          (pa - pc).squaredNorm() > max_edge2) {
        return;
      }
      Eigen::Vector3f n = (pb - pa).cross(pc - pa);
      const float len = n.norm();
      if (!(len > 0.0f)) return;
      n /= len;
      const Eigen::Vector3f centroid = (pa + pb + pc) / 3.0f;
      const Eigen::Vector3f to_eye = (eye - centroid).normalized();
      float c_los = n.dot(to_eye);
      if (c_los < 0) n = -n, c_los = -c_los;
      if (c_los < cos_grazing) return;
      out.patches.push_back({{a, b, c}, n, int(si)});
      const float r = std::max({(pa - centroid).norm(), (pb - centroid).norm(), (pc - centroid).norm()});
      out.max_patch_radius = std::max(out.max_patch_radius, double(r));
    };
    // A piece's window ends a block past the last block visited, so the cells a stride on are in it.
    for (int r = first_row; r + stride < row_end; r += stride) {
      for_columns(r, [&](int c) {
        if (c + stride >= col_end) return;
        const int p00 = id[index(r, c)], p01 = id[index(r, c + stride)];
        const int p10 = id[index(r + stride, c)], p11 = id[index(r + stride, c + stride)];
        if (p00 >= 0 && p01 >= 0 && p10 >= 0 && p11 >= 0) {
          // Split along the shorter diagonal.
          if ((out.points[p00] - out.points[p11]).squaredNorm() <= (out.points[p01] - out.points[p10]).squaredNorm()) {
            add(p00, p01, p11), add(p00, p11, p10);
          } else {
            add(p00, p01, p10), add(p01, p11, p10);
          }
        } else {
          add(p00, p01, p10), add(p01, p11, p10), add(p00, p01, p11), add(p00, p11, p10);
        }
      });
    }
    for (std::size_t i : touched) id[i] = -1;  // ready for the next piece
  }
  out.scan_begin.push_back(out.points.size());
  if (out.patches.empty() && !keep) {  // a tile of a tiled merge may hold nothing
    return MakeError(ErrorCode::kFailed, "merge: the scans' valid points form no surface (no adjacent valid cells)");
  }
  return out;
}

void RangePatches::BuildHash(double cell_m) {
  // Each patch goes into every cell its bounding box touches, so that a query visits only the
  // cells around x (large far-range triangles no longer widen every query).
  cell = std::max(cell_m, 1e-6);
  hash.clear();
  centroid.resize(patches.size());
  radius.resize(patches.size());
  const double inv = 1.0 / cell;
  for (std::size_t i = 0; i < patches.size(); ++i) {
    const Patch& p = patches[i];
    const Eigen::Vector3f &a = points[p.v[0]], &b = points[p.v[1]], &c = points[p.v[2]];
    centroid[i] = (a + b + c) / 3.0f;
    radius[i] = p.disc() ? disc_radius[p.scan]
                         : std::max({(a - centroid[i]).norm(), (b - centroid[i]).norm(), (c - centroid[i]).norm()});
    const Eigen::Vector3f reach = Eigen::Vector3f::Constant(p.disc() ? radius[i] : 0.0f);
    const Eigen::Vector3f lo = a.cwiseMin(b).cwiseMin(c) - reach, hi = a.cwiseMax(b).cwiseMax(c) + reach;
    const int x0 = int(std::floor(lo.x() * inv)), x1 = int(std::floor(hi.x() * inv));
    const int y0 = int(std::floor(lo.y() * inv)), y1 = int(std::floor(hi.y() * inv));
    const int z0 = int(std::floor(lo.z() * inv)), z1 = int(std::floor(hi.z() * inv));
    if (std::int64_t(x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > 4096) continue;  // far coarser than the grid
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) hash[BlockKey{x, y, z}].push_back(int(i));
  }
}

Eigen::Vector3f RangePatches::Closest(int id, const Eigen::Vector3f& x) const {
  const Patch& p = patches[id];
  const Eigen::Vector3f& a = points[p.v[0]];
  if (!p.disc()) return ClosestPointOnTriangle(x, a, points[p.v[1]], points[p.v[2]]);
  Eigen::Vector3f along = (x - a) - (x - a).dot(p.normal) * p.normal;  // in the disc's plane
  const float r = disc_radius[p.scan], len = along.norm();
  if (len > r) along *= r / len;
  return a + along;
}

float RangePatches::SightCosine(const Patch& p, const Eigen::Vector3f& at, const Eigen::Vector3f& dir) const {
  if (!viewpoint[p.scan]) return 1.0f;
  const Eigen::Vector3f los = (at - scanner[p.scan]).normalized();
  return std::max(std::abs(los.dot(dir)), 0.2f);
}

void RangePatches::Candidates(const Eigen::Vector3f& x, double radius_m, std::vector<int>* out) const {
  out->clear();
  const double inv = 1.0 / cell;
  const int x0 = int(std::floor((x.x() - radius_m) * inv)), x1 = int(std::floor((x.x() + radius_m) * inv));
  const int y0 = int(std::floor((x.y() - radius_m) * inv)), y1 = int(std::floor((x.y() + radius_m) * inv));
  const int z0 = int(std::floor((x.z() - radius_m) * inv)), z1 = int(std::floor((x.z() + radius_m) * inv));
  const bool single = x0 == x1 && y0 == y1 && z0 == z1;
  for (int k = z0; k <= z1; ++k) {
    for (int j = y0; j <= y1; ++j) {
      for (int i = x0; i <= x1; ++i) {
        const auto it = hash.find(BlockKey{i, j, k});
        if (it == hash.end()) continue;
        for (int p : it->second) {
          if (Reaches(p, x, float(radius_m))) out->push_back(p);
        }
      }
    }
  }
  if (!single) {  // a patch spanning several visited cells was added once per cell
    std::sort(out->begin(), out->end());
    out->erase(std::unique(out->begin(), out->end()), out->end());
  }
}

void PatchSpheres::Load(const RangePatches& patches, const std::vector<int>& ids) {
  ids_ = ids;
  const std::size_t n = ids.size();
  x_.resize(n), y_.resize(n), z_.resize(n), r_.resize(n), hit_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& c = patches.centroid[ids[i]];
    x_[i] = c.x(), y_[i] = c.y(), z_[i] = c.z(), r_[i] = patches.radius[ids[i]];
  }
}

void PatchSpheres::Filter(const Eigen::Vector3f& x, float radius_m, std::vector<int>* out) const {
  const std::size_t n = ids_.size();
  const float px = x.x(), py = x.y(), pz = x.z();
  const float* __restrict cx = x_.data();
  const float* __restrict cy = y_.data();
  const float* __restrict cz = z_.data();
  const float* __restrict r = r_.data();
  unsigned char* __restrict hit = hit_.data();
  // The same arithmetic as RangePatches::Reaches, in the same order.
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = cx[i] - px, dy = cy[i] - py, dz = cz[i] - pz;
    const float reach = radius_m + r[i];
    hit[i] = (dx * dx + dy * dy) + dz * dz <= reach * reach;
  }
  // Compacted without branches: every id is written, the next write moves on only past a hit.
  out->resize(n);
  int* __restrict o = out->data();
  const int* __restrict ids = ids_.data();
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    o[k] = ids[i];
    k += hit[i];
  }
  out->resize(k);
}

}  // namespace scanreg::merge
