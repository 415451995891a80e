// The curvature paper's user study (Argelaguet et al., EuroHaptics 2012, Section 4), run in silico through the
// daemon's own Pipeline (docs/STUDY.md): simulated participants explore each of the 24 targets with
// minimum-jerk strokes turned into mouse reports (core/lab/study_hand.hpp), the Pipeline moves the cursor over
// the target's scene, and a simulated observer (core/lab/study_observer.hpp) answers bump or hole.
//
// Procedure, per participant and technique: three blocks of the 24 targets, each block in its own random
// order, the first block training (run, not scored); at most 10 s of exploration per target. The observer
// neither learns nor tires, so the order of the techniques does not matter and every technique sees the same
// hands and the same perceptual noise (common random numbers: the streams are named by participant, block and
// place in the block, never by technique), which makes the comparison between techniques paired.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/engine/effect.hpp"
#include "core/engine/field.hpp"
#include "core/engine/method.hpp"
#include "core/engine/scene.hpp"
#include "core/engine/targets.hpp"
#include "core/lab/study_hand.hpp"
#include "core/lab/study_observer.hpp"

namespace ph {

// What a region's effects are made from: the target's fields (gradient and depth, both present) and its size.
using EffectsMaker = std::function<std::vector<EffectPtr>(const RegionFields& fields, std::int32_t w, std::int32_t h)>;

// A technique: a method with its parameters, and optionally frame effects layered on it.
struct StudyTechnique {
  std::string name;  // as the CSV files write it, e.g. "curvature", "curvature:sign-1", "curvature+materials"
  MethodPtr method;
  EffectsMaker effects;  // may be empty
};

struct StudyDesign {
  int participants = 12;
  std::uint64_t seed = 1;
  int blocks = 3;                  // per technique; the first is training
  double report_hz = 125.0;        // the mouse's report rate (a USB mouse's default polling)
  double counts_per_px = 1.0;      // mouse counts per motor px: the paper's acceleration was off (flat, gain 1)
  Rect desktop{0, 0, 1920, 1200};  // the paper's monitor
  std::int32_t area_px = 500;      // the square, centred on the desktop; the targets are its size
  HandParams hand;
  ObserverParams observer;
};

struct TrialRecord {
  int participant = 0;
  std::size_t technique = 0;  // index into the techniques run
  int block = 0;              // 0 is training
  int order = 0;              // place in the block
  std::size_t target = 0;     // index into all_targets()
  TargetShape answer = TargetShape::bump;
  bool correct = false;
  bool decided = false;  // the evidence reached the bound before the time limit
  double time_s = 0.0;   // exploration until the answer
  int strokes = 0;
  int frames = 0;  // mouse reports sent through the pipeline
  double evidence = 0.0;

  bool scored() const { return block > 0; }
};

// The Weber fraction of each participant (their spread around ObserverParams::weber), by participant index.
double participant_weber(const StudyDesign& design, int participant);

// Both fields of a target (gradient and depth), computed once and copied into each technique's scene.
RegionFields target_fields(const TargetSpec& target);

// The scene of one target under one technique: one region, the area, centred on the desktop, with the fields
// the technique's method reads (copied from `fields`, target_fields of the target).
Scene study_scene(const StudyDesign& design, const TargetSpec& target, const RegionFields& fields,
                  const StudyTechnique& technique);

// The square the participants explore, centred on the desktop.
Rect study_area(const StudyDesign& design);

// One trial: target `target` (an index into all_targets()) shown through `scene` (study_scene of it). Its hand
// and noise depend on (design.seed, participant, block, order) only.
TrialRecord run_trial(const StudyDesign& design, std::shared_ptr<const Scene> scene, std::size_t target,
                      int participant, int block, int order);

// The order of the 24 targets in one block of one participant (a permutation of all_targets() indices).
std::vector<std::size_t> block_order(const StudyDesign& design, int participant, int block);

// progress(done, total) is called after each participant of each technique.
using StudyProgress = std::function<void(std::size_t done, std::size_t total)>;

// Every trial of every participant for every technique, technique by technique, then by participant, block
// and order. Throws std::invalid_argument for a design without participants or blocks.
std::vector<TrialRecord> run_study(const StudyDesign& design, const std::vector<StudyTechnique>& techniques,
                                   const StudyProgress& progress = {});

}  // namespace ph
