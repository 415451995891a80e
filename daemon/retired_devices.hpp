// The devices the daemon is done with, destroyed on a thread of their own: the virtual devices of the mice it lets go
// of, the nodes of those unplugged and of the input devices it does not keep open. Destroying a uinput device, or
// closing an evdev node, waits for the kernel (an RCU grace period: milliseconds, tens under emulation), and a virtual
// device that has just written the release of a button must stay a moment longer, because the kernel discards what
// its readers (the compositor) have not read once it is removed. Neither may happen under the state lock that the
// other mice's readers wait for (docs/DESIGN.md, "Grab only when nothing is held").
#pragma once

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace ph {

class RetiredDevices {
 public:
  using Time = std::chrono::steady_clock::time_point;

  RetiredDevices() : thread_([this] { run(); }) {
    ::pthread_setname_np(thread_.native_handle(), "ph-device-free");  // for ps -L, top -H and /proc
  }
  // Returns once every device kept has been destroyed, each at its time: the daemon stopping must not cut a release
  // short.
  ~RetiredDevices() {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    changed_.notify_one();
    thread_.join();
  }
  RetiredDevices(const RetiredDevices&) = delete;
  RetiredDevices& operator=(const RetiredDevices&) = delete;

  // Returns once every device handed over has been destroyed.
  void wait_until_empty() {
    std::unique_lock lock(mutex_);
    emptied_.wait(lock, [this] { return kept_.empty() && !destroying_; });
  }

  // Hands the device over (any type: the last owner's deleter travels with it), to be destroyed at `until` (at once
  // if that has passed, or is left out). Does not wait.
  void keep(std::shared_ptr<void> device, Time until = {}) {
    if (!device) return;
    {
      const std::lock_guard lock(mutex_);
      kept_.emplace_back(until, std::move(device));
    }
    changed_.notify_one();
  }

 private:
  void run() {
    std::unique_lock lock(mutex_);
    for (;;) {
      if (kept_.empty()) {
        if (stopping_) return;
        changed_.wait(lock);
        continue;
      }
      const auto next =
          std::min_element(kept_.begin(), kept_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      if (const Time due = next->first; std::chrono::steady_clock::now() < due) {
        // (A copy: wait_until reads the time again after it wakes, and keep() may have moved the vector meanwhile.)
        changed_.wait_until(lock, due);  // or until another device comes, due sooner
        continue;
      }
      std::shared_ptr<void> device = std::move(next->second);
      kept_.erase(next);
      destroying_ = true;
      lock.unlock();
      device.reset();
      lock.lock();
      destroying_ = false;
      if (kept_.empty()) emptied_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable changed_;  // a device handed over, or the destructor called
  std::condition_variable emptied_;  // nothing left to destroy
  std::vector<std::pair<Time, std::shared_ptr<void>>> kept_;
  bool destroying_ = false;  // a device taken off `kept_` is being destroyed
  bool stopping_ = false;
  std::thread thread_;  // last: starts once the members above are ready
};

}  // namespace ph
