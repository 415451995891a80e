// pseudohapticd's event loop: one epoll over the udev monitor, a signalfd, timers, the reload worker's eventfd,
// the control socket and the pointers it does not take. Every mouse it takes gets its own reader thread, virtual
// device and frame assembler; all share one pipeline, so one cursor model, however many mice move it
// (docs/METHODS.md, "Cursor and output"). The readers and the loop take turns under one lock (`state_`).
#pragma once

#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "common/unique_fd.hpp"
#include "core/engine/pipeline.hpp"
#include "daemon/configuration.hpp"
#include "daemon/control_server.hpp"
#include "daemon/evdev_device.hpp"
#include "daemon/log.hpp"
#include "daemon/mouse_reader.hpp"
#include "daemon/retired_devices.hpp"
#include "daemon/scene_reloader.hpp"
#include "daemon/service_notifier.hpp"
#include "daemon/udev_watch.hpp"
#include "uinput/uinput_sink.hpp"

namespace ph {

class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Blocks SIGTERM, SIGINT and SIGHUP so that they wait for the event loop's signalfd. Call it first
// thing in main: a SIGHUP during a long start-up must not kill the daemon.
void block_daemon_signals();

// The first load of the configuration, on a thread of its own, while this thread waits for SIGTERM or SIGINT (blocked
// by block_daemon_signals): nullopt when one comes first (logged), and the caller ends the process (std::_Exit) rather
// than wait for the load, which may take long (a large image) or for ever (a FIFO named as the scene file). SIGHUP
// stays pending: the event loop reloads at its start. Throws what the load throws (ConfigError).
std::optional<Configuration> load_until_stopped(const ConfigChoice& choice, const Logger& log);

class Daemon final : private ControlHandler {
 public:
  // Takes the mice present now, with `loaded`, the configuration `choice` names (load_until_stopped). Expects
  // block_daemon_signals() to have run. Throws StartupError or UdevError with a message for the user. `control_path`:
  // where the control socket listens ("" for none); a socket that cannot be made is logged, not fatal.
  Daemon(ConfigChoice choice, Configuration loaded, const Logger& log, const ServiceNotifier& notifier,
         const std::string& control_path);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Runs until SIGTERM or SIGINT, or an error it cannot go on from (then exit status 1, said); then lets go of every
  // mouse. Returns the exit status.
  int run();
  // After run(): a reload's load was under way at the stop. It may take long yet (a large image, a FIFO named as the
  // scene file), and destroying the daemon would wait for it: the caller ends the process instead (std::_Exit), run()
  // having done what must be done before (mice let go of, virtual devices gone, the control socket removed).
  bool stopped_during_a_load() const { return stopped_during_a_load_; }

 private:
  // The event loop, until stop_; throws what it cannot go on from.
  void loop();
  // A mouse the daemon has opened: waiting for its buttons to be released or for another program's grab to
  // end, or taken (grabbed, with its virtual device and frame assembler). Let go of, its reader stops, then its
  // virtual devices release held buttons and go to `retired_`, then the grab and the node (to `retired_` too when the
  // mouse was unplugged).
  struct Mouse {
    std::unique_ptr<EvdevDevice> device;
    std::unique_ptr<UinputSink> sink;
    std::unique_ptr<FrameProcessor> frames;
    // Pass-through (docs/SERVICE.md, "Applications that lock the pointer"): a relative device that
    // carries the mouse's frames unchanged while `passing`, made the first time it is needed.
    std::unique_ptr<UinputSink> passthrough_sink;
    Frame raw_frame;
    bool passing = false;
    bool mid_frame = false;  // events of a frame have been routed, its SYN_REPORT not yet
    bool told_waiting = false;
    // Another program holds its grab: watched (not retried on the timer), taken once it reads events again.
    bool held_elsewhere = false;
    std::string ending;                   // not empty: its reader asked the loop to let go of it, for this reason
    std::unique_ptr<MouseReader> reader;  // once taken
  };

  using SteadyTime = std::chrono::steady_clock::time_point;

  // ControlHandler: the control socket's requests.
  control::Status status() const override;
  Vec2 cursor() const override;
  void position(Vec2 position, bool from_helper) override;
  void layout(Rect desktop, const std::vector<Rect>& outputs) override;
  void layout_source_gone() override;
  void helper_changed(bool present) override;
  void on_displays_changed();
  void change_desktop(Rect desktop, std::vector<Rect> outputs, std::string_view why);
  void passthrough(bool on) override;
  void set_passthrough(bool on);
  // Pass-through as asked, with `mode`: relative output already reaches such applications as motion.
  bool passthrough_with(OutputMode mode) const { return passthrough_asked_ && mode == OutputMode::absolute; }
  void route(Mouse& mouse, const InputEvent& event);
  bool make_passthrough_sink(const std::string& node, Mouse& mouse);

  void start_control(const std::string& path);
  void start_pipeline();
  void restart_devices(std::string_view why);
  void watch_untaken(const std::string& node, std::unique_ptr<EvdevDevice> device);
  void on_untaken_readable(int fd);
  void on_resync_tick();
  Texel cursor_pixel() const { return texel_at(pipeline_->cursor().position); }
  void start_holding();
  void release_held();
  inline void remember_emitted(SteadyTime now);  // (defined in daemon.cpp, its only user: the frame's path)
  bool emitted_recently(Texel pixel) const;
  void take_present_mice();
  void consider(const std::string& node);
  void try_take(const std::string& node, Mouse& mouse);
  void wait_for_release_elsewhere(const std::string& node, Mouse& mouse);
  bool on_released_elsewhere(int fd);
  void let_go(const std::string& node, std::string_view why);
  void let_go_of_all(std::string_view why);
  void retire_virtual_devices(Mouse& mouse);
  bool emit_what_the_grab_kept(Mouse& mouse, std::vector<InputEvent> events);
  void on_mouse_batch(const std::string& node, Mouse& mouse, const std::vector<InputEvent>& events, ReadStatus status,
                      const std::string& error);
  void ask_let_go(Mouse& mouse, std::string why);
  void on_mice_ended();
  void sync_mice();
  void on_hotplug();
  void on_signal();
  void on_retry_tick();
  void reload();
  void on_reload_ended();
  void apply(Configuration next);
  void update_retry_timer();
  std::string status_line() const;
  void log_notes(const Configuration& configuration) const;

  // Held by the event loop while it handles what woke it and by a mouse's reader while it hands on a batch.
  std::timed_mutex state_;
  ConfigChoice choice_;
  const Logger& log_;
  const ServiceNotifier& notifier_;
  Configuration config_;
  std::optional<Rect> helper_desktop_;   // the session helper's layout, over `desktop = "auto"`
  std::vector<Rect> helper_outputs_;     // and where on it its outputs are (Pipeline::set_desktop)
  bool helper_desktop_kept_up_ = false;  // the connection that gave it is open, and reports changes
  std::unique_ptr<Pipeline> pipeline_;
  UdevWatch udev_;
  UniqueFd epoll_, signals_, retry_timer_, watchdog_timer_, resync_timer_, hold_timer_;
  UniqueFd mice_ended_;  // an eventfd: a reader found its mouse gone (Mouse::ending says which)
  LogindSessions sessions_;
  SceneReloader reloader_;  // SIGHUP's load, on a worker thread
  SteadyTime reload_started_{};
  bool reload_failed_ = false;          // the last reload's load failed: said in the status line until one succeeds
  bool stopped_during_a_load_ = false;  // run() ended with a reload's load under way
  std::unique_ptr<ControlServer> control_;
  // Resync: pointers the daemon does not take, watched without a grab; the pixels it emitted lately (a
  // helper's report of one of those is the daemon's own motion, not a warp); when its mice last moved.
  std::map<std::string, std::unique_ptr<EvdevDevice>> untaken_;  // by node
  std::deque<std::pair<SteadyTime, Texel>> emitted_;
  SteadyTime last_motion_{};
  SteadyTime last_query_{};
  SteadyTime last_untaken_motion_{};
  bool settle_query_due_ = false;
  bool passthrough_asked_ = false;   // what the control socket asks for
  bool passthrough_wanted_ = false;  // what is done: as asked, with absolute output only
  // Motion after a pause waits for the helper's answer (at most kHoldForHelperNs): events by node.
  bool holding_ = false;
  std::vector<std::pair<std::string, InputEvent>> held_events_;
  // The virtual devices of mice let go of, and the nodes no longer needed, destroyed off the state lock.
  RetiredDevices retired_;
  std::map<std::string, std::unique_ptr<Mouse>> mice_;  // by node
  std::map<std::string, int> unopened_;                 // node -> tries left (not yet accessible)
  std::set<std::string> passed_over_;                   // not a pointer, not matched, ours, ungrabbable
  bool retry_armed_ = false;
  bool stop_ = false;
};

}  // namespace ph
