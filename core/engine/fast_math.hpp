// Cheap replacements for libm functions on the per-texel path, with their accuracy stated.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

// For what the walk calls once per step (a lambda, a method's arithmetic): GCC otherwise may leave it out of
// line once a translation unit has many walks, and the samples then go through memory.
#if defined(__GNUC__)
#define PH_ALWAYS_INLINE __attribute__((always_inline))
#else
#define PH_ALWAYS_INLINE
#endif

// Whether the engine uses its SSE2 forms (x86-64), or the portable ones that any other CPU compiles; both give the
// same bits. PH_PORTABLE_MATH (CMake option of the same name) asks for the portable ones on x86-64 too, so that they
// are compiled and tested (the sanitizer build does).
#if defined(__SSE2__) && !defined(PH_PORTABLE_MATH)
#define PH_SSE2 1
#else
#define PH_SSE2 0
#endif

namespace ph {

// atan to about 2e-7 rad (float accuracy) at a third of libm's cost: reduction to |r| <= tan(pi/8) and
// the classic odd minimax polynomial of single-precision atan. The curvature method only needs the
// angle difference of neighbouring texels in degrees to ~1e-5 (tests/test_methods.cpp checks the bound).
PH_ALWAYS_INLINE inline double fast_atan(double x) {
  constexpr double kTan3PiOver8 = 2.414213562373095;
  constexpr double kTanPiOver8 = 0.4142135623730950;
  // The polynomial, for |r| <= tan(pi/8).
  const auto odd = [](double r) PH_ALWAYS_INLINE {
    const double z = r * r;
    const double poly = (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1);
    return poly * z * r + r;
  };
  const double ax = std::abs(x);
  // The common case (neighbouring slopes): no reduction. The polynomial is odd, so reading x itself gives the
  // bits of the reduced form's result with its sign restored, one addition and a select shorter.
  if (ax <= kTanPiOver8) [[likely]]
    return odd(x);
  // Reduced about pi/2 or pi/4 (and a NaN, which stays NaN).
  const double result =
      ax > kTan3PiOver8 ? std::numbers::pi / 2 + odd(-1.0 / ax) : std::numbers::pi / 4 + odd((ax - 1.0) / (ax + 1.0));
  return x < 0.0 ? -result : result;
}

// -1, 0 or 1, without a branch: the sign of a frame's motion is random from frame to frame.
inline int sign_of(double v) { return static_cast<int>(v > 0.0) - static_cast<int>(v < 0.0); }

// floor for |v| < 2^31 without libm (floor is a ~40-instruction call on baseline x86-64).
inline std::int32_t floor_to_int(double v) {
  const auto i = static_cast<std::int32_t>(v);
  return i - (v < static_cast<double>(i) ? 1 : 0);
}

// std::round (halves away from zero) without the libm call (baseline x86-64 has no rounding instruction): the
// same value for every double, the sign of a zero included. From 2^52 on every double is whole.
inline double round_half_away(double v) {
  if (!(std::abs(v) < 4503599627370496.0)) return v;                       // whole already, or NaN or infinite
  const double whole = static_cast<double>(static_cast<std::int64_t>(v));  // toward zero
  const double rest = v - whole;                                           // exact
  double rounded = whole;
  if (rest >= 0.5) {
    rounded += 1.0;
  } else if (rest <= -0.5) {
    rounded -= 1.0;
  }
  return std::copysign(rounded, v);
}

// Length of a vector; falls back to hypot only where the squares could overflow or underflow to 0
// (a motion under 1e-162 px would otherwise have length 0 and be lost).
inline double fast_length(double x, double y) {
  const double ax = std::abs(x), ay = std::abs(y);
  if (ax < 1e150 && ay < 1e150 && (ax > 1e-150 || ay > 1e-150)) return std::sqrt(x * x + y * y);
  return std::hypot(x, y);
}

}  // namespace ph
