// Loads the configuration for a reload on a worker thread, so that the event loop keeps moving the
// cursor through the old scene while the new one is read, decoded and precomputed (seconds for a full-HD
// region with materials). When a load ends the worker writes to an eventfd that the event loop watches;
// the loop then collects the result and swaps it in between two frames. Requests during a load coalesce
// (ReloadQueue). docs/SERVICE.md, "Reloads".
#pragma once

#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/unique_fd.hpp"
#include "daemon/configuration.hpp"
#include "daemon/reload_queue.hpp"

namespace ph {

class SceneReloader {
 public:
  using Load = std::function<Configuration()>;

  // `load` runs on the worker thread: it must touch nothing the event loop uses. Throws std::system_error
  // when the eventfd cannot be made.
  explicit SceneReloader(Load load);
  ~SceneReloader();  // waits for a load under way
  SceneReloader(const SceneReloader&) = delete;
  SceneReloader& operator=(const SceneReloader&) = delete;

  // Readable when a load has ended; then call collect().
  int fd() const { return done_.get(); }
  bool loading() const { return queue_.loading(); }

  // Asks for a reload. True when a load started now; false when one is under way (another load, of
  // whatever the file says then, follows it).
  bool request();

  struct Outcome {
    std::optional<Configuration> configuration;  // nullopt: the load failed
    std::string error;                           // why, when it failed
    bool another_started = false;                // a request came during the load: a new load runs now
    bool idle_priority = false;                  // the load ran at idle priority (SCHED_IDLE)
  };
  // The ended load's outcome (nullopt when none has ended: a spurious wakeup). Starts the load asked for
  // meanwhile, if any.
  std::optional<Outcome> collect();

  // Drops `scene` on a thread of its own: the last reference to a replaced scene frees its fields and
  // effects (tens of MB for full HD), which is not the event loop's business.
  void dispose(std::shared_ptr<const Scene> scene);

 private:
  void start();

  Load load_;
  UniqueFd done_;
  ReloadQueue queue_;
  std::thread worker_;
  struct Disposer {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done;  // its scene is freed: joining it waits for nothing
  };
  std::vector<Disposer> disposers_;
  std::mutex mutex_;  // guards result_ and error_ between the worker and collect()
  std::optional<Configuration> result_;
  std::string error_;
  bool ended_ = false;
  bool idle_ = false;
};

}  // namespace ph
