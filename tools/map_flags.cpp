#include "tools/map_flags.hpp"

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

void apply_map_flags(const MapFlags& flags, FieldSources& sources) {
  sources.normal_options.green = flags.normal_green == "directx" ? GreenConvention::directx : GreenConvention::opengl;
  sources.normal_options.encoding = flags.normal_encoding == "unorm"    ? NormalEncoding::unorm
                                    : flags.normal_encoding == "signed" ? NormalEncoding::signed_values
                                                                        : NormalEncoding::automatic;
  sources.depth_options.depth_zero = flags.depth_zero;
  sources.depth_options.relief_px = flags.relief_px;
}

}  // namespace ph::tools
