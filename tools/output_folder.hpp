// The output folder of a command that measures for a long time before it writes: checked before the work starts,
// so that a folder that cannot take the files fails the command at once rather than after minutes of measuring.
#pragma once

#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include "config/staged_write.hpp"

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

// The files a command writes into its folder, as one set: each is written under a temporary name beside its own
// (`.NAME.PID.partial`), and commit() renames them all over their names once every one is written, so that a run
// that fails or is interrupted leaves the folder's files as they were (an interrupted one, its temporaries beside
// them), never some of this run's files beside an older run's. Temporaries not committed go with the set.
class OutputSet {
 public:
  explicit OutputSet(std::filesystem::path outdir) : outdir_(std::move(outdir)) {}
  ~OutputSet() {
    for (const auto& [path, staged] : files_) ::unlink(staged.c_str());
  }
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // Where to write the file `name` of the folder until commit(). A link, a FIFO or a device of that name is written
  // through, as CsvFile writes it (a rename would replace it).
  std::filesystem::path stage(std::string_view name) {
    std::filesystem::path path = outdir_ / name;
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) return path;
    std::filesystem::path staged = staged_path(path);
    files_.emplace_back(std::move(path), staged);
    return staged;
  }

  // Renames every staged file over its name (keeping the mode of a file it replaces).
  void commit() {
    for (const auto& [path, staged] : files_) {
      struct stat st {};
      if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::chmod(staged.c_str(), st.st_mode & 07777);
      if (::rename(staged.c_str(), path.c_str()) != 0)
        throw std::runtime_error(fmt::format("{}: cannot replace it: {}", path.string(), std::strerror(errno)));
    }
    files_.clear();
  }

 private:
  std::filesystem::path outdir_;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> files_;  // (its name, where it is written)
};

}  // namespace ph::tools
