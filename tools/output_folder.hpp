// The output folder of a command that measures for a long time before it writes: checked before the work starts,
// so that a folder that cannot take the files fails the command at once rather than after minutes of measuring.
#pragma once

#include <unistd.h>

#include <fmt/format.h>

#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string_view>

namespace ph::tools {

// Creates `outdir` if needed; throws std::runtime_error naming the file or folder when `outdir` cannot be written
// into or one of `names` in it is a folder.
inline void prepare_output_folder(const std::filesystem::path& outdir, std::initializer_list<std::string_view> names) {
  std::filesystem::create_directories(outdir);
  if (::access(outdir.c_str(), W_OK) != 0) {
    throw std::runtime_error(fmt::format("{}: cannot write into this folder", outdir.string()));
  }
  for (const std::string_view name : names) {
    const std::filesystem::path file = outdir / name;
    std::error_code ignored;
    if (std::filesystem::is_directory(file, ignored)) {
      throw std::runtime_error(
          fmt::format("{}: is a folder, where the results go to a file of that name", file.string()));
    }
  }
}

}  // namespace ph::tools
