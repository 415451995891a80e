// libFuzzer target for the evemu reader: any input either reads or fails with RecordingError, and what reads
// writes back into a file that reads to the same recording.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "recording/evemu.hpp"

namespace {

bool same(const ph::Recording& a, const ph::Recording& b) { return a.device == b.device && a.events == b.events; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  ph::Recording first;
  try {
    first = ph::read_evemu(in, "fuzz");
  } catch (const ph::RecordingError&) {
    return 0;  // refused with a message: fine
  }
  // Anything read must write and read back; an exception from here on escapes and counts as a crash.
  std::ostringstream out;
  ph::write_evemu(out, first);
  std::istringstream written(out.str());
  const ph::Recording second = ph::read_evemu(written, "fuzz round trip");
  if (!same(first, second)) __builtin_trap();
  return 0;
}
