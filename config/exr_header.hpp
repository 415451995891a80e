// A check of an OpenEXR file's headers before OpenImageIO opens it. OpenEXR allocates every attribute's
// value at the size the file claims before reading it, so a file of a few bytes that claims a 2 GB
// attribute makes the image reader child allocate and zero 2 GB (or fail on its address-space limit after
// seconds of work). No real file claims more bytes than it holds: such a file is refused here, from its
// headers alone, before any of it is decoded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "config/image_io.hpp"

namespace ph {

// Why the headers of an OpenEXR file (its first bytes; `file_size` is the whole file's size) cannot be
// those of a readable file within `limits`, or nothing. Reads the magic number, the version field, each
// attribute's name, type and size, and the values OpenEXR sizes itself by: a known fixed-size type must have
// its size, a channel list, string vector or preview must end where its size says, the data window and the
// number of channels must be within the limits. `head` may end before the file does; what it does not show
// is not checked.
std::optional<std::string> exr_header_problem(std::span<const std::uint8_t> head, std::uint64_t file_size,
                                              const ImageLimits& limits = {});

// Reads the start of `path` and throws FieldError("PATH: reason") on a problem exr_header_problem finds.
void check_exr_header(const std::filesystem::path& path, const ImageLimits& limits);

}  // namespace ph
