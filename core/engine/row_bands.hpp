#pragma once

// Work on a field cut into bands of rows, one band per thread: for load-time passes whose every output row depends
// only on rows of the input, so that the bands agree to the bit with the whole field worked out at once.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>

namespace ph {

// Rows [begin, end) of a field; the default is every row.
struct RowRange {
  std::int32_t begin = 0;
  std::int32_t end = std::numeric_limits<std::int32_t>::max();
  RowRange within(std::int32_t height) const { return {std::clamp(begin, 0, height), std::clamp(end, 0, height)}; }
  bool empty() const { return end <= begin; }
};

// A load makes at most this many threads for one pass: beyond it the passes wait for memory, not arithmetic.
inline constexpr unsigned kMaxRowBandThreads = 4;

// No band is cut of fewer rows than this: a thread costs tens of microseconds to start.
inline constexpr std::int32_t kMinRowBandRows = 64;

// How many bands a field of `height` rows is cut into for `threads` threads (0: one per core, at most
// kMaxRowBandThreads), none of fewer than kMinRowBandRows rows; at least one.
unsigned row_band_count(std::int32_t height, unsigned threads);

// Calls `work` for `bands` consecutive bands of rows that together cover [0, height), each but the first on a thread of
// its own; the caller's thread works out the first, and any band whose thread cannot be started. An exception thrown
// in any band (memory) is thrown again here once all have ended.
void for_each_row_band(std::int32_t height, unsigned bands, const std::function<void(RowRange)>& work);

// The passes' way in: `work` over bands of rows for `threads` threads (0: one per core, at most kMaxRowBandThreads;
// bands of kMinRowBandRows rows at least), for_each_row_band(height, row_band_count(height, threads), work).
void for_row_bands_on_threads(std::int32_t height, unsigned threads, const std::function<void(RowRange)>& work);

}  // namespace ph
