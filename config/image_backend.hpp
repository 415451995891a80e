// The interface between config/image_io.cpp and the image module (config/image_oiio.cpp, built as
// ph_image_oiio.so), which holds everything that touches OpenImageIO. The module is loaded with dlopen() on
// the first image read or written, so a program that never sees an image never maps OpenImageIO and its
// ~270 shared libraries. Internal to config/: callers use config/image_io.hpp.
//
// One exported symbol with C linkage returns the table; nothing else in the module is visible (a version
// script), so one dlsym finds it and nothing in the module interposes on the program's symbols. The table
// passes C++ types and lets FieldError through: module and program are built together from the same
// headers with the same compiler and share libstdc++ (exception types match by name on GCC/Linux).
// `version` changes whenever the table or a type it passes changes.
#pragma once

#include <cstdint>
#include <filesystem>

#include "config/image_io.hpp"
#include "core/engine/decode.hpp"

namespace ph::image_backend {

inline constexpr std::uint32_t kVersion = 1;
inline constexpr const char* kEntryPoint = "ph_image_backend_v1";
inline constexpr const char* kModuleFile = "ph_image_oiio.so";

enum class PixelType : std::uint32_t { uint8, uint16, float32 };

struct Table {
  std::uint32_t version = kVersion;
  // As ph::read_image_size and ph::read_image (config/image_io.hpp), errors included.
  ImageSize (*read_image_size)(const std::filesystem::path& path, const ImageLimits& limits) = nullptr;
  RawImage (*read_image)(const std::filesystem::path& path, const ImageLimits& limits) = nullptr;
  // Writes width x height pixels of `channels` interleaved values of `type` in the OpenImageIO format
  // `format` ("png", "openexr"), whatever the file name says. Throws FieldError("PATH: cannot write: ...").
  void (*write_image)(const std::filesystem::path& path, const char* format, std::int32_t width, std::int32_t height,
                      std::int32_t channels, PixelType type, const void* pixels) = nullptr;
};

using EntryPoint = const Table* (*)();

}  // namespace ph::image_backend
