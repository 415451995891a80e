#include "config/daemon_config.hpp"

#include <fmt/format.h>
#include <fnmatch.h>

namespace ph {

namespace {

constexpr std::string_view kAllowed =
    "allowed: \"name:GLOB\", \"usb:VVVV:PPPP\" or \"id:VVVV:PPPP\" (vendor:product, 4 hex digits each)";

std::optional<std::uint16_t> parse_hex4(std::string_view text) {
  if (text.size() != 4) return std::nullopt;
  std::uint16_t value = 0;
  for (char c : text) {
    int digit = 0;
    if (c >= '0' && c <= '9') {
      digit = c - '0';
    } else if (c >= 'a' && c <= 'f') {
      digit = c - 'a' + 10;
    } else if (c >= 'A' && c <= 'F') {
      digit = c - 'A' + 10;
    } else {
      return std::nullopt;
    }
    value = static_cast<std::uint16_t>(value * 16 + digit);
  }
  return value;
}

// What is wrong with a glob, or empty. fnmatch(3) takes any string, but an unterminated bracket or a
// trailing backslash is almost surely a typo.
std::string glob_error(std::string_view glob) {
  if (glob.empty()) return "the name glob is empty";
  for (std::size_t i = 0; i < glob.size(); ++i) {
    if (glob[i] == '\\') {
      if (i + 1 == glob.size()) return "the name glob ends with a lone backslash";
      ++i;
    } else if (glob[i] == '[') {
      std::size_t j = i + 1;
      if (j < glob.size() && (glob[j] == '!' || glob[j] == '^')) ++j;
      if (j < glob.size() && glob[j] == ']') ++j;  // a leading ] is a member
      while (j < glob.size() && glob[j] != ']') ++j;
      if (j == glob.size()) return "the name glob has a '[' without its ']'";
      i = j;
    }
  }
  return {};
}

}  // namespace

std::optional<DeviceMatch> parse_device_match(std::string_view text, std::string& error) {
  DeviceMatch match;
  if (text.starts_with("name:")) {
    const std::string_view glob = text.substr(5);
    if (std::string e = glob_error(glob); !e.empty()) {
      error = fmt::format("'{}': {}", text, e);
      return std::nullopt;
    }
    match.name_glob = std::string(glob);
    return match;
  }
  for (std::string_view prefix : {std::string_view("usb:"), std::string_view("id:")}) {
    if (!text.starts_with(prefix)) continue;
    const std::string_view ids = text.substr(prefix.size());
    const std::size_t colon = ids.find(':');
    const auto vendor = colon == std::string_view::npos ? std::nullopt : parse_hex4(ids.substr(0, colon));
    const auto product = colon == std::string_view::npos ? std::nullopt : parse_hex4(ids.substr(colon + 1));
    if (!vendor || !product) {
      error = fmt::format("'{}': vendor:product must be 4 hex digits each, like {}046d:c077", text, prefix);
      return std::nullopt;
    }
    match.vendor = vendor;
    match.product = product;
    match.written_usb = prefix == "usb:";
    return match;
  }
  error = fmt::format("'{}': unknown matcher ({})", text, kAllowed);
  return std::nullopt;
}

std::string format_device_match(const DeviceMatch& match) {
  if (match.name_glob) return "name:" + *match.name_glob;
  return fmt::format("{}:{:04x}:{:04x}", match.written_usb ? "usb" : "id", match.vendor.value_or(0),
                     match.product.value_or(0));
}

AccelSettings acceleration_of(const DaemonSettings& settings) {
  const AccelProfile fallback = settings.output == OutputMode::absolute ? AccelProfile::adaptive : AccelProfile::flat;
  return {settings.acceleration.value_or(fallback), settings.speed, settings.mouse_dpi};
}

PipelineConfig pipeline_config_of(const DaemonSettings& settings, Rect desktop) {
  PipelineConfig config;
  config.desktop = desktop;
  config.mode = settings.output;
  config.pointer_gain = settings.pointer_speed;
  config.acceleration = acceleration_of(settings);
  return config;
}

bool device_matches(const DaemonSettings& settings, std::string_view name, std::uint16_t vendor,
                    std::uint16_t product) {
  if (settings.devices.empty()) return true;
  const std::string name_z(name);  // fnmatch needs a terminated string
  for (const DeviceMatch& m : settings.devices) {
    if (m.name_glob && ::fnmatch(m.name_glob->c_str(), name_z.c_str(), 0) != 0) continue;
    if (m.vendor && *m.vendor != vendor) continue;
    if (m.product && *m.product != product) continue;
    return true;
  }
  return false;
}

}  // namespace ph
