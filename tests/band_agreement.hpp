// For the load-time passes that work in bands of rows on threads (core/engine/row_bands.hpp).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <functional>

#include "core/engine/field.hpp"

namespace ph {

// Expects `pass` (given its thread count) to give on 2, 3 and 4 threads the gradients it gives on one, to the bit.
inline void expect_bands_agree_with_one(const std::function<GradientField(unsigned threads)>& pass) {
  const GradientField one = pass(1);
  for (const unsigned threads : {2u, 3u, 4u}) {
    const GradientField banded = pass(threads);
    ASSERT_EQ(banded.values.size(), one.values.size());
    for (std::size_t i = 0; i < one.values.size(); ++i) {
      ASSERT_EQ(banded.values[i].x, one.values[i].x) << threads << " threads, texel " << i;
      ASSERT_EQ(banded.values[i].y, one.values[i].y) << threads << " threads, texel " << i;
    }
  }
}

}  // namespace ph
