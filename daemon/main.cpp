// pseudohapticd: the system-wide service. Takes the mice, rescales their motion over the scene's
// textures and re-emits it through virtual devices until SIGTERM; SIGHUP reloads the scene file.
#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>

#include "config/scene_file.hpp"
#include "daemon/daemon.hpp"
#include "daemon/log.hpp"
#include "daemon/service_notifier.hpp"

int main(int argc, char** argv) {
  ph::block_daemon_signals();
  CLI::App app{
      "pseudohapticd: pseudo-haptic textures for an ordinary mouse, system-wide.\n"
      "Grabs the mice, changes the control/display ratio of their motion over the textures of a scene and\n"
      "re-emits it through a virtual device named \"pseudohaptic <mouse name>\". Runs in the foreground;\n"
      "the systemd unit pseudohapticd.service runs it as a service. SIGHUP reloads the scene file;\n"
      "SIGTERM or SIGINT lets go of the mice and exits. See pseudohapticd(8)."};
  std::string config;
  bool default_scene = false;
  bool verbose = false;
  std::string control = ph::default_control_path();
  app.add_option("-c,--config", config,
                 fmt::format("Scene file (TOML; check it with `pseudohaptic check-config FILE`). Default: {} if it "
                             "exists, else the embedded default scene",
                             ph::kDefaultSceneFile))
      // An empty path (a drop-in's unset variable) must not quietly become the default file or the embedded scene.
      ->check([](const std::string& path) {
        return path.empty() ? std::string("an empty path; leave -c out for the default") : std::string();
      });
  app.add_flag("--default-scene", default_scene,
               "Use the embedded default scene (three targets of the curvature paper) and no file")
      ->excludes(app.get_option("--config"));
  app.add_option("--control", control,
                 "Control socket for the session helper, `pseudohaptic status` and `pseudohaptic cursor`; \"\" for "
                 "none. Default: $RUNTIME_DIRECTORY/control under systemd, else /run/pseudohaptic/control")
      ->capture_default_str();
  app.add_flag("-v,--verbose", verbose, "Also log debug messages (every device seen, every hotplug)");
  app.set_version_flag("--version", "pseudohapticd 0.1.0");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  const ph::Logger log(verbose, ph::Logger::stderr_is_journal());
  const ph::ServiceNotifier notifier;
  ph::ConfigChoice choice;
  if (!config.empty()) choice.file = config;
  choice.default_scene = default_scene;
  choice.default_file = std::string(ph::kDefaultSceneFile);
  try {
    std::optional<ph::Configuration> loaded = ph::load_until_stopped(choice, log);
    if (!loaded) {  // SIGTERM or SIGINT during the load: nothing taken yet, nothing to let go of
      notifier.stopping();
      log.info("stopped (the scene load under way is not waited for)");
      std::_Exit(0);
    }
    ph::Daemon daemon(choice, std::move(*loaded), log, notifier, control);
    const int status = daemon.run();
    if (daemon.stopped_during_a_load()) std::_Exit(status);  // not waiting for the load (daemon/daemon.hpp)
    return status;
  } catch (const std::exception& e) {
    log.error("{}", e.what());
    notifier.status(std::string("failed: ") + e.what());
    return 1;
  }
}
