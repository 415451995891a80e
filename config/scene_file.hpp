// Scene files (TOML): regions with their images, method and parameters, and the optional [daemon] table
// (config/daemon_config.hpp); the scene file is the daemon's config file. Every error names the file, the
// line and the key, and says what is allowed. Unknown keys are errors: a typo must not pass silently.
#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/field_loader.hpp"
#include "core/effect_materials.hpp"
#include "core/effect_wells.hpp"
#include "core/method_curvature.hpp"
#include "core/method_depth.hpp"
#include "core/scene.hpp"

namespace ph {

// Where the daemon reads its scene file when it is given none.
inline constexpr std::string_view kDefaultSceneFile = "/etc/pseudohaptic/scene.toml";

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// none: C/D 1 (a region rendered by its effects only: materials, gravity wells).
enum class MethodKind { curvature, depth, none };

std::optional<MethodKind> parse_method_kind(std::string_view name);
std::string_view method_kind_name(MethodKind kind);

// A region as the scene file describes it, before its images are read.
struct RegionSpec {
  std::string name;
  Rect rect;
  MethodKind method = MethodKind::curvature;
  FieldSources sources;  // paths already resolved against the scene file's folder
  CurvatureParams curvature;
  DepthParams depth;
  std::optional<MaterialsParams> materials;  // [region.materials]: curvature classes as materials
  std::optional<WellsParams> wells;          // [region.wells]: isophote or contour gravity wells
  int line = 0;                              // where the region starts in the file
};

struct SceneSpec {
  std::filesystem::path file;  // empty for a scene given as text
  std::vector<RegionSpec> regions;
  DaemonSettings daemon;  // the [daemon] table; its defaults when there is none
};

// `origin` names the text in errors and is the base for relative image paths.
SceneSpec parse_scene_text(std::string_view text, const std::filesystem::path& origin);
SceneSpec parse_scene_file(const std::filesystem::path& file);

MethodPtr make_method(const RegionSpec& region);

struct SceneLoadReport {
  std::vector<FieldLoadReport> regions;
};

// Reads every region's images (only those its method needs). Throws ConfigError naming the scene file
// and the region for an image that cannot be used.
Scene load_scene(const SceneSpec& spec, SceneLoadReport* report = nullptr);

// One line per region and map with invalid texels (counted, repaired and reported at load: docs/METHODS.md,
// "Screen, regions and fields"), "FILE:LINE: region 'NAME': " and invalid_texel_notes' text; none for a clean scene.
std::vector<std::string> invalid_texel_warnings(const SceneSpec& spec, const SceneLoadReport& report);

}  // namespace ph
