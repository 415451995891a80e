// What the image reader child does with one request (config/image_reader_main.cpp): read, decode and
// resample a region's maps, or read an image's size, in this process through the image module. Every
// error becomes a Failure answer. Kept apart from main() so that the fuzz target runs the same path.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "config/image_io.hpp"
#include "config/image_wire.hpp"

namespace ph {

image_wire::Answer serve_image_request(const image_wire::Request& request, const ImageLimits& limits = {});

// The answer to a request, encoded for the wire. Out of memory on the way (the fields, or their copy for the wire,
// past the reader's address space) it is a Failure that says so, not the end of the reader.
std::vector<std::byte> answer_image_request(const std::vector<std::byte>& request);

// `answer` encoded for the wire; out of memory for the copy, a Failure that says so.
std::vector<std::byte> encode_answer(const image_wire::Answer& answer);

// What a Failure says when the reader ran out of memory.
std::string reader_out_of_memory();

}  // namespace ph
