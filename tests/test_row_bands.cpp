// Bands of rows worked out on threads of their own (core/engine/row_bands.hpp): every row once, whatever the count,
// and an exception in one band thrown again once all have ended.
#include "core/engine/row_bands.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace ph {
namespace {

TEST(RowBands, CoverEveryRowOnceInBandsOfAtLeastTheLeast) {
  for (const std::int32_t height : {0, 1, 5, 63, 64, 129, 1000}) {
    for (const unsigned threads : {0u, 1u, 2u, 3u, 4u, 9u}) {
      SCOPED_TRACE(testing::Message() << height << " rows, " << threads << " threads");
      const unsigned bands = row_band_count(height, threads);
      EXPECT_GE(bands, 1u);
      EXPECT_LE(bands, threads == 0 ? kMaxRowBandThreads : threads);
      if (bands > 1) {
        EXPECT_GE(height / static_cast<std::int32_t>(bands), kMinRowBandRows);
      }
      std::vector<std::atomic<int>> seen(static_cast<std::size_t>(height));
      std::atomic<unsigned> calls{0};
      for_each_row_band(height, bands, [&](RowRange rows) {
        ++calls;
        for (std::int32_t y = rows.begin; y < rows.end; ++y) ++seen[static_cast<std::size_t>(y)];
      });
      EXPECT_EQ(calls, bands);
      for (std::int32_t y = 0; y < height; ++y) EXPECT_EQ(seen[static_cast<std::size_t>(y)], 1) << "row " << y;
    }
  }
}

TEST(RowBands, AnExceptionInOneBandIsThrownAgainAfterTheOthersEnded) {
  std::atomic<int> ended{0};
  EXPECT_THROW(for_each_row_band(400, 4,
                                 [&](RowRange rows) {
                                   if (rows.begin == 200) throw std::runtime_error("band 3");
                                   ++ended;
                                 }),
               std::runtime_error);
  EXPECT_EQ(ended, 3);
}

}  // namespace
}  // namespace ph
