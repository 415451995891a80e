// pseudohaptic-session's Wayland backend (session/wayland_desktop.cpp) against a stand-in compositor made
// with libwayland-server: it offers wl_output (version 3) and, unless told not to, zxdg_output_manager_v1
// (version 2, as weston 10 does), and adds, changes and removes outputs while the client runs. The real
// compositor check (weston, one fixed output) is tests/vm/wayland_session_check.cpp.
#include <gtest/gtest.h>
#include <poll.h>
#include <wayland-server.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "session/wayland_desktop.hpp"
#include "tests/geometry_printers.hpp"
#include "tests/scratch_dir.hpp"
#include "xdg-output-unstable-v1-server-protocol.h"

namespace ph::session {
namespace {

using namespace std::chrono_literals;

// A compositor with outputs of given logical rectangles and scales, run on its own thread. Changes are
// queued to that thread (libwayland-server is not thread-safe).
class StandInCompositor {
 public:
  StandInCompositor(const std::string& runtime_dir, bool xdg_output) {
    ::setenv("XDG_RUNTIME_DIR", runtime_dir.c_str(), 1);
    display_ = wl_display_create();
    const char* socket = wl_display_add_socket_auto(display_);
    if (socket == nullptr) throw std::runtime_error("wl_display_add_socket_auto failed");
    socket_ = socket;
    if (xdg_output) wl_global_create(display_, &zxdg_output_manager_v1_interface, 2, this, bind_manager);
    thread_ = std::thread([this] {
      wl_event_loop* loop = wl_display_get_event_loop(display_);
      while (!stop_) {
        wl_event_loop_dispatch(loop, 10);
        run_queued();
        wl_display_flush_clients(display_);
      }
    });
  }
  ~StandInCompositor() {
    stop_ = true;
    thread_.join();
    wl_display_destroy_clients(display_);
    wl_display_destroy(display_);
  }
  StandInCompositor(const StandInCompositor&) = delete;
  StandInCompositor& operator=(const StandInCompositor&) = delete;

  const std::string& socket() const { return socket_; }

  // Adds an output showing `logical` at `scale`, its mode `mode_scale` times the logical size (a fractional
  // scale where that differs from `scale`, which wl_output rounds up); returns its index for change() and
  // remove().
  int add(Rect logical, int scale = 1, double mode_scale = 0) {
    const int index = next_index_++;
    queue([this, index, logical, scale, mode_scale] {
      auto o = std::make_unique<Output>();
      o->compositor = this;
      o->logical = logical;
      o->scale = scale;
      o->mode_scale = mode_scale > 0 ? mode_scale : scale;
      o->global = wl_global_create(display_, &wl_output_interface, 3, o.get(), bind_output);
      outputs_.resize(std::max<std::size_t>(outputs_.size(), static_cast<std::size_t>(index) + 1));
      outputs_[static_cast<std::size_t>(index)] = std::move(o);
    });
    return index;
  }
  // Moves or resizes output `index`: new events and `done` to every client that bound it.
  void change(int index, Rect logical) {
    queue([this, index, logical] {
      Output& o = *outputs_.at(static_cast<std::size_t>(index));
      o.logical = logical;
      for (wl_resource* r : o.resources) describe(o, r);
      for (wl_resource* x : o.xdg_resources) describe_xdg(o, x);
    });
  }
  // Removes output `index` (wl_registry.global_remove to every client).
  void remove(int index) {
    queue([this, index] {
      Output& o = *outputs_.at(static_cast<std::size_t>(index));
      wl_global_destroy(o.global);
      o.global = nullptr;
    });
  }

 private:
  struct Output {
    StandInCompositor* compositor = nullptr;
    Rect logical;
    int scale = 1;
    double mode_scale = 1;
    wl_global* global = nullptr;
    std::vector<wl_resource*> resources, xdg_resources;
  };

  void queue(std::function<void()> task) {
    std::lock_guard lock(mutex_);
    tasks_.push_back(std::move(task));
  }
  void run_queued() {
    std::vector<std::function<void()>> tasks;
    {
      std::lock_guard lock(mutex_);
      tasks.swap(tasks_);
    }
    for (auto& t : tasks) t();
  }

  static void describe(const Output& o, wl_resource* r) {
    wl_output_send_geometry(r, o.logical.x, o.logical.y, 600, 340, WL_OUTPUT_SUBPIXEL_UNKNOWN, "ph", "stand-in",
                            WL_OUTPUT_TRANSFORM_NORMAL);
    wl_output_send_mode(r, WL_OUTPUT_MODE_CURRENT, static_cast<std::int32_t>(o.logical.w * o.mode_scale),
                        static_cast<std::int32_t>(o.logical.h * o.mode_scale), 60000);
    if (wl_resource_get_version(r) >= WL_OUTPUT_SCALE_SINCE_VERSION) wl_output_send_scale(r, o.scale);
    if (wl_resource_get_version(r) >= WL_OUTPUT_DONE_SINCE_VERSION) wl_output_send_done(r);
  }
  static void describe_xdg(const Output& o, wl_resource* x) {
    zxdg_output_v1_send_logical_position(x, o.logical.x, o.logical.y);
    zxdg_output_v1_send_logical_size(x, o.logical.w, o.logical.h);
    zxdg_output_v1_send_done(x);  // version 2: done ends xdg-output's part
  }

  static void forget(std::vector<wl_resource*>& list, wl_resource* r) { std::erase(list, r); }

  static void output_release(wl_client*, wl_resource* r) { wl_resource_destroy(r); }
  static constexpr struct wl_output_interface kOutputImpl { output_release };
  static void output_destroyed(wl_resource* r) {
    if (auto* o = static_cast<Output*>(wl_resource_get_user_data(r))) forget(o->resources, r);
  }
  static void bind_output(wl_client* client, void* data, std::uint32_t version, std::uint32_t id) {
    auto& o = *static_cast<Output*>(data);
    wl_resource* r = wl_resource_create(client, &wl_output_interface, static_cast<int>(version), id);
    wl_resource_set_implementation(r, &kOutputImpl, &o, output_destroyed);
    o.resources.push_back(r);
    describe(o, r);
  }

  static void xdg_output_destroy(wl_client*, wl_resource* r) { wl_resource_destroy(r); }
  static constexpr struct zxdg_output_v1_interface kXdgOutputImpl { xdg_output_destroy };
  static void xdg_output_destroyed(wl_resource* r) {
    if (auto* o = static_cast<Output*>(wl_resource_get_user_data(r))) forget(o->xdg_resources, r);
  }
  static void manager_destroy(wl_client*, wl_resource* r) { wl_resource_destroy(r); }
  static void get_xdg_output(wl_client* client, wl_resource* manager, std::uint32_t id, wl_resource* output) {
    auto* o = static_cast<Output*>(wl_resource_get_user_data(output));
    wl_resource* x = wl_resource_create(client, &zxdg_output_v1_interface, wl_resource_get_version(manager), id);
    wl_resource_set_implementation(x, &kXdgOutputImpl, o, xdg_output_destroyed);
    o->xdg_resources.push_back(x);
    describe_xdg(*o, x);
  }
  static constexpr struct zxdg_output_manager_v1_interface kManagerImpl { manager_destroy, get_xdg_output };
  static void bind_manager(wl_client* client, void*, std::uint32_t version, std::uint32_t id) {
    wl_resource* r = wl_resource_create(client, &zxdg_output_manager_v1_interface, static_cast<int>(version), id);
    wl_resource_set_implementation(r, &kManagerImpl, nullptr, nullptr);
  }

  wl_display* display_ = nullptr;
  std::string socket_;
  std::vector<std::unique_ptr<Output>> outputs_;  // by index; only the compositor's thread touches them
  int next_index_ = 0;
  std::mutex mutex_;
  std::vector<std::function<void()>> tasks_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Reads the desktop's events until they say the layout changed; false after 5 s without.
bool wait_for_layout_change(WaylandDesktop& desktop) {
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (desktop.read_events().layout) return true;
    pollfd p{desktop.fd(), POLLIN, 0};
    ::poll(&p, 1, 100);
  }
  return false;
}

// Waits until the compositor's queued changes have reached the client and were read.
void settle(WaylandDesktop& desktop) {
  for (int i = 0; i < 5; ++i) {
    std::this_thread::sleep_for(30ms);
    desktop.read_events();
  }
}

TEST(WaylandDesktop, FollowsOutputsThatComeChangeAndGo) {
  ScratchDir runtime("wl-runtime");
  StandInCompositor compositor(runtime.path().string(), true);
  const int left = compositor.add({0, 0, 1920, 1080});
  // 3200x1800 at a scale of 2.5 (wl_output says 3): only xdg-output gives 1280x720, not 1066x600.
  const int right = compositor.add({1920, 0, 1280, 720}, 3, 2.5);
  std::this_thread::sleep_for(50ms);  // both are globals before the client comes
  WaylandDesktop desktop(compositor.socket(), nullptr);
  EXPECT_TRUE(desktop.has_xdg_output());
  EXPECT_EQ(desktop.backend_name(), "wayland");
  EXPECT_FALSE(desktop.knows_pointer());
  EXPECT_EQ(desktop.pointer(), std::nullopt);
  EXPECT_EQ(desktop.layout(), (Rect{0, 0, 3200, 1080}));
  EXPECT_FALSE(desktop.read_events().layout);  // nothing new since it connected

  // Of different heights: the space below the smaller one is no output's.
  EXPECT_EQ(desktop.outputs(), (std::vector<Rect>{{0, 0, 1920, 1080}, {1920, 0, 1280, 720}}));

  const int above = compositor.add({0, -900, 1600, 900});  // plugged in
  ASSERT_TRUE(wait_for_layout_change(desktop));
  EXPECT_EQ(desktop.layout(), (Rect{0, -900, 3200, 1980}));

  compositor.change(right, {-1280, 100, 1280, 720});  // moved to the left
  ASSERT_TRUE(wait_for_layout_change(desktop));
  EXPECT_EQ(desktop.layout(), (Rect{-1280, -900, 3200, 1980}));

  compositor.change(right, {-1280, 100, 1280, 720});  // the same again: no change to report
  settle(desktop);
  EXPECT_FALSE(desktop.read_events().layout);

  // Plugged in at a fractional scale: the first layout reported is already the logical one.
  const int far = compositor.add({3200, 0, 1280, 720}, 3, 2.5);
  ASSERT_TRUE(wait_for_layout_change(desktop));
  EXPECT_EQ(desktop.layout(), (Rect{-1280, -900, 5760, 1980}));
  compositor.remove(far);
  ASSERT_TRUE(wait_for_layout_change(desktop));
  EXPECT_EQ(desktop.layout(), (Rect{-1280, -900, 3200, 1980}));

  compositor.remove(above);
  ASSERT_TRUE(wait_for_layout_change(desktop));
  EXPECT_EQ(desktop.layout(), (Rect{-1280, 0, 3200, 1080}));
  compositor.remove(left);
  compositor.remove(right);
  ASSERT_TRUE(wait_for_layout_change(desktop));
  settle(desktop);
  EXPECT_EQ(desktop.layout(), std::nullopt);  // no output: nothing to tell the daemon
}

TEST(WaylandDesktop, WithoutXdgOutputUsesTheModeDividedByTheScale) {
  ScratchDir runtime("wl-runtime");
  StandInCompositor compositor(runtime.path().string(), false);
  compositor.add({0, 0, 1920, 1080}, 2);  // 3840x2160 at scale 2
  std::this_thread::sleep_for(50ms);
  WaylandDesktop desktop(compositor.socket(), nullptr);
  EXPECT_FALSE(desktop.has_xdg_output());
  EXPECT_EQ(desktop.layout(), (Rect{0, 0, 1920, 1080}));
}

TEST(WaylandDesktop, SaysWhenTheCompositorHasGone) {
  ScratchDir runtime("wl-runtime");
  std::string socket;
  std::unique_ptr<WaylandDesktop> desktop;
  {
    StandInCompositor compositor(runtime.path().string(), true);
    compositor.add({0, 0, 800, 600});
    std::this_thread::sleep_for(50ms);
    socket = compositor.socket();
    desktop = std::make_unique<WaylandDesktop>(socket, nullptr);
    EXPECT_EQ(desktop->layout(), (Rect{0, 0, 800, 600}));
  }
  pollfd p{desktop->fd(), POLLIN, 0};
  ::poll(&p, 1, 2000);
  EXPECT_THROW(desktop->read_events(), WaylandError);
  EXPECT_THROW(WaylandDesktop(socket, nullptr), WaylandError);  // nothing listens there any more
}

}  // namespace
}  // namespace ph::session
