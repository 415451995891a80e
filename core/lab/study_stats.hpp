// Summaries of a simulated study (docs/STUDY.md, its opening section): error rate and decision time per technique and
// group of targets, as a mean over participants with a 95 % confidence interval over participants (Student's
// t), as the paper's within-subject analysis treats participants.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/engine/targets.hpp"
#include "core/lab/study.hpp"

namespace ph {

struct MeanCi {
  double mean = 0.0;
  double lo = 0.0, hi = 0.0;  // 95 % interval of the mean; equal to the mean for fewer than 2 values
  int n = 0;
};

// The 97.5 % quantile of Student's t with df degrees of freedom (df >= 1), within 0.2 % of the exact value.
double t_quantile_975(int df);
// The interval is cut to [least, most], the values' possible range: a t-interval is symmetric, and around a small
// error rate it would reach below 0 %. Cutting it keeps its coverage at 95 % or more.
MeanCi mean_ci(const std::vector<double>& values, double least = -std::numeric_limits<double>::infinity(),
               double most = std::numeric_limits<double>::infinity());

struct GroupSummary {
  std::size_t technique = 0;
  std::string grouping;      // "overall", "height_radius", "profile", "shape", "cell"
  std::string group;         // "all", "h0.25-r200", "gaussian", "bump", "gaussian-h1-r100"
  int trials = 0;            // scored trials in the group, over all participants
  MeanCi error_pct;          // per participant: misclassified scored trials, percent
  MeanCi time_s;             // per participant: mean exploration time of scored trials
  double decided_pct = 0.0;  // scored trials answered before the time limit, percent
};

// The label of a target's group within one grouping.
using GroupKey = std::function<std::string(const TargetSpec&)>;

struct Grouping {
  std::string name;
  GroupKey key;
};

// "overall", "height_radius", "profile", "shape" and "cell" (profile, height and radius: the paper's Fig. 4).
std::vector<Grouping> standard_groupings();

// One summary per technique and group, techniques in index order, groups in the order all_targets() meets them. The
// intervals are cut to what a rate (0-100 %) and a decision time (0 to `time_limit_s`, a trial's longest) can be.
std::vector<GroupSummary> summarise(const std::vector<TrialRecord>& trials, std::size_t techniques, int participants,
                                    const Grouping& grouping,
                                    double time_limit_s = std::numeric_limits<double>::infinity());

}  // namespace ph
