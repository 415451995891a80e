// libFuzzer target for the scene file parser (TOML, the daemon's config file): any input either parses or
// throws ConfigError, and what parses holds what the loader relies on: every region has a non-empty
// rectangle and a method that can be made, and the pointer speed is finite and in range. Images are not
// read (a path in the text is only resolved).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config/scene_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ph::SceneSpec spec;
  try {
    spec = ph::parse_scene_text(text, "/fuzz/scene.toml");
  } catch (const ph::ConfigError&) {
    return 0;  // refused with a message: fine
  }
  // An exception from here on escapes and counts as a crash.
  const double speed = spec.daemon.pointer_speed;
  if (!std::isfinite(speed) || speed <= 0 || speed > ph::kMaxPointerSpeed) __builtin_trap();
  for (const ph::RegionSpec& region : spec.regions) {
    if (region.rect.w <= 0 || region.rect.h <= 0) __builtin_trap();
    if (ph::make_method(region) == nullptr) __builtin_trap();
  }
  return 0;
}
