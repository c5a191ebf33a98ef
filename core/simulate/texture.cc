#include "core/simulate/texture.h"

#include <algorithm>
#include <cmath>

#include "core/simulate/random.h"

namespace scanreg {
namespace {

using sim::Hash;
using sim::ToUnit;

std::uint64_t Cell(std::int64_t i) { return static_cast<std::uint64_t>(i); }

double Smooth(double t) { return t * t * (3.0 - 2.0 * t); }

// Value noise in [-1, 1] on a unit lattice.
double ValueNoise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = Smooth(x - fx), ty = Smooth(y - fy);
  auto lattice = [&](std::int64_t a, std::int64_t b) { return 2.0 * ToUnit(Hash(seed, Cell(a), Cell(b))) - 1.0; };
  const double v00 = lattice(ix, iy), v10 = lattice(ix + 1, iy);
  const double v01 = lattice(ix, iy + 1), v11 = lattice(ix + 1, iy + 1);
  return (v00 * (1 - tx) + v10 * tx) * (1 - ty) + (v01 * (1 - tx) + v11 * tx) * ty;
}

double FractalNoise(const SurfaceTexture& t, double u, double v) {
  double sum = 0.0, amp = 1.0, norm = 0.0, freq = 1.0 / t.noise_wavelength_m;
  for (int o = 0; o < t.noise_octaves; ++o) {
    sum += amp * ValueNoise(u * freq, v * freq, Hash(t.seed, 11, static_cast<std::uint64_t>(o)));
    norm += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  return sum / norm;
}

double Blobs(const SurfaceTexture& t, double u, double v) {
  const double cs = t.blob_cell_m;
  const auto ci = static_cast<std::int64_t>(std::floor(u / cs)), cj = static_cast<std::int64_t>(std::floor(v / cs));
  double out = 0.0;
  for (std::int64_t i = ci - 1; i <= ci + 1; ++i) {
    for (std::int64_t j = cj - 1; j <= cj + 1; ++j) {
      const std::uint64_t h = Hash(t.seed, 23, Cell(i), Cell(j));
      if (ToUnit(h) >= t.blob_probability) continue;
      const double cu = (static_cast<double>(i) + ToUnit(Hash(h, 1))) * cs;
      const double cv = (static_cast<double>(j) + ToUnit(Hash(h, 2))) * cs;
      const double r = t.blob_radius_m * (0.35 + 0.65 * ToUnit(Hash(h, 3)));
      const double aspect = 0.6 + ToUnit(Hash(h, 4));
      const double du = (u - cu) / aspect, dv = (v - cv) * aspect;
      const double d = std::sqrt(du * du + dv * dv);
      if (d >= r) continue;
      const double edge = std::clamp((r - d) / (0.2 * r), 0.0, 1.0);
      const double sign = ToUnit(Hash(h, 5)) < 0.5 ? -1.0 : 1.0;
      out += sign * (0.5 + 0.5 * ToUnit(Hash(h, 6))) * edge;
    }
  }
  return out;
}

double Strokes(const SurfaceTexture& t, double u, double v) {
  const double cs = t.stroke_cell_m;
  const auto ci = static_cast<std::int64_t>(std::floor(u / cs)), cj = static_cast<std::int64_t>(std::floor(v / cs));
  double out = 0.0;
  for (std::int64_t i = ci - 1; i <= ci + 1; ++i) {
    for (std::int64_t j = cj - 1; j <= cj + 1; ++j) {
      const std::uint64_t h = Hash(t.seed, 37, Cell(i), Cell(j));
      if (ToUnit(h) >= t.stroke_probability) continue;
      const double au = (static_cast<double>(i) + ToUnit(Hash(h, 1))) * cs;
      const double av = (static_cast<double>(j) + ToUnit(Hash(h, 2))) * cs;
      const double ang = 6.283185307179586 * ToUnit(Hash(h, 3));
      const double len = t.stroke_length_m * (0.4 + 0.6 * ToUnit(Hash(h, 4)));
      const double du = std::cos(ang), dv = std::sin(ang);
      const double s = std::clamp((u - au) * du + (v - av) * dv, 0.0, len);
      const double eu = u - (au + s * du), ev = v - (av + s * dv);
      const double w = t.stroke_width_m * (0.5 + ToUnit(Hash(h, 5)));
      if (eu * eu + ev * ev >= w * w) continue;
      out += ToUnit(Hash(h, 6)) < 0.5 ? -1.0 : 1.0;
    }
  }
  return out;
}

// Returns true and sets *albedo when (u, v) falls on a window or its frame.
bool Window(const WindowGrid& g, std::uint64_t seed, double u, double v, float* albedo) {
  if (u < g.u_min || u > g.u_max || v < g.v_min || v > g.v_max) return false;
  const double lu = u - g.u_min, lv = v - g.v_min;
  const double iu = std::floor(lu / g.spacing_u), iv = std::floor(lv / g.spacing_v);
  const double cu = lu - iu * g.spacing_u - g.offset_u, cv = lv - iv * g.spacing_v - g.offset_v;
  const double fw = g.frame_width;
  if (cu < -fw || cu > g.width + fw || cv < -fw || cv > g.height + fw) return false;
  // The whole window (frame included) must lie inside the region.
  const double wu0 = g.u_min + iu * g.spacing_u + g.offset_u, wv0 = g.v_min + iv * g.spacing_v + g.offset_v;
  if (wu0 - fw < g.u_min || wu0 + g.width + fw > g.u_max || wv0 - fw < g.v_min || wv0 + g.height + fw > g.v_max)
    return false;
  if (cu < 0 || cu > g.width || cv < 0 || cv > g.height) {
    *albedo = g.frame_albedo;
    return true;
  }
  float a = g.glass_albedo;
  if (g.variation > 0.0f) {
    const std::uint64_t h = Hash(seed, 51, Cell(static_cast<std::int64_t>(iu)), Cell(static_cast<std::int64_t>(iv)));
    a += g.variation * static_cast<float>(ToUnit(h));
    // Some windows have a half-drawn blind: brighter upper part.
    if (ToUnit(Hash(h, 1)) < 0.3 && cv > g.height * (0.3 + 0.5 * ToUnit(Hash(h, 2)))) a += 2.0f * g.variation;
  }
  *albedo = a;
  return true;
}

// Road paint and ground zones; returns the zone's base albedo and sets *paint when painted.
float Ground(const GroundMarkings& g, float asphalt, double u, double v, bool* paint) {
  const double av = std::abs(v);
  *paint = false;
  if (av >= g.sidewalk_outer) return g.verge_albedo;
  if (av >= g.road_half_width) {
    // Paving slabs 0.5 m with dark joints; a light kerb stone.
    if (av < g.road_half_width + 0.15) return g.sidewalk_albedo + 0.25f;
    const double pu = u - 0.5 * std::floor(u / 0.5), pv = av - 0.5 * std::floor(av / 0.5);
    return (pu < 0.02 || pv < 0.02) ? g.sidewalk_albedo - 0.15f : g.sidewalk_albedo;
  }
  // Dashed centre line (3 m dash, 6 m period), solid edge lines, zebra crossings.
  const double du = u - 6.0 * std::floor(u / 6.0);
  if (av < 0.06 && du < 3.0) *paint = true;
  if (av > g.road_half_width - 0.35 && av < g.road_half_width - 0.2) *paint = true;
  for (double cx : g.crosswalk_u) {
    if (std::abs(u - cx) < 2.0 && av < g.road_half_width - 0.5 && std::fmod(av + 0.25, 1.0) < 0.5) *paint = true;
  }
  return asphalt;
}

}  // namespace

float SurfaceTexture::Albedo(double u, double v, double footprint_half_m) const {
  if (checker_half_m > 0.0 && std::abs(u) <= checker_half_m && std::abs(v) <= checker_half_m) {
    // A Gaussian beam of standard deviation h: sign(u) sign(v) and the Gaussian are separable, so
    // the beam's average is the product of the averages of each sign, erf(u / (h sqrt 2)) erf(...).
    const double k = 1.0 / (std::max(footprint_half_m, 1e-6) * std::sqrt(2.0));
    const double s = std::erf(u * k) * std::erf(v * k);
    return static_cast<float>(0.5 * (checker_light + checker_dark) + 0.5 * (checker_light - checker_dark) * s);
  }
  double a = base;
  bool paint = false;
  if (ground.enabled) a = Ground(ground, base, u, v, &paint);
  if (noise_amplitude > 0.0f) a += noise_amplitude * FractalNoise(*this, u, v);
  if (blob_contrast > 0.0f) a += blob_contrast * Blobs(*this, u, v);
  if (stroke_contrast > 0.0f) a += stroke_contrast * Strokes(*this, u, v);
  if (paint) a = ground.paint_albedo + 0.3 * (a - base);  // worn paint keeps some of the asphalt detail
  if (windows.enabled) {
    float w = 0.0f;
    if (Window(windows, seed, u, v, &w)) a = w;
  }
  return static_cast<float>(std::clamp(a, 0.02, 0.98));
}

}  // namespace scanreg
