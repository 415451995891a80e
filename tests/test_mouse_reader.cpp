// The reader thread of a taken mouse, on a pipe standing in for the evdev node: it hands on batches only under
// the state lock, sync() waits for what was queued before it, and it stops promptly whether it waits in read()
// or for the lock (stop() then gives back the batch in hand), and after its mouse went away.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "common/unique_fd.hpp"
#include "daemon/mouse_reader.hpp"

namespace ph {
namespace {

using namespace std::chrono_literals;

// A blocking pipe read as a mouse: events as raw InputEvent records; end of file is the mouse unplugged.
class PipeMouse {
 public:
  PipeMouse() {
    std::array<int, 2> ends{};
    if (::pipe2(ends.data(), O_CLOEXEC) != 0) throw std::runtime_error("pipe2");
    read_end_ = UniqueFd(ends[0]);
    write_end_ = UniqueFd(ends[1]);
  }

  void send(int value) {
    const std::array<InputEvent, 2> frame{InputEvent{0, 2, 0, value}, InputEvent{0, 0, 0, 0}};
    ASSERT_EQ(::write(write_end_.get(), frame.data(), sizeof frame), static_cast<ssize_t>(sizeof frame));
  }
  void unplug() { write_end_.reset(); }

  ReadStatus read(std::vector<InputEvent>& events, Wait wait) {
    events.clear();
    if (wait == Wait::no) {
      pollfd queued{read_end_.get(), POLLIN, 0};
      if (::poll(&queued, 1, 0) == 0) return ReadStatus::ok;
    }
    std::array<InputEvent, 16> batch{};
    const ssize_t n = ::read(read_end_.get(), batch.data(), sizeof batch);
    if (n < 0 && errno == EINTR) return ReadStatus::ok;
    if (n < 0) throw std::runtime_error(std::string("read: ") + std::strerror(errno));
    if (n == 0) return ReadStatus::gone;
    events.assign(batch.begin(), batch.begin() + n / static_cast<ssize_t>(sizeof(InputEvent)));
    return ReadStatus::ok;
  }

 private:
  UniqueFd read_end_, write_end_;
};

// What the reader handed on, kept under the state lock as the daemon keeps its state.
struct Handed {
  std::vector<int> values;
  int ends = 0;
  std::string error;
};

MouseReader make_reader(PipeMouse& mouse, std::timed_mutex& state, Handed& handed) {
  return MouseReader([&mouse](std::vector<InputEvent>& events, Wait wait) { return mouse.read(events, wait); }, state,
                     [&handed](const std::vector<InputEvent>& events, ReadStatus status, const std::string& error) {
                       for (const InputEvent& e : events) {
                         if (e.type == 2) handed.values.push_back(e.value);
                       }
                       if (status == ReadStatus::gone) {
                         ++handed.ends;
                         handed.error = error;
                       }
                     });
}

TEST(MouseReader, SyncReturnsOnceWhatWasQueuedBeforeItIsHandedOn) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  MouseReader reader = make_reader(mouse, state, handed);
  for (int i = 1; i <= 300; ++i) {
    mouse.send(i);
    reader.sync();
    const std::lock_guard lock(state);
    ASSERT_EQ(handed.values.size(), static_cast<std::size_t>(i)) << "frame " << i << " not handed on by sync()";
    ASSERT_EQ(handed.values.back(), i);
  }
}

TEST(MouseReader, HandsOnNothingWhileTheStateLockIsHeld) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  MouseReader reader = make_reader(mouse, state, handed);
  {
    const std::lock_guard lock(state);
    mouse.send(7);
    std::this_thread::sleep_for(30ms);
    EXPECT_TRUE(handed.values.empty());
  }
  reader.sync();
  const std::lock_guard lock(state);
  EXPECT_EQ(handed.values, std::vector<int>{7});
}

TEST(MouseReader, StopsPromptlyWhileWaitingInRead) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  const auto start = std::chrono::steady_clock::now();
  {
    MouseReader reader = make_reader(mouse, state, handed);
    std::this_thread::sleep_for(20ms);  // blocked in read() by now
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
  EXPECT_EQ(handed.ends, 0);
}

// The daemon lets go of a mouse with the state lock held: the reader, waiting for that lock with a batch in hand,
// must give up rather than deadlock, and must not hand the batch on.
TEST(MouseReader, StopsWhileTheCallerHoldsTheStateLock) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  std::unique_lock lock(state);
  {
    MouseReader reader = make_reader(mouse, state, handed);
    mouse.send(3);
    std::this_thread::sleep_for(20ms);  // read, and waiting for the lock
  }
  EXPECT_TRUE(handed.values.empty());
}

// ... and that batch, read from a grabbed mouse, reached no one: stop() gives it to the caller, which emits it. Once.
TEST(MouseReader, StopReturnsTheBatchThatWaitedForTheLock) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  std::promise<void> read_once;
  bool said = false;
  std::unique_lock lock(state);
  MouseReader reader(
      [&](std::vector<InputEvent>& events, Wait wait) {
        const ReadStatus status = mouse.read(events, wait);
        if (!events.empty() && !std::exchange(said, true)) read_once.set_value();
        return status;
      },
      state,
      [&handed](const std::vector<InputEvent>& events, ReadStatus, const std::string&) {
        for (const InputEvent& e : events) handed.values.push_back(e.value);
      });
  mouse.send(4);
  ASSERT_EQ(read_once.get_future().wait_for(10s), std::future_status::ready);  // read: now waiting for the lock
  const std::vector<InputEvent> kept = reader.stop();
  ASSERT_EQ(kept.size(), 2U);
  EXPECT_EQ(kept[0].type, 2);
  EXPECT_EQ(kept[0].value, 4);
  EXPECT_TRUE(handed.values.empty());
  EXPECT_TRUE(reader.stop().empty());  // stopped: nothing more, and no second wait
}

// A reader stopped while it waits in read() has nothing in hand.
TEST(MouseReader, StopReturnsNothingWhenNothingWasRead) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  MouseReader reader = make_reader(mouse, state, handed);
  mouse.send(5);
  reader.sync();  // handed on
  EXPECT_TRUE(reader.stop().empty());
  const std::lock_guard lock(state);
  EXPECT_EQ(handed.values, std::vector<int>{5});
}

TEST(MouseReader, AMouseThatWentAwayIsSaidOnceAndSyncStillReturns) {
  PipeMouse mouse;
  std::timed_mutex state;
  Handed handed;
  MouseReader reader = make_reader(mouse, state, handed);
  mouse.send(1);
  mouse.unplug();
  for (int i = 0; i < 200; ++i) {
    {
      const std::lock_guard lock(state);
      if (handed.ends > 0) break;
    }
    std::this_thread::sleep_for(5ms);
  }
  reader.sync();  // the reader has ended: must not wait for it
  const std::lock_guard lock(state);
  EXPECT_EQ(handed.values, std::vector<int>{1});
  EXPECT_EQ(handed.ends, 1);
  EXPECT_EQ(handed.error, "");
}

TEST(MouseReader, AReadErrorEndsTheReadingWithItsMessage) {
  std::timed_mutex state;
  Handed handed;
  int reads = 0;
  {
    MouseReader reader(
        [&reads](std::vector<InputEvent>&, Wait) -> ReadStatus {
          ++reads;
          throw std::runtime_error("/dev/input/event9: read failed: Input/output error");
        },
        state,
        [&handed](const std::vector<InputEvent>&, ReadStatus status, const std::string& error) {
          handed.ends += status == ReadStatus::gone;
          handed.error = error;
        });
    reader.sync();
  }
  EXPECT_EQ(reads, 1);
  EXPECT_EQ(handed.ends, 1);
  EXPECT_EQ(handed.error, "/dev/input/event9: read failed: Input/output error");
}

// The daemon installs the handler at start, so that the signal sent from outside before any mouse is taken does not
// end it (its default action would).
TEST(MouseReader, TheWakeSignalDoesNothingOnceItsHandlerIsInstalled) {
  install_reader_wake_handler();
  EXPECT_EQ(::raise(SIGRTMIN), 0);
  struct sigaction now {};
  ASSERT_EQ(::sigaction(SIGRTMIN, nullptr, &now), 0);
  EXPECT_NE(now.sa_handler, SIG_DFL);
  EXPECT_EQ(now.sa_flags & SA_RESTART, 0);  // it must interrupt a read()
}

}  // namespace
}  // namespace ph
