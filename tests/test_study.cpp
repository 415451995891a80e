// The simulated study's parts (core/lab/study*.hpp): the random streams, the hand, the observer, the statistics,
// and one trial through the pipeline.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/lab/study.hpp"
#include "core/lab/study_random.hpp"
#include "core/lab/study_stats.hpp"

namespace ph {
namespace {

TEST(StudyRandom, SameSeedSameNumbersAndPlausibleMoments) {
  StudyRng a(42), b(42), c(43);
  double sum = 0.0, sum2 = 0.0;
  bool differs = false;
  constexpr int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double x = a.normal();
    EXPECT_EQ(x, b.normal());
    differs = differs || x != c.normal();
    sum += x;
    sum2 += x * x;
  }
  EXPECT_TRUE(differs);
  EXPECT_NEAR(sum / n, 0.0, 0.03);
  EXPECT_NEAR(sum2 / n, 1.0, 0.04);
  for (int i = 0; i < 1000; ++i) {
    const double u = a.uniform();
    EXPECT_GE(u, 0.0);
    EXPECT_LT(u, 1.0);
    EXPECT_LT(a.below(7), 7u);
  }
  EXPECT_NE(stream_seed({1, 2, 3}), stream_seed({1, 3, 2}));
}

TEST(StudyHand, MinimumJerkStartsAndEndsAtRest) {
  EXPECT_EQ(minimum_jerk(0.0), 0.0);
  EXPECT_EQ(minimum_jerk(1.0), 1.0);
  EXPECT_NEAR(minimum_jerk(0.5), 0.5, 1e-12);
  const double h = 1e-6;
  EXPECT_NEAR((minimum_jerk(h) - minimum_jerk(0.0)) / h, 0.0, 1e-6);
  EXPECT_NEAR((minimum_jerk(0.5 + h) - minimum_jerk(0.5 - h)) / (2 * h), 1.875, 1e-6);  // peak speed 1.875 A/T
}

TEST(StudyHand, StrokesGoBackAndForthAcrossTheArea) {
  StudyRng rng(7);
  const Rect area{710, 350, 500, 500};
  const Vec2 start{700, 600};
  Hand hand(HandParams{}, HandTraits{350.0}, area, start, true, rng);
  double min_x = 1e9, max_x = -1e9;
  Vec2 cursor = start;
  for (int k = 0; k <= 1000; ++k) {  // 8 s at 125 Hz; the cursor follows the hand at C/D 1
    cursor = start + hand.position(k * 0.008, cursor);
    min_x = std::min(min_x, cursor.x);
    max_x = std::max(max_x, cursor.x);
  }
  EXPECT_GE(hand.strokes(), 3);
  EXPECT_LT(min_x, area.x + 40.0);
  EXPECT_GT(max_x, area.x + area.w - 40.0);
}

// A window in which the cursor moved `cursor_px` while the hand moved 40 px to the right, at cursor x.
PerceptWindow window(double x, double cursor_px) { return {{40.0, 0.0}, {cursor_px, 0.0}, {x, 600.0}, 0.1}; }

TEST(StudyObserver, SlowingInTheFirstHalfIsABumpInTheSecondAHole) {
  const Rect area{710, 350, 500, 500};
  ObserverParams params;
  params.bound = 2.0;
  StudyRng n1(1), n2(1), coin(3);
  Observer bump(params, 0.01, area, n1), hole(params, 0.01, area, n2);
  int windows = 0;
  while (!bump.decided() && windows < 100) {
    bump.observe(window(850.0, 20.0));   // first half, moving right: half speed
    hole.observe(window(1100.0, 20.0));  // second half
    ++windows;
  }
  EXPECT_TRUE(bump.decided());
  EXPECT_TRUE(hole.decided());
  EXPECT_EQ(bump.answer(coin), TargetShape::bump);
  EXPECT_EQ(hole.answer(coin), TargetShape::hole);
  EXPECT_NEAR(windows, 4, 1);  // 0.5 of evidence a window, bound 2
}

TEST(StudyObserver, SpeedUpsAndTheOutsideGiveNoEvidence) {
  const Rect area{710, 350, 500, 500};
  StudyRng noise(1);
  Observer o(ObserverParams{}, 0.001, area, noise);
  for (int i = 0; i < 50; ++i) {
    o.observe(window(850.0, 80.0));  // twice the hand's speed
    o.observe(window(600.0, 10.0));  // slow, but left of the area
  }
  EXPECT_NEAR(o.evidence(), 0.0, 0.05);
  EXPECT_FALSE(o.decided());
}

TEST(StudyStats, StudentQuantileAndInterval) {
  EXPECT_NEAR(t_quantile_975(1), 12.706, 1e-3);
  EXPECT_NEAR(t_quantile_975(11), 2.201, 2e-3);
  EXPECT_NEAR(t_quantile_975(30), 2.042, 2e-3);
  EXPECT_NEAR(t_quantile_975(1000), 1.962, 2e-3);
  const MeanCi m = mean_ci({1.0, 2.0, 3.0, 4.0});
  EXPECT_DOUBLE_EQ(m.mean, 2.5);
  EXPECT_NEAR(m.hi - m.mean, 3.1824 * std::sqrt(5.0 / 3.0 / 4.0), 1e-4);
  EXPECT_EQ(mean_ci({5.0}).lo, 5.0);
  // An error rate of 0 % for eleven participants and 25 % for one: the t-interval reaches below 0 %, which no
  // error rate can; it is cut there, and its upper end stays.
  std::vector<double> rates(11, 0.0);
  rates.push_back(25.0);
  const MeanCi open = mean_ci(rates), cut = mean_ci(rates, 0.0, 100.0);
  EXPECT_LT(open.lo, 0.0);
  EXPECT_EQ(cut.lo, 0.0);
  EXPECT_EQ(cut.hi, open.hi);
  EXPECT_EQ(cut.mean, open.mean);
  EXPECT_EQ(mean_ci({99.0, 100.0, 100.0}, 0.0, 100.0).hi, 100.0);
}

TEST(StudyDesignTest, BlockOrdersArePermutationsThatDifferBetweenBlocks) {
  StudyDesign design;
  const auto a = block_order(design, 0, 1), b = block_order(design, 0, 2);
  EXPECT_EQ(std::set<std::size_t>(a.begin(), a.end()).size(), all_targets().size());
  EXPECT_NE(a, b);
  EXPECT_EQ(a, block_order(design, 0, 1));
}

// A technique's region holds the fields its method reads: the hybrid's, its normals and the heights it reads where
// given, and finds the rim's steps from them as the scene files' regions do.
TEST(StudyScene, GivesEachMethodTheFieldsItReads) {
  const StudyDesign design;
  const TargetSpec target = all_targets()[6];  // bump-gaussian-h1-r100: its rim steps by about 1 px
  const RegionFields fields = target_fields(target);
  ASSERT_TRUE(fields.gradient && fields.depth);
  const StudyTechnique hybrid{"hybrid", std::make_shared<HybridMethod>(HybridParams{}), {}};
  const StudyTechnique curvature{"curvature", std::make_shared<CurvatureMethod>(CurvatureParams{}), {}};
  const Scene with_heights = study_scene(design, target, fields, hybrid);
  const RegionFields& got = with_heights.regions().at(0).fields;
  ASSERT_TRUE(got.gradient && got.depth && got.discontinuity);
  EXPECT_GT(std::count_if(got.discontinuity->values.begin(), got.discontinuity->values.end(),
                          [](std::uint8_t m) { return m != 0; }),
            0);
  EXPECT_FALSE(study_scene(design, target, fields, curvature).regions().at(0).fields.depth);
}

TEST(StudyTrial, TheTextureDecidesTheAnswerAndTheSameSeedTheTrial) {
  StudyDesign design;
  std::size_t bump_index = 0;
  const std::vector<TargetSpec> targets = all_targets();
  while (targets[bump_index].name() != "bump-gaussian-h1-r200") ++bump_index;
  const StudyTechnique depth{"depth", std::make_shared<DepthMethod>(DepthParams{}), {}};
  const StudyTechnique flat{"none", std::make_shared<FlatMethod>(FlatMethod::Params{}), {}};
  const RegionFields fields = target_fields(targets[bump_index]);
  auto scene = std::make_shared<const Scene>(study_scene(design, targets[bump_index], fields, depth));
  const TrialRecord r = run_trial(design, scene, bump_index, 0, 1, 0);
  EXPECT_TRUE(r.decided);
  EXPECT_TRUE(r.correct);
  EXPECT_GT(r.frames, 50);
  const TrialRecord again = run_trial(design, scene, bump_index, 0, 1, 0);
  EXPECT_EQ(again.time_s, r.time_s);
  EXPECT_EQ(again.frames, r.frames);
  EXPECT_EQ(again.evidence, r.evidence);
  // The same hand over a flat region: the evidence is the noise's, far from the bump's.
  auto flat_scene = std::make_shared<const Scene>(study_scene(design, targets[bump_index], fields, flat));
  const TrialRecord f = run_trial(design, flat_scene, bump_index, 0, 1, 0);
  EXPECT_LT(std::abs(f.evidence), r.evidence);
}

}  // namespace
}  // namespace ph

namespace ph {
namespace {

TEST(StudyTrial, OnAFlatRegionTheObserverIsAtChance) {
  // The observer's own noise must not lean toward either answer: rectified noise that piles up in the half of
  // the square where strokes start slowly would read as "bump".
  StudyDesign design;
  const StudyTechnique flat{"none", std::make_shared<FlatMethod>(FlatMethod::Params{}), {}};
  const std::vector<TargetSpec> targets = all_targets();
  auto scene = std::make_shared<const Scene>(study_scene(design, targets[0], target_fields(targets[0]), flat));
  int bumps = 0, trials = 0;
  for (int p = 0; p < 16; ++p) {
    for (int o = 0; o < 24; ++o, ++trials) bumps += run_trial(design, scene, 0, p, 1, o).answer == TargetShape::bump;
  }
  // 384 trials: a fair coin lands within 0.43-0.57 with probability 0.99.
  EXPECT_GT(static_cast<double>(bumps) / trials, 0.43);
  EXPECT_LT(static_cast<double>(bumps) / trials, 0.57);
}

TEST(StudyStats, SummariesAreMeansOverParticipantsOfScoredTrials) {
  const std::vector<TargetSpec> targets = all_targets();
  std::size_t low_wide = 0, high_narrow = 0;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (targets[i].name() == "bump-linear-h0.25-r200") low_wide = i;
    if (targets[i].name() == "hole-gaussian-h1-r100") high_narrow = i;
  }
  auto trial = [](int participant, int block, std::size_t target, bool correct, double time) {
    TrialRecord r;
    r.participant = participant;
    r.block = block;
    r.target = target;
    r.correct = correct;
    r.time_s = time;
    return r;
  };
  // Participant 0: one error in two low, wide trials; participant 1: none. The training trial does not count.
  const std::vector<TrialRecord> trials = {trial(0, 1, low_wide, false, 4.0),  trial(0, 2, low_wide, true, 2.0),
                                           trial(1, 1, low_wide, true, 6.0),   trial(1, 2, low_wide, true, 6.0),
                                           trial(1, 0, low_wide, false, 10.0), trial(1, 1, high_narrow, true, 1.0)};
  const Grouping by_cell = standard_groupings()[1];
  ASSERT_EQ(by_cell.name, "height_radius");
  for (const GroupSummary& s : summarise(trials, 1, 2, by_cell, 10.0)) {
    if (s.group == "h0.25-r200") {
      EXPECT_EQ(s.trials, 4);
      EXPECT_DOUBLE_EQ(s.error_pct.mean, 25.0);  // (50 % + 0 %) / 2
      EXPECT_DOUBLE_EQ(s.time_s.mean, 4.5);      // (3 s + 6 s) / 2
      EXPECT_EQ(s.error_pct.n, 2);
      // Two participants give t(1) = 12.7: each interval is cut to what a rate and a time can be.
      EXPECT_EQ(s.error_pct.lo, 0.0);
      EXPECT_EQ(s.error_pct.hi, 100.0);
      EXPECT_EQ(s.time_s.lo, 0.0);
      EXPECT_EQ(s.time_s.hi, 10.0);  // the time limit: no trial takes longer (t(1) reached past 40 s)
    } else if (s.group == "h1-r100") {
      EXPECT_EQ(s.trials, 1);
      EXPECT_EQ(s.error_pct.n, 1);
    } else {
      EXPECT_EQ(s.trials, 0) << s.group;
    }
  }
}

}  // namespace
}  // namespace ph
