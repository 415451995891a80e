#include "config/image_reader.hpp"

#include <exception>
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
  } catch (const std::exception& e) {  // e.g. std::bad_alloc under the memory limit
    return image_wire::Failure{std::string("cannot read the image: ") + e.what()};
  }
}

}  // namespace ph
