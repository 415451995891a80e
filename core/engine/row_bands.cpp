#include "core/engine/row_bands.hpp"

#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace ph {

unsigned row_band_count(std::int32_t height, unsigned threads) {
  if (threads == 0) threads = std::min(std::max(std::thread::hardware_concurrency(), 1u), kMaxRowBandThreads);
  const auto most = static_cast<unsigned>(std::max<std::int32_t>(height / kMinRowBandRows, 1));
  return std::max(std::min(threads, most), 1u);
}

void for_each_row_band(std::int32_t height, unsigned bands, const std::function<void(RowRange)>& work) {
  const auto count = static_cast<std::int32_t>(std::max(bands, 1u));
  auto band = [&](std::int32_t b) {
    return RowRange{static_cast<std::int32_t>(std::int64_t{height} * b / count),
                    static_cast<std::int32_t>(std::int64_t{height} * (b + 1) / count)};
  };
  std::vector<std::exception_ptr> failed(static_cast<std::size_t>(count));
  const auto run_band = [&](std::int32_t b) {
    try {
      work(band(b));
    } catch (...) {
      failed[static_cast<std::size_t>(b)] = std::current_exception();
    }
  };
  {
    std::vector<std::jthread> workers;
    std::vector<std::int32_t> here{0};
    for (std::int32_t b = 1; b < count; ++b) {
      try {
        workers.emplace_back(run_band, b);
      } catch (const std::system_error&) {
        here.push_back(b);
      }
    }
    for (std::int32_t b : here) run_band(b);
  }  // the workers join here
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
}

void for_row_bands_on_threads(std::int32_t height, unsigned threads, const std::function<void(RowRange)>& work) {
  for_each_row_band(height, row_band_count(height, threads), work);
}

}  // namespace ph
