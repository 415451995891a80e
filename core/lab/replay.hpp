// A recorded stream through the pipeline, in memory: what `pseudohaptic replay` and the tests run.
#pragma once

#include <vector>

#include "core/engine/device.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {

// Source over a recording's events.
class RecordingSource final : public EventSource {
 public:
  explicit RecordingSource(const std::vector<InputEvent>& events) : events_(events) {}
  std::optional<InputEvent> next() override {
    if (index_ >= events_.size()) return std::nullopt;
    return events_[index_++];
  }

 private:
  const std::vector<InputEvent>& events_;
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
Recording replay(const Recording& input, const Scene& scene, const PipelineConfig& config,
                 std::vector<FrameReport>* reports = nullptr);

}  // namespace ph
