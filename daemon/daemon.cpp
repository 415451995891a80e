#include "daemon/daemon.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <future>
#include <string>
#include <string_view>
#include <thread>

#include "config/scene_file.hpp"
#include "core/engine/default_scene.hpp"
#include "core/engine/frame_path.hpp"

namespace ph {

namespace {

// How often a mouse with a held button, or a node not yet accessible, is looked at again.
constexpr long kRetryIntervalNs = 50'000'000;
// A node that udev has not made accessible after this many tries (5 s) is given up.
constexpr int kOpenTries = 100;
// Virtual devices of pseudohapticd, this one or another: never taken.
constexpr std::string_view kOwnDevicePrefix = "pseudohaptic ";
// Resync with the session helper (docs/SERVICE.md, "Resync"): its clock, a pause of the mice after which
// the next motion asks where the cursor is, how often it asks anyway (application warps), how soon
// after another pointer stops, how often at most while one moves, and how long a pixel the daemon
// emitted still explains a report.
constexpr long kResyncTickNs = 100'000'000;
constexpr std::chrono::milliseconds kPauseBeforeQuery{300};
constexpr std::chrono::milliseconds kQueryEvery{1000};
constexpr std::chrono::milliseconds kSettleAfterOtherPointer{100};
constexpr std::chrono::milliseconds kQueryAtMostEvery{50};
constexpr std::chrono::milliseconds kEmittedMemory{2000};
constexpr std::size_t kEmittedAlwaysKept = 8;
// The first frames after a pause wait this long at most for the helper's answer, so that they start
// from where the cursor really is (an application may have warped it during the pause).
constexpr long kHoldForHelperNs = 30'000'000;

[[noreturn]] void fail_system(std::string_view what) {
  throw StartupError(fmt::format("{}: {}", what, std::strerror(errno)));
}

void watch(int epoll, int fd) {
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = fd;
  if (::epoll_ctl(epoll, EPOLL_CTL_ADD, fd, &event) < 0) fail_system("cannot watch a file descriptor (epoll)");
}

void set_timer(int timer, long interval_ns) {
  itimerspec spec{};
  spec.it_interval.tv_sec = interval_ns / 1'000'000'000;
  spec.it_interval.tv_nsec = interval_ns % 1'000'000'000;
  spec.it_value = spec.it_interval;  // zero disarms
  ::timerfd_settime(timer, 0, &spec, nullptr);
}

void drain_timer(int timer) {
  std::uint64_t expirations = 0;
  [[maybe_unused]] const ssize_t n = ::read(timer, &expirations, sizeof expirations);
}

bool retry_later(int error) { return error == EACCES || error == EPERM || error == ENOENT || error == ENXIO; }

std::string quoted_name(const EvdevDevice& device) { return fmt::format("\"{}\"", device.name()); }

sigset_t daemon_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, s);
  return set;
}

}  // namespace

void block_daemon_signals() {
  const sigset_t set = daemon_signals();
  ::sigprocmask(SIG_BLOCK, &set, nullptr);  // fails only for an invalid `how`
}

std::optional<Configuration> load_until_stopped(const ConfigChoice& choice, const Logger& log) {
  // Shared with the thread, which may outlive this function.
  auto load = std::make_shared<std::packaged_task<Configuration()>>([choice] { return load_configuration(choice); });
  std::future<Configuration> loaded = load->get_future();
  std::thread worker([load] { (*load)(); });
  ::pthread_setname_np(worker.native_handle(), "ph-scene-load");
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGTERM);
  sigaddset(&stop, SIGINT);
  const timespec tick{0, 50'000'000};  // how often the load is looked at: at most this much later a start
  while (loaded.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    const int signal = ::sigtimedwait(&stop, nullptr, &tick);
    if (signal == SIGTERM || signal == SIGINT) {
      log.info("{} received while the scene loads; stopping", signal == SIGTERM ? "SIGTERM" : "SIGINT");
      worker.detach();
      return std::nullopt;
    }
  }
  worker.join();
  return loaded.get();
}

Daemon::Daemon(ConfigChoice choice, Configuration loaded, const Logger& log, const ServiceNotifier& notifier,
               const std::string& control_path)
    : choice_(std::move(choice)),
      log_(log),
      notifier_(notifier),
      config_(std::move(loaded)),
      reloader_([choice = choice_] { return load_configuration(choice); }) {
  log_notes(config_);
  // Without /dev/uinput there is nothing to emit through: say so now rather than at the first mouse.
  if (::access("/dev/uinput", R_OK | W_OK) != 0) throw StartupError(uinput_error_message(-errno));

  install_reader_wake_handler();
  const sigset_t handled = daemon_signals();
  signals_ = UniqueFd(::signalfd(-1, &handled, SFD_NONBLOCK | SFD_CLOEXEC));
  epoll_ = UniqueFd(::epoll_create1(EPOLL_CLOEXEC));
  retry_timer_ = UniqueFd(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  watchdog_timer_ = UniqueFd(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  resync_timer_ = UniqueFd(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  hold_timer_ = UniqueFd(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  mice_ended_ = UniqueFd(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC));
  if (!signals_ || !epoll_ || !retry_timer_ || !watchdog_timer_ || !resync_timer_ || !hold_timer_ || !mice_ended_)
    fail_system("cannot set up the event loop");
  for (int fd : {signals_.get(), udev_.fd(), retry_timer_.get(), watchdog_timer_.get(), resync_timer_.get(),
                 hold_timer_.get(), reloader_.fd(), mice_ended_.get()})
    watch(epoll_.get(), fd);
  if (const auto interval = ServiceNotifier::watchdog_interval()) {
    set_timer(watchdog_timer_.get(), static_cast<long>(interval->count()) * 1000);
    log_.debug("watchdog ping every {} ms", interval->count() / 1000);
  }

  start_pipeline();
  const PipelineConfig& p = config_.pipeline;
  log_.info("scene: {} ({} regions); desktop {}x{}+{}+{}; {} output; {} acceleration, speed {}", config_.source,
            config_.scene->regions().size(), p.desktop.w, p.desktop.h, p.desktop.x, p.desktop.y,
            p.mode == OutputMode::relative ? "relative" : "absolute", accel_profile_name(p.acceleration.profile),
            p.acceleration.speed);
  if (!control_path.empty()) start_control(control_path);
  if (udev_.uses_kernel_events()) log_.info("no udev daemon running; listening to kernel uevents for hotplug");
  const std::lock_guard lock(state_);  // the readers start with the first mouse taken
  take_present_mice();
  if (mice_.empty()) log_.notice("no mouse to take yet; waiting for one to be plugged in");
}

Daemon::~Daemon() {
  const std::lock_guard lock(state_);
  mice_.clear();  // the readers stop first, while everything they hand frames to is still there
}

void Daemon::start_pipeline() { pipeline_ = std::make_unique<Pipeline>(config_.scene, config_.pipeline); }

void Daemon::start_control(const std::string& path) {
  try {
    control_ = std::make_unique<ControlServer>(path, epoll_.get(), sessions_, log_);
    log_.info("control socket: {}", path);
  } catch (const ControlSocketInUse& e) {
    // Another daemon runs: it holds the mice already, and this one would only fight it for new ones.
    throw StartupError(e.what());
  } catch (const std::exception& e) {
    log_.warning("{}; running without a control socket (no session helper, no `pseudohaptic status`)", e.what());
  }
}

void Daemon::take_present_mice() {
  for (const std::string& node : udev_.event_nodes()) consider(node);
}

int Daemon::run() {
  notifier_.ready(status_line());
  int status = 0;
  try {
    loop();
  } catch (const std::exception& e) {
    // (udev failing while the mice are taken again, a reader thread that cannot be made, epoll out of memory): the
    // mice are let go of as on a stop, and a load under way is not waited for, as on a stop (it may never end).
    log_.error("{}; stopping", e.what());
    notifier_.status(std::string("failed: ") + e.what());
    status = 1;
  }
  const std::lock_guard lock(state_);
  notifier_.stopping();
  let_go_of_all("stopping");
  if (reloader_.loading()) {
    stopped_during_a_load_ = true;
    retired_.wait_until_empty();  // the releases read, the virtual devices gone
    control_.reset();             // the socket removed
    log_.info("stopped (the scene load under way is not waited for)");
    return status;
  }
  log_.info("stopped");
  return status;
}

[[gnu::hot]] void Daemon::loop() {
  std::array<epoll_event, 16> events{};
  while (!stop_) {
    const int n = ::epoll_wait(epoll_.get(), events.data(), static_cast<int>(events.size()), -1);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_system("epoll_wait failed");
    }
    std::unique_lock lock(state_);
    // A control request is answered after every frame written into a mouse before it was asked: the mice's
    // readers hand on what they had queued first, and the requests go last among what woke the loop.
    if (control_ && std::any_of(events.begin(), events.begin() + n,
                                [this](const epoll_event& e) { return control_->owns(e.data.fd); })) {
      lock.unlock();
      sync_mice();  // (only this thread adds or removes mice)
      lock.lock();
      std::stable_partition(events.begin(), events.begin() + n,
                            [this](const epoll_event& e) { return !(control_ && control_->owns(e.data.fd)); });
    }
    for (int i = 0; i < n && !stop_; ++i) {
      const int fd = events[static_cast<std::size_t>(i)].data.fd;
      if (fd == signals_.get()) {
        on_signal();
      } else if (fd == udev_.fd()) {
        on_hotplug();
      } else if (fd == retry_timer_.get()) {
        drain_timer(fd);
        on_retry_tick();
      } else if (fd == watchdog_timer_.get()) {
        drain_timer(fd);
        notifier_.watchdog();
      } else if (fd == hold_timer_.get()) {
        drain_timer(fd);
        log_.debug("resync: no answer from the session helper within {} ms; going on from the model",
                   kHoldForHelperNs / 1'000'000);
        release_held();
      } else if (fd == reloader_.fd()) {
        on_reload_ended();
      } else if (fd == mice_ended_.get()) {
        drain_timer(fd);  // (an eventfd reads as a counter too)
        on_mice_ended();
      } else if (fd == resync_timer_.get()) {
        drain_timer(fd);
        on_resync_tick();
      } else if (control_ && control_->owns(fd)) {
        control_->on_readable(fd, *this);
      } else if (!on_released_elsewhere(fd)) {
        on_untaken_readable(fd);
      }
    }
  }
}

void Daemon::consider(const std::string& node) {
  if (mice_.contains(node) || passed_over_.contains(node)) return;
  std::unique_ptr<EvdevDevice> device;
  try {
    device = std::make_unique<EvdevDevice>(node);
  } catch (const DeviceError& e) {
    if (retry_later(e.error())) {
      // udev may not have set the node's permissions yet: look again shortly.
      if (unopened_.emplace(node, kOpenTries).second) log_.debug("{}; trying again", e.what());
      update_retry_timer();
    } else {
      log_.debug("{}; not taken", e.what());
    }
    return;
  }
  unopened_.erase(node);
  const std::string name = device->name();
  if (name.starts_with(kOwnDevicePrefix)) {
    log_.debug("{} {}: a virtual device of pseudohapticd; not taken", node, quoted_name(*device));
    passed_over_.insert(node);
    retired_.keep(std::move(device));  // closed off the lock
    return;
  }
  if (!device->is_pointer()) {
    log_.debug("{} {}: not a pointer (needs REL_X, REL_Y and a button); not taken", node, quoted_name(*device));
    passed_over_.insert(node);
    if (device->moves_the_cursor()) {
      watch_untaken(node, std::move(device));
    } else {
      retired_.keep(std::move(device));  // a keyboard plugged in: closed off the lock
    }
    return;
  }
  const DeviceDescription description = device->description();
  if (!device_matches(config_.settings, name, description.vendor, description.product)) {
    log_.info("{} {} ({:04x}:{:04x}): not in [daemon] devices; not taken", node, quoted_name(*device),
              description.vendor, description.product);
    passed_over_.insert(node);
    watch_untaken(node, std::move(device));
    return;
  }
  auto& mouse = *mice_.emplace(node, std::make_unique<Mouse>()).first->second;
  mouse.device = std::move(device);
  try_take(node, mouse);
}

// The order matters: no press may be grabbed without its release, and nothing the desktop has already
// seen may be emitted a second time.
void Daemon::try_take(const std::string& node, Mouse& mouse) {
  EvdevDevice& device = *mouse.device;
  if (device.any_key_held()) {
    if (!mouse.told_waiting) log_.info("{} {}: a button is held; taking it once released", node, quoted_name(device));
    mouse.told_waiting = true;
    update_retry_timer();
    return;
  }
  try {
    mouse.sink = std::make_unique<UinputSink>(output_device(device.description(), pipeline_->config()));
    // What was queued before the grab went to the desktop as well: read it and let it go. (Motion reported while the
    // grab itself is under way, which waits for the kernel, may reach both: the kernel does not say to which of its
    // readers it gave an event. A press there is seen held by the check after the grab, which lets go again.)
    if (device.read_available([](const InputEvent&) {}) == ReadStatus::gone) {
      let_go(node, "unplugged");
      return;
    }
    device.grab();
    device.set_blocking(true);  // its reader waits in read()
  } catch (const DeviceError& e) {
    if (e.error() == EBUSY) {
      // Here, not on the retiring thread: a mouse held elsewhere has no virtual device once that is said (status,
      // and the VM case "[6] a mouse another program holds" looks for none), at the cost of destroying it under
      // the lock.
      mouse.sink.reset();
      log_.warning("{}; taking it once that program lets go", e.what());
      wait_for_release_elsewhere(node, mouse);
      return;
    }
    log_.warning("{}; leaving it to the desktop", e.what());
    passed_over_.insert(node);
    let_go(node, "");
    return;
  } catch (const UinputError& e) {
    log_.error("{} {}: {}", node, quoted_name(device), e.what());
    passed_over_.insert(node);
    let_go(node, "");
    return;
  }
  if (device.any_key_held()) {  // pressed between the check and the grab: the desktop has the press
    device.ungrab();
    mouse.sink.reset();  // as above: a mouse not taken has no virtual device
    update_retry_timer();
    return;
  }
  mouse.frames = std::make_unique<FrameProcessor>(*pipeline_, *mouse.sink);
  if (passthrough_wanted_) make_passthrough_sink(node, mouse);
  mouse.reader = std::make_unique<MouseReader>(
      [d = &device](std::vector<InputEvent>& events, Wait wait) { return d->read_batch(events, wait); }, state_,
      [this, node, m = &mouse](const std::vector<InputEvent>& events, ReadStatus status, const std::string& error) {
        on_mouse_batch(node, *m, events, status, error);
      });
  log_.info("took {} {}; emitting through {} \"{}\"", node, quoted_name(device), mouse.sink->devnode(),
            output_device(device.description(), pipeline_->config()).name);
  notifier_.status(status_line());
  update_retry_timer();
}

// While another program holds the grab, the kernel gives the mouse's events to that program alone: the
// first event this open file reads again says that the grab has ended (or, with an error, that the mouse
// has gone). Events queued before the other grab are let go first, so they do not count.
void Daemon::wait_for_release_elsewhere(const std::string& node, Mouse& mouse) {
  if (mouse.device->read_available([](const InputEvent&) {}) == ReadStatus::gone) {
    let_go(node, "unplugged");
    return;
  }
  mouse.held_elsewhere = true;
  watch(epoll_.get(), mouse.device->fd());
  update_retry_timer();
  notifier_.status(status_line());
}

bool Daemon::on_released_elsewhere(int fd) {
  const auto it = std::find_if(mice_.begin(), mice_.end(), [fd](const auto& entry) {
    return entry.second->held_elsewhere && entry.second->device->fd() == fd;
  });
  if (it == mice_.end()) return false;
  const std::string node = it->first;  // try_take may let go of the mouse, and its entry with it
  Mouse& mouse = *it->second;
  // Unplugged while the other program held it: the node hangs up (evdev's poll says POLLHUP once the device is
  // gone), which is no release; nothing to take, and no virtual device to make for it.
  if (mouse.device->hung_up()) {
    log_.info("{} {}: unplugged while another program held it", node, quoted_name(*mouse.device));
    let_go(node, "");
    return true;
  }
  ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, fd, nullptr);
  mouse.held_elsewhere = false;
  log_.info("{} {}: the other program let go of it", node, quoted_name(*mouse.device));
  try_take(node, mouse);
  return true;
}

void Daemon::let_go(const std::string& node, std::string_view why) {
  // Frames held for the session helper's answer go out first, in order, before what this mouse's grab kept (which came
  // after them).
  if (holding_) {
    if (const auto m = mice_.find(node); m != mice_.end() && m->second->reader) release_held();
  }
  if (const auto u = untaken_.find(node); u != untaken_.end()) {
    ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, u->second->fd(), nullptr);
    retired_.keep(std::move(u->second));  // not grabbed: closed off the lock
    untaken_.erase(u);
  }
  const auto it = mice_.find(node);
  if (it == mice_.end()) {
    unopened_.erase(node);
    return;
  }
  Mouse& mouse = *it->second;
  const bool held_elsewhere = mouse.held_elsewhere;
  if (held_elsewhere) ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, mouse.device->fd(), nullptr);
  const bool taken = mouse.frames != nullptr;
  if (taken && !why.empty()) log_.info("let go of {} {} ({})", node, quoted_name(*mouse.device), why);
  retire_virtual_devices(mouse);
  mice_.erase(it);  // ungrabs, closes the node
  if (taken || held_elsewhere) notifier_.status(status_line());
  update_retry_timer();
}

// Its reader stopped and what the grab kept emitted, a mouse's virtual devices release what they hold and go to
// `retired_`: one that wrote a button's release lately (its own, or the mouse's: the kernel releases what an unplugged
// mouse held) stays kReleaseGrace for its readers to read it. Here, under the state lock, either wait would stall every
// other mouse's reader (at 8 kHz a mouse's kernel buffer overflows in 50 ms).
void Daemon::retire_virtual_devices(Mouse& mouse) {
  // (What it emits now was stamped earlier, maybe more than kReleaseGrace earlier: the grace is given for it too.)
  const bool emitted_late = mouse.reader && emit_what_the_grab_kept(mouse, mouse.reader->stop());
  mouse.reader.reset();
  mouse.frames.reset();
  const SteadyTime now = std::chrono::steady_clock::now();
  const TimeUs grace_began =
      std::chrono::duration_cast<std::chrono::microseconds>((now - UinputSink::kReleaseGrace).time_since_epoch())
          .count();
  for (std::unique_ptr<UinputSink>* sink : {&mouse.sink, &mouse.passthrough_sink}) {
    if (!*sink) continue;
    const bool released = (*sink)->release_held() || (*sink)->wrote_a_key_since(grace_began) || emitted_late;
    retired_.keep(std::move(*sink), released ? now + UinputSink::kReleaseGrace : now);
  }
  // An unplugged mouse's node too: closing it lets go of the grab, which waits for the kernel. (One still there is
  // let go of here: it may be taken again at once, and a grab not yet let go of would refuse that.)
  if (mouse.device && mouse.device->hung_up()) retired_.keep(std::move(mouse.device));
}

void Daemon::let_go_of_all(std::string_view why) {
  // (Copies: let_go erases the entry whose key it was given, and may look the node up after that.)
  while (!mice_.empty()) let_go(std::string(mice_.begin()->first), why);
  while (!untaken_.empty()) let_go(std::string(untaken_.begin()->first), why);
  unopened_.clear();
  passed_over_.clear();
}

// The per-frame path, on the mouse's reader thread with the state lock held: what one read() gave, the frames
// through the pipeline, one write() each; the time is the kernel's stamp on the events (CLOCK_MONOTONIC,
// steady_clock's), not a clock read.
PH_FRAME_PATH void Daemon::on_mouse_batch(const std::string& node, Mouse& mouse, const std::vector<InputEvent>& events,
                                          ReadStatus status, const std::string& error) {
  if (!mouse.ending.empty()) return;
  try {
    if (!events.empty()) {
      const SteadyTime now{std::chrono::microseconds(events.front().time)};
      // Motion after a pause: whatever happened meanwhile (a warp, another pointer), ask where the cursor is. Not
      // in pass-through, where the model is not used (its frames would only wait for the answer).
      if (now - last_motion_ > kPauseBeforeQuery && !passthrough_wanted_ && control_ && control_->has_helper()) {
        control_->query_helper();
        last_query_ = now;
        if (!holding_) start_holding();
      }
      last_motion_ = now;
      if (holding_) {
        for (const InputEvent& e : events) held_events_.emplace_back(node, e);
      } else {
        for (const InputEvent& e : events) route(mouse, e);
      }
      remember_emitted(now);
    }
    if (status == ReadStatus::gone) {
      if (!error.empty()) log_.warning("{}", error);
      ask_let_go(mouse, error.empty() ? "unplugged" : "read error");
    }
  } catch (const UinputError& e) {
    log_.error("{}", e.what());
    ask_let_go(mouse, "virtual device failed");
  }
}

// A reader cannot let go of its own mouse (that stops and waits for it): the event loop does.
void Daemon::ask_let_go(Mouse& mouse, std::string why) {
  mouse.ending = std::move(why);
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(mice_ended_.get(), &one, sizeof one);
}

void Daemon::on_mice_ended() {
  std::vector<std::pair<std::string, std::string>> ended;  // node, why: let_go changes mice_
  for (const auto& [node, mouse] : mice_) {
    if (!mouse->ending.empty()) ended.emplace_back(node, mouse->ending);
  }
  for (const auto& [node, why] : ended) let_go(node, why);
}

void Daemon::sync_mice() {
  for (const auto& [node, mouse] : mice_) {
    if (mouse->reader) mouse->reader->sync();
  }
}

void Daemon::on_hotplug() {
  const UdevWatch::Received received = udev_.receive_all();
  for (const InputHotplug& hotplug : received.inputs) {
    if (hotplug.action == InputHotplug::Action::add) {
      log_.debug("{} added", hotplug.devnode);
      passed_over_.erase(hotplug.devnode);  // a new device may reuse the node of one passed over
      consider(hotplug.devnode);
    } else {
      log_.debug("{} removed", hotplug.devnode);
      passed_over_.erase(hotplug.devnode);
      let_go(hotplug.devnode, "removed");
    }
  }
  if (received.displays_changed) on_displays_changed();
}

void Daemon::on_signal() {
  signalfd_siginfo info{};
  while (::read(signals_.get(), &info, sizeof info) == static_cast<ssize_t>(sizeof info)) {
    if (info.ssi_signo == SIGHUP) {
      reload();
    } else {
      log_.info("{} received; stopping", info.ssi_signo == SIGTERM ? "SIGTERM" : "SIGINT");
      stop_ = true;
      return;
    }
  }
}

void Daemon::on_retry_tick() {
  std::vector<std::string> nodes;
  for (auto& [node, tries] : unopened_) nodes.push_back(node);
  for (const std::string& node : nodes) {
    if (--unopened_[node] <= 0) {
      log_.warning("{}: still not accessible after {} s; not taken", node,
                   kOpenTries * kRetryIntervalNs / 1'000'000'000);
      unopened_.erase(node);
      continue;
    }
    consider(node);
  }
  std::vector<std::string> waiting;
  for (const auto& [node, mouse] : mice_) {
    if (mouse->frames == nullptr && !mouse->held_elsewhere) waiting.push_back(node);
  }
  for (const std::string& node : waiting) try_take(node, *mice_.at(node));
  update_retry_timer();
}

void Daemon::update_retry_timer() {
  bool needed = !unopened_.empty();
  for (const auto& [node, mouse] : mice_) needed = needed || (mouse->frames == nullptr && !mouse->held_elsewhere);
  if (needed == retry_armed_) return;
  set_timer(retry_timer_.get(), needed ? kRetryIntervalNs : 0);
  retry_armed_ = needed;
}

// A frame goes through the pipeline, or unchanged through the pass-through device; the route changes
// only between frames and while no button is held on the device in use, so no press loses its release.
// Inline into the per-frame path (each call there costs, docs/PERFORMANCE.md, "Against a bare re-emitter").
#if defined(__GNUC__)
[[gnu::always_inline]]
#endif
inline void
Daemon::route(Mouse& mouse, const InputEvent& event) {
  if (!mouse.mid_frame) {  // a frame starts here: the one place the route may change
    if (passthrough_wanted_ && !mouse.passing && mouse.passthrough_sink && !mouse.sink->holds_keys()) {
      mouse.passing = true;
    } else if (!passthrough_wanted_ && mouse.passing && !mouse.passthrough_sink->holds_keys()) {
      mouse.passing = false;
    }
  }
  const bool ends_frame = event.type == ev::kSyn && event.code == ev::kSynReport;
  mouse.mid_frame = !ends_frame;
  if (!mouse.passing) {
    mouse.frames->push(event);
    return;
  }
  mouse.raw_frame.events.push_back(event);
  if (!ends_frame) return;
  mouse.passthrough_sink->write(mouse.raw_frame);
  mouse.raw_frame.events.clear();
}

bool Daemon::make_passthrough_sink(const std::string& node, Mouse& mouse) {
  if (mouse.passthrough_sink) return true;
  PipelineConfig relative = config_.pipeline;
  relative.mode = OutputMode::relative;
  DeviceDescription description = output_device(mouse.device->description(), relative);
  description.name += " (pass-through)";
  try {
    mouse.passthrough_sink = std::make_unique<UinputSink>(description);
  } catch (const UinputError& e) {
    log_.warning("{}: no pass-through device: {}", node, e.what());
    return false;
  }
  log_.info("{} {}: pass-through device {} \"{}\"", node, quoted_name(*mouse.device), mouse.passthrough_sink->devnode(),
            description.name);
  return true;
}

void Daemon::passthrough(bool on) {
  passthrough_asked_ = on;
  set_passthrough(passthrough_with(config_.pipeline.mode));
}

void Daemon::set_passthrough(bool on) {
  if (on == passthrough_wanted_) return;
  passthrough_wanted_ = on;
  log_.info(
      "pass-through {}: {}", on ? "on" : "off",
      on ? "the mice's motion goes unchanged to the application that holds the pointer" : "the textures are back");
  for (auto& [node, mouse] : mice_) {
    if (on && mouse->frames != nullptr) make_passthrough_sink(node, *mouse);
  }
  // The application may have moved the cursor while it held it: ask where it is, and hold the mice's frames until
  // the answer, as after a pause, so that motion that goes on across the switch does not start from the model of
  // before (the cursor would jump back, and the answer, a pixel the daemon had just emitted, be taken for its own).
  // Nothing the daemon emitted before is still on its way through the desktop.
  if (!on && control_ && control_->has_helper()) {
    emitted_.clear();
    control_->query_helper();
    if (!holding_) start_holding();
  }
  notifier_.status(status_line());
}

void Daemon::start_holding() {
  holding_ = true;
  itimerspec once{};
  once.it_value.tv_nsec = kHoldForHelperNs;
  ::timerfd_settime(hold_timer_.get(), 0, &once, nullptr);
}

// The frames read while waiting for the helper, in order, through the mice that are still taken.
void Daemon::release_held() {
  if (!holding_) return;
  holding_ = false;
  set_timer(hold_timer_.get(), 0);
  std::vector<std::pair<std::string, InputEvent>> held;
  held.swap(held_events_);
  for (const auto& [node, event] : held) {
    const auto it = mice_.find(node);
    if (it == mice_.end() || it->second->frames == nullptr) continue;
    try {
      route(*it->second, event);
    } catch (const UinputError& e) {
      log_.error("{}", e.what());
      it->second->ending = "virtual device failed";  // (nothing more is written to it as it is let go of)
      let_go(node, "virtual device failed");
    }
  }
  remember_emitted(std::chrono::steady_clock::now());
}

// A taken mouse let go of while still there (the daemon stopping, the mice taken again after a reload): what its grab
// kept from the desktop and is not emitted yet (the batch its reader held, what the kernel still queues for the grab)
// goes out through its virtual device before that releases the buttons it holds, so that a click made at that moment
// reaches the desktop. Whether anything went out.
bool Daemon::emit_what_the_grab_kept(Mouse& mouse, std::vector<InputEvent> events) {
  if (!mouse.ending.empty() || !mouse.frames || !mouse.device) return false;  // it went away, or its device failed
  std::vector<InputEvent> queued;
  try {
    mouse.device->read_batch(queued, Wait::no);  // (gone: what was read, if anything)
  } catch (const DeviceError& e) {
    log_.debug("{}", e.what());
  }
  events.insert(events.end(), queued.begin(), queued.end());
  if (events.empty()) return false;
  try {
    for (const InputEvent& e : events) route(mouse, e);
  } catch (const UinputError& e) {
    log_.error("{}", e.what());
    return true;  // (some may have gone out)
  }
  remember_emitted(std::chrono::steady_clock::now());
  log_.debug("{} {}: {} events its grab kept emitted as it is let go of", mouse.device->node(),
             quoted_name(*mouse.device), events.size());
  return true;
}

void Daemon::watch_untaken(const std::string& node, std::unique_ptr<EvdevDevice> device) {
  // A repeated udev "add" (coldplug after the start-up listing) replaces the node watched: closed off the lock.
  if (const auto old = untaken_.find(node); old != untaken_.end()) {
    ::epoll_ctl(epoll_.get(), EPOLL_CTL_DEL, old->second->fd(), nullptr);
    retired_.keep(std::move(old->second));
    untaken_.erase(old);
  }
  watch(epoll_.get(), device->fd());
  log_.debug("{} {}: watched without a grab; its motion makes the daemon ask where the cursor is", node,
             quoted_name(*device));
  untaken_[node] = std::move(device);
}

void Daemon::on_untaken_readable(int fd) {
  for (auto& [node, device] : untaken_) {
    if (device->fd() != fd) continue;
    bool moved = false;
    const ReadStatus status = device->read_available([&](const InputEvent& e) {
      moved = moved || ((e.type == ev::kRel && (e.code == ev::kRelX || e.code == ev::kRelY)) ||
                        (e.type == ev::kAbs && (e.code == ev::kAbsX || e.code == ev::kAbsY)));
    });
    if (status == ReadStatus::gone) {
      const std::string gone = node;
      let_go(gone, "unplugged");
      return;
    }
    if (!moved || !control_) return;
    const SteadyTime now = std::chrono::steady_clock::now();
    last_untaken_motion_ = now;
    settle_query_due_ = true;
    if (now - last_query_ >= kQueryAtMostEvery) {
      control_->query_helper();
      last_query_ = now;
    }
    return;
  }
}

void Daemon::on_resync_tick() {
  if (!control_ || !control_->has_helper()) return;
  const SteadyTime now = std::chrono::steady_clock::now();
  const bool settled = settle_query_due_ && now - last_untaken_motion_ >= kSettleAfterOtherPointer;
  if (settled || now - last_query_ >= kQueryEvery) {
    control_->query_helper();
    last_query_ = now;
    if (settled) settle_query_due_ = false;
  }
}

// The pixel the desktop shows the cursor on: floor of the model's position, what absolute output emits.
// Not the traversal's texel: a model stopped on a pixel's left or top edge after moving right or down is
// still in the texel before it, and the helper would report the pixel itself.
// Inline in the frame's path: out of line it sat on a page of its own (core/engine/frame_path.hpp).
[[gnu::always_inline]] inline void Daemon::remember_emitted(SteadyTime now) {
  const Texel pixel = cursor_pixel();
  if (emitted_.empty() || emitted_.back().second != pixel) emitted_.emplace_back(now, pixel);
  while (emitted_.size() > kEmittedAlwaysKept && now - emitted_.front().first > kEmittedMemory) emitted_.pop_front();
}

bool Daemon::emitted_recently(Texel pixel) const {
  return std::any_of(emitted_.begin(), emitted_.end(), [pixel](const auto& e) { return e.second == pixel; });
}

control::Status Daemon::status() const {
  control::Status s;
  s.absolute = config_.pipeline.mode == OutputMode::absolute;
  for (const auto& [node, mouse] : mice_) {
    s.mice += mouse->frames != nullptr;
    s.held_elsewhere += mouse->held_elsewhere;
  }
  s.regions = static_cast<int>(config_.scene->regions().size());
  s.desktop = pipeline_->config().desktop;
  s.cursor = pipeline_->cursor().position;
  s.passthrough = passthrough_wanted_;
  s.scene = config_.embedded ? "default" : config_.source;
  return s;
}

Vec2 Daemon::cursor() const { return pipeline_->cursor().position; }

void Daemon::position(Vec2 position, bool from_helper) {
  const Texel pixel = texel_at(position);
  // The helper reports pixels; one the daemon put the cursor on lately is its own motion still on its way
  // through the desktop, not a move by someone else.
  if (from_helper && (pixel == cursor_pixel() || emitted_recently(pixel))) {
    release_held();
    return;
  }
  const Vec2 was = pipeline_->cursor().position;
  pipeline_->move_cursor_to(position);
  emitted_.clear();
  remember_emitted(std::chrono::steady_clock::now());
  log_.debug("resync: the cursor is at ({:.1f}, {:.1f}) ({}); the model was at ({:.1f}, {:.1f})", position.x,
             position.y, from_helper ? "session helper" : "set by a client", was.x, was.y);
  if (from_helper) release_held();
}

// Kept even while the scene file sets the desktop: a reload to desktop = "auto" then takes it (the helper sends a
// layout only when it changes).
void Daemon::layout(Rect desktop, const std::vector<Rect>& outputs) {
  helper_desktop_ = desktop;
  helper_outputs_ = outputs;
  helper_desktop_kept_up_ = true;
  if (config_.settings.desktop) {
    if (desktop != config_.pipeline.desktop)
      log_.notice("the session helper says the desktop is {}x{}+{}+{}; keeping the scene file's desktop", desktop.w,
                  desktop.h, desktop.x, desktop.y);
    return;
  }
  change_desktop(desktop, outputs, "from the session helper");
}

void Daemon::layout_source_gone() {
  helper_desktop_kept_up_ = false;
  if (helper_desktop_ && !config_.settings.desktop)
    log_.info(
        "the session helper's layout {}x{}+{}+{} stays until the connected displays change (the connection "
        "that gave it has closed)",
        helper_desktop_->w, helper_desktop_->h, helper_desktop_->x, helper_desktop_->y);
}

// desktop = "auto": the connected displays, read again when DRM says they changed. The session helper's layout
// knows the arrangement, which sysfs does not, so it stays while the helper that gave it is connected (and reports
// the change itself) and, once it has gone, until the displays change: after a logout nothing else would tell the
// daemon that a monitor was unplugged, and the cursor would stay bounded by a desktop that is no longer there.
void Daemon::on_displays_changed() {
  if (config_.settings.desktop) return;
  if (helper_desktop_) {
    if (helper_desktop_kept_up_) {
      log_.info("the connected displays changed; the session helper's layout stays (the helper reports it)");
      return;
    }
    helper_desktop_.reset();
    helper_outputs_.clear();
    log_.info(
        "the connected displays changed and the session helper that gave the layout has gone: "
        "following the displays");
  }
  std::string no_display;
  const Rect desktop = resolve_desktop(std::nullopt, choice_.drm_dir, no_display);
  if (!no_display.empty() && desktop != config_.pipeline.desktop) log_.warning("{}", no_display);
  change_desktop(desktop, {}, "the connected displays changed");
}

namespace {

// "; the pointer stays on its outputs 2560x1440+0+0, 1920x1080+2560+0", or "" for none.
std::string outputs_said(const std::vector<Rect>& outputs) {
  std::string said;
  for (const Rect& o : outputs) said += fmt::format("{}{}x{}+{}+{}", said.empty() ? "" : ", ", o.w, o.h, o.x, o.y);
  return said.empty() ? said : "; the pointer stays on its outputs " + said;
}

}  // namespace

void Daemon::change_desktop(Rect desktop, std::vector<Rect> outputs, std::string_view why) {
  outputs = pointer_outputs(desktop, std::move(outputs));
  const bool same_ranges = desktop == config_.pipeline.desktop;
  if (same_ranges && outputs == config_.pipeline.outputs) return;
  log_.info("desktop {}x{}+{}+{} ({}){}", desktop.w, desktop.h, desktop.x, desktop.y, why, outputs_said(outputs));
  // On one monitor, not across a seam or into space no monitor shows.
  const Rect laid_out_on = default_scene_area(desktop, outputs);
  if (config_.embedded && !default_scene_laid_out_for(*config_.scene, laid_out_on)) {
    std::shared_ptr<const Scene> replaced = config_.scene;
    config_.scene = std::make_shared<const Scene>(default_scene(laid_out_on));
    pipeline_->set_scene(config_.scene);
    reloader_.dispose(std::move(replaced));  // freed off the event loop
    log_.info("the embedded default scene laid out again for it: {}", default_scene_places(*config_.scene));
  }
  if (same_ranges) {
    // The same axes' ranges: the virtual devices stay, the model is bounded by the outputs from the next frame on.
    config_.pipeline.outputs = outputs;
    pipeline_->set_desktop(desktop, std::move(outputs));
    return;
  }
  // The scene file could not say this: its desktop is "auto" (config/scene_file.hpp, desktop_warnings).
  for (const std::string& note : off_desktop_notes(*config_.scene, desktop))
    log_.warning("{}: {}", config_.source, note);
  config_.pipeline.desktop = desktop;
  config_.pipeline.outputs = outputs;
  if (config_.pipeline.mode == OutputMode::relative) {
    pipeline_->set_desktop(desktop, std::move(outputs));
  } else {
    restart_devices("the desktop changed");  // absolute ranges are fixed when a device is made
  }
}

void Daemon::helper_changed(bool present) {
  set_timer(resync_timer_.get(), present ? kResyncTickNs : 0);
  if (!present) release_held();
  notifier_.status(status_line());
}

void Daemon::restart_devices(std::string_view why) {
  let_go_of_all(why);
  const Vec2 cursor = pipeline_->cursor().position;  // (after the motion that letting go emits)
  // The old virtual devices go before new ones of the same names come: whoever finds a device by its name (the
  // desktop's configuration, a test) would find either. No mouse's reader runs now: the wait costs no frame.
  retired_.wait_until_empty();
  config_.pipeline.start = cursor;
  start_pipeline();
  take_present_mice();
}

// SIGHUP: the scene is loaded on the reloader's thread while frames go on through the old one
// (docs/SERVICE.md, "Reloads"); on_reload_ended swaps it in.
void Daemon::reload() {
  // What the load reads (daemon/configuration.cpp), which need not be what was loaded last: the default file may
  // have been made or removed since.
  const std::string what =
      choice_.file ? choice_.file->string()
      : choice_.default_scene
          ? std::string("the embedded default scene")
          : fmt::format("{} (the embedded default scene where it does not exist)", choice_.default_file.string());
  if (!reloader_.request()) {
    log_.info("SIGHUP received during a reload; {} will be read again once the load under way ends", what);
    return;
  }
  reload_started_ = std::chrono::steady_clock::now();
  notifier_.reloading();
  log_.info("SIGHUP received; reloading {}", what);
}

void Daemon::on_reload_ended() {
  std::optional<SceneReloader::Outcome> outcome = reloader_.collect();
  if (!outcome) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - reload_started_).count();
  log_.debug("the load ran {}", outcome->idle_priority ? "at idle priority (SCHED_IDLE)"
                                                       : "at the event loop's priority (SCHED_IDLE refused)");
  if (outcome->configuration) {
    apply(std::move(*outcome->configuration));
    log_.info("reloaded: {} ({} regions), loaded in {:.2f} s while the cursor moved on", config_.source,
              config_.scene->regions().size(), seconds);
    reload_failed_ = false;
  } else {
    log_.warning("reload failed: {}; keeping the previous scene", outcome->error);
    reload_failed_ = true;
  }
  if (outcome->another_started) {
    reload_started_ = std::chrono::steady_clock::now();
    log_.info("reloading again: SIGHUP came during the load");
    return;  // still reloading: READY=1 once the newest file is in
  }
  notifier_.ready(status_line());
}

// Between two frames: the loop runs one handler at a time, and a frame's events wait in its assembler
// until SYN_REPORT, so every frame goes through one scene.
void Daemon::apply(Configuration next) {
  // The helper's layout, where it is kept up to date or was in use: one left from a helper that has gone while the
  // scene file set the desktop may be out of date, with no display change seen meanwhile to say so.
  if (helper_desktop_ && !next.settings.desktop && (helper_desktop_kept_up_ || !config_.settings.desktop)) {
    next.pipeline.desktop = *helper_desktop_;
    next.pipeline.outputs = pointer_outputs(next.pipeline.desktop, helper_outputs_);
    std::erase(next.warnings, next.desktop_guessed);  // not guessed: the helper's
  } else if (!next.settings.desktop) {
    helper_desktop_.reset();
    helper_outputs_.clear();
  }
  const Rect laid_out_on = default_scene_area(next.pipeline.desktop, next.pipeline.outputs);
  if (next.embedded && !default_scene_laid_out_for(*next.scene, laid_out_on)) {
    next.scene = std::make_shared<const Scene>(default_scene(laid_out_on));
    next.notes.push_back("the embedded default scene laid out again for the session helper's desktop: " +
                         default_scene_places(*next.scene));
  }
  log_notes(next);
  std::shared_ptr<const Scene> replaced = config_.scene;
  if (only_scene_differs(config_, next)) {
    pipeline_->set_scene(next.scene);
    config_ = std::move(next);
  } else {
    // New [daemon] settings: new virtual devices, and the mice chosen again; the cursor stays put.
    log_.info("the [daemon] settings changed; taking the mice again");
    config_ = std::move(next);
    // Pass-through as asked, with the new output (the mice are taken again below, with its devices where on).
    const bool passing = passthrough_with(config_.pipeline.mode);
    if (passing != passthrough_wanted_)
      log_.info("pass-through {} with {} output", passing ? "on again" : "off", passing ? "absolute" : "relative");
    passthrough_wanted_ = passing;
    restart_devices("settings changed");
  }
  reloader_.dispose(std::move(replaced));  // the last reference: freed off the event loop
}

std::string Daemon::status_line() const {
  std::string names;
  std::size_t taken = 0, held = 0;
  for (const auto& [node, mouse] : mice_) {
    held += mouse->held_elsewhere;
    if (mouse->frames == nullptr) continue;
    names += (taken++ == 0 ? "" : ", ") + mouse->device->name();
  }
  std::string mice = taken == 0 ? std::string("waiting for a mouse") : fmt::format("{} mice: {}", taken, names);
  if (held > 0) mice += fmt::format("; {} held by another program", held);
  const bool helper = control_ && control_->has_helper();
  return fmt::format("{}; scene: {} ({} regions); {} output{}{}", mice, config_.source, config_.scene->regions().size(),
                     config_.pipeline.mode == OutputMode::absolute ? "absolute" : "relative",
                     helper ? "; session helper connected" : "",
                     reload_failed_ ? "; the last reload failed, the scene before it kept (see the log)" : "");
}

void Daemon::log_notes(const Configuration& configuration) const {
  for (const std::string& note : configuration.notes) log_.notice("{}", note);
  for (const std::string& warning : configuration.warnings) log_.warning("{}", warning);
}

}  // namespace ph
