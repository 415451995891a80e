#include "session/kwin_cursor.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <systemd/sd-bus.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <vector>

#include "common/unique_fd.hpp"

namespace ph::session {

namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kKWinService = "org.kde.KWin";
constexpr const char* kScriptingPath = "/Scripting";
constexpr const char* kScriptingInterface = "org.kde.kwin.Scripting";
constexpr const char* kScriptInterface = "org.kde.kwin.Script";

struct BusCloser {
  void operator()(sd_bus* bus) const { sd_bus_flush_close_unref(bus); }
};
struct SlotCloser {
  void operator()(sd_bus_slot* slot) const { sd_bus_slot_unref(slot); }
};
struct MessageCloser {
  void operator()(sd_bus_message* message) const { sd_bus_message_unref(message); }
};
using BusPtr = std::unique_ptr<sd_bus, BusCloser>;
using SlotPtr = std::unique_ptr<sd_bus_slot, SlotCloser>;
using MessagePtr = std::unique_ptr<sd_bus_message, MessageCloser>;

// An sd_bus_error that frees itself.
class BusError {
 public:
  BusError() = default;
  ~BusError() { sd_bus_error_free(&error_); }
  BusError(const BusError&) = delete;
  BusError& operator=(const BusError&) = delete;
  sd_bus_error* get() { return &error_; }
  bool has_name(const char* name) const { return sd_bus_error_has_name(&error_, name) != 0; }
  // "NAME: MESSAGE" for an error reply, else the errno's text.
  std::string describe(int r) const {
    if (sd_bus_error_is_set(&error_) != 0) {
      return fmt::format("{}: {}", error_.name, error_.message != nullptr ? error_.message : "");
    }
    return std::strerror(-r);
  }

 private:
  sd_bus_error error_{};  // SD_BUS_ERROR_NULL, whose compound literal is C only
};

std::uint64_t monotonic_usec() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000U + static_cast<std::uint64_t>(ts.tv_nsec) / 1000U;
}

// One argument of any D-Bus integer or floating type, as a double: KWin's engine hands callDBus a JS
// number, which reaches the bus as an int32 when it is whole and a double otherwise.
std::optional<double> read_number(sd_bus_message* m, char type) {
  const auto read = [&](auto value) -> std::optional<double> {
    if (sd_bus_message_read_basic(m, type, &value) < 0) return std::nullopt;
    return static_cast<double>(value);
  };
  switch (type) {
    case 'y':
      return read(std::uint8_t{});
    case 'n':
      return read(std::int16_t{});
    case 'q':
      return read(std::uint16_t{});
    case 'i':
      return read(std::int32_t{});
    case 'u':
      return read(std::uint32_t{});
    case 'x':
      return read(std::int64_t{});
    case 't':
      return read(std::uint64_t{});
    case 'd':
      return read(double{});
    default:
      return std::nullopt;
  }
}

std::optional<Vec2> read_point(sd_bus_message* m) {
  const char* signature = sd_bus_message_get_signature(m, 1);
  if (signature == nullptr || std::strlen(signature) != 2) return std::nullopt;
  const std::optional<double> x = read_number(m, signature[0]);
  const std::optional<double> y = x ? read_number(m, signature[1]) : std::nullopt;
  if (!x || !y || !std::isfinite(*x) || !std::isfinite(*y)) return std::nullopt;
  return Vec2{*x, *y};
}

// KWin 5 rounds its position half up to whole pixels (QPointF::toPoint). An absolute device, the daemon's
// included, puts the pointer on pixel centres, p + 0.5, which KWin 5 names p + 1: the pixel centre that
// rounds to n, n - 0.5, is on the pixel the pointer is on for every such position. Taken as it comes, the
// daemon would see p + 1, a pixel it did not emit, and move its model there at every resync.
double kwin5_coordinate(double n) { return n == std::floor(n) ? n - 0.5 : n; }

Vec2 kwin5_report(Vec2 at) { return {kwin5_coordinate(at.x), kwin5_coordinate(at.y)}; }

std::string script_directory(const KWinOptions& options) {
  if (!options.script_dir.empty()) return options.script_dir;
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  if (runtime != nullptr && *runtime != '\0') return runtime;
  return std::filesystem::temp_directory_path().string();
}

// Writes the script to a new file only this user can read (mkstemps makes it 0600); its path, or empty.
std::string write_script(const std::string& directory, const std::string& text, std::string& why) {
  std::string path = directory + "/pseudohaptic-kwin-XXXXXX.js";
  const UniqueFd fd(::mkstemps(path.data(), 3));
  if (!fd) {
    why = fmt::format("cannot write the KWin script in {}: {}", directory, std::strerror(errno));
    return "";
  }
  std::string_view rest = text;
  while (!rest.empty()) {
    const ssize_t n = ::write(fd.get(), rest.data(), rest.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      why = fmt::format("cannot write the KWin script {}: {}", path, std::strerror(errno));
      ::unlink(path.c_str());
      return "";
    }
    rest.remove_prefix(static_cast<std::size_t>(n));
  }
  return path;
}

}  // namespace

std::string kwin_cursor_script(std::string_view bus_name) {
  return fmt::format(
      "// Loaded by pseudohaptic-session (docs/SERVICE.md): tells it where the pointer is, now and whenever it\n"
      "// moves. Unloaded when the helper exits.\n"
      "function pseudohapticReport() {{\n"
      "    var at = workspace.cursorPos;\n"
      "    callDBus(\"{}\", \"{}\", \"{}\", \"{}\", at.x, at.y);\n"
      "}}\n"
      "workspace.cursorPosChanged.connect(pseudohapticReport);\n"
      "pseudohapticReport();\n",
      bus_name, kKWinCallbackPath, kKWinCallbackInterface, kKWinCallbackMethod);
}

bool kde_session(std::string_view kde_session_version, std::string_view xdg_current_desktop) {
  if (!kde_session_version.empty()) return true;
  while (!xdg_current_desktop.empty()) {
    const std::size_t colon = xdg_current_desktop.find(':');
    const std::string_view entry = xdg_current_desktop.substr(0, colon);
    if (entry.size() == 3 && std::toupper(static_cast<unsigned char>(entry[0])) == 'K' &&
        std::toupper(static_cast<unsigned char>(entry[1])) == 'D' &&
        std::toupper(static_cast<unsigned char>(entry[2])) == 'E') {
      return true;
    }
    if (colon == std::string_view::npos) break;
    xdg_current_desktop.remove_prefix(colon + 1);
  }
  return false;
}

struct KWinCursor::State {
  BusPtr bus;
  // After the bus, so that they go before it.
  SlotPtr callback_object, owner_match;
  std::string bus_name;
  std::string kwin_owner;   // KWin's unique name on the bus: positions from anyone else are refused
  std::string script_path;  // empty while none is written
  bool script_loaded = false;
  bool reload = false;  // KWin came back to the bus: load the script again
  bool broken = false;  // the bus connection failed
  // KWin 5 (its script at /<id>): cursorPos is a QPoint, rounded half up from KWin's position (see
  // kwin5_report()).
  bool rounded = false;
  std::optional<Vec2> position;

  ~State() {
    if (script_loaded && !broken) unload();
    if (!script_path.empty()) ::unlink(script_path.c_str());
  }

  void unload() {
    BusError error;
    sd_bus_call_method(bus.get(), kKWinService, kScriptingPath, kScriptingInterface, "unloadScript", error.get(),
                       nullptr, "s", kKWinScriptPlugin);
    script_loaded = false;
  }

  // Loads the script (after unloading any a helper left behind) and runs it.
  bool load_and_run(std::string& why) {
    unload();
    BusError error;
    sd_bus_message* raw = nullptr;
    int r = sd_bus_call_method(bus.get(), kKWinService, kScriptingPath, kScriptingInterface, "loadScript", error.get(),
                               &raw, "ss", script_path.c_str(), kKWinScriptPlugin);
    const MessagePtr reply(raw);
    if (r < 0) {
      why = fmt::format("KWin did not load the script ({})", error.describe(r));
      return false;
    }
    std::int32_t id = -1;
    if (sd_bus_message_read(reply.get(), "i", &id) < 0 || id < 0) {
      why = fmt::format("KWin did not load the script (loadScript answered {})", id);
      return false;
    }
    script_loaded = true;
    return run(id, why);
  }

  // KWin 6 puts a loaded script's object at /Scripting/Script<id>, KWin 5 at /<id>; where neither is,
  // /Scripting's start() runs every script loaded and not yet running.
  bool run(std::int32_t id, std::string& why) {
    for (const auto& [path, kwin5] :
         {std::pair{fmt::format("/Scripting/Script{}", id), false}, std::pair{fmt::format("/{}", id), true}}) {
      BusError error;
      const int r =
          sd_bus_call_method(bus.get(), kKWinService, path.c_str(), kScriptInterface, "run", error.get(), nullptr, "");
      if (r >= 0) {
        rounded = kwin5;
        return true;
      }
      if (!error.has_name(SD_BUS_ERROR_UNKNOWN_OBJECT) && !error.has_name(SD_BUS_ERROR_UNKNOWN_METHOD) &&
          !error.has_name(SD_BUS_ERROR_UNKNOWN_INTERFACE)) {
        why = fmt::format("KWin did not run the script ({})", error.describe(r));
        return false;
      }
    }
    BusError error;
    rounded = true;  // only KWin 5 lacks a script object to run
    const int r = sd_bus_call_method(bus.get(), kKWinService, kScriptingPath, kScriptingInterface, "start", error.get(),
                                     nullptr, "");
    if (r < 0) why = fmt::format("KWin did not run the script ({})", error.describe(r));
    return r >= 0;
  }

  // Handles everything that has arrived; false when the connection failed.
  bool process() {
    for (;;) {
      const int r = sd_bus_process(bus.get(), nullptr);
      if (r < 0) {
        broken = true;
        position.reset();
        return false;
      }
      if (r == 0) return true;
    }
  }

  // The script's call: two numbers, from KWin only.
  static int on_call(sd_bus_message* m, void* data, sd_bus_error*) {
    auto& state = *static_cast<State*>(data);
    if (sd_bus_message_is_method_call(m, kKWinCallbackInterface, kKWinCallbackMethod) <= 0) return 0;
    const char* sender = sd_bus_message_get_sender(m);
    if (sender == nullptr || state.kwin_owner != sender) {
      return sd_bus_reply_method_errorf(m, SD_BUS_ERROR_ACCESS_DENIED, "only KWin's script reports the pointer here");
    }
    const std::optional<Vec2> at = read_point(m);
    if (!at) return sd_bus_reply_method_errorf(m, SD_BUS_ERROR_INVALID_ARGS, "expected two numbers: x, y");
    state.position = state.rounded ? kwin5_report(*at) : *at;
    return sd_bus_reply_method_return(m, nullptr);  // KWin's call waits for a reply
  }

  // org.kde.KWin changed hands: a KWin that left took the script with it; one that came gets it again.
  static int on_owner_changed(sd_bus_message* m, void* data, sd_bus_error*) {
    auto& state = *static_cast<State*>(data);
    const char *name = nullptr, *old_owner = nullptr, *new_owner = nullptr;
    if (sd_bus_message_read(m, "sss", &name, &old_owner, &new_owner) < 0 || std::strcmp(name, kKWinService) != 0) {
      return 0;
    }
    state.kwin_owner = new_owner;
    state.position.reset();
    state.script_loaded = false;
    state.reload = !state.kwin_owner.empty();
    return 0;
  }
};

std::unique_ptr<KWinCursor> KWinCursor::start(const KWinOptions& options, std::string& why) {
  auto state = std::make_unique<State>();
  sd_bus* raw = nullptr;
  int r = 0;
  if (options.bus_address.empty()) {
    r = sd_bus_open_user(&raw);
    state->bus.reset(raw);
  } else {
    r = sd_bus_new(&raw);
    state->bus.reset(raw);
    if (r >= 0) r = sd_bus_set_address(raw, options.bus_address.c_str());
    if (r >= 0) r = sd_bus_set_bus_client(raw, 1);
    if (r >= 0) r = sd_bus_start(raw);
  }
  if (r < 0) {
    why = fmt::format("cannot connect to the session bus: {}", std::strerror(-r));
    state->broken = true;
    return nullptr;
  }
  sd_bus* bus = state->bus.get();
  sd_bus_set_method_call_timeout(bus,
                                 static_cast<std::uint64_t>(std::chrono::microseconds(options.call_timeout).count()));

  sd_bus_slot* slot = nullptr;
  r = sd_bus_add_match(bus, &slot,
                       "type='signal',sender='org.freedesktop.DBus',path='/org/freedesktop/DBus',"
                       "interface='org.freedesktop.DBus',member='NameOwnerChanged',arg0='org.kde.KWin'",
                       &State::on_owner_changed, state.get());
  state->owner_match.reset(slot);
  BusError error;
  sd_bus_message* raw_reply = nullptr;
  if (r >= 0) {
    r = sd_bus_call_method(bus, "org.freedesktop.DBus", "/org/freedesktop/DBus", "org.freedesktop.DBus", "GetNameOwner",
                           error.get(), &raw_reply, "s", kKWinService);
  }
  const MessagePtr owner_reply(raw_reply);
  const char* owner = nullptr;
  if (r < 0 || sd_bus_message_read(owner_reply.get(), "s", &owner) < 0) {
    why = fmt::format("KWin ({}) is not on the session bus ({})", kKWinService, error.describe(r));
    return nullptr;
  }
  state->kwin_owner = owner;

  state->bus_name = fmt::format("{}.p{}", kKWinCallbackInterface, ::getpid());
  r = sd_bus_request_name(bus, state->bus_name.c_str(), 0);
  if (r >= 0) r = sd_bus_add_object(bus, &slot, kKWinCallbackPath, &State::on_call, state.get());
  if (r < 0) {
    why = fmt::format("cannot own {} on the session bus: {}", state->bus_name, std::strerror(-r));
    return nullptr;
  }
  state->callback_object.reset(slot);

  state->script_path = write_script(script_directory(options), kwin_cursor_script(state->bus_name), why);
  if (state->script_path.empty() || !state->load_and_run(why)) return nullptr;

  const auto deadline = Clock::now() + options.first_position_timeout;
  while (state->process() && !state->position) {
    const auto left = std::chrono::ceil<std::chrono::microseconds>(deadline - Clock::now()).count();
    if (left <= 0) break;
    sd_bus_wait(bus, static_cast<std::uint64_t>(left));
  }
  if (!state->position && options.first_position_timeout.count() > 0) {
    why = state->broken ? "the session bus went away"
                        : fmt::format("KWin ran the script but it sent no position within {} ms",
                                      options.first_position_timeout.count());
    return nullptr;
  }
  return std::unique_ptr<KWinCursor>(new KWinCursor(std::move(state)));
}

KWinCursor::KWinCursor(std::unique_ptr<State> state)
    : state_(std::move(state)), where_("the session bus, as " + state_->bus_name) {}

KWinCursor::~KWinCursor() = default;

std::optional<Vec2> KWinCursor::position() {
  dispatch();  // the newest position may wait in the socket
  return state_->position;
}

Watch KWinCursor::watch() const {
  if (state_->broken) return {};
  sd_bus* bus = state_->bus.get();
  Watch w;
  w.fd = sd_bus_get_fd(bus);
  const int events = sd_bus_get_events(bus);
  w.events = static_cast<short>(events > 0 ? events : POLLIN);
  std::uint64_t until = 0;
  if (sd_bus_get_timeout(bus, &until) >= 0 && until != UINT64_MAX) {
    const std::uint64_t now = monotonic_usec();
    w.timeout_ms = until <= now ? 0 : static_cast<int>(std::min<std::uint64_t>((until - now + 999) / 1000, 60000));
  }
  return w;
}

void KWinCursor::dispatch() {
  if (state_->broken || !state_->process()) return;
  if (state_->reload) {
    state_->reload = false;
    std::string why;  // a KWin that comes back without scripting leaves the helper without positions
    state_->load_and_run(why);
  }
}

const std::string& KWinCursor::bus_name() const { return state_->bus_name; }

const std::string& KWinCursor::script_path() const { return state_->script_path; }

}  // namespace ph::session
