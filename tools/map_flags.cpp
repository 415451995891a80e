#include "tools/map_flags.hpp"

#include <stdexcept>

#include "core/engine/decode.hpp"
#include "tools/finite_check.hpp"

namespace ph::tools {

void add_map_flags(CLI::App& app, MapFlags& flags) {
  flags.options = {
      app.add_option("--normal-green", flags.normal_green, "Green channel convention of the normal map")
          ->check(CLI::IsMember({"opengl", "directx"}))
          ->capture_default_str(),
      app.add_option("--normal-encoding", flags.normal_encoding,
                     "auto: unorm for integer images, signed for float ones")
          ->check(CLI::IsMember({"auto", "unorm", "signed"}))
          ->capture_default_str(),
      app.add_option("--depth-zero", flags.depth_zero, "Depth map value of height 0")
          ->check(finite_number())
          ->check(CLI::Range(-kMaxDepthZero, kMaxDepthZero))
          ->capture_default_str(),
      app.add_option("--relief-px", flags.relief_px, "Screen px of height per unit of depth map value")
          ->check(finite_number())
          ->check(CLI::Range(-kMaxReliefPx, kMaxReliefPx))
          ->capture_default_str(),
  };
}

std::vector<std::string> given_map_flags(const MapFlags& flags) {
  std::vector<std::string> given;
  for (const CLI::Option* option : flags.options) {
    if (option->count() > 0) given.push_back(option->get_name());
  }
  return given;
}

void check_map_flags_have_their_map(const MapFlags& flags, bool normal_map, bool depth_map) {
  for (const CLI::Option* option : flags.options) {
    if (option->count() == 0) continue;
    const std::string name = option->get_name();
    const bool for_normals = name == "--normal-green" || name == "--normal-encoding";
    if (for_normals && !normal_map) {
      throw std::invalid_argument(name + " says how to decode a normal map: give --normal-map, or leave it out");
    }
    if (!for_normals && !depth_map) {
      throw std::invalid_argument(name + " says how to decode a depth map: give --depth-map, or leave it out");
    }
  }
}

void apply_map_flags(const MapFlags& flags, FieldSources& sources) {
  sources.normal_options.green = flags.normal_green == "directx" ? GreenConvention::directx : GreenConvention::opengl;
  sources.normal_options.encoding = flags.normal_encoding == "unorm"    ? NormalEncoding::unorm
                                    : flags.normal_encoding == "signed" ? NormalEncoding::signed_values
                                                                        : NormalEncoding::automatic;
  sources.depth_options.depth_zero = flags.depth_zero;
  sources.depth_options.relief_px = flags.relief_px;
}

}  // namespace ph::tools
