#include "daemon/mouse_reader.hpp"

#include <pthread.h>

#include <chrono>
#include <csignal>
#include <exception>

namespace ph {

namespace {

// How often a waiting reader looks whether it is being stopped, and how often a signal is sent again
// (one sent just before the thread entered read() finds nothing to interrupt).
constexpr std::chrono::milliseconds kRecheck{1};

int wake_signal() { return SIGRTMIN; }

extern "C" void on_wake_signal(int) {}

}  // namespace

// Setting it again for each reader changes nothing.
void install_reader_wake_handler() {
  struct sigaction action {};
  action.sa_handler = on_wake_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  ::sigaction(wake_signal(), &action, nullptr);
}

MouseReader::MouseReader(Read read, std::timed_mutex& state, OnBatch on_batch)
    : read_(std::move(read)), state_(state), on_batch_(std::move(on_batch)) {
  install_reader_wake_handler();
  thread_ = std::thread([this] { run(); });
  ::pthread_setname_np(thread_.native_handle(), "ph-mouse-reader");  // for ps -L, top -H and /proc
}

MouseReader::~MouseReader() { stop(); }

std::vector<InputEvent> MouseReader::stop() {
  if (!thread_.joinable()) return {};
  stopping_ = true;
  std::unique_lock lock(sync_mutex_);
  while (!ended_) {
    interrupt();
    synced_.wait_for(lock, kRecheck);
  }
  lock.unlock();
  thread_.join();  // (after which the thread's members are the caller's)
  if (!kept_) return {};
  kept_ = false;
  return std::move(events_);
}

void MouseReader::sync() {
  std::unique_lock lock(sync_mutex_);
  const std::uint64_t asked = ++syncs_asked_;
  while (syncs_done_ < asked && !ended_) {
    interrupt();
    synced_.wait_for(lock, kRecheck);
  }
}

void MouseReader::interrupt() { ::pthread_kill(thread_.native_handle(), wake_signal()); }

[[gnu::hot]] void MouseReader::run() {
  sigset_t wake;
  sigemptyset(&wake);
  sigaddset(&wake, wake_signal());
  ::pthread_sigmask(SIG_UNBLOCK, &wake, nullptr);
  while (!stopping_) {
    const std::uint64_t asked = syncs_asked_.load();
    if (asked == syncs_done_) {  // (syncs_done_ is written by this thread only)
      if (!deliver(Wait::yes)) break;
      continue;
    }
    // Asked to sync: what is queued now, then say so.
    if (!deliver(Wait::no)) break;
    {
      const std::lock_guard lock(sync_mutex_);
      syncs_done_ = asked;
    }
    synced_.notify_all();
  }
  {
    const std::lock_guard lock(sync_mutex_);
    ended_ = true;
  }
  synced_.notify_all();
}

[[gnu::hot]] bool MouseReader::deliver(Wait wait) {
  ReadStatus status = ReadStatus::ok;
  std::string error;
  try {
    status = read_(events_, wait);
  } catch (const std::exception& e) {
    status = ReadStatus::gone;
    error = e.what();
    events_.clear();
  }
  if (status == ReadStatus::ok && events_.empty()) return true;  // interrupted, or nothing queued
  std::unique_lock lock(state_, std::try_to_lock);  // (try_lock_for reads the clock even when the lock is free)
  while (!lock.owns_lock() && !lock.try_lock_for(kRecheck)) {
    if (stopping_) break;
  }
  if (stopping_) {  // the batch is stop()'s (a mouse gone meanwhile: its caller finds the node hung up)
    kept_ = !events_.empty();
    return false;
  }
  on_batch_(events_, status, error);
  return status == ReadStatus::ok;
}

}  // namespace ph
