// libFuzzer target for what the daemon's image reader child does with an image (config/image_reader.cpp): libpng for
// PNG (config/image_png.cpp), OpenImageIO's TIFF and OpenEXR readers through the image module, then decoding, repair
// and resampling to a region's size; and the answer as the daemon checks it (config/image_wire.cpp); and a PNG that
// config/png_whole.cpp reads whole must be what libpng reads, to the bit. The first byte picks the file's extension
// (which reader reads it), whether it is read as a normal map or a depth map and, for a PNG, whether every chunk's
// CRC is set right before it is read (so that mutated chunks reach the inflating and unfiltering of
// config/png_whole.cpp and libpng instead of failing their CRC); the rest is the file. Any input must give fields the
// daemon accepts or a Failure; a crash here is one the child would have had (and only the child, in the daemon). An
// exception other than the refusals (FieldError, bad_alloc), which the reader answers as a Failure in the daemon,
// escapes in fuzz builds (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION) and counts as a crash.
#include <fcntl.h>
#include <unistd.h>

#include <libdeflate.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "config/image_png.hpp"
#include "config/image_reader.hpp"
#include "config/image_wire.hpp"
#include "config/png_whole.hpp"

namespace {

// Files in a tmpfs, rewritten for each input, removed when the process ends (libFuzzer's fork mode starts a process
// per job: they piled up in /dev/shm).
struct ScratchFiles {
  std::string base = "/dev/shm/ph-fuzz-image-" + std::to_string(::getpid());
  std::string paths[3] = {base + ".png", base + ".tif", base + ".exr"};
  ~ScratchFiles() {
    for (const std::string& path : paths) ::unlink(path.c_str());
  }
};
const std::string& scratch(const char* extension) {
  static const ScratchFiles files;
  const int i = extension[1] == 'p' ? 0 : extension[1] == 't' ? 1 : 2;
  return files.paths[i];
}

// Sets the CRC of every whole chunk of a PNG file (after the 8-byte signature: length, type, data, CRC).
void set_png_crcs(std::vector<std::uint8_t>& png) {
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::size_t length =
        std::size_t{png[at]} << 24 | std::size_t{png[at + 1]} << 16 | std::size_t{png[at + 2]} << 8 | png[at + 3];
    if (length > png.size() - at - 12) return;
    const std::uint32_t crc = libdeflate_crc32(0, &png[at + 4], length + 4);
    for (int k = 0; k < 4; ++k) png[at + 8 + length + k] = static_cast<std::uint8_t>(crc >> (24 - 8 * k));
    at += 12 + length;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".png", ".tif", ".exr"};
  const std::string& path = scratch(kExtensions[data[0] % 3]);
  std::vector<std::uint8_t> file(data + 1, data + size);
  if (data[0] % 3 == 0 && (data[0] / 6) % 2 == 1) set_png_crcs(file);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return 0;
  const bool written = ::write(fd, file.data(), file.size()) == static_cast<ssize_t>(file.size());
  ::close(fd);
  if (!written) return 0;

  ph::image_wire::FieldsRequest request;
  const bool as_normals = (data[0] / 3) % 2 == 1;
  if (as_normals) {
    request.sources.normal_map = path;
    request.needs.gradient = true;
  } else {
    request.sources.depth_map = path;
    request.needs = {true, true};  // gradient from depth as well
  }
  request.width = 24;  // larger and smaller than the seeds: both ways of resampling
  request.height = 4;
  // Smaller limits than the daemon's, so that a header claiming a large image is refused rather than
  // allocated and zeroed (at 2^20 pixels that alone held the fuzzer to 20 executions a second; the child
  // has RLIMIT_AS for the daemon's limits). The decoders still see every size up to 256 x 256.
  ph::ImageLimits limits;
  limits.max_pixels = 1 << 16;
  limits.max_side = 1024;
  limits.max_channels = 4;  // what normal and depth maps use
  const ph::image_wire::Request as_request{request};
  const ph::image_wire::Answer answer = ph::serve_image_request(as_request, limits);
  // What the daemon does with it: an answer it would refuse (a NaN, a field of the wrong size) is a bug
  // of the reader, so the WireError escapes and counts as a crash.
  const ph::image_wire::Answer checked = ph::image_wire::decode_answer(ph::image_wire::encode(answer), as_request);
  if (answer.index() != checked.index()) __builtin_trap();
  // A PNG the whole-file reader takes must be what libpng reads, to the bit.
  if (data[0] % 3 == 0) {
    if (const std::optional<ph::RawImage> whole = ph::read_png_whole(path, limits)) {
      const ph::RawImage libpng = ph::read_png_with_libpng(path, limits);  // throws: a file libpng refuses
      if (whole->width != libpng.width || whole->height != libpng.height || whole->channels != libpng.channels ||
          whole->code_max != libpng.code_max || whole->pixels.size() != libpng.pixels.size() ||
          std::memcmp(whole->pixels.data(), libpng.pixels.data(), whole->pixels.size() * sizeof(float)) != 0) {
        __builtin_trap();
      }
    }
  }
  // The size request (materials ask it) opens the file as the fields request did: not repeated here,
  // which would halve the executions for no new path.
  return 0;
}

// A smaller quarantine than ASan's 256 MB: OpenImageIO's reads free buffers of megabytes, and poisoning
// them took most of the time. OpenImageIO keeps its last error message per thread for good, which
// LeakSanitizer would call a leak. An allocation too large fails as it does in the reader child (under
// RLIMIT_AS): std::bad_alloc, which the reader answers as a Failure.
extern "C" const char* __asan_default_options() {
  return "quarantine_size_mb=32:detect_leaks=0:allocator_may_return_null=1";
}
