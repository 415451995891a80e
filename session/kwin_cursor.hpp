// Where the pointer is under KWin (docs/SERVICE.md, "The session helper"). KWin tells only its own scripts
// (`workspace.cursorPos`), and a script cannot return a value to whoever loaded it, so the helper owns a
// name on the session bus, exports a method there, and loads through KWin's scripting D-Bus API a script
// that calls that method once at start and on every `workspace.cursorPosChanged`. The helper keeps the
// latest position and answers the daemon from it. sd-bus (libsystemd) speaks D-Bus.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/engine/geometry.hpp"
#include "session/compositor_cursor.hpp"

namespace ph::session {

// The object, interface and method the script calls, and the plugin name it is loaded under: one name for
// every helper of the user, so that a new helper unloads the script one that did not exit cleanly left.
inline constexpr const char* kKWinCallbackPath = "/org/pseudohaptic/Session";
inline constexpr const char* kKWinCallbackInterface = "org.pseudohaptic.Session";
inline constexpr const char* kKWinCallbackMethod = "Position";
inline constexpr const char* kKWinScriptPlugin = "pseudohaptic-session";

// The script's text: it reports workspace.cursorPos to `bus_name` with callDBus, now and on every
// cursorPosChanged. Plain ECMAScript 5, which KWin 5's and KWin 6's engines both run.
std::string kwin_cursor_script(std::string_view bus_name);

// Whether the environment says this is a KDE Plasma session: KDE_SESSION_VERSION is set, or
// XDG_CURRENT_DESKTOP (a colon-separated list) names KDE.
bool kde_session(std::string_view kde_session_version, std::string_view xdg_current_desktop);

struct KWinOptions {
  std::string bus_address;  // empty: the user's session bus ($DBUS_SESSION_BUS_ADDRESS, else $XDG_RUNTIME_DIR/bus)
  std::string script_dir;   // where the script's file goes; empty: $XDG_RUNTIME_DIR, else the temp directory
  std::chrono::milliseconds call_timeout{2000};  // each call to KWin
  // How long start() waits for the script's first position (it sends one as it starts); zero: not at all.
  std::chrono::milliseconds first_position_timeout{2000};
};

class KWinCursor : public CursorSource {
 public:
  // Connects to the session bus, finds KWin there (org.kde.KWin), owns org.pseudohaptic.Session.p<PID>,
  // writes the script to a private file, loads it and runs it, then waits for its first position. Returns
  // nullptr, with the reason in `why`, where any of that fails: no KWin, an error reply (a KWin that
  // refuses scripts), or a script that sends nothing.
  static std::unique_ptr<KWinCursor> start(const KWinOptions& options, std::string& why);
  ~KWinCursor() override;  // unloads the script and removes its file
  KWinCursor(const KWinCursor&) = delete;
  KWinCursor& operator=(const KWinCursor&) = delete;

  // The latest position the script sent: KWin 6's fractional one as it comes, KWin 5's whole pixels (rounded
  // half up) as the pixel centre that rounds to them, n - 0.5 (docs/SERVICE.md); nullopt before the first,
  // and after KWin left the bus.
  std::optional<Vec2> position() override;
  std::string name() const override { return "kwin"; }
  const std::string& socket() const override { return where_; }  // "the session bus, as NAME"
  Watch watch() const override;
  // Handles what has arrived on the bus: positions, KWin leaving or coming back (which loads the script
  // again).
  void dispatch() override;

  const std::string& bus_name() const;     // the name the script calls
  const std::string& script_path() const;  // the script's file

  struct State;  // the bus, its slots and what KWin sent (kwin_cursor.cpp)

 private:
  explicit KWinCursor(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
  std::string where_;
};

}  // namespace ph::session
