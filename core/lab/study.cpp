#include "core/lab/study.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/engine/event.hpp"
#include "core/engine/pipeline.hpp"

namespace ph {

namespace {

// Names of the random streams (any distinct numbers would do).
constexpr std::uint64_t kHandTraitsKey = 1, kWeberKey = 2, kOrderKey = 3, kHandKey = 4, kNoiseKey = 5;

HandTraits participant_hand(const StudyDesign& design, int participant) {
  StudyRng rng(stream_seed({design.seed, static_cast<std::uint64_t>(participant), kHandTraitsKey}));
  return draw_hand_traits(design.hand, rng);
}

// The pixel the screen shows the cursor in, as its centre.
Vec2 displayed(Vec2 position) {
  const Texel t = texel_at(position);
  return {t.x + 0.5, t.y + 0.5};
}

}  // namespace

Rect study_area(const StudyDesign& design) {
  const Rect d = design.desktop;
  return {d.x + (d.w - design.area_px) / 2, d.y + (d.h - design.area_px) / 2, design.area_px, design.area_px};
}

double participant_weber(const StudyDesign& design, int participant) {
  StudyRng rng(stream_seed({design.seed, static_cast<std::uint64_t>(participant), kWeberKey}));
  return rng.log_normal(design.observer.weber, design.observer.participant_sigma);
}

std::vector<std::size_t> block_order(const StudyDesign& design, int participant, int block) {
  std::vector<std::size_t> order(all_targets().size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  StudyRng rng(stream_seed(
      {design.seed, static_cast<std::uint64_t>(participant), static_cast<std::uint64_t>(block), kOrderKey}));
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng.below(i)]);  // Fisher-Yates
  return order;
}

RegionFields target_fields(const TargetSpec& target) {
  RegionFields all;
  all.gradient = target_gradient_field(target);
  all.depth = target_depth_field(target);
  return all;
}

Scene study_scene(const StudyDesign& design, const TargetSpec& target, const RegionFields& fields,
                  const StudyTechnique& technique) {
  if (!technique.method) throw std::invalid_argument("study technique " + technique.name + " has no method");
  const Rect area = study_area(design);
  Region region;
  region.name = target.name();
  region.rect = {area.x + (area.w - target.size) / 2, area.y + (area.h - target.size) / 2, target.size, target.size};
  if (technique.effects) region.effects = technique.effects(fields, target.size, target.size);
  const FieldNeeds needs = technique.method->needs();
  if (needs.gradient) region.fields.gradient = fields.gradient;
  if (needs.reads_depth(fields.depth.has_value())) region.fields.depth = fields.depth;
  region.method = technique.method;
  std::vector<Region> regions;
  regions.push_back(std::move(region));
  return Scene(std::move(regions));
}

TrialRecord run_trial(const StudyDesign& design, std::shared_ptr<const Scene> scene, std::size_t target,
                      int participant, int block, int order) {
  const auto p = static_cast<std::uint64_t>(participant);
  const auto b = static_cast<std::uint64_t>(block);
  const auto o = static_cast<std::uint64_t>(order);
  StudyRng hand_rng(stream_seed({design.seed, p, b, o, kHandKey}));
  StudyRng noise(stream_seed({design.seed, p, b, o, kNoiseKey}));
  const Rect area = study_area(design);

  // The paper does not say where a trial starts: the cursor anywhere across the square, on a row drawn as the
  // strokes' are, and the first stroke toward either side. (Always starting at one side would put every
  // trial's first, slow start of a stroke in the first half of the square: a bias toward "bump".)
  const double across = hand_rng.uniform(0.0, area.w);
  const double row = std::clamp(hand_rng.normal(0.0, design.hand.row_sd_px), -area.h / 2.0 + 1.0, area.h / 2.0 - 1.0);
  const bool rightward = hand_rng.uniform() < 0.5;
  const Vec2 start{area.x + across, area.y + area.h / 2.0 + row};

  PipelineConfig config;  // relative output, flat acceleration at gain 1: the paper's "acceleration disabled"
  config.desktop = design.desktop;
  config.start = start;
  config.pointer_gain = 1.0 / design.counts_per_px;  // a count moves the cursor 1 / counts_per_px px at C/D 1
  Pipeline pipeline(std::move(scene), config);
  Hand hand(design.hand, participant_hand(design, participant), area, start, rightward, hand_rng);
  Observer observer(design.observer, participant_weber(design, participant), area, noise);

  const double dt = 1.0 / design.report_hz;
  const long window_frames = std::max(1L, std::lround(design.observer.window_s * design.report_hz));
  const long max_frames = static_cast<long>(std::floor(design.observer.time_limit_s * design.report_hz + 1e-9));
  TrialRecord record;
  record.participant = participant;
  record.block = block;
  record.order = order;
  record.target = target;
  record.time_s = design.observer.time_limit_s;

  Frame frame;
  double counts_x = 0.0, counts_y = 0.0;  // the sensor's whole counts so far (the hand starts at 0)
  Vec2 window_hand{};
  Vec2 window_cursor = displayed(pipeline.cursor().position);
  for (long k = 1; k <= max_frames; ++k) {
    const double t = static_cast<double>(k) * dt;
    const Vec2 seen = displayed(pipeline.cursor().position);
    const Vec2 h = hand.position(t, seen);
    const double cx = std::floor(h.x * design.counts_per_px), cy = std::floor(h.y * design.counts_per_px);
    const auto dx = static_cast<std::int32_t>(cx - counts_x), dy = static_cast<std::int32_t>(cy - counts_y);
    counts_x = cx;
    counts_y = cy;
    if (dx != 0 || dy != 0) {
      // A mouse report: the axes that moved, then SYN_REPORT.
      const TimeUs us = std::llround(t * 1e6);
      frame.events.clear();
      if (dx != 0) frame.events.push_back({us, ev::kRel, ev::kRelX, dx});
      if (dy != 0) frame.events.push_back({us, ev::kRel, ev::kRelY, dy});
      frame.events.push_back({us, ev::kSyn, ev::kSynReport, 0});
      pipeline.process(frame);
      ++record.frames;
    }
    if (k % window_frames != 0) continue;
    const Vec2 cursor = displayed(pipeline.cursor().position);
    const PerceptWindow window{h - window_hand, cursor - window_cursor, (cursor + window_cursor) * 0.5,
                               static_cast<double>(window_frames) * dt};
    window_hand = h;
    window_cursor = cursor;
    if (observer.observe(window)) {
      record.decided = true;
      record.time_s = t;
      break;
    }
  }
  record.strokes = hand.strokes();
  record.evidence = observer.evidence();
  record.answer = observer.answer(noise);
  record.correct = record.answer == all_targets()[target].shape;
  return record;
}

std::vector<TrialRecord> run_study(const StudyDesign& design, const std::vector<StudyTechnique>& techniques,
                                   const StudyProgress& progress) {
  if (design.participants < 1) throw std::invalid_argument("a study needs at least one participant");
  if (design.blocks < 2) throw std::invalid_argument("a study needs at least two blocks (the first is training)");
  if (!(design.report_hz > 0.0)) throw std::invalid_argument("the report rate must be > 0");
  const std::vector<TargetSpec> targets = all_targets();
  std::vector<TrialRecord> trials;
  trials.reserve(techniques.size() * static_cast<std::size_t>(design.participants) *
                 static_cast<std::size_t>(design.blocks) * targets.size());
  const std::size_t total = techniques.size() * static_cast<std::size_t>(design.participants);
  std::size_t done = 0;
  std::vector<RegionFields> fields;
  for (const TargetSpec& target : targets) fields.push_back(target_fields(target));
  for (std::size_t ti = 0; ti < techniques.size(); ++ti) {
    std::vector<std::shared_ptr<const Scene>> scenes;
    for (std::size_t i = 0; i < targets.size(); ++i) {
      scenes.push_back(std::make_shared<const Scene>(study_scene(design, targets[i], fields[i], techniques[ti])));
    }
    for (int p = 0; p < design.participants; ++p) {
      for (int b = 0; b < design.blocks; ++b) {
        const std::vector<std::size_t> order = block_order(design, p, b);
        for (std::size_t o = 0; o < order.size(); ++o) {
          TrialRecord r = run_trial(design, scenes[order[o]], order[o], p, b, static_cast<int>(o));
          r.technique = ti;
          trials.push_back(r);
        }
      }
      if (progress) progress(++done, total);
    }
  }
  return trials;
}

}  // namespace ph
