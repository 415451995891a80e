#include <fmt/core.h>

#include "config/target_files.hpp"
#include "core/engine/targets.hpp"
#include "tools/argument_checks.hpp"
#include "tools/commands.hpp"
#include "tools/progress_line.hpp"

namespace ph::tools {

Run add_targets_command(CLI::App& app) {
  auto outdir = std::make_shared<std::string>();
  app.add_option("OUTDIR", *outdir, "Folder to write into (created if needed); existing target files are overwritten")
      ->required()
      ->check(non_empty_path());
  app.footer(
      "For each target NAME (e.g. bump-gaussian-h1-r200) writes NAME.normal.png (16-bit, exact analytic normals,\n"
      "OpenGL green), NAME.depth.png (16-bit, v = (depth + 1) / 2 of the depth normalised to [-1, 1]) and\n"
      "NAME.toml, a one-region scene that uses both. 500 x 500 px; bump or hole; linear, Gaussian (sigma 1/3)\n"
      "or polynomial (1 - u^4) profile; height 0.25 or 1 (1 = 100 px of relief); radius 100 or 200 px.");
  return [outdir] {
    const auto targets = all_targets();
    ProgressLine progress;
    write_target_files(*outdir, targets, [&progress](std::size_t done, std::size_t total, const TargetSpec& spec) {
      progress.show(fmt::format("[{:2}/{}] {}", done, total, spec.name()));
    });
    progress.finish();
    fmt::print("wrote {} targets to {}\n", targets.size(), *outdir);
    return 0;
  };
}

}  // namespace ph::tools
