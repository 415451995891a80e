// Two doubles at once, for the per-step arithmetic of the walk: the compiler's vector extension (GCC and
// clang), so that two independent values of a step take one instruction each (one SSE2 instruction on
// x86-64). Every operation is the scalar one done twice, correctly rounded, so the values are bit for bit
// those of the scalar code.
#pragma once

#include <cmath>
#include <cstring>

#include "core/engine/fast_math.hpp"
#include "core/engine/field.hpp"
#include "core/engine/geometry.hpp"

#if PH_SSE2
#include <emmintrin.h>
#endif

namespace ph {

using Double2 = double __attribute__((vector_size(16)));
using Float2 = float __attribute__((vector_size(8)));
static_assert(sizeof(Gradient) == sizeof(Float2), "a gradient is two floats, loaded as one pair");

using Mask2 = long long __attribute__((vector_size(16)));  // a comparison of two Double2: all ones or zero per lane
PH_ALWAYS_INLINE inline Double2 splat(double v) { return Double2{v, v}; }
inline constexpr Double2 kOnes = {1.0, 1.0};

// A point or displacement as a pair, in one load.
static_assert(sizeof(Vec2) == sizeof(Double2), "a Vec2 is two doubles, loaded as one pair");
PH_ALWAYS_INLINE inline Double2 load2(const Vec2& v) {
  Double2 pair;
  std::memcpy(&pair, &v, sizeof pair);
  return pair;
}

// |v| of each lane: the sign bit cleared.
PH_ALWAYS_INLINE inline Double2 abs2(Double2 v) {
  return Double2(Mask2(v) & Mask2{0x7fffffffffffffffLL, 0x7fffffffffffffffLL});
}

// a in the lanes where m is all ones, b in the others: the bits of one or the other, unchanged.
PH_ALWAYS_INLINE inline Double2 select2(Mask2 m, Double2 a, Double2 b) {
  return Double2((Mask2(a) & m) | (Mask2(b) & ~m));
}

// Whether both lanes of a comparison hold.
PH_ALWAYS_INLINE inline bool all_true(Mask2 m) {
#if PH_SSE2
  return _mm_movemask_pd(__m128d(m)) == 3;
#else
  return m[0] != 0 && m[1] != 0;
#endif
}

// The square root of each lane (a vector extension has no square root of its own).
PH_ALWAYS_INLINE inline Double2 sqrt2(Double2 v) {
#if PH_SSE2
  return Double2(_mm_sqrt_pd(__m128d(v)));
#else
  return Double2{std::sqrt(v[0]), std::sqrt(v[1])};
#endif
}

// The slopes along the direction (mx, my in both lanes) of two gradients: g.x * m.x + g.y * m.y of each, in
// double, as the scalar expression computes it.
PH_ALWAYS_INLINE inline Double2 slopes_along(const Gradient* a, const Gradient* b, Double2 mx, Double2 my) {
#if PH_SSE2
  // One load and one conversion per gradient (GCC makes two of each from the generic form).
  const Double2 da = Double2(_mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(a)))));
  const Double2 db = Double2(_mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(b)))));
#else
  Float2 fa, fb;
  std::memcpy(&fa, a, sizeof fa);
  std::memcpy(&fb, b, sizeof fb);
  const Double2 da = __builtin_convertvector(fa, Double2), db = __builtin_convertvector(fb, Double2);
#endif
  return __builtin_shufflevector(da, db, 0, 2) * mx + __builtin_shufflevector(da, db, 1, 3) * my;
}

}  // namespace ph
