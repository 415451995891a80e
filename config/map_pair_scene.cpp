#include "config/map_pair_scene.hpp"
#include "common/unique_fd.hpp"

#include <fmt/format.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "config/image_io.hpp"
#include "config/staged_write.hpp"
#include "config/write_all.hpp"

namespace ph {

std::string toml_float(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // 'n': inf and nan need no suffix
  return text;
}

// With the file system's reason, which std::ofstream does not keep ("Is a directory", "No space left on device").
void write_text_file(const std::filesystem::path& path, const std::string& text) {
  const auto fail = [&path](const char* what) {
    throw std::runtime_error(fmt::format("{}: cannot {}: {}", path.string(), what, std::strerror(errno)));
  };
  UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666));
  if (!fd) fail("write");
  if (!write_all(fd.get(), text.data(), text.size())) fail("write");  // (closed on the way out, errno kept)
  if (fd.close() != 0) fail("write");
}

std::string map_pair_scene_text(const MapPairScene& scene) {
  return fmt::format(
      "{header}"
      "[[region]]\n"
      "name = \"{name}\"\n"
      "x = 0\n"
      "y = 0\n"
      "width = {size}\n"
      "height = {size}\n"
      "method = \"curvature\"\n"
      "normal_map = \"{name}.normal.png\"\n"
      "normal_green = \"opengl\"\n"
      "depth_map = \"{name}.depth.png\"\n"
      "depth_zero = 0.5\n"
      "relief_px = {scene_relief}   # {comment}\n",
      fmt::arg("header", scene.header), fmt::arg("name", scene.name), fmt::arg("size", scene.size),
      fmt::arg("scene_relief", toml_float(2.0 * scene.relief_px)), fmt::arg("comment", scene.relief_comment));
}

void write_map_pair_files(const std::filesystem::path& outdir, const MapPairScene& scene, const NormalImage& normals,
                          const Grid<float>& heights) {
  Grid<float> values = heights;  // h / relief_px in [-1, 1] mapped to v in [0, 1], the range a unorm image holds
  for (float& v : values.values) v = static_cast<float>((v / scene.relief_px + 1.0) / 2.0);
  // Each whole or as it was: a run cut short leaves no truncated map that the next run takes for a target's.
  write_staged(outdir / (scene.name + ".normal.png"), [&](const auto& path) { write_normal_png16(path, normals); });
  write_staged(outdir / (scene.name + ".depth.png"), [&](const auto& path) { write_gray_png16(path, values); });
  write_staged(outdir / (scene.name + ".toml"),
               [&](const auto& path) { write_text_file(path, map_pair_scene_text(scene)); });
}

}  // namespace ph
