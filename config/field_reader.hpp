// Where a scene's region fields come from: read and decoded in this process (the tools), or in a
// short-lived sandboxed child (the daemon, config/image_child.hpp), so that the process that holds the
// mice never maps the image library nor parses an image file.
#pragma once

#include <cstdint>
#include <filesystem>

#include "config/field_loader.hpp"
#include "config/image_io.hpp"

namespace ph {

class FieldReader {
 public:
  virtual ~FieldReader() = default;
  // As load_region_fields (config/field_loader.hpp), errors included.
  virtual RegionFields load_fields(const FieldSources& sources, std::int32_t width, std::int32_t height,
                                   FieldNeeds needs, FieldLoadReport& report) = 0;
  // As read_image_size (config/image_io.hpp).
  virtual ImageSize image_size(const std::filesystem::path& path) = 0;
};

// Reads the images here, through the image module.
class InProcessFieldReader final : public FieldReader {
 public:
  RegionFields load_fields(const FieldSources& sources, std::int32_t width, std::int32_t height, FieldNeeds needs,
                           FieldLoadReport& report) override {
    return load_region_fields(sources, width, height, needs, report);
  }
  ImageSize image_size(const std::filesystem::path& path) override { return read_image_size(path); }
};

}  // namespace ph
