// What the image reader child does with one request (config/image_reader_main.cpp): read, decode and
// resample a region's maps, or read an image's size, in this process through the image module. Every
// error becomes a Failure answer. Kept apart from main() so that the fuzz target runs the same path.
#pragma once

#include "config/image_io.hpp"
#include "config/image_wire.hpp"

namespace ph {

image_wire::Answer serve_image_request(const image_wire::Request& request, const ImageLimits& limits = {});

}  // namespace ph
