#include "core/features/whole_dots.h"

#include <cmath>
#include <immintrin.h>

#include "core/features/sift.h"

namespace scanreg {
namespace {

constexpr int kDims = kSiftDescriptorSize;

std::int32_t PlainDot(const std::int16_t* a, const std::int16_t* b) {
  std::int32_t sum = 0;
  for (int d = 0; d < kDims; ++d) sum += static_cast<std::int32_t>(a[d]) * b[d];
  return sum;
}

__attribute__((target("avx2"))) std::int32_t Sum8(__m256i v) {
  __m128i s = _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
  s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0x4e));
  s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0xb1));
  return _mm_cvtsi128_si32(s);
}

__attribute__((target("avx2"))) __m256i Load(const std::int16_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// acc += the pairwise products of 16 values, summed in pairs into 8 lanes (vpmaddwd: exact, as
// no pair of products of values in [0, 255] comes near 2^31).
__attribute__((target("avx2"))) __m256i MulAdd(__m256i acc, __m256i a, __m256i b) {
  return _mm256_add_epi32(acc, _mm256_madd_epi16(a, b));
}

__attribute__((target("avx2"))) std::int32_t Avx2Dot(const std::int16_t* a, const std::int16_t* b) {
  __m256i acc = _mm256_setzero_si256();
  for (int d = 0; d < kDims; d += 16) acc = MulAdd(acc, Load(a + d), Load(b + d));
  return Sum8(acc);
}

// Four queries against two train descriptors per step: eight sums held in registers, each train
// value loaded once for four queries.
__attribute__((target("avx2"))) void Avx2Dots(const std::int16_t* train, int nt, const std::int16_t* query, int nb,
                                              std::int32_t* out) {
  int k = 0;
  for (; k + 4 <= nb; k += 4) {
    const std::int16_t* q0 = query + static_cast<std::size_t>(k) * kDims;
    const std::int16_t* q1 = q0 + kDims;
    const std::int16_t* q2 = q1 + kDims;
    const std::int16_t* q3 = q2 + kDims;
    std::int32_t* o0 = out + static_cast<std::size_t>(k) * nt;
    std::int32_t* o1 = o0 + nt;
    std::int32_t* o2 = o1 + nt;
    std::int32_t* o3 = o2 + nt;
    int j = 0;
    for (; j + 2 <= nt; j += 2) {
      const std::int16_t* t0 = train + static_cast<std::size_t>(j) * kDims;
      const std::int16_t* t1 = t0 + kDims;
      __m256i a00 = _mm256_setzero_si256(), a01 = a00, a10 = a00, a11 = a00, a20 = a00, a21 = a00, a30 = a00,
              a31 = a00;
      for (int d = 0; d < kDims; d += 16) {
        const __m256i x0 = Load(t0 + d), x1 = Load(t1 + d);
        __m256i y = Load(q0 + d);
        a00 = MulAdd(a00, x0, y);
        a01 = MulAdd(a01, x1, y);
        y = Load(q1 + d);
        a10 = MulAdd(a10, x0, y);
        a11 = MulAdd(a11, x1, y);
        y = Load(q2 + d);
        a20 = MulAdd(a20, x0, y);
        a21 = MulAdd(a21, x1, y);
        y = Load(q3 + d);
        a30 = MulAdd(a30, x0, y);
        a31 = MulAdd(a31, x1, y);
      }
      o0[j] = Sum8(a00), o0[j + 1] = Sum8(a01);
      o1[j] = Sum8(a10), o1[j + 1] = Sum8(a11);
      o2[j] = Sum8(a20), o2[j + 1] = Sum8(a21);
      o3[j] = Sum8(a30), o3[j + 1] = Sum8(a31);
    }
    for (; j < nt; ++j) {
      const std::int16_t* t = train + static_cast<std::size_t>(j) * kDims;
      o0[j] = Avx2Dot(q0, t), o1[j] = Avx2Dot(q1, t), o2[j] = Avx2Dot(q2, t), o3[j] = Avx2Dot(q3, t);
    }
  }
  for (; k < nb; ++k)
    for (int j = 0; j < nt; ++j)
      out[static_cast<std::size_t>(k) * nt + j] =
          Avx2Dot(query + static_cast<std::size_t>(k) * kDims, train + static_cast<std::size_t>(j) * kDims);
}

}  // namespace

std::vector<std::int16_t> WholeDescriptors(const float* descriptors, int n) {
  const std::size_t count = static_cast<std::size_t>(n > 0 ? n : 0) * kDims;
  std::vector<std::int16_t> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    const float v = descriptors[i];
    if (!(v >= 0.f && v <= 255.f) || v != std::floor(v)) return {};
    out[i] = static_cast<std::int16_t>(v);
  }
  return out;
}

bool WholeDotsAreFast() {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
}

void WholeDots(const std::int16_t* train, int nt, const std::int16_t* query, int nb, std::int32_t* out) {
  if (WholeDotsAreFast()) return Avx2Dots(train, nt, query, nb, out);
  for (int k = 0; k < nb; ++k)
    for (int j = 0; j < nt; ++j)
      out[static_cast<std::size_t>(k) * nt + j] =
          PlainDot(query + static_cast<std::size_t>(k) * kDims, train + static_cast<std::size_t>(j) * kDims);
}

}  // namespace scanreg
