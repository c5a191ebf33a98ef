// Counter-based hashing and a small portable generator for the simulator. Every random number of
// a scan is a pure function of (seed, cell, stream), so results do not depend on thread count or
// on the standard library's distributions (which are implementation-defined).
#pragma once

#include <cmath>
#include <cstdint>

namespace scanreg::sim {

// SplitMix64 finaliser: a bijective 64-bit mixer.
inline std::uint64_t Mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

inline std::uint64_t Hash(std::uint64_t a, std::uint64_t b) { return Mix64(a ^ Mix64(b + 0x9e3779b97f4a7c15ULL)); }
inline std::uint64_t Hash(std::uint64_t a, std::uint64_t b, std::uint64_t c) { return Hash(Hash(a, b), c); }
inline std::uint64_t Hash(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  return Hash(Hash(Hash(a, b), c), d);
}

// Uniform in [0, 1) from the top 53 bits.
inline double ToUnit(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

// Standard normal from a hash (Box-Muller on two derived uniforms).
inline double GaussianFromHash(std::uint64_t h) {
  const double u1 = 1.0 - ToUnit(Mix64(h ^ 0x5851f42d4c957f2dULL));  // (0, 1]
  const double u2 = ToUnit(Mix64(h ^ 0x14057b7ef767814fULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// Sequential generator for building scenes and poses (single-threaded use).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(Mix64(seed + 0x2545f4914f6cdd1dULL)) {}
  std::uint64_t Next() { return Mix64(state_ += 0x9e3779b97f4a7c15ULL); }
  double Uniform() { return ToUnit(Next()); }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  int UniformInt(int lo, int hi) { return lo + static_cast<int>(Uniform() * (hi - lo + 1)); }  // [lo, hi]
  bool Chance(double p) { return Uniform() < p; }
  double Gaussian() { return GaussianFromHash(Next()); }

 private:
  std::uint64_t state_;
};

}  // namespace scanreg::sim
