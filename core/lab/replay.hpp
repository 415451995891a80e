// A recorded stream through the pipeline, in memory: what `pseudohaptic replay` and the tests run.
#pragma once

#include <functional>
#include <vector>

#include "core/engine/device.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {

// Source over a recording's events.
class RecordingSource final : public EventSource {
 public:
  // `progress`, when given, is told how many events were read, every kProgressEvery of them (a long recording takes
  // seconds; the caller decides whether and how often to say so).
  static constexpr std::size_t kProgressEvery = std::size_t{1} << 16;
  explicit RecordingSource(const std::vector<InputEvent>& events, std::function<void(std::size_t)> progress = nullptr)
      : events_(events), progress_(std::move(progress)) {}
  std::optional<InputEvent> next() override {
    if (index_ >= events_.size()) return std::nullopt;
    if (progress_ && index_ % kProgressEvery == 0) [[unlikely]]
      progress_(index_);
    return events_[index_++];
  }

 private:
  const std::vector<InputEvent>& events_;
  std::function<void(std::size_t)> progress_;
  std::size_t index_ = 0;
};

// Sink that appends every frame's events to a recording.
class RecordingSink final : public EventSink {
 public:
  explicit RecordingSink(std::vector<InputEvent>& events) : events_(events) {}
  void write(const Frame& frame) override { events_.insert(events_.end(), frame.events.begin(), frame.events.end()); }

 private:
  std::vector<InputEvent>& events_;
};

// Runs every event of `source` through a pipeline into `sink`; one report per frame when `reports` is
// given.
void run_stream(EventSource& source, Pipeline& pipeline, EventSink& sink, std::vector<FrameReport>* reports = nullptr);

// The recording the daemon would emit for `input` over `scene`: same timestamps, the output device's
// description, every non-motion event unchanged and in its frame.
// `progress`: as RecordingSource's.
Recording replay(const Recording& input, const Scene& scene, const PipelineConfig& config,
                 std::vector<FrameReport>* reports = nullptr, std::function<void(std::size_t)> progress = nullptr);

}  // namespace ph
