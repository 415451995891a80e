// A frame on the flat outside (core/engine/traversal.hpp): the cursor moves by the motor with C/D 1, no walk; one
// axis at a time for the traversal's own flat frames, both axes at once for advance()'s frames far from every region.
#pragma once

#include <cstddef>

#include "core/engine/frame.hpp"
#include "core/engine/grid_walk.hpp"
#include "core/engine/pair_math.hpp"

namespace ph {

// A frame that meets no region and no effect: C/D 1 all the way, no walk.
// Written component by component, and the texel stored whole: reading back a texel just stored as two halves
// costs a failed store-to-load forwarding each time. So does GCC's packing of the motor's two doubles (two
// registers) into one through the stack to add them as a pair, hence no SLP vectorisation here (gcc 12: about
// a third of a flat frame's time).
#if defined(__GNUC__) && !defined(__clang__)
#define PH_NO_SLP [[gnu::optimize("no-tree-slp-vectorize")]]
#else
#define PH_NO_SLP
#endif
PH_NO_SLP PH_ALWAYS_INLINE inline FrameResult flat_frame(CursorState& cursor, Vec2 motor) {
  const double ex = cursor.position.x + motor.x, ey = cursor.position.y + motor.y;
  Texel t = cursor.texel;
  if (motor.x != 0.0) t.x = cell_behind_predictable(ex, motor.x);
  if (motor.y != 0.0) t.y = cell_behind_predictable(ey, motor.y);
  cursor.texel = t;
  cursor.came_from = t;
  cursor.position.x = ex;
  cursor.position.y = ey;
  FrameResult result;
  result.display.x = motor.x;
  result.display.y = motor.y;
  return result;
}

#if PH_SSE2
// flat_frame with both axes at once, for advance()'s frames far from every region, a motor finite and not zero: the
// cursor moves by the motor, each axis's texel is the cell behind the motion (cell_behind_predictable), an axis without
// motion keeping its texel, and came_from is the texel; display = motor, C/D 1. Without a branch, and the
// position and both texels each read and written whole (a store read back in halves cannot be forwarded).
PH_ALWAYS_INLINE inline FrameResult flat_frame_pair(CursorState& cursor, Double2 motor) {
  const __m128d m = __m128d(motor), zero = _mm_setzero_pd();
  const __m128d end = _mm_add_pd(_mm_loadu_pd(&cursor.position.x), m);
  // The low dword of each lane of a comparison: -1 where it holds, for the cells' int32 pairs.
  const auto dwords = [](__m128d mask) PH_ALWAYS_INLINE { return _mm_shuffle_epi32(_mm_castpd_si128(mask), 0x08); };
  __m128i cell = _mm_cvttpd_epi32(end);                                          // truncated toward 0
  cell = _mm_add_epi32(cell, dwords(_mm_cmplt_pd(end, _mm_cvtepi32_pd(cell))));  // floor
  // On a whole coordinate, the cell behind a positive motion is the one before.
  const __m128d whole = _mm_cmpeq_pd(end, _mm_cvtepi32_pd(cell));
  cell = _mm_add_epi32(cell, dwords(_mm_and_pd(whole, _mm_cmplt_pd(zero, m))));
  const __m128i still = dwords(_mm_cmpeq_pd(m, zero));
  const __m128i kept = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&cursor.texel));
  cell = _mm_or_si128(_mm_and_si128(still, kept), _mm_andnot_si128(still, cell));
  static_assert(offsetof(CursorState, came_from) == offsetof(CursorState, texel) + sizeof(Texel));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(&cursor.texel), _mm_unpacklo_epi64(cell, cell));  // and came_from
  _mm_storeu_pd(&cursor.position.x, end);
  FrameResult result;
  _mm_storeu_pd(&result.display.x, m);
  return result;
}
#else
PH_ALWAYS_INLINE inline FrameResult flat_frame_pair(CursorState& cursor, Double2 motor) {
  return flat_frame(cursor, {motor[0], motor[1]});
}
#endif

}  // namespace ph
