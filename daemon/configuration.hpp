// What the daemon runs with: the scene and its [daemon] settings, loaded from the scene file or the
// embedded default scene, with the desktop resolved. Loaded at start and again on SIGHUP.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/daemon_config.hpp"
#include "config/desktop_geometry.hpp"
#include "core/engine/pipeline.hpp"
#include "core/engine/scene.hpp"

namespace ph {

struct ConfigChoice {
  std::optional<std::filesystem::path> file;  // --config; nullopt: the default path if it exists
  bool default_scene = false;                 // --default-scene: the embedded scene, no file
  std::filesystem::path default_file;         // kDefaultSceneFile; a parameter so tests can point elsewhere
  std::filesystem::path drm_dir = kDrmDir;
};

struct Configuration {
  std::string source;     // "FILE" or "the embedded default scene", for the log
  bool embedded = false;  // the embedded default scene, not a file
  std::shared_ptr<const Scene> scene;
  DaemonSettings settings;
  PipelineConfig pipeline;
  std::vector<std::string> notes;     // for the log: the embedded default scene in use
  std::vector<std::string> warnings;  // for the log: invalid texels repaired, per region and map; the desktop guessed
  std::string desktop_guessed;        // that last warning, "" when a display or the file set the desktop
};

// Throws ConfigError (scene file) with a message that names the file, line and key.
Configuration load_configuration(const ConfigChoice& choice);

// True when a reload can keep the running pipeline and devices and only swap the scene.
bool only_scene_differs(const Configuration& a, const Configuration& b);

}  // namespace ph
