#include "config/image_reader.hpp"

#include <fmt/format.h>

#include <sys/resource.h>

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <variant>

#include "config/field_loader.hpp"

namespace ph {

image_wire::Answer serve_image_request(const image_wire::Request& request, const ImageLimits& limits) {
  try {
    if (const auto* f = std::get_if<image_wire::FieldsRequest>(&request)) {
      image_wire::FieldsAnswer a;
      a.fields = load_region_fields(f->sources, f->width, f->height, f->needs, a.report, limits);
      return a;
    }
    return read_image_size(std::get<image_wire::SizeRequest>(request).path, limits);
  } catch (const FieldError& e) {
    return image_wire::Failure{e.what()};
  } catch (const std::bad_alloc&) {
    return image_wire::Failure{reader_out_of_memory()};
  } catch (const std::exception& e) {
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    throw;  // not a refusal of the file but a bug of ours (an out_of_range, say): what fuzz/fuzz_image.cpp looks for
#endif
    return image_wire::Failure{std::string("cannot read the image: ") + e.what()};
  }
}

std::string reader_out_of_memory() {
  // The limit the reader runs under: its own (config/reader_sandbox.hpp), or a tighter one it was started under.
  rlimit limit{};
  std::string allowed = "the memory the reader could have";
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    const std::uint64_t bytes = limit.rlim_cur;
    allowed = bytes % (std::uint64_t{1} << 30) == 0 ? fmt::format("the {} GiB the image reader may use", bytes >> 30)
                                                    : fmt::format("the {} MiB the image reader may use", bytes >> 20);
  }
  return fmt::format(
      "not enough memory to read it: reading the map for the region exceeds {} (at the peak the map's decoded "
      "texels, their copy resampled to the region's size and the region's fields with their copy for the daemon lie "
      "in memory together); make the region smaller",
      allowed);
}

std::vector<std::byte> encode_answer(const image_wire::Answer& answer) {
  try {
    return image_wire::encode(answer);
  } catch (const std::bad_alloc&) {  // the answer's copy for the wire
    return image_wire::encode(image_wire::Answer{image_wire::Failure{reader_out_of_memory()}});
  }
}

std::vector<std::byte> answer_image_request(const std::vector<std::byte>& request) {
  return encode_answer(serve_image_request(image_wire::decode_request(request)));
}

}  // namespace ph
