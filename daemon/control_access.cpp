#include "daemon/control_access.hpp"

#include <fmt/format.h>
#include <systemd/sd-login.h>

#include <cstdlib>

namespace ph {

bool LogindSessions::has_active_local_session(uid_t uid) const {
  char** sessions = nullptr;
  const int n = sd_uid_get_sessions(uid, 1, &sessions);  // 1: active sessions only
  bool local = false;
  for (int i = 0; i < n; ++i) {
    if (sd_session_is_remote(sessions[i]) == 0) local = true;
    std::free(sessions[i]);
  }
  std::free(static_cast<void*>(sessions));
  return local;
}

std::optional<std::string> control_refusal(uid_t uid, const SessionDirectory& sessions) {
  if (uid == 0 || sessions.has_active_local_session(uid)) return std::nullopt;
  return fmt::format("uid {} is neither root nor the user of an active local session", uid);
}

}  // namespace ph
