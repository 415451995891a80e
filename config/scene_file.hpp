// Scene files (TOML): regions with their images, method and parameters, and the optional [daemon] table
// (config/daemon_config.hpp); the scene file is the daemon's config file. Every error names the file, the
// line and the key, and says what is allowed. Unknown keys are errors: a typo must not pass silently.
#pragma once

#include <any>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/field_loader.hpp"
#include "config/field_reader.hpp"
#include "core/effects/effect_materials.hpp"
#include "core/effects/effect_wells.hpp"
#include "core/engine/methods.hpp"
#include "core/engine/scene.hpp"

namespace ph {

// Where the daemon reads its scene file when it is given none.
inline constexpr std::string_view kDefaultSceneFile = "/etc/pseudohaptic/scene.toml";

// A region's width and height in px are at most this, and its area at most kMaxRegionTexels: an 8192 x 8192 hybrid
// region with materials and contour wells takes the image reader 3.3 GB of its 8 GiB and over a minute on two cores
// (docs/SERVICE.md, "Images"); a 16384 x 16384 one cannot be read under that limit.
inline constexpr std::int32_t kMaxRegionSide = 1 << 14;
inline constexpr std::int64_t kMaxRegionTexels = std::int64_t{1} << 26;  // 8192 x 8192
// The longest scene file read: thousands of regions take a few hundred KiB.
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t{4} << 20;

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A region as the scene file describes it, before its images are read.
struct RegionSpec {
  std::string name;
  Rect rect;
  // A method of the scene's registry (core/engine/methods.hpp); "none" is C/D 1, a region rendered by its
  // effects only (materials, gravity wells).
  std::string method = "curvature";
  FieldSources sources;  // paths already resolved against the scene file's folder
  // Per method name, the parameters of its [region.NAME] table; a method without one gets its defaults.
  std::map<std::string, MethodParams, std::less<>> method_params;
  std::map<std::string, int, std::less<>> method_table_lines;  // the method tables given, and their lines
  std::string method_in_file;                // `method` as the file gives it (the tools' --method may replace `method`)
  std::optional<MaterialsParams> materials;  // [region.materials]: curvature classes as materials
  std::optional<WellsParams> wells;          // [region.wells]: isophote or contour gravity wells
  // The region's own traversal, sampling and lut_directions (over the [daemon] table's); none: the scene's.
  std::optional<EngineOptions> engine;
  bool engine_auto = false;   // traversal = "auto": the traversal is chosen at load (core/engine/variant_choice.hpp)
  double accuracy_px = 0.25;  // auto's budget: the error a frame may add, px
  int line = 0;               // where the region starts in the file
  int normal_map_line = 0;    // where its normal_map and depth_map keys are (0: not given)
  int depth_map_line = 0;
  // Where the keys that say how to decode a map are written (normal_green, normal_encoding, depth_zero, relief_px).
  std::map<std::string, int, std::less<>> decoding_key_lines;
  bool own_lut_directions = false;  // the region sets lut_directions itself (not taking the [daemon] table's)
};

// The parameters of method class M in a region: its table's, else M's defaults (added to the region).
template <typename M>
typename M::Params& method_params(RegionSpec& region) {
  auto [at, added] = region.method_params.try_emplace(std::string(M::kName), typename M::Params{});
  return std::any_cast<typename M::Params&>(at->second);
}
template <typename M>
typename M::Params method_params(const RegionSpec& region) {
  const auto at = region.method_params.find(M::kName);
  return at == region.method_params.end() ? typename M::Params{} : std::any_cast<typename M::Params>(at->second);
}

struct SceneSpec {
  std::filesystem::path file;  // empty for a scene given as text
  std::vector<RegionSpec> regions;
  DaemonSettings daemon;                       // the [daemon] table; its defaults when there is none
  int mouse_dpi_line = 0;                      // where the [daemon] table sets mouse_dpi (0: it does not)
  int lut_directions_line = 0;                 // where the [daemon] table sets lut_directions (0: it does not)
  MethodRegistry methods = builtin_methods();  // what the regions' methods may be
};

// `origin` names the text in errors and is the base for relative image paths. `methods`: the methods a
// region may name (a test or a tool may add its own to the built-in ones).
SceneSpec parse_scene_text(std::string_view text, const std::filesystem::path& origin,
                           MethodRegistry methods = builtin_methods());
SceneSpec parse_scene_file(const std::filesystem::path& file, MethodRegistry methods = builtin_methods());

// Whether nothing is at `file` (the default scene file left out: the embedded scene runs). A folder on its path that
// the caller may not search says nothing of the file: not absent, so that parse_scene_file says why it cannot be read
// rather than the daemon running the embedded scene in its place.
bool scene_file_absent(const std::filesystem::path& file);

// The region's method from `methods`, with its parameters; throws ConfigError for a name not in `methods`
// and std::invalid_argument for parameters that are not valid.
MethodPtr make_method(const RegionSpec& region, const MethodRegistry& methods = builtin_methods());

struct SceneLoadReport {
  std::vector<FieldLoadReport> regions;
  std::vector<std::string> variants;  // per region: its traversal variant and why
};

// Reads every region's images (only those its method needs) through `reader` (nullptr: in this
// process). Throws ConfigError naming the scene file and the region for an image that cannot be used.
Scene load_scene(const SceneSpec& spec, SceneLoadReport* report = nullptr, FieldReader* reader = nullptr);

// One line per region and map with invalid texels (counted, repaired and reported at load: docs/METHODS.md,
// "Screen, regions and fields") or stretched out of proportion to the region, "FILE:LINE: region 'NAME': " and
// map_notes' text; none for a clean scene.
std::vector<std::string> map_warnings(const SceneSpec& spec, const SceneLoadReport& report);

// What the hybrid method found of a region's two maps (RegionFields::slope_comparison): whether their slopes have one
// sign, along each axis, and the ratio of the normal map's slopes to the depth map's, with the setting that would make
// them agree. Empty where the region has none of that (another method, a single map, too little resolved slope).
struct ReliefScale {
  SlopeComparison comparison;
  double relief_px = 100.0;                         // the region's
  GreenConvention green = GreenConvention::opengl;  // the region's normal_green
  // Along x, along y: most slopes both maps resolve are of opposite signs.
  bool opposite_x() const { return comparison.opposite_x.value_or(0.0) > 0.5; }
  bool opposite_y() const { return comparison.opposite_y.value_or(0.0) > 0.5; }
  // Most slopes the normal map resolves lie on depth map slopes it does not.
  bool depth_flat() const { return comparison.depth_flat.value_or(0.0) > 0.5; }
  // The ratio off 1 by more than a quarter, or any of the above.
  bool mismatched() const;
  // "the normal map's slopes are R times the depth map's ..." and, where mismatched, what to change to make them
  // agree; or which of the above holds, and what to check.
  std::string described() const;
  // described() and why it matters: for a warning where it is mismatched.
  std::string warning() const { return described() + " (the hybrid method compares them to find steps and noise)"; }
};
std::optional<ReliefScale> relief_scale(const RegionSpec& region, const RegionFields& fields);

// One line per region whose maps' scales are mismatched (relief_scale), "FILE:LINE: region 'NAME': " and what
// relief_px would make them agree; none where they agree.
std::vector<std::string> relief_scale_warnings(const SceneSpec& spec, const Scene& scene);

// One line per region whose gravity wells found no pattern texel (contour levels outside the heights, an isophote no
// normal meets), "FILE:LINE: region 'NAME': wells: ..." and what to check: such wells do nothing. None otherwise.
std::vector<std::string> effect_warnings(const SceneSpec& spec, const Scene& scene);

// One line per region whose method's settings make it feel flat, "FILE:LINE: region 'NAME': " and which: a depth
// region with gain = 0 (C/D 1 everywhere), as relief_px = 0 is warned of among the map notes. None otherwise.
std::vector<std::string> method_warnings(const SceneSpec& spec);

// One line per method table a region gives for a method it does not use ("FILE:LINE: region 'NAME': " and which):
// the daemon reads only its method's (the hybrid method none: it takes curvature's and depth's defaults);
// `pseudohaptic trace --method` reads the table of the method it is given.
std::vector<std::string> unused_method_table_warnings(const SceneSpec& spec);

// One line per key that says how to decode a map the region does not have ("FILE:LINE: region 'NAME': " and which):
// normal_green or normal_encoding without a normal_map, depth_zero or relief_px without a depth_map.
std::vector<std::string> unused_key_warnings(const SceneSpec& spec);

// A line for each [daemon] key that changes nothing: mouse_dpi with the flat profile in force, which does not read
// it (libinput's flat filter scales a mouse's own counts); lut_directions when no frame walks with a direction
// table of that count (neither the [daemon] traversal nor a region's without its own lut_directions is
// direction_lut).
std::vector<std::string> daemon_warnings(const SceneSpec& spec);

// What loading the scene found to warn of, in this order: map_warnings, relief_scale_warnings, effect_warnings,
// method_warnings, unused_method_table_warnings, unused_key_warnings and daemon_warnings. What the daemon logs at load
// (with desktop_warnings), and what the tools that load a scene file print.
std::vector<std::string> load_warnings(const SceneSpec& spec, const SceneLoadReport& report, const Scene& scene);

// Where a region of `rect` lies wholly or partly off `desktop`: "at X,Y (WxH px) lies outside the desktop X,Y WxH px:
// the cursor never reaches it, ..." or "at X,Y (WxH px): only WxH px of it lie on the desktop ..."; nullopt where
// all of it lies on the desktop.
std::optional<std::string> off_desktop_note(const Rect& rect, const Rect& desktop);

// One line per region of `scene` that lies wholly or partly off `desktop`, "region 'NAME' " and off_desktop_note's
// text: for a desktop learnt while running (the displays, the session helper's layout, a replay's --desktop).
std::vector<std::string> off_desktop_notes(const Scene& scene, const Rect& desktop);

// A folder the service's sandbox hides, and the setting of pseudohapticd.service that hides it.
struct HiddenFolder {
  std::string_view folder;   // "/home"
  std::string_view setting;  // "ProtectHome=yes"
  bool operator==(const HiddenFolder&) const = default;
};

// The folder of those the service's sandbox hides that `path` lies in, or nullopt: /home, /root and /run/user
// (ProtectHome=yes: there but empty or not to be entered), /tmp and /var/tmp (PrivateTmp=yes: the service has its
// own, empty). `path` made absolute against the working folder, as the scene file resolved it, as written and with the
// links it passes through followed.
std::optional<HiddenFolder> hidden_from_the_service(const std::filesystem::path& path);

// Why a user other than the owner and the group cannot read the file at `path` (not readable by others, or a folder
// on its path they may not enter), or nullopt (also when it is missing: its load says so). The service's user is such
// a user; ACLs are not looked at.
std::optional<std::string> unreadable_by_others(const std::filesystem::path& path);

// One line per region and map that lies where the service cannot read it (hidden_from_the_service, at its key's line:
// "FILE:LINE: region 'NAME': " and the map, the folder and where to keep images instead) or that its user may not
// read (unreadable_by_others), and one for the scene file itself if either is so; none where every file can be read.
// pseudohapticd run by hand reads them; under systemd its load fails.
std::vector<std::string> service_path_warnings(const SceneSpec& spec);

// One line per region that lies wholly or partly off the [daemon] table's desktop, "FILE:LINE: region 'NAME' " and
// off_desktop_note's text; none for desktop = "auto", whose size only the running daemon learns.
std::vector<std::string> desktop_warnings(const SceneSpec& spec);

}  // namespace ph
