// A taken mouse read on a thread of its own, which waits in a blocking read() of the node: under an emulator
// the event loop's wake-up through epoll costs a frame about a tenth more than a re-emitter that blocks in
// read() (docs/PERFORMANCE.md, "Against a bare re-emitter"). What the thread reads it hands on with the
// daemon's state lock held, so the rest of the daemon stays as single-threaded as its event loop.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/engine/event.hpp"
#include "daemon/evdev_device.hpp"

namespace ph {

// Sets the process's disposition of the signal that wakes a reader (SIGRTMIN): a handler that does nothing, without
// SA_RESTART, so that it interrupts a read(). The daemon calls it at start: sent from outside, before any mouse is
// taken, the signal would otherwise end the process. Each reader sets it too.
void install_reader_wake_handler();

class MouseReader {
 public:
  // Fills `events` from the mouse, waiting for at least one with Wait::yes (a signal that interrupts the wait
  // returns ok with none), taking only what is queued with Wait::no. May throw (a read error).
  using Read = std::function<ReadStatus(std::vector<InputEvent>& events, Wait wait)>;
  // Called with the state lock held, for each batch read, and once at the end: ReadStatus::gone when the
  // mouse went away, and then `error` names a read that failed ("" when it was unplugged). Not called once
  // stop() has been called (the batch in hand is stop()'s).
  using OnBatch =
      std::function<void(const std::vector<InputEvent>& events, ReadStatus status, const std::string& error)>;

  // Starts the thread. `state` must outlive the reader.
  MouseReader(Read read, std::timed_mutex& state, OnBatch on_batch);
  // Stops the thread and waits for it; the caller may hold the state lock (the thread gives up waiting for it). Returns
  // the events it had read and not handed on (a batch that waited for the lock): read from a grabbed mouse, they
  // reached no one, and the caller that lets go of the mouse emits them. Empty once stopped.
  std::vector<InputEvent> stop();
  // stop(), dropping what it returns.
  ~MouseReader();
  MouseReader(const MouseReader&) = delete;
  MouseReader& operator=(const MouseReader&) = delete;

  // Returns once every event the mouse had queued when it was called has been handed on (or the reading has
  // ended): what a control request answers must include a frame written into the mouse before it was asked.
  // The caller must not hold the state lock.
  void sync();

 private:
  void run();
  // Reads and hands on what it read; false once reading has ended (the mouse gone, or the reader stopping).
  bool deliver(Wait wait);
  // Interrupts a read() that waits: the signal's handler does nothing, the read returns EINTR.
  void interrupt();

  Read read_;
  std::timed_mutex& state_;
  OnBatch on_batch_;
  std::vector<InputEvent> events_;  // the thread's
  bool kept_ = false;               // events_ were read and not handed on: the thread stopped first (stop() takes them)
  std::atomic<bool> stopping_{false};
  std::mutex sync_mutex_;
  std::condition_variable synced_;
  // Asked is read by the thread on each turn without a lock (a lock is a call, and under an emulator each call
  // on a frame's path costs); done and ended are written under sync_mutex_.
  std::atomic<std::uint64_t> syncs_asked_{0};
  std::uint64_t syncs_done_ = 0;
  bool ended_ = false;
  std::thread thread_;  // last: starts once the members above are ready
};

}  // namespace ph
