// The virtual devices a let-go mouse leaves: handed over without a wait, each destroyed on the retiring thread once
// its time is up and not before, and the daemon stopping waits for those still kept.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "daemon/retired_devices.hpp"

namespace ph {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct Destruction {
  int id;
  Clock::time_point at;
  std::thread::id thread;
};

// Stands in for a virtual device: says when, and on which thread, it is destroyed.
class Device {
 public:
  Device(int id, std::mutex& mutex, std::vector<Destruction>& log) : id_(id), mutex_(mutex), log_(log) {}
  ~Device() {
    const std::lock_guard lock(mutex_);
    log_.push_back({id_, Clock::now(), std::this_thread::get_id()});
  }

 private:
  int id_;
  std::mutex& mutex_;
  std::vector<Destruction>& log_;
};

TEST(RetiredDevices, EachIsDestroyedOnTheRetiringThreadOnceItsTimeIsUp) {
  std::mutex mutex;
  std::vector<Destruction> log;
  const Clock::time_point start = Clock::now();
  {
    RetiredDevices retired;
    retired.keep(std::make_unique<Device>(1, mutex, log), start + 60ms);
    retired.keep(std::make_unique<Device>(2, mutex, log), start + 20ms);
    retired.keep(std::make_unique<Device>(3, mutex, log), start);  // due at once
    retired.keep(nullptr, start);                                  // nothing: ignored
  }                                                                // waits for the last
  ASSERT_EQ(log.size(), 3u);
  EXPECT_EQ(log[0].id, 3);
  EXPECT_EQ(log[1].id, 2);
  EXPECT_EQ(log[2].id, 1);
  EXPECT_GE(log[1].at - start, 20ms);
  EXPECT_GE(log[2].at - start, 60ms);
  for (const Destruction& d : log) EXPECT_NE(d.thread, std::this_thread::get_id());
}

// A device due sooner than the one the thread waits for is destroyed at its own time, not after the other's.
TEST(RetiredDevices, OneDueSoonerThanTheOneWaitedForIsNotHeldBack) {
  std::mutex mutex;
  std::vector<Destruction> log;
  const Clock::time_point start = Clock::now();
  RetiredDevices retired;
  retired.keep(std::make_unique<Device>(1, mutex, log), start + 1500ms);
  std::this_thread::sleep_for(10ms);  // the thread now waits for device 1's time
  retired.keep(std::make_unique<Device>(2, mutex, log), start);
  for (;;) {
    {
      const std::lock_guard lock(mutex);
      if (!log.empty()) break;
    }
    ASSERT_LT(Clock::now() - start, 1s) << "device 2 was not destroyed within 1 s";
    std::this_thread::sleep_for(1ms);
  }
  const std::lock_guard lock(mutex);
  EXPECT_EQ(log.front().id, 2);
}

// The daemon remaking its devices waits for the old ones to be gone, a release's wait included.
TEST(RetiredDevices, WaitingUntilEmptyWaitsForTheLastDestruction) {
  std::mutex mutex;
  std::vector<Destruction> log;
  RetiredDevices retired;
  retired.wait_until_empty();  // nothing kept: returns at once
  const Clock::time_point start = Clock::now();
  retired.keep(std::make_unique<Device>(1, mutex, log), start + 40ms);
  retired.keep(std::make_unique<Device>(2, mutex, log), start);
  retired.wait_until_empty();
  EXPECT_GE(Clock::now() - start, 40ms);
  const std::lock_guard lock(mutex);
  EXPECT_EQ(log.size(), 2u);
}

// Destroying a device waits for the kernel: keep() must not wait with it.
class SlowDevice {
 public:
  explicit SlowDevice(std::shared_future<void> allowed) : allowed_(std::move(allowed)) {}
  ~SlowDevice() { allowed_.wait_for(5s); }

 private:
  std::shared_future<void> allowed_;
};

TEST(RetiredDevices, HandingOverDoesNotWaitForTheDestruction) {
  std::promise<void> allow;
  const std::shared_future<void> allowed = allow.get_future().share();
  RetiredDevices retired;
  const Clock::time_point start = Clock::now();
  retired.keep(std::make_unique<SlowDevice>(allowed), start);
  retired.keep(std::make_unique<SlowDevice>(allowed), start);
  EXPECT_LT(Clock::now() - start, 4s);  // a destruction on this thread would have waited 5 s
  allow.set_value();
}

}  // namespace
}  // namespace ph
