#include "session/wayland_desktop.hpp"

#include <poll.h>
#include <wayland-client.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "session/compositor_answers.hpp"
#include "session/protocol.hpp"
#include "xdg-output-unstable-v1-client-protocol.h"

namespace ph::session {

namespace {

struct DisplayCloser {
  void operator()(wl_display* d) const { wl_display_disconnect(d); }
};
struct RegistryCloser {
  void operator()(wl_registry* r) const { wl_registry_destroy(r); }
};
struct ManagerCloser {
  void operator()(zxdg_output_manager_v1* m) const { zxdg_output_manager_v1_destroy(m); }
};
struct XdgOutputCloser {
  void operator()(zxdg_output_v1* o) const { zxdg_output_v1_destroy(o); }
};
struct OutputCloser {
  void operator()(wl_output* o) const {
    if (wl_output_get_version(o) >= WL_OUTPUT_RELEASE_SINCE_VERSION) {
      wl_output_release(o);
    } else {
      wl_output_destroy(o);
    }
  }
};

// The versions this client speaks: wl_output 4 (name, description), xdg-output 3 (done on wl_output).
constexpr std::uint32_t kOutputVersion = 4;
constexpr std::uint32_t kXdgOutputVersion = 3;

}  // namespace

struct WaylandDesktop::State {
  struct Output {
    State* state = nullptr;
    std::uint32_t global = 0;  // its name in the registry
    std::unique_ptr<wl_output, OutputCloser> output;
    std::unique_ptr<zxdg_output_v1, XdgOutputCloser> xdg;
    WaylandOutput pending, current;  // what the events say, and what their `done` made of it
    bool described = false;          // a `done` has arrived
  };

  std::unique_ptr<wl_display, DisplayCloser> display;
  std::unique_ptr<wl_registry, RegistryCloser> registry;
  std::unique_ptr<zxdg_output_manager_v1, ManagerCloser> manager;
  std::vector<std::unique_ptr<Output>> outputs;
  bool changed = false;

  void add_xdg_output(Output& o) {
    if (!manager || o.xdg) return;
    o.xdg.reset(zxdg_output_manager_v1_get_xdg_output(manager.get(), o.output.get()));
    zxdg_output_v1_add_listener(o.xdg.get(), &kXdgOutputListener, &o);
  }

  static void commit(Output& o) {
    // With xdg-output, an output's first description waits for its logical size: the mode divided by
    // the scale is wrong for fractional scales, and would reach the daemon for a moment.
    if (o.state->manager && !o.pending.logical) return;
    const bool differs = !o.described || logical_rect(o.pending) != logical_rect(o.current);
    o.current = o.pending;
    o.described = true;
    if (differs) o.state->changed = true;
  }

  // wl_output ------------------------------------------------------------------------------------------------
  static void on_geometry(void* data, wl_output*, std::int32_t x, std::int32_t y, std::int32_t, std::int32_t,
                          std::int32_t, const char*, const char*, std::int32_t transform) {
    auto& o = *static_cast<Output*>(data);
    o.pending.x = x;
    o.pending.y = y;
    o.pending.transform = transform;
  }
  static void on_mode(void* data, wl_output* output, std::uint32_t flags, std::int32_t width, std::int32_t height,
                      std::int32_t) {
    auto& o = *static_cast<Output*>(data);
    if ((flags & WL_OUTPUT_MODE_CURRENT) == 0) return;
    o.pending.mode_width = width;
    o.pending.mode_height = height;
    if (wl_output_get_version(output) < WL_OUTPUT_DONE_SINCE_VERSION) commit(o);  // version 1 has no `done`
  }
  static void on_done(void* data, wl_output*) { commit(*static_cast<Output*>(data)); }
  static void on_scale(void* data, wl_output*, std::int32_t factor) {
    static_cast<Output*>(data)->pending.scale = factor;
  }
  static void on_name(void*, wl_output*, const char*) {}
  static void on_description(void*, wl_output*, const char*) {}
  static constexpr wl_output_listener kOutputListener{on_geometry, on_mode, on_done, on_scale, on_name, on_description};

  // zxdg_output_v1 -----------------------------------------------------------------------------------------
  static Rect& logical(Output& o) {
    if (!o.pending.logical) o.pending.logical = Rect{};
    return *o.pending.logical;
  }
  static void on_logical_position(void* data, zxdg_output_v1*, std::int32_t x, std::int32_t y) {
    Rect& r = logical(*static_cast<Output*>(data));
    r.x = x;
    r.y = y;
  }
  static void on_logical_size(void* data, zxdg_output_v1*, std::int32_t width, std::int32_t height) {
    Rect& r = logical(*static_cast<Output*>(data));
    r.w = width;
    r.h = height;
  }
  static void on_xdg_done(void* data, zxdg_output_v1* xdg) {
    // From version 3 on, wl_output's `done` ends a description and this event is not sent.
    if (zxdg_output_v1_get_version(xdg) < 3) commit(*static_cast<Output*>(data));
  }
  static void on_xdg_name(void*, zxdg_output_v1*, const char*) {}
  static void on_xdg_description(void*, zxdg_output_v1*, const char*) {}
  static constexpr zxdg_output_v1_listener kXdgOutputListener{on_logical_position, on_logical_size, on_xdg_done,
                                                              on_xdg_name, on_xdg_description};

  // wl_registry --------------------------------------------------------------------------------------------
  static void on_global(void* data, wl_registry* registry, std::uint32_t name, const char* interface,
                        std::uint32_t version) {
    auto& state = *static_cast<State*>(data);
    if (std::strcmp(interface, wl_output_interface.name) == 0) {
      auto o = std::make_unique<Output>();
      o->state = &state;
      o->global = name;
      o->output.reset(static_cast<wl_output*>(
          wl_registry_bind(registry, name, &wl_output_interface, std::min(version, kOutputVersion))));
      wl_output_add_listener(o->output.get(), &kOutputListener, o.get());
      state.add_xdg_output(*o);
      state.outputs.push_back(std::move(o));
    } else if (std::strcmp(interface, zxdg_output_manager_v1_interface.name) == 0 && !state.manager) {
      state.manager.reset(static_cast<zxdg_output_manager_v1*>(
          wl_registry_bind(registry, name, &zxdg_output_manager_v1_interface, std::min(version, kXdgOutputVersion))));
      for (auto& o : state.outputs) state.add_xdg_output(*o);
    }
  }
  static void on_global_remove(void* data, wl_registry*, std::uint32_t name) {
    auto& state = *static_cast<State*>(data);
    const auto gone = std::remove_if(state.outputs.begin(), state.outputs.end(),
                                     [&](const std::unique_ptr<Output>& o) { return o->global == name; });
    if (gone == state.outputs.end()) return;
    state.outputs.erase(gone, state.outputs.end());
    state.changed = true;
  }
  static constexpr wl_registry_listener kRegistryListener{on_global, on_global_remove};

  std::vector<WaylandOutput> described() const {
    std::vector<WaylandOutput> them;
    for (const auto& o : outputs) {
      if (o->described) them.push_back(o->current);
    }
    return them;
  }
  std::optional<Rect> layout() const { return wayland_layout(described()); }
  std::vector<Rect> output_rects() const {
    const std::optional<Rect> desktop = layout();
    return desktop ? outputs_to_report(*desktop, wayland_output_rects(described())) : std::vector<Rect>{};
  }
};

WaylandDesktop::WaylandDesktop(const std::string& display, std::unique_ptr<CursorSource> cursor)
    : state_(std::make_unique<State>()), cursor_(std::move(cursor)) {
  state_->display.reset(wl_display_connect(display.empty() ? nullptr : display.c_str()));
  if (!state_->display) {
    const int error = errno;
    // libwayland reads $WAYLAND_DISPLAY itself where no name is given: name what it read.
    const char* from_environment = std::getenv("WAYLAND_DISPLAY");
    const std::string name = !display.empty() ? display
                             : from_environment != nullptr && *from_environment != '\0'
                                 ? std::string(from_environment) + " ($WAYLAND_DISPLAY)"
                                 : std::string("wayland-0 (the default: $WAYLAND_DISPLAY is not set)");
    throw WaylandUnreachable("cannot connect to the Wayland display " + name + ": " + std::strerror(error));
  }
  state_->registry.reset(wl_display_get_registry(state_->display.get()));
  wl_registry_add_listener(state_->registry.get(), &State::kRegistryListener, state_.get());
  // The first round trip lists the globals (binding the outputs), the second brings their descriptions.
  if (wl_display_roundtrip(state_->display.get()) < 0 || wl_display_roundtrip(state_->display.get()) < 0) {
    throw WaylandError("the Wayland compositor closed the connection while listing its outputs");
  }
  state_->changed = false;
}

WaylandDesktop::~WaylandDesktop() = default;

std::string WaylandDesktop::backend_name() const { return cursor_ ? "wayland-" + cursor_->name() : "wayland"; }

int WaylandDesktop::fd() const { return wl_display_get_fd(state_->display.get()); }

bool WaylandDesktop::has_xdg_output() const { return state_->manager != nullptr; }

WaylandDesktop::Changes WaylandDesktop::read_events() {
  wl_display* d = state_->display.get();
  pollfd p{wl_display_get_fd(d), POLLIN, 0};
  // Only when something is there to read, so that this never blocks: wl_display_dispatch would wait.
  if (wl_display_dispatch_pending(d) < 0 || (::poll(&p, 1, 0) > 0 && wl_display_dispatch(d) < 0) ||
      (wl_display_flush(d) < 0 && errno != EAGAIN)) {
    const int error = wl_display_get_error(d);
    throw WaylandError(std::string("the Wayland compositor went away") +
                       (error != 0 ? std::string(" (") + std::strerror(error) + ")" : ""));
  }
  if (cursor_) cursor_->dispatch();  // what KWin's script sent
  Changes changes;
  changes.layout = std::exchange(state_->changed, false);
  return changes;
}

std::optional<Rect> WaylandDesktop::layout() const { return state_->layout(); }

std::vector<Rect> WaylandDesktop::outputs() const { return state_->output_rects(); }

std::optional<Vec2> WaylandDesktop::pointer() const { return cursor_ ? cursor_->position() : std::nullopt; }

}  // namespace ph::session
