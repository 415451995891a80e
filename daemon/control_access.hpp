// Who may use the control socket: root, and the user of an active local session as logind sees it
// (docs/SERVICE.md, "The control socket"). The policy is a pure function of the peer's uid and a view of
// the sessions, so it is tested without logind.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>

namespace ph {

class SessionDirectory {
 public:
  virtual ~SessionDirectory() = default;
  virtual bool has_active_local_session(uid_t uid) const = 0;
};

// logind through libsystemd's sd-login (reads /run/systemd; works inside the service's sandbox).
class LogindSessions final : public SessionDirectory {
 public:
  bool has_active_local_session(uid_t uid) const override;
};

// nullopt when the peer may talk to the daemon; else why not, for the refusal and the log.
std::optional<std::string> control_refusal(uid_t uid, const SessionDirectory& sessions);

}  // namespace ph
