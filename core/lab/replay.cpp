#include "core/lab/replay.hpp"

namespace ph {

void run_stream(EventSource& source, Pipeline& pipeline, EventSink& sink, std::vector<FrameReport>* reports) {
  FrameProcessor processor(pipeline, sink);
  FrameReport report;
  bool frame_done = false;
  while (const std::optional<InputEvent> event = source.next()) {
    processor.push(*event, reports != nullptr ? &report : nullptr, &frame_done);
    if (frame_done && reports != nullptr) reports->push_back(report);
  }
  processor.finish();
}

Recording replay(const Recording& input, const Scene& scene, const PipelineConfig& config,
                 std::vector<FrameReport>* reports, std::function<void(std::size_t)> progress) {
  Recording output;
  // Absolute output describes a tablet-like device of the desktop's size, for a pointer the daemon takes; a device
  // without relative motion (a tablet, a keyboard) the daemon never takes, and its description stays its own.
  const bool taken = input.device.has(ev::kRel, ev::kRelX) && input.device.has(ev::kRel, ev::kRelY);
  output.device = config.mode == OutputMode::absolute && taken ? output_device(input.device, config) : input.device;
  if (!taken) {  // every event passes through, unchanged, as the daemon leaves such a device to the desktop
    output.events = input.events;
    return output;
  }
  output.events.reserve(input.events.size());
  // The scene outlives this call: share it without owning it.
  Pipeline pipeline(std::shared_ptr<const Scene>(std::shared_ptr<const Scene>(), &scene), config);
  RecordingSource source(input.events, std::move(progress));
  RecordingSink sink(output.events);
  run_stream(source, pipeline, sink, reports);
  return output;
}

}  // namespace ph
