#include "daemon/scene_reloader.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <system_error>
#include <utility>

namespace ph {

SceneReloader::SceneReloader(Load load) : load_(std::move(load)), done_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (!done_) throw std::system_error(errno, std::generic_category(), "cannot make the reload's eventfd");
}

SceneReloader::~SceneReloader() {
  if (worker_.joinable()) worker_.join();
  for (Disposer& d : disposers_) d.thread.join();
}

void SceneReloader::dispose(std::shared_ptr<const Scene> scene) {
  // The threads that have freed their scene are joined (at once); one still freeing is left to it: joining it here
  // would wait, under the daemon's state lock, for a thread at idle priority on a busy CPU (a desktop change soon
  // after another lays the scene out twice).
  std::erase_if(disposers_, [](Disposer& d) {
    if (!d.done->load()) return false;
    d.thread.join();
    return true;
  });
  auto done = std::make_shared<std::atomic<bool>>(false);
  std::thread thread([scene = std::move(scene), done]() mutable {
    const sched_param no_priority{};
    pthread_setschedparam(pthread_self(), SCHED_IDLE, &no_priority);
    scene.reset();
    done->store(true);
  });
  ::pthread_setname_np(thread.native_handle(), "ph-scene-free");
  disposers_.push_back({std::move(thread), std::move(done)});
}

bool SceneReloader::request() {
  if (!queue_.request()) return false;
  start();
  return true;
}

void SceneReloader::start() {
  if (worker_.joinable()) worker_.join();  // the previous load has ended: its thread is done
  worker_ = std::thread([this] {
    // On a machine with one free CPU the load would share it equally with the event loop; at idle
    // priority it gets only what the loop leaves. Lowering a priority needs no privilege, but the
    // unit's system call filter refuses it (~@resources): then it runs at the loop's priority.
    const sched_param no_priority{};
    const bool idle = pthread_setschedparam(pthread_self(), SCHED_IDLE, &no_priority) == 0;
    std::optional<Configuration> result;
    std::string error;
    try {
      result = load_();
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "unknown error";
    }
    {
      const std::lock_guard lock(mutex_);
      result_ = std::move(result);
      error_ = std::move(error);
      ended_ = true;
      idle_ = idle;
    }
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(done_.get(), &one, sizeof one);
  });
  ::pthread_setname_np(worker_.native_handle(), "ph-scene-load");
}

std::optional<SceneReloader::Outcome> SceneReloader::collect() {
  std::uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = ::read(done_.get(), &count, sizeof count);
  Outcome outcome;
  {
    const std::lock_guard lock(mutex_);
    if (!ended_) return std::nullopt;
    ended_ = false;
    outcome.configuration = std::move(result_);
    outcome.error = std::move(error_);
    outcome.idle_priority = idle_;
    result_.reset();
    error_.clear();
  }
  worker_.join();
  outcome.another_started = queue_.finished();
  if (outcome.another_started) start();
  return outcome;
}

}  // namespace ph
