// The reload worker: loads run off the calling thread, a request during a load makes one more load (of
// what the file says then), and a failed load is reported, not thrown.
#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "daemon/reload_queue.hpp"
#include "daemon/scene_reloader.hpp"

namespace ph {
namespace {

TEST(ReloadQueue, RequestsDuringALoadMakeOneMoreLoad) {
  ReloadQueue queue;
  EXPECT_FALSE(queue.loading());
  EXPECT_TRUE(queue.request());   // idle: load now
  EXPECT_FALSE(queue.request());  // during the load: later
  EXPECT_FALSE(queue.request());  // and again: still one later load
  EXPECT_TRUE(queue.loading());
  EXPECT_TRUE(queue.finished());  // the coalesced load starts
  EXPECT_TRUE(queue.loading());
  EXPECT_FALSE(queue.finished());  // nothing asked for meanwhile: idle
  EXPECT_FALSE(queue.loading());
  EXPECT_TRUE(queue.request());
}

// A load function that blocks until released, and says which version of the "file" it read.
class GatedLoad {
 public:
  Configuration operator()() {
    std::unique_lock lock(mutex_);
    const int version = version_;  // the file is read first, then decoded (the wait)
    ++started_;
    changed_.notify_all();
    changed_.wait(lock, [&] { return open_ > 0; });
    --open_;
    if (version < 0) throw std::runtime_error("bad file");
    Configuration c;
    c.source = "version " + std::to_string(version);
    return c;
  }
  void set_version(int v) {
    const std::lock_guard lock(mutex_);
    version_ = v;
  }
  void release_one() {
    const std::lock_guard lock(mutex_);
    ++open_;
    changed_.notify_all();
  }
  bool wait_started(int n) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(10), [&] { return started_ >= n; });
  }
  int started() {
    const std::lock_guard lock(mutex_);
    return started_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int started_ = 0, open_ = 0, version_ = 0;
};

bool readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) == 1;
}

TEST(SceneReloader, LoadsOffTheCallingThreadAndCoalescesRequests) {
  GatedLoad load;
  SceneReloader reloader([&] { return load(); });
  load.set_version(1);
  EXPECT_TRUE(reloader.request());
  ASSERT_TRUE(load.wait_started(1));
  // The caller is free while the load runs: nothing to collect yet.
  EXPECT_FALSE(readable(reloader.fd(), 0));
  EXPECT_FALSE(reloader.collect().has_value());
  EXPECT_FALSE(reloader.request());
  load.set_version(2);
  EXPECT_FALSE(reloader.request());
  load.set_version(3);  // the file as it is when the first load ends is what the second reads
  load.release_one();
  ASSERT_TRUE(readable(reloader.fd(), 10'000));
  std::optional<SceneReloader::Outcome> first = reloader.collect();
  ASSERT_TRUE(first.has_value());
  ASSERT_TRUE(first->configuration.has_value());
  EXPECT_EQ(first->configuration->source, "version 1");
  EXPECT_TRUE(first->another_started);
  ASSERT_TRUE(load.wait_started(2));
  load.release_one();
  ASSERT_TRUE(readable(reloader.fd(), 10'000));
  std::optional<SceneReloader::Outcome> second = reloader.collect();
  ASSERT_TRUE(second.has_value() && second->configuration.has_value());
  EXPECT_EQ(second->configuration->source, "version 3");
  EXPECT_FALSE(second->another_started);
  EXPECT_FALSE(reloader.loading());
  EXPECT_EQ(load.started(), 2);  // three requests, two loads
}

TEST(SceneReloader, AFailedLoadIsReportedWithItsMessage) {
  GatedLoad load;
  SceneReloader reloader([&] { return load(); });
  load.set_version(-1);
  load.release_one();
  EXPECT_TRUE(reloader.request());
  ASSERT_TRUE(readable(reloader.fd(), 10'000));
  std::optional<SceneReloader::Outcome> outcome = reloader.collect();
  ASSERT_TRUE(outcome.has_value());
  EXPECT_FALSE(outcome->configuration.has_value());
  EXPECT_EQ(outcome->error, "bad file");
  EXPECT_FALSE(outcome->another_started);
  // And the next request loads again.
  load.set_version(4);
  load.release_one();
  EXPECT_TRUE(reloader.request());
  ASSERT_TRUE(readable(reloader.fd(), 10'000));
  outcome = reloader.collect();
  ASSERT_TRUE(outcome.has_value() && outcome->configuration.has_value());
  EXPECT_EQ(outcome->configuration->source, "version 4");
}

TEST(SceneReloader, AReplacedSceneIsFreedOffTheCallingThread) {
  std::thread::id freed_on;
  {
    SceneReloader reloader([] { return Configuration{}; });
    reloader.dispose(std::shared_ptr<const Scene>(new Scene(), [&](const Scene* scene) {
      freed_on = std::this_thread::get_id();
      delete scene;
    }));
  }  // the reloader waits for its threads
  EXPECT_NE(freed_on, std::thread::id());
  EXPECT_NE(freed_on, std::this_thread::get_id());
}

// A scene replaced while the one before is still being freed (slowly, at idle priority on a busy CPU) does not wait
// for it: dispose() is called under the daemon's state lock, which every mouse's reader takes.
TEST(SceneReloader, DisposingDoesNotWaitForTheSceneBefore) {
  std::promise<void> let_go;
  std::shared_future<void> released = let_go.get_future().share();
  std::atomic<int> freed{0};
  // The first free ends after 1 s whatever happens (a dispose() that waited for it would wait that long, not hang).
  std::thread releaser([&] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    let_go.set_value();
  });
  {
    SceneReloader reloader([] { return Configuration{}; });
    reloader.dispose(std::shared_ptr<const Scene>(new Scene(), [&, released](const Scene* scene) {
      released.wait();  // a free that takes its time
      delete scene;
      ++freed;
    }));
    const auto start = std::chrono::steady_clock::now();
    reloader.dispose(std::shared_ptr<const Scene>(new Scene(), [&](const Scene* scene) {
      delete scene;
      ++freed;
    }));
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(500));
    releaser.join();
  }  // the reloader waits for both
  EXPECT_EQ(freed.load(), 2);
}

}  // namespace
}  // namespace ph
