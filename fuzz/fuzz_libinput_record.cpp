// libFuzzer target for the libinput record reader: any input must either parse or throw RecordingError.
// Any other exception escaping (yaml-cpp's own, say) or any crash is a bug in the reader. (The reader's last safety
// net, which turns a yaml-cpp exception its checks missed into a RecordingError, lets it through in fuzz builds:
// FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION.)
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "recording/libinput_record.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const ph::Recording recording = ph::read_libinput_record(in, "fuzz");
    (void)recording;
  } catch (const ph::RecordingError&) {
  }
  return 0;
}
