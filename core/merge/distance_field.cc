#include "core/merge/distance_field.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

namespace scanreg::merge {

namespace {

constexpr int kMaxBins = 512;

// erf to 1.5e-7 (Abramowitz & Stegun 7.1.26), several times faster than std::erf.
inline double FastErf(double x) {
  const double a = std::abs(x);
  const double t = 1.0 / (1.0 + 0.3275911 * a);
  const double y = 1.0 - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t + 0.254829592) *
                             t * std::exp(-a * a);
  return x < 0 ? -y : y;
}

}  // namespace

double CandidateRadius(const MergeOptions& options) {
  switch (options.method) {
    case MergeMethod::kMaximumLikelihood:
      return options.Band() + 3.0 * options.sigma_m;
    case MergeMethod::kConsensus:
      return std::sqrt(options.Band() * options.Band() + options.voxel_m * options.voxel_m);
    case MergeMethod::kTsdf:
      break;
  }
  return options.Band();
}

bool ConsensusDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                       const std::vector<int>& candidates, float* distance, float* weight) {
  // The kernel along the surface: half a voxel, cut at one. Measured on a simulated street (5 cm voxels,
  // RMS to the noise-free scene; the input points 9.95 mm): h = 1.5 voxels 11.0 mm, 1 9.0 mm, 0.7
  // 7.9 mm, 0.5 7.0 mm (holes 14 % against 11 % at 1 voxel), 0.35 6.6 mm but a surface with more holes:
  // wider kernels round edges and mix surfaces more than they average noise.
  const float band = float(options.Band()), h = 0.5f * float(options.voxel_m);
  const float sigma2 = float(options.sigma_m * options.sigma_m);
  struct Vote {
    Eigen::Vector3f to_x;  // x minus the patch's centre
    Eigen::Vector3f normal;
    double w;
  };
  thread_local std::vector<Vote> votes;
  votes.clear();
  float d_min = std::numeric_limits<float>::max();
  Eigen::Vector3f nearest_normal = Eigen::Vector3f::Zero();
  // fill_holes: the patches x lies over (inside a wide triangle or disc), their noise-weighted
  // signed distances, and the nearest one's distance.
  float over_d = std::numeric_limits<float>::max();
  double over_sum = 0.0, over_w = 0.0;
  const float on_patch2 = 1e-6f * h * h;
  for (int id : candidates) {
    const Patch& p = patches.patches[id];
    // The patch's corners are read only for its nearest point: its centre and radius are stored.
    const Eigen::Vector3f& centre = patches.centroid[id];
    const Eigen::Vector3f to_x = x - centre;
    // The patch's nearest point only where it may be nearer than the nearest so far (its bounding
    // sphere's): the same d_min and nearest normal, without most of the closest-point tests.
    if (options.fill_holes || to_x.norm() - patches.radius[id] < d_min + 1e-6f) {
      const Eigen::Vector3f closest = patches.Closest(id, x);
      const float d = (closest - x).norm();
      if (d < d_min) d_min = d, nearest_normal = p.normal;
      if (options.fill_holes && d <= band) {  // x over the patch: its closest point is x's projection
        const Eigen::Vector3f off = x - closest;
        const float across = off.dot(p.normal);
        if (off.squaredNorm() - across * across <= on_patch2) {
          const float cos_phi = patches.SightCosine(p, closest, p.normal);
          const double w = 1.0 / (sigma2 * cos_phi * cos_phi);
          over_d = std::min(over_d, d), over_sum += w * across, over_w += w;
        }
      }
    }
    const float s = to_x.dot(p.normal);  // > 0: x in front of the patch (its normal faces its scanner)
    if (std::abs(s) > band) continue;
    const float t2 = std::max(0.0f, to_x.squaredNorm() - s * s);  // along the surface, from its centre
    if (t2 > 4.0f * h * h) continue;
    // Range noise along the line of sight, seen along the normal: sigma cos(phi) (S's sigma').
    const float cos_phi = patches.SightCosine(p, centre, p.normal);
    votes.push_back({to_x, p.normal, std::exp(-double(t2) / (h * h)) / (sigma2 * cos_phi * cos_phi)});
  }
  if (d_min > band) return false;  // no measurement near
  if (votes.empty()) {
    // None beside x along the surface: no surface invented here (a hole stays a hole), unless the
    // user asked for holes filled — then, where x lies over a patch (inside a wide triangle, not
    // beside a surface's edge), that patch's plane with a token weight (the vertices there are
    // marked: vertex_info.h).
    if (!options.fill_holes || over_d > d_min + 1e-3f * h) return false;  // the nearest surface's edge: no
    *distance = float(over_sum / over_w);
    *weight = kFilledWeight;
    return true;
  }
  // The consensus normal of the surface nearest x (patches facing the other way - the far side of a
  // thin wall - do not vote), then each patch's signed distance along it: one triangle's normal is
  // as noisy as its three points, and x lies up to a voxel beside it.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const Vote& v : votes)
    if (v.normal.dot(nearest_normal) > 0.0f) normal += v.w * v.normal.cast<double>();
  if (!(normal.norm() > 0.0)) return false;
  const Eigen::Vector3f n = normal.normalized().cast<float>();
  double sum = 0.0, sum_w = 0.0;
  for (const Vote& v : votes) {
    if (v.normal.dot(nearest_normal) <= 0.0f) continue;
    sum += v.w * v.to_x.dot(n);
    sum_w += v.w;
  }
  *distance = float(sum / sum_w);
  *weight = float(sum_w);
  return true;
}

bool MaximumLikelihoodDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                               const std::vector<int>& candidates, float* distance) {
  const double sigma = options.sigma_m, band = options.Band();
  if (candidates.empty()) return false;
  // Step 1: nearest point p' of every candidate patch; d_min.
  struct Near {
    float dist;
    float sigma;  // sigma' = sigma cos(phi)
    float vote;   // +1 when x is in front of the patch ((p' - x) . n < 0), -1 behind
  };
  thread_local std::vector<Near> near;
  thread_local std::vector<Eigen::Vector3f> closest;
  near.clear();
  closest.resize(candidates.size());
  float d_min = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    closest[i] = patches.Closest(candidates[i], x);
    d_min = std::min(d_min, (closest[i] - x).norm());
  }
  if (d_min > band) return false;
  const float limit = float(d_min + 3.0 * sigma);
  float nearest_vote = 1.0f;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Eigen::Vector3f to_x = x - closest[i];
    const float d = to_x.norm();
    if (d > limit) continue;
    const Patch& p = patches.patches[candidates[i]];
    // Step 2: phi between the patch's line of sight and the direction to x (the normal when x is on it).
    const Eigen::Vector3f dir = d > 1e-7f ? Eigen::Vector3f(to_x / d) : p.normal;
    const float cos_phi = patches.SightCosine(p, closest[i], dir);
    const float side = -to_x.dot(p.normal);                        // (p' - x) . n
    const float vote = side < 0 ? 1.0f : (side > 0 ? -1.0f : 0.0f);
    if (d == d_min) nearest_vote = vote == 0.0f ? 1.0f : vote;
    near.push_back({d, float(sigma) * cos_phi, vote});
  }
  // Step 3: the histogram over [d_lo, d_min + 3 sigma).
  double bin = options.Bin();
  const double d_lo = std::max(0.0, double(d_min) - 3.0 * sigma);
  int bins = int(std::ceil((limit - d_lo) / bin)) + 1;
  if (bins > kMaxBins) bins = kMaxBins, bin = (limit - d_lo) / (kMaxBins - 1);
  // P1 as a product of (1 - F_p(d_k)) with its binary exponent kept apart (thousands of factors
  // underflow a double): a multiply per patch and bin instead of a log1p.
  thread_local std::vector<double> p_any, p1, vote_sum, cdf;
  thread_local std::vector<int> p1_exp, saturated;  // saturated: patches with F_p = 1 from bin k on (P1 = 0)
  p_any.assign(bins, 0.0), p1.assign(bins, 1.0), vote_sum.assign(bins, 0.0);
  p1_exp.assign(bins, 0), saturated.assign(bins + 1, 0);
  cdf.resize(bins + 1);
  for (const Near& n : near) {
    // F_p is 0 below dist - 6 sigma' and 1 above dist + 6 sigma': erf only in between, and no
    // work at all below k0 (nothing in the bins, factor 1) or above k1 (nothing, factor 0).
    const double inv = 1.0 / (std::sqrt(2.0) * n.sigma);
    const int k0 = std::clamp(int(std::floor((n.dist - 6.0 * n.sigma - d_lo) / bin)), 0, bins);
    const int k1 = std::clamp(int(std::ceil((n.dist + 6.0 * n.sigma - d_lo) / bin)), 0, bins);
    for (int k = k0; k <= k1; ++k) cdf[k] = 0.5 * (1.0 + FastErf((d_lo + k * bin - n.dist) * inv));
    if (k1 < bins) cdf[k1 + 1] = 1.0;
    int k = k0;
    for (const int last = std::min(k1, bins - 1); k <= last && cdf[k] < 1.0; ++k) {
      const double in_bin = cdf[k + 1] - cdf[k];  // P(d_k <= D_p < d_{k+1})
      p_any[k] += in_bin;
      vote_sum[k] += in_bin * n.vote;
      p1[k] *= 1.0 - cdf[k];  // no patch nearer than d_k
      if (p1[k] < 1e-150) {
        int e;
        p1[k] = std::frexp(p1[k], &e);
        p1_exp[k] += e;
      }
    }
    ++saturated[k];  // F_p = 1 from bin k on (k = bins: never)
  }
  // Step 4: the most likely bin (compared as logarithms); step 5: parabola through its neighbours.
  thread_local std::vector<double> log_pb;
  log_pb.assign(bins, -std::numeric_limits<double>::infinity());
  int best = 0;
  for (int k = 0, m = 0; k < bins; ++k) {
    m += saturated[k];
    if (m == 0 && p_any[k] > 0.0) log_pb[k] = std::log(p_any[k] * p1[k]) + p1_exp[k] * M_LN2;
    if (log_pb[k] > log_pb[best]) best = k;
  }
  double offset = 0.0;
  if (best > 0 && best + 1 < bins && std::isfinite(log_pb[best])) {
    // P_b relative to the best bin (the vertex of the parabola does not depend on the scale).
    const double a = std::exp(log_pb[best - 1] - log_pb[best]), c = std::exp(log_pb[best + 1] - log_pb[best]);
    const double den = a - 2.0 + c;
    if (den < 0.0) offset = std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
  }
  const double magnitude = std::max(0.0, d_lo + (best + 0.5 + offset) * bin);
  // Step 6: sign by the weighted vote W(x, d) of the chosen bin.
  const double w = vote_sum[best];
  const float sign = w > 0.0 ? 1.0f : (w < 0.0 ? -1.0f : nearest_vote);
  *distance = sign * float(magnitude);
  return true;
}

float TsdfDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                   const int* near_begin, const int* near_end, const std::vector<int>& candidates, float* distance) {
  const float band = float(options.Band());
  double sum = 0.0, weight = 0.0;
  bool projected = false;
  for (const int* s = near_begin; s != near_end; ++s) {
    const RangeView& view = patches.views[*s];
    if (view.empty()) continue;
    projected = true;
    float surface = 0.0f, range = 0.0f;
    if (!view.RangeAlong(x, band, &surface, &range)) continue;
    const float sdf = surface - range;  // > 0: x lies in front of the surface (outside)
    if (std::abs(sdf) > band) continue;
    sum += sdf;
    weight += 1.0;
  }
  // Scans without a range image: the nearest patch of each within the band.
  thread_local std::vector<std::pair<float, int>> nearest;  // per scan: (distance, patch)
  if (!candidates.empty()) nearest.assign(patches.scanner.size(), {std::numeric_limits<float>::max(), -1});
  for (int id : candidates) {
    const Patch& p = patches.patches[id];
    if (!patches.views[p.scan].empty() || !patches.Reaches(id, x, band)) continue;
    const float d = (patches.Closest(id, x) - x).norm();
    if (d <= band && d < nearest[p.scan].first) nearest[p.scan] = {d, id};
  }
  bool unviewed = false;
  for (std::size_t s = 0; !candidates.empty() && s < nearest.size(); ++s) {
    if (nearest[s].second < 0) continue;
    const Patch& p = patches.patches[nearest[s].second];
    unviewed |= bool(patches.viewpoint[s]);  // the fallback below: scans with a scanner only
    if (!patches.viewpoint[s]) {
      // No scanner to look along (a cloud seen from several places): the consensus of its discs
      // beside x along their normals; one disc's normal alone may face the wrong way.
      thread_local std::vector<int> own;
      own.clear();
      for (int id : candidates)
        if (patches.patches[id].scan == int(s)) own.push_back(id);
      float sdf = 0.0f, w = 0.0f;
      if (!ConsensusDistance(patches, x, options, own, &sdf, &w) || std::abs(sdf) > band) continue;
      sum += sdf;
      weight += 1.0;
      continue;
    }
    const Eigen::Vector3f& eye = patches.scanner[s];
    const Eigen::Vector3f ray = x - eye;
    const float range = ray.norm();
    if (!(range > 0.0f)) continue;
    const Eigen::Vector3f u = ray / range;
    const float un = u.dot(p.normal);  // < 0: the normal faces the scanner
    if (std::abs(un) < 0.05f) continue;
    // Range of the patch's plane along the scanner's line of sight through x.
    const float t = (patches.points[p.v[0]] - eye).dot(p.normal) / un;
    const float sdf = t - range;  // > 0: x lies in front of the surface (outside)
    if (std::abs(sdf) > band) continue;
    const double w = std::abs(un);
    sum += w * sdf;
    weight += w;
  }
  if (weight <= 0.0) {
    if (projected || !unviewed) return 0.0f;  // range images say: not near their surface (or occluded)
    // Scans without angles only, each seeing its nearest patch too obliquely: the distance along the normal of the
    // nearest patch, with a token weight, so that the surface has no hole there.
    float best = std::numeric_limits<float>::max();
    for (const auto& [d, id] : nearest) {
      if (id < 0 || d >= best || !patches.viewpoint[patches.patches[id].scan]) continue;
      const Patch& p = patches.patches[id];
      best = d;
      *distance = (x - patches.points[p.v[0]]).dot(p.normal);
    }
    return 1e-3f;
  }
  *distance = float(sum / weight);
  return float(weight);
}

Expected<SparseGrid> ComputeField(RangePatches& patches, const MergeOptions& options, ProgressSink& progress,
                                  const CancelToken& cancel, const SparseGrid::Bounds* bounds) {
  if (Status s = options.Validate(); !s) return s.error();
  const double band = options.Band();
  const bool ml = options.method == MergeMethod::kMaximumLikelihood;
  const bool consensus = options.method == MergeMethod::kConsensus;
  // TSDF projects into range images: the patch hash only for scans without one (and for ML).
  const bool unviewed = std::any_of(patches.views.begin(), patches.views.end(), [](const RangeView& v) { return v.empty(); });
  const bool use_patches = ml || consensus || unviewed;
  if (use_patches) patches.BuildHash(CandidateRadius(options));
  SparseGrid grid(patches.origin, options.voxel_m);
  if (bounds) grid.Restrict(*bounds);
  progress.Report(0.0, "allocating blocks");
  {  // counted first: the blocks are allocated once, without reallocations (a tile's margin included)
    BlockCounter counter(options.voxel_m, band, patches.points.size() * 27 + 1);
    for (const Eigen::Vector3f& p : patches.points) counter.Add(p);
    grid.Reserve(counter.count());
  }
  // For TSDF, the scans with a point within the band of each block (ascending; CSR over blocks):
  // the range images a grid point of the block is projected into.
  std::vector<std::pair<std::uint32_t, int>> touches;  // (block, scan)
  std::vector<int> last_scan;                          // per block: the last scan that touched it
  for (std::size_t s = 0; s + 1 < patches.scan_begin.size(); ++s) {
    for (std::size_t i = patches.scan_begin[s]; i < patches.scan_begin[s + 1]; ++i) {
      if ((i & 0xFFFFF) == 0 && cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
      if (ml || consensus) {
        grid.AllocateAround(patches.points[i], band);
        continue;
      }
      grid.AllocateAround(patches.points[i], band, [&](std::size_t b) {
        if (b >= last_scan.size()) last_scan.resize(std::max(b + 1, 2 * last_scan.size()), -1);
        if (last_scan[b] != int(s)) last_scan[b] = int(s), touches.emplace_back(std::uint32_t(b), int(s));
      });
    }
  }
  last_scan = {};
  std::vector<std::size_t> near_begin(grid.num_blocks() + 1, 0);
  for (const auto& t : touches) ++near_begin[t.first + 1];
  for (std::size_t b = 0; b < grid.num_blocks(); ++b) near_begin[b + 1] += near_begin[b];
  std::vector<int> near_scans(touches.size());
  {
    std::vector<std::size_t> cursor(near_begin.begin(), near_begin.end() - 1);
    for (const auto& t : touches) near_scans[cursor[t.first]++] = t.second;
  }
  touches = {};
  const long n = long(grid.num_blocks());
  std::atomic<long> done{0};
  std::atomic<bool> cancelled{false};
  const char* stage = ml ? "maximum-likelihood distance" : consensus ? "consensus distance" : "TSDF";
  constexpr int B = SparseGrid::kBlock, G = 4;
  static_assert(B % G == 0);
  const double radius = CandidateRadius(options);
  // Half the diagonal of a group, with a margin for float rounding.
  const double group_reach = 0.5 * std::sqrt(3.0) * (G - 1) * options.voxel_m * 1.001 + 1e-6;
#pragma omp parallel for schedule(dynamic, 4)
  for (long bi = 0; bi < n; ++bi) {
    if (cancelled.load(std::memory_order_relaxed)) continue;
    if (cancel.IsCancelled()) {
      cancelled = true;
      continue;
    }
    SparseGrid::Block& b = grid.block(bi);
    const int* near = near_scans.data() + near_begin[bi];
    const int* near_end = near_scans.data() + near_begin[bi + 1];
    std::vector<int> group, candidates;
    PatchSpheres spheres;
    // One hash query per G^3 group of grid points, then a bounding-sphere filter per point: the
    // same candidates as a query per point, without its hash look-ups and sorting.
    for (int gz = 0; gz < B; gz += G) {
      for (int gy = 0; gy < B; gy += G) {
        for (int gx = 0; gx < B; gx += G) {
          const Eigen::Vector3f centre =
              0.5f * (grid.Position(b.key, gx, gy, gz) + grid.Position(b.key, gx + G - 1, gy + G - 1, gz + G - 1));
          if (use_patches) patches.Candidates(centre, radius + group_reach, &group);
          if (group.empty() && near == near_end) continue;
          if (ml || consensus) spheres.Load(patches, group);
          for (int z = gz; z < gz + G; ++z) {
            for (int y = gy; y < gy + G; ++y) {
              for (int x = gx; x < gx + G; ++x) {
                const int l = SparseGrid::Local(x, y, z);
                const Eigen::Vector3f p = grid.Position(b.key, x, y, z);
                float d = 0.0f;
                if (ml) {
                  spheres.Filter(p, float(radius), &candidates);
                  if (MaximumLikelihoodDistance(patches, p, options, candidates, &d)) {
                    b.distance[l] = d, b.weight[l] = 1.0f;
                  }
                } else if (consensus) {
                  spheres.Filter(p, float(radius), &candidates);
                  float w = 0.0f;
                  if (ConsensusDistance(patches, p, options, candidates, &d, &w)) b.distance[l] = d, b.weight[l] = w;
                } else {  // its bounding-sphere test is inside
                  const float w = TsdfDistance(patches, p, options, near, near_end, group, &d);
                  if (w > 0.0f) b.distance[l] = d, b.weight[l] = w;
                }
              }
            }
          }
        }
      }
    }
    const long k = ++done;
    if (k * 200 / n != (k - 1) * 200 / n) progress.Report(double(k) / n, stage);
  }
  if (cancelled || cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
  FixIsolatedSigns(grid);
  if (options.smooth_iterations > 0) {
    progress.Report(1.0, "smoothing the field");
    SmoothField(grid, options.smooth_iterations);
  }
  return grid;
}

Expected<SparseGrid> ComputeField(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                  const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  std::vector<const Scan*> ptrs;
  for (const Scan& s : scans) ptrs.push_back(&s);
  auto patches = BuildRangePatches(ptrs, options.max_grazing_deg, cancel, options.voxel_m);
  if (!patches) return patches.error();
  return ComputeField(*patches, options, progress, cancel);
}

}  // namespace scanreg::merge
