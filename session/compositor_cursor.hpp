// Where the pointer is, asked of the compositors that say it (docs/SERVICE.md, "The session helper"):
// Hyprland through its request socket (`cursorpos`), Wayfire through its IPC socket (the ipc-rules
// plugin's `window-rules/get_cursor_position`). One short connection per question, with a deadline, so
// that a compositor that hangs never stalls the helper for long.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "core/engine/geometry.hpp"
#include "session/desktop.hpp"

namespace ph::session {

class CursorSource {
 public:
  virtual ~CursorSource() = default;
  // Where the pointer is, in the desktop's logical pixels; nullopt when the compositor did not say.
  virtual std::optional<Vec2> position() = 0;
  // The compositor's name, as the helper tells it to the daemon: "hyprland", "wayfire".
  virtual std::string name() const = 0;
  // Where it asks (for messages).
  virtual const std::string& socket() const = 0;
  // A source that is told rather than asks (KWin's script, kwin_cursor.hpp): what the helper's loop waits
  // on for it, and the handling of what arrived there, which never blocks.
  virtual Watch watch() const { return {}; }
  virtual void dispatch() {}
};

inline constexpr std::chrono::milliseconds kCursorQueryTimeout{250};

class HyprlandCursor : public CursorSource {
 public:
  explicit HyprlandCursor(std::string socket, std::chrono::milliseconds timeout = kCursorQueryTimeout)
      : socket_(std::move(socket)), timeout_(timeout) {}
  std::optional<Vec2> position() override;
  std::string name() const override { return "hyprland"; }
  const std::string& socket() const override { return socket_; }

 private:
  std::string socket_;
  std::chrono::milliseconds timeout_;
};

class WayfireCursor : public CursorSource {
 public:
  explicit WayfireCursor(std::string socket, std::chrono::milliseconds timeout = kCursorQueryTimeout)
      : socket_(std::move(socket)), timeout_(timeout) {}
  std::optional<Vec2> position() override;
  std::string name() const override { return "wayfire"; }
  const std::string& socket() const override { return socket_; }

 private:
  std::string socket_;
  std::chrono::milliseconds timeout_;
};

// The compositor's cursor source that this session's environment names: Hyprland where
// HYPRLAND_INSTANCE_SIGNATURE names a socket that exists, Wayfire where WAYFIRE_SOCKET does; nullptr for
// any other compositor (GNOME, KDE, sway, weston...; KWin's source is kwin_cursor.hpp). Where a variable is set but
// names no socket (left in the user manager by a session that has ended, or mistyped), `unmet` (when given) says
// which and where it looked; it is left empty otherwise.
std::unique_ptr<CursorSource> cursor_source_from_environment(std::string* unmet = nullptr);

}  // namespace ph::session
