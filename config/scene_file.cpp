#include "config/scene_file.hpp"

#include <fmt/format.h>
#include <grp.h>
#include <sys/stat.h>

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <new>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "core/engine/method_hybrid.hpp"
#include "core/engine/variant_choice.hpp"

namespace ph {

namespace {

// Builds "FILE:LINE: key: message" errors.
class Reporter {
 public:
  explicit Reporter(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const toml::node* at, std::string_view key, std::string_view message) const {
    const int line = at != nullptr ? static_cast<int>(at->source().begin.line) : 0;
    if (line > 0) throw ConfigError(fmt::format("{}:{}: {}: {}", origin_, line, key, message));
    throw ConfigError(fmt::format("{}: {}: {}", origin_, key, message));
  }

 private:
  std::string origin_;
};

// A region's own keys, besides its tables; no table within a region has one of them (the method tables',
// [region.materials]' and [region.wells]' keys are other words: tests/test_scene_file.cpp checks that they stay so).
const std::set<std::string_view> kRegionOwnKeys = {"name",
                                                   "x",
                                                   "y",
                                                   "width",
                                                   "height",
                                                   "method",
                                                   "normal_map",
                                                   "normal_green",
                                                   "normal_encoding",
                                                   "depth_map",
                                                   "depth_zero",
                                                   "relief_px",
                                                   "traversal",
                                                   "sampling",
                                                   "lut_directions",
                                                   "accuracy_px"};
// The [daemon] table's keys that no region has.
const std::set<std::string_view> kDaemonOnlyKeys = {"devices", "output",    "desktop",      "acceleration",
                                                    "speed",   "mouse_dpi", "pointer_speed"};

// How many single-character edits (insert, delete, replace, swap two neighbours) turn `a` into `b`, letter case aside.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const auto lower = [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) && lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// What an unknown key likely meant: the allowed key a slip away ("did you mean 'normal_map'?"), or the table the key
// belongs to where it is another table's, each said after ": "; "" where neither.
std::string likely_meant(std::string_view key, const std::set<std::string_view>& allowed, std::string_view where) {
  const std::size_t slips = key.size() <= 4 ? 1 : 2;
  std::string_view best;
  std::size_t best_distance = slips + 1;
  for (std::string_view a : allowed) {
    const std::size_t distance = edit_distance(key, a);
    if (distance < best_distance) {
      best = a;
      best_distance = distance;
    }
  }
  if (!best.empty()) return fmt::format(": did you mean '{}'?", best);
  if (kDaemonOnlyKeys.contains(key) && where != "daemon.")
    return ": it is a [daemon] key, written in the [daemon] table";
  if (kRegionOwnKeys.contains(key) && !where.starts_with("region["))
    return ": it is a region's key, written in a [[region]] table";
  return "";
}

void reject_unknown_keys(const Reporter& rep, const toml::table& table, const std::set<std::string_view>& allowed,
                         std::string_view where) {
  for (const auto& [key, value] : table) {
    if (!allowed.contains(key.str())) {
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      rep.fail(&value, fmt::format("{}{}", where, key.str()),
               fmt::format("unknown key{} (allowed: {})", likely_meant(key.str(), allowed, where), list));
    }
  }
}

// In TOML every key below a table's header is that table's: a region's own key added at the end of a region that has
// a [region.curvature] (or materials, wells) table is read as the table's, and the region would then be said to lack
// it. Said as what it is, at its line.
void reject_region_keys_in_its_tables(const Reporter& rep, const toml::table& t, const std::string& where,
                                      const std::string& table_path = "") {
  for (const auto& [name, node] : t) {
    const toml::table* sub = node.as_table();
    if (sub == nullptr) continue;
    const std::string path = table_path.empty() ? std::string(name.str()) : table_path + "." + std::string(name.str());
    for (const auto& [key, value] : *sub) {
      if (kRegionOwnKeys.contains(key.str())) {
        rep.fail(&value, fmt::format("{}{}.{}", where, path, key.str()),
                 fmt::format("is a region's own key, read here as the [region.{}] table's (in TOML every key below "
                             "a table's header belongs to that table): write it with the region's keys, above the "
                             "region's first [region.NAME] table",
                             path));
      }
    }
    reject_region_keys_in_its_tables(rep, *sub, where, path);
  }
}

double get_number(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where,
                  double fallback) {
  const toml::node* node = t.get(key);
  if (node == nullptr) return fallback;
  if (auto v = node->value<double>()) return *v;  // integers convert too
  rep.fail(node, fmt::format("{}{}", where, key), "must be a number");
}

std::int32_t get_int(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where,
                     std::optional<std::int32_t> fallback, std::int64_t lo, std::int64_t hi) {
  const toml::node* node = t.get(key);
  if (node == nullptr) {
    if (fallback) return *fallback;
    rep.fail(&t, fmt::format("{}{}", where, key), "is required");
  }
  const auto v = node->value_exact<std::int64_t>();
  if (!v) rep.fail(node, fmt::format("{}{}", where, key), "must be a whole number");
  if (*v < lo || *v > hi) {
    rep.fail(node, fmt::format("{}{}", where, key), fmt::format("must be between {} and {} (got {})", lo, hi, *v));
  }
  return static_cast<std::int32_t>(*v);
}

// direction_lut's table: 8 or 16 directions, said as such (a range would suggest the counts between).
std::int32_t get_lut_directions(const Reporter& rep, const toml::table& t, std::string_view where,
                                std::int32_t fallback) {
  const toml::node* node = t.get("lut_directions");
  if (node == nullptr) return fallback;
  const auto count = node->value_exact<std::int64_t>();
  if (!count || (*count != 8 && *count != 16)) {
    rep.fail(node, fmt::format("{}lut_directions", where),
             count ? fmt::format("must be 8 or 16 (got {})", *count) : std::string("must be 8 or 16"));
  }
  return static_cast<std::int32_t>(*count);
}

std::optional<std::string> get_string(const Reporter& rep, const toml::table& t, std::string_view key,
                                      std::string_view where) {
  const toml::node* node = t.get(key);
  if (node == nullptr) return std::nullopt;
  if (auto v = node->value_exact<std::string>()) return *v;
  rep.fail(node, fmt::format("{}{}", where, key), "must be a string");
}

const toml::table* get_table(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where) {
  const toml::node* node = t.get(key);
  if (node == nullptr) return nullptr;
  if (const toml::table* table = node->as_table()) return table;
  rep.fail(node, fmt::format("{}{}", where, key), "must be a table");
}

// The node of `key` in `t`, or `t` itself where the key is not written (its default is what is wrong): where an error
// about that key points.
const toml::node* key_or_table(const toml::table& t, std::string_view key) {
  const toml::node* node = t.get(key);
  return node != nullptr ? node : &t;
}

// Checks one parameter where it is written, so that the error names its line and key.
template <typename Check>
void check_key(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where, Check ok,
               std::string_view allowed) {
  if (t.get(key) != nullptr && !ok()) rep.fail(t.get(key), fmt::format("{}{}", where, key), allowed);
}

// A method's [region.NAME] table as its parser reads it (core/engine/method_registry.hpp).
class TomlParamReader final : public ParamReader {
 public:
  TomlParamReader(const Reporter& rep, const toml::table& table, std::string_view where)
      : rep_(rep), table_(table), where_(where) {}

  std::optional<double> number(std::string_view key) const override {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    if (auto v = node->value<double>()) return *v;  // integers convert too
    reject(key, "must be a number");
  }
  std::optional<std::pair<double, double>> pair(std::string_view key) const override {
    const toml::node* node = table_.get(key);
    if (node == nullptr) return std::nullopt;
    const toml::array* arr = node->as_array();
    if (arr == nullptr || arr->size() != 2 || !(*arr)[0].value<double>() || !(*arr)[1].value<double>()) {
      reject(key, "must be a pair of numbers [lower, upper]");
    }
    return std::pair(*(*arr)[0].value<double>(), *(*arr)[1].value<double>());
  }
  [[noreturn]] void reject(std::string_view key, std::string_view message) const override {
    if (key.empty()) rep_.fail(&table_, where_.substr(0, where_.size() - 1), message);
    const toml::node* node = table_.get(key);
    rep_.fail(node != nullptr ? node : &table_, fmt::format("{}{}", where_, key), message);
  }

 private:
  const Reporter& rep_;
  const toml::table& table_;
  std::string_view where_;
};

// A named choice among `names` ("a", "b" or "c" in the message).
template <typename T, typename Parse>
T get_choice(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where, T fallback,
             Parse parse, std::string_view allowed) {
  const std::optional<std::string> text = get_string(rep, t, key, where);
  if (!text) return fallback;
  const auto value = parse(*text);
  if (!value)
    rep.fail(t.get(key), fmt::format("{}{}", where, key), fmt::format("unknown '{}' (allowed: {})", *text, allowed));
  return *value;
}

void get_number_into(const Reporter& rep, const toml::table& t, std::string_view key, std::string_view where,
                     double& value) {
  value = get_number(rep, t, key, where, value);
}

// A parameter struct's own check, reported at its table: the message names the parameter and its range.
// Where `name` stands in `text` as a word of its own (not inside a longer key), or npos.
std::size_t find_key(std::string_view text, std::string_view name) {
  const auto part_of_key = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; };
  for (std::size_t at = text.find(name); at != std::string_view::npos; at = text.find(name, at + 1)) {
    const bool starts = at == 0 || (!part_of_key(text[at - 1]) && text[at - 1] != '.');
    const bool ends = at + name.size() == text.size() || !part_of_key(text[at + name.size()]);
    if (starts && ends) return at;
  }
  return std::string_view::npos;
}

// Whether UTF-8 `text` holds a character that would split or shift a log line, status line or CSV cell: a C0 control
// (a line break, a tab), DEL, a C1 control (U+0080-U+009F, NEL among them) or U+2028/U+2029 (line and paragraph
// separators).
bool has_control_characters(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) return true;
    const auto next = [&](std::size_t k) { return i + k < text.size() ? static_cast<unsigned char>(text[i + k]) : 0; };
    if (c == 0xc2 && next(1) >= 0x80 && next(1) <= 0x9f) return true;                       // U+0080-U+009F
    if (c == 0xe2 && next(1) == 0x80 && (next(2) == 0xa8 || next(2) == 0xa9)) return true;  // U+2028, U+2029
  }
  return false;
}

// The node of `t` (or of a table in it, as "table.key") that a validate() message names first, so that the error
// points at that key's line; `t` itself where it names none.
const toml::node* node_named_in(const toml::table& t, std::string_view problem) {
  const toml::node* named = &t;
  std::size_t first = std::string_view::npos;
  const auto consider = [&](const std::string& name, const toml::node& node) {
    const std::size_t at = find_key(problem, name);
    if (at < first) first = at, named = &node;
  };
  for (const auto& [key, node] : t) {
    if (const toml::table* inner = node.as_table()) {
      for (const auto& [inner_key, inner_node] : *inner)
        consider(std::string(key.str()) + "." + std::string(inner_key.str()), inner_node);
    } else {
      consider(std::string(key.str()), node);
    }
  }
  return named;
}

void check_params(const Reporter& rep, const toml::table& t, std::string_view where, const std::string& problem) {
  if (!problem.empty()) rep.fail(node_named_in(t, problem), std::string(where.substr(0, where.size() - 1)), problem);
}

// Bit depth of the map a region's classes come from: 8-bit maps get the wider filter and tolerances.
int class_map_bit_depth(const FieldSources& sources, const MaterialsParams& params, FieldReader& reader) {
  const bool from_depth = params.source == ClassSource::depth || !sources.normal_map;
  const std::optional<std::filesystem::path>& map = from_depth ? sources.depth_map : sources.normal_map;
  if (!map) return 16;
  return reader.image_size(*map).code_max == 255 ? 8 : 16;
}

MaterialsParams parse_materials(const Reporter& rep, const toml::table& t, std::string_view where) {
  reject_unknown_keys(rep, t,
                      {"source", "filter_radius", "planar_curvedness", "parabolic_ratio", "planar", "parabolic",
                       "elliptic", "hyperbolic", "damping", "friction", "stick_slip"},
                      where);
  MaterialsParams m;
  m.source = get_choice(rep, t, "source", where, m.source, parse_class_source, "auto, normals, depth");
  m.filter_radius = get_int(rep, t, "filter_radius", where, 0, 0, 64);
  if (t.get("planar_curvedness") != nullptr) m.planar_curvedness = get_number(rep, t, "planar_curvedness", where, 0.0);
  if (t.get("parabolic_ratio") != nullptr) m.parabolic_ratio = get_number(rep, t, "parabolic_ratio", where, 0.0);
  const char* const classes[] = {"planar", "parabolic", "elliptic", "hyperbolic"};
  for (std::size_t i = 0; i < 4; ++i) {
    m.materials[i] =
        get_choice(rep, t, classes[i], where, m.materials[i], parse_material, "none, damping, friction, stick_slip");
  }
  if (const toml::table* d = get_table(rep, t, "damping", where)) {
    const std::string w = std::string(where) + "damping.";
    reject_unknown_keys(rep, *d, {"k", "cd_max", "fallback_interval_ms"}, w);
    get_number_into(rep, *d, "k", w, m.damping.k);
    get_number_into(rep, *d, "cd_max", w, m.damping.cd_max);
    get_number_into(rep, *d, "fallback_interval_ms", w, m.damping.fallback_interval_ms);
  }
  if (const toml::table* f = get_table(rep, t, "friction", where)) {
    const std::string w = std::string(where) + "friction.";
    reject_unknown_keys(rep, *f, {"stuck_cd", "breakaway_px", "slip_cd", "rest_ms"}, w);
    get_number_into(rep, *f, "stuck_cd", w, m.friction.stuck_cd);
    get_number_into(rep, *f, "breakaway_px", w, m.friction.breakaway_px);
    get_number_into(rep, *f, "slip_cd", w, m.friction.slip_cd);
    get_number_into(rep, *f, "rest_ms", w, m.friction.rest_ms);
  }
  if (const toml::table* s = get_table(rep, t, "stick_slip", where)) {
    const std::string w = std::string(where) + "stick_slip.";
    reject_unknown_keys(rep, *s, {"stuck_cd", "breakaway_px", "slip_cd", "slip_px", "rest_ms"}, w);
    get_number_into(rep, *s, "stuck_cd", w, m.stick_slip.stuck_cd);
    get_number_into(rep, *s, "breakaway_px", w, m.stick_slip.breakaway_px);
    get_number_into(rep, *s, "slip_cd", w, m.stick_slip.slip_cd);
    get_number_into(rep, *s, "slip_px", w, m.stick_slip.slip_px);
    get_number_into(rep, *s, "rest_ms", w, m.stick_slip.rest_ms);
  }
  check_params(rep, t, where, validate(m));
  return m;
}

std::optional<WellPattern> parse_well_pattern(std::string_view name) {
  if (name == "isophotes") return WellPattern::isophotes;
  if (name == "contours") return WellPattern::contours;
  return std::nullopt;
}

std::optional<PatternRule> parse_pattern_rule(std::string_view name) {
  if (name == "crossing") return PatternRule::crossing;
  if (name == "band") return PatternRule::band;
  return std::nullopt;
}

WellsParams parse_wells(const Reporter& rep, const toml::table& t, std::string_view where) {
  reject_unknown_keys(rep, t,
                      {"pattern", "radius_px", "strength", "max_gain", "min_gain", "snap_px", "snap_fraction", "light",
                       "cos_alpha", "levels", "rule", "tolerance"},
                      where);
  WellsParams w;
  w.pattern = get_choice(rep, t, "pattern", where, w.pattern, parse_well_pattern, "isophotes, contours");
  get_number_into(rep, t, "radius_px", where, w.radius_px);
  get_number_into(rep, t, "strength", where, w.strength);
  get_number_into(rep, t, "max_gain", where, w.max_gain);
  get_number_into(rep, t, "min_gain", where, w.min_gain);
  get_number_into(rep, t, "snap_px", where, w.snap_px);
  // Left out, it is at most min_gain / 2 (its bound): a min_gain below 0.5 needs no snap_fraction beside it.
  if (t.get("snap_fraction") == nullptr) w.snap_fraction = std::min(w.snap_fraction, w.min_gain / 2.0);
  get_number_into(rep, t, "snap_fraction", where, w.snap_fraction);
  const bool isophotes = w.pattern == WellPattern::isophotes;
  const PatternRule rule =
      get_choice(rep, t, "rule", where, PatternRule::crossing, parse_pattern_rule, "crossing, band");
  // The crossing rule's line is one texel thin whatever the tolerance: a tolerance there would change nothing.
  if (rule == PatternRule::crossing && t.get("tolerance") != nullptr)
    rep.fail(t.get("tolerance"), std::string(where) + "tolerance",
             "is for rule = \"band\" (the crossing rule has none)");
  if (isophotes) {
    w.isophotes.rule = rule;
    get_number_into(rep, t, "tolerance", where, w.isophotes.tol);
    get_number_into(rep, t, "cos_alpha", where, w.isophotes.cos_alpha);
    if (const toml::node* light = t.get("light")) {
      const toml::array* a = light->as_array();
      if (a == nullptr || a->size() != 3 || !(*a)[0].value<double>() || !(*a)[1].value<double>() ||
          !(*a)[2].value<double>()) {
        rep.fail(light, std::string(where) + "light", "must be three numbers [x, y, z] (toward the light, y down)");
      }
      w.isophotes.light = {*(*a)[0].value<double>(), *(*a)[1].value<double>(), *(*a)[2].value<double>()};
    }
    for (const char* key : {"levels"}) {
      if (t.get(key) != nullptr) rep.fail(t.get(key), std::string(where) + key, "is for pattern = \"contours\"");
    }
  } else {
    w.contours.rule = rule;
    get_number_into(rep, t, "tolerance", where, w.contours.tol);
    if (const toml::node* levels = t.get("levels")) {
      if (auto count = levels->value_exact<std::int64_t>()) {
        if (*count < 0 || *count > kMaxContourLevels) {
          rep.fail(levels, std::string(where) + "levels", fmt::format("must be between 0 and {}", kMaxContourLevels));
        }
        w.contours.count = static_cast<std::int32_t>(*count);
      } else if (const toml::array* a = levels->as_array()) {
        // An empty list would read as "not given": the default count of evenly spaced levels, not none.
        if (a->empty())
          rep.fail(levels, std::string(where) + "levels", "is an empty list: give heights, or a count (0 for none)");
        for (const toml::node& level : *a) {
          const auto v = level.value<double>();
          if (!v || !std::isfinite(*v))
            rep.fail(&level, std::string(where) + "levels", "levels must be finite numbers");
          w.contours.levels.push_back(*v);
        }
      } else {
        rep.fail(levels, std::string(where) + "levels",
                 "must be a count of evenly spaced levels or a list of heights (px)");
      }
    }
    for (const char* key : {"light", "cos_alpha"}) {
      if (t.get(key) != nullptr) rep.fail(t.get(key), std::string(where) + key, "is for pattern = \"isophotes\"");
    }
  }
  check_params(rep, t, where, validate(w));
  return w;
}

std::filesystem::path resolve(const std::filesystem::path& base_dir, const std::string& path) {
  const std::filesystem::path p(path);
  return p.is_absolute() ? p : base_dir / p;
}

constexpr std::int64_t kMaxCoordinate = kMaxDesktopCoordinate;

// Every method's parameters: its [region.NAME] table, else its defaults.
void parse_method_tables(const Reporter& rep, const toml::table& t, const std::string& where,
                         const MethodRegistry& methods, RegionSpec& r) {
  for (const auto& entry : methods.entries()) {
    const toml::table* table = entry->keys.empty() ? nullptr : get_table(rep, t, entry->name, where);
    if (table == nullptr) {
      r.method_params[entry->name] = entry->defaults();
      continue;
    }
    const std::string w = where + entry->name + ".";
    r.method_table_lines[entry->name] = static_cast<int>(table->source().begin.line);
    reject_unknown_keys(rep, *table, std::set<std::string_view>(entry->keys.begin(), entry->keys.end()), w);
    r.method_params[entry->name] = entry->parse(TomlParamReader(rep, *table, w));
  }
}

// traversal, sampling and lut_directions of a region, over the [daemon] table's; traversal = "auto" with its
// accuracy_px.
void parse_region_engine(const Reporter& rep, const toml::table& t, const std::string& where,
                         const EngineOptions& scene_engine, RegionSpec& r) {
  const bool any = t.get("traversal") != nullptr || t.get("sampling") != nullptr || t.get("lut_directions") != nullptr;
  if (t.get("accuracy_px") != nullptr && get_string(rep, t, "traversal", where).value_or("") != "auto") {
    rep.fail(t.get("accuracy_px"), where + "accuracy_px", "applies to traversal = \"auto\" only");
  }
  if (!any) return;
  EngineOptions e = scene_engine;
  r.engine_auto = get_string(rep, t, "traversal", where) == std::optional<std::string>("auto");
  if (r.engine_auto) {
    e.traversal = Traversal::exact;  // chosen at load (load_scene)
    r.accuracy_px = get_number(rep, t, "accuracy_px", where, r.accuracy_px);
    check_key(
        rep, t, "accuracy_px", where, [&] { return std::isfinite(r.accuracy_px) && r.accuracy_px > 0.0; },
        "must be a number > 0");
  } else {
    e.traversal = get_choice(rep, t, "traversal", where, e.traversal, parse_traversal,
                             "exact, unit_steps, frame_midpoint, direction_lut, auto");
  }
  e.sampling = get_choice(rep, t, "sampling", where, e.sampling, parse_sampling, "nearest, bilinear");
  e.lut_directions = get_lut_directions(rep, t, where, e.lut_directions);
  r.own_lut_directions = t.get("lut_directions") != nullptr;
  if (r.engine_auto && e.sampling == Sampling::bilinear) {
    // "auto" chooses among the nearest-sampling variants: a bilinear [daemon] table is the others' default, not
    // this region's; bilinear asked for in the region itself contradicts it.
    if (t.get("sampling") != nullptr) {
      rep.fail(t.get("sampling"), where + "sampling",
               "traversal = \"auto\" chooses with nearest sampling: set sampling = \"nearest\" or leave it out");
    }
    e.sampling = Sampling::nearest;
  }
  // Set in the region for a traversal that has no direction table, the count would change nothing: said, as
  // accuracy_px without "auto" is. "auto" chooses between exact and frame_midpoint (core/engine/variant_choice.hpp).
  if (t.get("lut_directions") != nullptr && (r.engine_auto || e.traversal != Traversal::direction_lut)) {
    rep.fail(t.get("lut_directions"), where + "lut_directions",
             r.engine_auto ? "changes nothing with traversal = \"auto\", which chooses between exact and "
                             "frame_midpoint"
                           : "applies to traversal = \"direction_lut\" only");
  }
  if (const std::string problem = validate(e); !problem.empty()) {
    // Said at the region's key that meets the [daemon] table's other one, or at its traversal where it sets both.
    if (t.get("traversal") == nullptr && t.get("sampling") != nullptr) {
      rep.fail(t.get("sampling"), where + "sampling", problem + " (the traversal is the [daemon] table's)");
    }
    rep.fail(key_or_table(t, "traversal"), where + "traversal",
             problem + (t.get("sampling") == nullptr ? " (the sampling is the [daemon] table's)" : ""));
  }
  r.engine = e;
}

RegionSpec parse_region(const Reporter& rep, const toml::table& t, std::size_t index,
                        const std::filesystem::path& base_dir, const MethodRegistry& methods,
                        const EngineOptions& scene_engine) {
  const std::string where = fmt::format("region[{}].", index);
  // Its own keys and its tables (materials, wells, a method's parameters).
  std::set<std::string_view> keys = kRegionOwnKeys;
  keys.insert({"materials", "wells"});
  for (const auto& entry : methods.entries()) {
    if (!entry->keys.empty()) keys.insert(entry->name);  // its parameter table
  }
  reject_unknown_keys(rep, t, keys, where);
  reject_region_keys_in_its_tables(rep, t, where);
  RegionSpec r;
  r.line = static_cast<int>(t.source().begin.line);
  r.name = get_string(rep, t, "name", where).value_or(fmt::format("region {}", index));
  // A name is written into log lines, status and CSV cells: a line break or a tab there would split or shift them.
  if (r.name.empty()) rep.fail(t.get("name"), where + "name", "must not be empty (leave it out for 'region N')");
  if (has_control_characters(r.name))
    rep.fail(t.get("name"), where + "name", "must not hold control characters (a line break, a tab)");
  if (r.name.find_first_not_of(' ') == std::string::npos)
    rep.fail(t.get("name"), where + "name", "must hold more than spaces");
  r.rect.x = get_int(rep, t, "x", where, 0, -kMaxCoordinate, kMaxCoordinate);
  r.rect.y = get_int(rep, t, "y", where, 0, -kMaxCoordinate, kMaxCoordinate);
  r.rect.w = get_int(rep, t, "width", where, std::nullopt, 1, kMaxRegionSide);
  r.rect.h = get_int(rep, t, "height", where, std::nullopt, 1, kMaxRegionSide);
  if (const std::int64_t texels = std::int64_t{r.rect.w} * r.rect.h; texels > kMaxRegionTexels) {
    rep.fail(t.get("height"), where + "height",
             fmt::format("a {} x {} region has {} px, more than the {} (8192 x 8192) a region may have: its fields "
                         "would take gigabytes and minutes to build; make it smaller, or split the relief into "
                         "regions side by side",
                         r.rect.w, r.rect.h, texels, kMaxRegionTexels));
  }

  r.method = get_string(rep, t, "method", where).value_or("curvature");
  r.method_in_file = r.method;
  const MethodEntry* entry = methods.find(r.method);
  if (entry == nullptr)
    rep.fail(t.get("method"), where + "method",
             fmt::format("unknown method '{}' (allowed: {})", r.method, methods.names()));

  for (const auto& [key, map, line] : {std::tuple{"normal_map", &r.sources.normal_map, &r.normal_map_line},
                                       std::tuple{"depth_map", &r.sources.depth_map, &r.depth_map_line}}) {
    const std::optional<std::string> path = get_string(rep, t, key, where);
    if (!path) continue;
    *line = static_cast<int>(t.get(key)->source().begin.line);
    // Resolved against the scene file's folder, "" would name that folder: said here, at its line.
    if (path->empty()) rep.fail(t.get(key), where + key, "must be the path of an image file, not empty");
    *map = resolve(base_dir, *path);
  }
  const std::string green = get_string(rep, t, "normal_green", where).value_or("opengl");
  if (green == "opengl") {
    r.sources.normal_options.green = GreenConvention::opengl;
  } else if (green == "directx") {
    r.sources.normal_options.green = GreenConvention::directx;
  } else {
    rep.fail(t.get("normal_green"), where + "normal_green", "must be \"opengl\" or \"directx\"");
  }
  const std::string encoding = get_string(rep, t, "normal_encoding", where).value_or("auto");
  if (encoding == "auto") {
    r.sources.normal_options.encoding = NormalEncoding::automatic;
  } else if (encoding == "unorm") {
    r.sources.normal_options.encoding = NormalEncoding::unorm;
  } else if (encoding == "signed") {
    r.sources.normal_options.encoding = NormalEncoding::signed_values;
  } else {
    rep.fail(t.get("normal_encoding"), where + "normal_encoding", "must be \"auto\", \"unorm\" or \"signed\"");
  }
  for (const char* key : {"normal_green", "normal_encoding", "depth_zero", "relief_px"}) {
    if (const toml::node* node = t.get(key)) r.decoding_key_lines[key] = static_cast<int>(node->source().begin.line);
  }
  r.sources.depth_options.depth_zero = get_number(rep, t, "depth_zero", where, 0.0);
  r.sources.depth_options.relief_px = get_number(rep, t, "relief_px", where, 100.0);
  const auto bounded = [&](const char* key, double value, double bound) {
    check_key(
        rep, t, key, where, [&] { return std::abs(value) <= bound; },  // (NaN fails)
        fmt::format("must be a finite number from -{0:g} to {0:g}", bound));
  };
  bounded("depth_zero", r.sources.depth_options.depth_zero, kMaxDepthZero);
  bounded("relief_px", r.sources.depth_options.relief_px, kMaxReliefPx);

  if (!r.sources.normal_map && !r.sources.depth_map)
    rep.fail(&t, where + "normal_map", "a region needs a normal_map or a depth_map");
  if (entry->make(entry->defaults())->needs().depth && !r.sources.depth_map) {
    rep.fail(&t, where + "depth_map",
             fmt::format("the {} method needs a depth_map (a normal map alone is not enough)", r.method));
  }
  parse_method_tables(rep, t, where, methods, r);
  parse_region_engine(rep, t, where, scene_engine, r);
  if (const toml::table* m = get_table(rep, t, "materials", where)) {
    r.materials = parse_materials(rep, *m, where + "materials.");
    const bool needs_depth = r.materials->source == ClassSource::depth;
    const bool needs_normals = r.materials->source == ClassSource::normals;
    // Each source needs its own map: "normals" from a depth map's slopes would filter the heights at the normal
    // map's radius, too small for them (docs/INTERROGATION.md, "Classes"), and make a flat plane's texels noise.
    if ((needs_depth && !r.sources.depth_map) || (needs_normals && !r.sources.normal_map)) {
      rep.fail(key_or_table(*m, "source"), where + "materials.source",
               needs_depth ? "source = \"depth\" needs a depth_map, which the region has not"
                           : "source = \"normals\" needs a normal_map, which the region has not (\"auto\" takes the "
                             "classes from the depth map)");
    }
  }
  if (const toml::table* w = get_table(rep, t, "wells", where)) {
    r.wells = parse_wells(rep, *w, where + "wells.");
    if (r.wells->pattern == WellPattern::contours && !r.sources.depth_map) {
      rep.fail(key_or_table(*w, "pattern"), where + "wells.pattern", "contour wells need a depth_map (heights)");
    }
  }
  return r;
}

DaemonSettings parse_daemon(const Reporter& rep, const toml::table& t) {
  const std::string where = "daemon.";
  reject_unknown_keys(rep, t,
                      {"devices", "output", "desktop", "acceleration", "speed", "mouse_dpi", "pointer_speed",
                       "traversal", "sampling", "lut_directions"},
                      where);
  DaemonSettings d;
  d.engine.traversal = get_choice(rep, t, "traversal", where, d.engine.traversal, parse_traversal,
                                  "exact, unit_steps, frame_midpoint, direction_lut");
  d.engine.sampling = get_choice(rep, t, "sampling", where, d.engine.sampling, parse_sampling, "nearest, bilinear");
  d.engine.lut_directions = get_lut_directions(rep, t, where, d.engine.lut_directions);
  // (Only direction_lut with bilinear sampling is refused: said at the sampling line, which asked for it.)
  if (const std::string problem = validate(d.engine); !problem.empty())
    rep.fail(key_or_table(t, "sampling"), "daemon.sampling", problem);

  if (const toml::node* node = t.get("devices")) {
    const char* allowed =
        "must be \"any\" or a list of matchers like [\"name:Logitech*\", \"usb:046d:c077\", \"id:046d:c077\"]";
    if (auto any = node->value_exact<std::string>()) {
      if (*any != "any") rep.fail(node, "daemon.devices", allowed);
    } else if (const toml::array* arr = node->as_array()) {
      if (arr->empty()) rep.fail(node, "daemon.devices", fmt::format("is empty; {}", allowed));
      for (std::size_t i = 0; i < arr->size(); ++i) {
        const toml::node& item = (*arr)[i];
        const std::string key = fmt::format("daemon.devices[{}]", i);
        const auto text = item.value_exact<std::string>();
        if (!text) rep.fail(&item, key, "must be a string like \"name:Logitech*\" or \"id:046d:c077\"");
        std::string error;
        const auto match = parse_device_match(*text, error);
        if (!match) rep.fail(&item, key, error);
        d.devices.push_back(*match);
      }
    } else {
      rep.fail(node, "daemon.devices", allowed);
    }
  }

  const std::string output = get_string(rep, t, "output", where).value_or("absolute");
  if (output == "relative") {
    d.output = OutputMode::relative;
  } else if (output == "absolute") {
    d.output = OutputMode::absolute;
  } else {
    rep.fail(t.get("output"), "daemon.output", "must be \"relative\" or \"absolute\"");
  }

  if (const toml::node* node = t.get("desktop")) {
    const char* allowed = "must be \"auto\" or [x, y, width, height] in whole px";
    if (auto text = node->value_exact<std::string>()) {
      if (*text != "auto") rep.fail(node, "daemon.desktop", allowed);
    } else if (const toml::array* arr = node->as_array()) {
      if (arr->size() != 4) rep.fail(node, "daemon.desktop", allowed);
      std::int64_t v[4] = {};
      for (std::size_t i = 0; i < 4; ++i) {
        const auto n = (*arr)[i].value_exact<std::int64_t>();
        constexpr std::array<const char*, 4> kNames = {"x", "y", "width", "height"};
        if (!n)
          rep.fail(&(*arr)[i], fmt::format("daemon.desktop[{}]", i),
                   fmt::format("{} must be a whole number of px; {}", kNames[i], allowed));
        v[i] = *n;
      }
      if (v[0] < -kMaxCoordinate || v[0] > kMaxCoordinate || v[1] < -kMaxCoordinate || v[1] > kMaxCoordinate)
        rep.fail(
            node, "daemon.desktop",
            fmt::format("x and y must be between {} and {} (got {}, {})", -kMaxCoordinate, kMaxCoordinate, v[0], v[1]));
      if (v[2] < 1 || v[2] > kMaxCoordinate || v[3] < 1 || v[3] > kMaxCoordinate)
        rep.fail(node, "daemon.desktop",
                 fmt::format("width and height must be between 1 and {} (got {}, {})", kMaxCoordinate, v[2], v[3]));
      d.desktop = Rect{static_cast<std::int32_t>(v[0]), static_cast<std::int32_t>(v[1]),
                       static_cast<std::int32_t>(v[2]), static_cast<std::int32_t>(v[3])};
    } else {
      rep.fail(node, "daemon.desktop", allowed);
    }
  }

  if (const auto profile = get_string(rep, t, "acceleration", where)) {
    if (*profile == "adaptive") {
      d.acceleration = AccelProfile::adaptive;
    } else if (*profile == "flat") {
      d.acceleration = AccelProfile::flat;
    } else {
      rep.fail(t.get("acceleration"), "daemon.acceleration", "must be \"adaptive\" or \"flat\"");
    }
  }
  d.speed = get_number(rep, t, "speed", where, d.speed);
  check_key(
      rep, t, "speed", where, [&] { return std::isfinite(d.speed) && d.speed >= -1.0 && d.speed <= 1.0; },
      "must be a number from -1 to 1 (the desktop's pointer speed setting; 0 is the default)");
  d.mouse_dpi = get_number(rep, t, "mouse_dpi", where, d.mouse_dpi);
  check_key(
      rep, t, "mouse_dpi", where,
      [&] { return std::isfinite(d.mouse_dpi) && d.mouse_dpi >= kMinMouseDpi && d.mouse_dpi <= kMaxMouseDpi; },
      fmt::format("must be a number from {} to {} (the mouse's resolution in dots per inch)", kMinMouseDpi,
                  kMaxMouseDpi));

  d.pointer_speed = get_number(rep, t, "pointer_speed", where, d.pointer_speed);
  check_key(
      rep, t, "pointer_speed", where,
      [&] { return d.pointer_speed >= kMinPointerSpeed && d.pointer_speed <= kMaxPointerSpeed; },  // (NaN fails)
      fmt::format("must be a finite number from {} to {} (screen px per device count at C/D 1)", kMinPointerSpeed,
                  kMaxPointerSpeed));
  return d;
}

}  // namespace

namespace {

// `origin` names the text in errors; relative image paths are resolved against `base_dir`.
SceneSpec parse_scene(std::string_view text, const std::filesystem::path& origin, const std::filesystem::path& base_dir,
                      MethodRegistry methods) {
  const Reporter rep(origin.string());
  toml::table root;
  try {
    root = toml::parse(text, origin.string());
  } catch (const toml::parse_error& e) {
    // toml++'s words for a bare word where a value goes, the likeliest slip in a hand-written file: said plainly. (A
    // word that starts as nan, inf, true or false is taken for one of those first; no key is a boolean.)
    const std::string_view said = e.description();
    const bool bare_word = said.find("could not determine value type") != std::string_view::npos ||
                           said.find("expected 'nan'") != std::string_view::npos ||
                           said.find("expected 'inf'") != std::string_view::npos ||
                           said.find("expected 'true'") != std::string_view::npos ||
                           said.find("expected 'false'") != std::string_view::npos;
    throw ConfigError(fmt::format("{}:{}: {}{}", origin.string(), e.source().begin.line, e.description(),
                                  bare_word ? " (text needs quotes: key = \"value\")" : ""));
  }
  reject_unknown_keys(rep, root, {"daemon", "region"}, "");
  SceneSpec spec;
  spec.file = origin;
  spec.methods = std::move(methods);
  if (const toml::table* daemon = get_table(rep, root, "daemon", "")) {
    spec.daemon = parse_daemon(rep, *daemon);
    if (const toml::node* dpi = daemon->get("mouse_dpi"))
      spec.mouse_dpi_line = static_cast<int>(dpi->source().begin.line);
    if (const toml::node* lut = daemon->get("lut_directions"))
      spec.lut_directions_line = static_cast<int>(lut->source().begin.line);
  }
  const toml::node* regions = root.get("region");
  if (regions == nullptr) return spec;
  const toml::array* arr = regions->as_array();
  if (arr == nullptr || !arr->is_array_of_tables()) rep.fail(regions, "region", "must be written as [[region]] tables");
  std::map<std::string, std::size_t> named;  // name -> the region that has it
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::table& table = *(*arr)[i].as_table();
    spec.regions.push_back(parse_region(rep, table, i, base_dir, spec.methods, spec.daemon.engine));
    // The logs, check-config, status and trace's CSV tell regions apart by name alone.
    const auto [first, fresh] = named.emplace(spec.regions.back().name, i);
    if (!fresh) {
      const toml::node* at = table.get("name");
      rep.fail(at != nullptr ? at : &table, fmt::format("region[{}].name", i),
               fmt::format("'{}' is already the name of region[{}] (line {}); each region needs a name of its own",
                           spec.regions.back().name, first->second, spec.regions[first->second].line));
    }
  }
  return spec;
}

}  // namespace

SceneSpec parse_scene_text(std::string_view text, const std::filesystem::path& origin, MethodRegistry methods) {
  return parse_scene(text, origin, origin.parent_path(), std::move(methods));
}

namespace {

// Said after a file the service could not open where its sandbox hides the folder: to the service the folder is
// there but cannot be entered (Permission denied), or empty. Only in a process systemd started (it sets
// INVOCATION_ID for each unit it runs): elsewhere nothing hides the folder, the file is missing or unreadable
// there too, and the hint would send the user after the wrong cause.
std::string service_hint(const std::filesystem::path& path) {
  if (std::getenv("INVOCATION_ID") == nullptr) return "";
  const std::optional<HiddenFolder> hidden = hidden_from_the_service(path);
  if (!hidden) return "";
  return fmt::format(
      " ({} is hidden from pseudohapticd.service, {}: keep scene files and images under "
      "/etc/pseudohaptic or /usr/local/share)",
      hidden->folder, hidden->setting);
}

}  // namespace

namespace {

// A region's maps with their keys and the lines the keys are on (a map not given: its path empty, line 0), for what
// is said of a map at its key.
struct MapKey {
  std::string_view key;
  const std::optional<std::filesystem::path>* path;
  int line;
};
std::array<MapKey, 2> map_keys(const RegionSpec& r) {
  return {{{"normal_map", &r.sources.normal_map, r.normal_map_line},
           {"depth_map", &r.sources.depth_map, r.depth_map_line}}};
}

// What the region's method and effects read together: the loader builds nothing else.
FieldNeeds region_needs(const RegionSpec& r, const Method& method) {
  FieldNeeds needs = method.needs();
  if (r.materials) {
    needs =
        joined(needs, materials_needs(*r.materials, r.sources.normal_map.has_value(), r.sources.depth_map.has_value()));
  }
  if (r.wells) needs = joined(needs, wells_needs(*r.wells));
  return needs;
}

// Whether the loader opens the map `key` names (config/field_loader.hpp, maps_opened).
bool map_is_read(std::string_view key, const RegionSpec& r, FieldNeeds needs) {
  const MapsOpened opened = maps_opened(r.sources, needs);
  return key == "normal_map" ? opened.normal_map : opened.depth_map;
}

// `path` (absolute) with the links on it followed as far as they can be read: reading a link needs no access to where
// it leads (under the service, a hidden folder cannot be entered, and canonical() fails there), and a name that cannot
// be looked at ends the walk, the rest taken as written.
std::filesystem::path follow_links(std::filesystem::path path) {
  for (int hops = 0; hops < 40; ++hops) {  // as the kernel's limit on links in one lookup
    std::filesystem::path walked = path.root_path();
    const std::filesystem::path relative = path.relative_path();
    bool followed = false;
    for (auto it = relative.begin(); it != relative.end() && !followed; ++it) {
      const std::filesystem::path next = walked / *it;
      std::error_code error;
      if (std::filesystem::symlink_status(next, error).type() != std::filesystem::file_type::symlink || error) {
        walked = next;
        continue;
      }
      const std::filesystem::path target = std::filesystem::read_symlink(next, error);
      if (error) return path;
      std::filesystem::path rest;
      for (auto r = std::next(it); r != relative.end(); ++r) rest /= *r;
      path = (target.is_absolute() ? target : walked / target);
      if (!rest.empty()) path /= rest;
      path = path.lexically_normal();
      followed = true;
    }
    if (!followed) return path;
  }
  return path;
}

}  // namespace

std::optional<HiddenFolder> hidden_from_the_service(const std::filesystem::path& path) {
  static constexpr std::array<HiddenFolder, 5> kHidden = {{{"/home", "ProtectHome=yes"},
                                                           {"/root", "ProtectHome=yes"},
                                                           {"/run/user", "ProtectHome=yes"},
                                                           {"/tmp", "PrivateTmp=yes"},
                                                           {"/var/tmp", "PrivateTmp=yes"}}};
  std::error_code ignored;
  const std::filesystem::path normal = std::filesystem::absolute(path, ignored).lexically_normal();
  // And where its links lead: a link outside the folders that points into one is as hidden.
  for (const std::filesystem::path& where : {normal, follow_links(normal)}) {
    for (const HiddenFolder& hidden : kHidden) {
      const std::filesystem::path inside = where.lexically_relative(std::filesystem::path(hidden.folder));
      if (!inside.empty() && *inside.begin() != "..") return hidden;
    }
  }
  return std::nullopt;
}

namespace {

// Whether the service's user may use a file or folder of this status for `need` (others_read, others_exec): as
// anyone else, or through its groups (pseudohapticd.service: SupplementaryGroups=input uinput).
bool service_may(const std::filesystem::path& path, const std::filesystem::file_status& status,
                 std::filesystem::perms need_as_others, std::filesystem::perms need_as_group) {
  using std::filesystem::perms;
  if ((status.permissions() & need_as_others) != perms::none) return true;
  if ((status.permissions() & need_as_group) == perms::none) return false;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;
  for (const char* name : {"input", "uinput"}) {
    if (const ::group* g = ::getgrnam(name); g != nullptr && g->gr_gid == st.st_gid) return true;
  }
  return false;
}

// The first folder above `file` that the service's user may not enter, and its mode.
std::optional<std::string> closed_folder_above(const std::filesystem::path& file) {
  std::error_code error;
  for (std::filesystem::path folder = file.parent_path(); !folder.empty(); folder = folder.parent_path()) {
    const std::filesystem::file_status s = std::filesystem::status(folder, error);
    if (!error && !service_may(folder, s, std::filesystem::perms::others_exec, std::filesystem::perms::group_exec))
      return fmt::format("the folder {} (mode {:o}) does not let others through", folder.string(),
                         static_cast<unsigned>(s.permissions() & std::filesystem::perms::mask));
    if (folder == folder.root_path()) break;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> unreadable_by_others(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::path file = std::filesystem::absolute(path, error).lexically_normal();
  const std::filesystem::file_status status = std::filesystem::status(file, error);  // through links
  if (error || !std::filesystem::is_regular_file(status)) return std::nullopt;       // missing: the load says so
  if (!service_may(file, status, std::filesystem::perms::others_read, std::filesystem::perms::group_read))
    return fmt::format("its mode {:o} does not let others read it",
                       static_cast<unsigned>(status.permissions() & std::filesystem::perms::mask));
  // The folders on the path as written, and on the path its links lead to.
  if (std::optional<std::string> closed = closed_folder_above(file)) return closed;
  std::error_code unresolved;
  const std::filesystem::path resolved = std::filesystem::canonical(file, unresolved);
  if (!unresolved && resolved != file) return closed_folder_above(resolved);
  return std::nullopt;
}

std::vector<std::string> service_path_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  constexpr std::string_view kRunsAs =
      "pseudohapticd.service runs as a user of its own (DynamicUser=yes), which cannot read it: chmod a+r the file, "
      "a+x the folders on its path";
  if (const std::optional<HiddenFolder> hidden = hidden_from_the_service(spec.file)) {
    out.push_back(
        fmt::format("{} lies under {}, which pseudohapticd.service cannot read ({}; the daemon run by hand "
                    "can): the service reads /etc/pseudohaptic/scene.toml; keep a scene file of its own "
                    "under /etc/pseudohaptic",
                    spec.file.string(), hidden->folder, hidden->setting));
  } else if (const std::optional<std::string> why = unreadable_by_others(spec.file)) {
    out.push_back(fmt::format("{}: {}; {}", spec.file.string(), *why, kRunsAs));
  }
  for (const RegionSpec& r : spec.regions) {
    const FieldNeeds needs = region_needs(r, *make_method(r, spec.methods));
    for (const auto& [key, path, line] : map_keys(r)) {
      const std::optional<std::filesystem::path>& map = *path;
      if (!map || !map_is_read(key, r, needs)) continue;
      if (const std::optional<HiddenFolder> hidden = hidden_from_the_service(*map)) {
        out.push_back(
            fmt::format("{}:{}: region '{}': {} {} lies under {}, which pseudohapticd.service cannot read "
                        "({}; the daemon run by hand can): keep the images under "
                        "/etc/pseudohaptic or /usr/local/share",
                        spec.file.string(), line, r.name, key, map->string(), hidden->folder, hidden->setting));
      } else if (const std::optional<std::string> why = unreadable_by_others(*map)) {
        out.push_back(fmt::format("{}:{}: region '{}': {} {}: {}; {}", spec.file.string(), line, r.name, key,
                                  map->string(), *why, kRunsAs));
      }
    }
  }
  return out;
}

namespace {

// Where relative image paths in `file` start from: its folder, or for a symbolic link the folder of the file it leads
// to, where the images written beside it are (`pseudohaptic targets` writes scenes that name their images so, and a
// scene file linked into /etc/pseudohaptic/ finds them).
std::filesystem::path images_base_dir(const std::filesystem::path& file) {
  std::error_code error;
  if (!std::filesystem::is_symlink(std::filesystem::symlink_status(file, error))) return file.parent_path();
  const std::filesystem::path target = std::filesystem::canonical(file, error);
  return error ? file.parent_path() : target.parent_path();
}

// What is read as a file though it is none: a pipe the caller opened for the program, which has a writer (a shell's
// <(...) names one /dev/fd/N), and /dev/null, an empty scene.
bool read_as_a_file(const std::filesystem::path& file) {
  const std::string name = file.string();
  return name == "/dev/null" || name == "/dev/stdin" || name.starts_with("/dev/fd/") ||
         name.starts_with("/proc/self/fd/");
}

}  // namespace

SceneSpec parse_scene_file(const std::filesystem::path& file, MethodRegistry methods) {
  // A FIFO, a device or a socket named by mistake: its open() or read() would wait for ever for a writer.
  std::error_code status_error;
  const std::filesystem::file_status status = std::filesystem::status(file, status_error);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status) &&
      !std::filesystem::is_directory(status) && !read_as_a_file(file)) {
    throw ConfigError(
        fmt::format("{}: is not a regular file (a FIFO, a device or a socket), not a scene file", file.string()));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw ConfigError(fmt::format("{}: cannot open the scene file: {}{}", file.string(), std::strerror(error),
                                  error == ENOENT || error == EACCES ? service_hint(file) : ""));
  }
  // A folder opens, and reads as an empty scene: a daemon given /etc/pseudohaptic/ would run flat, silently.
  std::error_code ignored;
  if (std::filesystem::is_directory(file, ignored))
    throw ConfigError(fmt::format("{}: is a folder, not a scene file", file.string()));
  // Read up to a bound: /dev/zero or a huge file named by mistake must not take all the memory there is.
  std::string text;
  std::array<char, 1 << 16> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneFileBytes) {
      throw ConfigError(fmt::format("{}: longer than {} MiB, which no scene file is: is it the file meant?",
                                    file.string(), kMaxSceneFileBytes >> 20));
    }
  }
  if (in.bad()) throw ConfigError(fmt::format("{}: cannot read the scene file", file.string()));
  return parse_scene(text, file, images_base_dir(file), std::move(methods));
}

bool scene_file_absent(const std::filesystem::path& file) {
  std::error_code error;
  return std::filesystem::symlink_status(file, error).type() == std::filesystem::file_type::not_found;
}

MethodPtr make_method(const RegionSpec& region, const MethodRegistry& methods) {
  const MethodEntry* entry = methods.find(region.method);
  if (entry == nullptr) {
    throw ConfigError(
        fmt::format("region '{}': unknown method '{}' (allowed: {})", region.name, region.method, methods.names()));
  }
  const auto params = region.method_params.find(region.method);
  return entry->make(params != region.method_params.end() ? params->second : entry->defaults());
}

Scene load_scene(const SceneSpec& spec, SceneLoadReport* report, FieldReader* reader) {
  InProcessFieldReader here;
  FieldReader& fields_from = reader != nullptr ? *reader : here;
  std::vector<Region> regions;
  for (const RegionSpec& r : spec.regions) {
    Region region;
    region.name = r.name;
    region.rect = r.rect;
    region.method = make_method(r, spec.methods);
    const FieldNeeds method_needs = region.method->needs();
    const FieldNeeds needs = region_needs(r, *region.method);
    FieldLoadReport field_report;
    for (const auto& [key, map, line] : map_keys(r)) {
      std::error_code ignored;
      if (*map && std::filesystem::is_directory(**map, ignored)) {
        throw ConfigError(fmt::format("{}:{}: region '{}': {} {}: is a folder, not an image file", spec.file.string(),
                                      line, r.name, key, (*map)->string()));
      }
    }
    try {
      region.fields = fields_from.load_fields(r.sources, r.rect.w, r.rect.h, needs, field_report);
      // Effects keep what they precompute (a class map, a nearest-pattern field), not the fields.
      if (r.materials) {
        region.effects.push_back(make_materials_effect(region.fields, r.rect.w, r.rect.h, *r.materials,
                                                       class_map_bit_depth(r.sources, *r.materials, fields_from)));
      }
      if (r.wells) region.effects.push_back(make_wells_effect(region.fields, r.rect.w, r.rect.h, *r.wells));
    } catch (const FieldError& e) {
      std::string hint;
      for (const auto& map : {r.sources.normal_map, r.sources.depth_map}) {
        std::error_code ignored;
        if (map && hint.empty() && !std::filesystem::exists(*map, ignored)) hint = service_hint(*map);
      }
      // An image's error begins with its path: said at the key that names it (the region's line otherwise).
      int line = r.line;
      std::string key;
      for (const auto& [name, map, at] : map_keys(r)) {
        if (*map && key.empty() && std::string_view(e.what()).starts_with((*map)->string() + ": ")) {
          line = at;
          key = std::string(name) + ": ";
        }
      }
      throw ConfigError(
          fmt::format("{}:{}: region '{}': {}{}{}", spec.file.string(), line, r.name, key, e.what(), hint));
    } catch (const std::invalid_argument& e) {
      throw ConfigError(fmt::format("{}:{}: region '{}': {}", spec.file.string(), r.line, r.name, e.what()));
    } catch (const std::bad_alloc&) {
      // Said with the region, as any other load error: "std::bad_alloc" alone names nothing to change.
      throw ConfigError(
          fmt::format("{}:{}: region '{}': not enough memory for its fields ({}x{} px, about {} MiB "
                      "a field of 8 bytes a texel): make it smaller, or give the process more memory",
                      spec.file.string(), r.line, r.name, r.rect.w, r.rect.h,
                      static_cast<std::int64_t>(r.rect.w) * r.rect.h * 8 / (1 << 20)));
    }
    if (!method_needs.gradient) region.fields.gradient.reset();
    if (!method_needs.reads_depth(true)) region.fields.depth.reset();
    std::string variant = label_of(spec.daemon.engine) + " (the [daemon] table's)";
    if (r.engine_auto) {
      variant = "auto";  // chosen below, once the scene has prepared the region
    } else if (r.engine) {
      region.options = r.engine;
      variant = label_of(*r.engine) + " (set in the region)";
    }
    if (report != nullptr) {
      report->regions.push_back(field_report);
      report->variants.push_back(variant);
    }
    regions.push_back(std::move(region));
  }
  Scene scene(std::move(regions));
  // traversal = "auto" looks at each region as its method prepared it: before, a hybrid region's step marks did not
  // exist yet, and auto took its steps' C/D for curvature's on flat normals.
  for (std::size_t i = 0; i < spec.regions.size(); ++i) {
    const RegionSpec& r = spec.regions[i];
    if (!r.engine_auto) continue;
    VariantChoice choice = choose_variant(scene.regions()[i], {r.accuracy_px});
    choice.options.sampling = r.engine->sampling;
    choice.options.lut_directions = r.engine->lut_directions;
    scene.set_region_options(i, choice.options);
    if (report != nullptr)
      report->variants.at(report->variants.size() - spec.regions.size() + i) = "auto: " + choice.reason;
  }
  scene.set_options(spec.daemon.engine);  // builds what the variant precomputes (direction tables), only then
  return scene;
}

std::vector<std::string> map_warnings(const SceneSpec& spec, const SceneLoadReport& report) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < spec.regions.size() && i < report.regions.size(); ++i) {
    const RegionSpec& r = spec.regions[i];
    for (const std::string& note : map_notes(r.sources, report.regions[i], r.rect.w, r.rect.h))
      out.push_back(fmt::format("{}:{}: region '{}': {}", spec.file.string(), r.line, r.name, note));
  }
  return out;
}

std::optional<ReliefScale> relief_scale(const RegionSpec& region, const RegionFields& fields) {
  if (!fields.slope_comparison || !region.sources.normal_map || !region.sources.depth_map) return std::nullopt;
  const ReliefScale scale{*fields.slope_comparison, region.sources.depth_options.relief_px,
                          region.sources.normal_options.green};
  if (!scale.comparison.ratio && !scale.opposite_x() && !scale.opposite_y() && !scale.depth_flat()) return std::nullopt;
  return scale;
}

std::vector<std::string> load_warnings(const SceneSpec& spec, const SceneLoadReport& report, const Scene& scene) {
  std::vector<std::string> out = map_warnings(spec, report);
  for (std::string& w : relief_scale_warnings(spec, scene)) out.push_back(std::move(w));
  for (std::string& w : effect_warnings(spec, scene)) out.push_back(std::move(w));
  for (std::string& w : method_warnings(spec)) out.push_back(std::move(w));
  for (std::string& w : unused_method_table_warnings(spec)) out.push_back(std::move(w));
  for (std::string& w : unused_key_warnings(spec)) out.push_back(std::move(w));
  for (std::string& w : daemon_warnings(spec)) out.push_back(std::move(w));
  return out;
}

std::vector<std::string> daemon_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  if (spec.mouse_dpi_line != 0 && acceleration_of(spec.daemon).profile == AccelProfile::flat) {
    out.push_back(
        fmt::format("{}:{}: daemon.mouse_dpi changes nothing with the flat profile, which scales the mice's "
                    "own counts as libinput's does (the adaptive profile reads it){}",
                    spec.file.string(), spec.mouse_dpi_line,
                    spec.daemon.acceleration ? "" : "; the flat profile is the default for relative output"));
  }
  const auto walks_with_the_scenes_table = [](const RegionSpec& r) {
    return r.engine && !r.engine_auto && r.engine->traversal == Traversal::direction_lut && !r.own_lut_directions;
  };
  if (spec.lut_directions_line != 0 && spec.daemon.engine.traversal != Traversal::direction_lut &&
      std::none_of(spec.regions.begin(), spec.regions.end(), walks_with_the_scenes_table)) {
    out.push_back(
        fmt::format("{}:{}: daemon.lut_directions changes nothing: it applies to traversal = "
                    "\"direction_lut\", which neither the [daemon] table nor a region without a "
                    "lut_directions of its own walks with",
                    spec.file.string(), spec.lut_directions_line));
  }
  return out;
}

std::vector<std::string> unused_method_table_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  for (const RegionSpec& r : spec.regions) {
    // (The file's own method's table is read by the daemon; the method a tool's --method gives, by that tool.)
    for (const auto& [name, line] : r.method_table_lines) {
      if (name == r.method || name == r.method_in_file) continue;
      out.push_back(
          fmt::format("{}:{}: region '{}': [region.{}] changes nothing here: the region's method is {}, which {} (only "
                      "`pseudohaptic trace` and `replay` with --method {} read it)",
                      spec.file.string(), line, r.name, name, r.method_in_file,
                      r.method_in_file == HybridMethod::kName ? "takes the curvature and depth methods' defaults"
                      : r.method_in_file == FlatMethod::kName ? "has no table"
                                                              : "reads its own table alone",
                      name));
    }
  }
  return out;
}

std::vector<std::string> unused_key_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  for (const RegionSpec& r : spec.regions) {
    for (const auto& [key, line] : r.decoding_key_lines) {
      const bool of_normals = key.starts_with("normal_");
      if (of_normals ? r.sources.normal_map.has_value() : r.sources.depth_map.has_value()) continue;
      out.push_back(
          fmt::format("{}:{}: region '{}': {} changes nothing: it says how to read a {}, which the region "
                      "has not",
                      spec.file.string(), line, r.name, key, of_normals ? "normal_map" : "depth_map"));
    }
  }
  return out;
}

std::vector<std::string> method_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  for (const RegionSpec& r : spec.regions) {
    if (r.method != DepthMethod::kName) continue;
    const double gain = method_params<DepthMethod>(r).gain;
    if (gain == 0.0) {
      out.push_back(
          fmt::format("{}:{}: region '{}': depth.gain = 0 makes the depth method's C/D 1 everywhere: the "
                      "region feels flat",
                      spec.file.string(), r.line, r.name));
    } else if (gain < 0.0) {
      // Allowed (it is the formula's sign), but more often a white-is-deep map read the wrong way round: relief_px
      // is the key for that, since it turns the relief for every method and for the interrogation effects alike.
      out.push_back(
          fmt::format("{}:{}: region '{}': depth.gain = {:g} turns the relief over: bumps are felt as holes (for a "
                      "depth map stored white-is-deep, a negative relief_px reads it the right way round instead)",
                      spec.file.string(), r.line, r.name, gain));
    }
  }
  return out;
}

bool ReliefScale::mismatched() const {
  const std::optional<double>& ratio = comparison.ratio;
  return opposite_x() || opposite_y() || depth_flat() || (ratio && !(*ratio >= 0.8 && *ratio <= 1.25));
}

std::string ReliefScale::described() const {
  const auto percent = [](const std::optional<double>& share) { return fmt::format("{:.0f} %", 100.0 * *share); };
  const std::string flipped_sign = fmt::format("relief_px = {:.3g} (now {:.3g})", -relief_px, relief_px);
  if (opposite_x() && opposite_y()) {
    return fmt::format(
        "the normal map's slopes are of the opposite sign to the depth map's ({} along x, {} along y of those both "
        "show); if both hold the same relief, {} makes them agree",
        percent(comparison.opposite_x), percent(comparison.opposite_y), flipped_sign);
  }
  if (opposite_x() || opposite_y()) {
    const bool y = opposite_y();
    const std::optional<double>& other = y ? comparison.opposite_x : comparison.opposite_y;
    const std::string other_green =
        fmt::format("normal_green = \"{}\" (now \"{}\")", green == GreenConvention::opengl ? "directx" : "opengl",
                    green == GreenConvention::opengl ? "opengl" : "directx");
    // Along y alone: the other green convention; along x alone: a map mirrored. Where the relief slopes along one
    // axis only, the other says nothing, and the sign of the whole relief may be what is wrong.
    const std::string remedy = other ? (y ? other_green + " makes them agree" : "one of the two maps is mirrored")
                                     : (y ? other_green + " or " + flipped_sign : flipped_sign) +
                                           " makes them agree, if both hold the same relief";
    return fmt::format(
        "along {} the normal map's slopes are of the opposite sign to the depth map's ({} of those both "
        "show), along {} {}: {}",
        y ? "y" : "x", percent(y ? comparison.opposite_y : comparison.opposite_x), y ? "x" : "y",
        other ? "of one sign" : "too few to tell", remedy);
  }
  if (depth_flat()) {
    return fmt::format(
        "the depth map is all but flat where the normal map shows the relief sloping ({} of its slopes): relief_px "
        "(now {:.3g}) is far too small for the normal map's relief, or the depth map holds another relief",
        percent(comparison.depth_flat), relief_px);
  }
  const double ratio = *comparison.ratio;
  std::string line =
      fmt::format("the normal map's slopes are {:.2g} times the depth map's where both show the relief sloping", ratio);
  if (mismatched()) {
    line += fmt::format("; if both hold the same relief, relief_px = {:.3g} (now {:.3g}) makes them agree",
                        relief_px * ratio, relief_px);
  }
  return line;
}

std::vector<std::string> relief_scale_warnings(const SceneSpec& spec, const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < spec.regions.size() && i < scene.regions().size(); ++i) {
    const RegionSpec& r = spec.regions[i];
    const std::optional<ReliefScale> scale = relief_scale(r, scene.regions()[i].fields);
    if (!scale || !scale->mismatched()) continue;
    out.push_back(fmt::format("{}:{}: region '{}': {}", spec.file.string(), r.line, r.name, scale->warning()));
  }
  return out;
}

namespace {

// Whether a nearest-pattern field holds no pattern texel: every texel is kNoPattern, including those on the pattern
// itself, which are (0, 0).
bool pattern_is_empty(const PatternField& field) {
  return std::all_of(field.offsets.values.begin(), field.offsets.values.end(),
                     [](const PatternOffset& o) { return o.dx == kNoPatternComponent; });
}

}  // namespace

std::vector<std::string> effect_warnings(const SceneSpec& spec, const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < spec.regions.size() && i < scene.regions().size(); ++i) {
    const RegionSpec& r = spec.regions[i];
    for (const EffectPtr& effect : scene.regions()[i].effects) {
      const auto* wells = dynamic_cast<const WellsEffect*>(effect.get());
      if (wells == nullptr || !pattern_is_empty(wells->field())) continue;
      const WellsParams& p = wells->params();
      const std::string why =
          p.pattern != WellPattern::contours ? "no texel's normal lies on the isophote (check light and cos_alpha)"
          : p.contours.levels.empty() && p.contours.count == 0
              ? "levels = 0 asks for no contour"
              : "no contour level lies within the region's heights (check levels against the depth map's heights, "
                "(v - depth_zero) * relief_px)";
      out.push_back(fmt::format("{}:{}: region '{}': wells: {}, so the pattern is empty and the wells do nothing",
                                spec.file.string(), r.line, r.name, why));
    }
  }
  return out;
}

namespace {

// The width and height of the part of `a` that lies inside `b` (0 where they do not meet).
std::pair<std::int64_t, std::int64_t> overlap(const Rect& a, const Rect& b) {
  const auto along = [](std::int64_t a0, std::int64_t an, std::int64_t b0, std::int64_t bn) {
    return std::max<std::int64_t>(0, std::min(a0 + an, b0 + bn) - std::max(a0, b0));
  };
  return {along(a.x, a.w, b.x, b.w), along(a.y, a.h, b.y, b.h)};
}

}  // namespace

std::optional<std::string> off_desktop_note(const Rect& rect, const Rect& desktop) {
  const auto [w, h] = overlap(rect, desktop);
  if (w == rect.w && h == rect.h) return std::nullopt;
  const std::string region = fmt::format("at {},{} ({}x{} px)", rect.x, rect.y, rect.w, rect.h);
  const std::string on = fmt::format("the desktop {},{} {}x{} px", desktop.x, desktop.y, desktop.w, desktop.h);
  if (w == 0 || h == 0) {
    return fmt::format("{} lies outside {}: the cursor never reaches it, and its fields are loaded for nothing", region,
                       on);
  }
  return fmt::format("{}: only {}x{} px of it lie on {}", region, w, h, on);
}

std::vector<std::string> off_desktop_notes(const Scene& scene, const Rect& desktop) {
  std::vector<std::string> out;
  for (const Region& region : scene.regions()) {
    if (const std::optional<std::string> note = off_desktop_note(region.rect, desktop))
      out.push_back(fmt::format("region '{}' {}", region.name, *note));
  }
  return out;
}

std::vector<std::string> desktop_warnings(const SceneSpec& spec) {
  std::vector<std::string> out;
  if (!spec.daemon.desktop) return out;
  for (const RegionSpec& r : spec.regions) {
    if (const std::optional<std::string> note = off_desktop_note(r.rect, *spec.daemon.desktop))
      out.push_back(fmt::format("{}:{}: region '{}' {}", spec.file.string(), r.line, r.name, *note));
  }
  return out;
}

}  // namespace ph
