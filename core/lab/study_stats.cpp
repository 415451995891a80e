#include "core/lab/study_stats.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace ph {

double t_quantile_975(int df) {
  // Exact values for small df, then the Cornish-Fisher expansion around the normal quantile.
  static constexpr double kSmall[] = {12.7062, 4.3027, 3.1824, 2.7764, 2.5706};
  if (df < 1) df = 1;
  if (df <= 5) return kSmall[df - 1];
  const double z = 1.959964;
  const double n = df;
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4.0 * n) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n) +
         (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * n * n * n);
}

MeanCi mean_ci(const std::vector<double>& values, double least, double most) {
  MeanCi r;
  r.n = static_cast<int>(values.size());
  if (values.empty()) return r;
  double sum = 0.0;
  for (double v : values) sum += v;
  r.mean = sum / r.n;
  r.lo = r.hi = r.mean;
  if (r.n < 2) return r;
  double ss = 0.0;
  for (double v : values) ss += (v - r.mean) * (v - r.mean);
  const double half = t_quantile_975(r.n - 1) * std::sqrt(ss / (r.n - 1) / r.n);
  r.lo = std::max(r.mean - half, least);
  r.hi = std::min(r.mean + half, most);
  return r;
}

namespace {

// The parts of a target's name, "bump-gaussian-h1-r200": shape, profile, height, radius.
std::string name_part(const TargetSpec& t, int index) {
  const std::string name = t.name();
  std::size_t begin = 0;
  for (int i = 0; i < index; ++i) begin = name.find('-', begin) + 1;
  return name.substr(begin, name.find('-', begin) - begin);
}

}  // namespace

std::vector<Grouping> standard_groupings() {
  return {
      {"overall", [](const TargetSpec&) { return std::string("all"); }},
      {"height_radius", [](const TargetSpec& t) { return name_part(t, 2) + "-" + name_part(t, 3); }},
      {"profile", [](const TargetSpec& t) { return name_part(t, 1); }},
      {"shape", [](const TargetSpec& t) { return name_part(t, 0); }},
      {"cell", [](const TargetSpec& t) { return name_part(t, 1) + "-" + name_part(t, 2) + "-" + name_part(t, 3); }},
  };
}

std::vector<GroupSummary> summarise(const std::vector<TrialRecord>& trials, std::size_t techniques, int participants,
                                    const Grouping& grouping, double time_limit_s) {
  const std::vector<TargetSpec> targets = all_targets();
  std::vector<std::string> groups;    // in order of first appearance
  std::vector<std::size_t> group_of;  // per target
  for (const TargetSpec& t : targets) {
    const std::string g = grouping.key(t);
    auto it = std::find(groups.begin(), groups.end(), g);
    group_of.push_back(static_cast<std::size_t>(it - groups.begin()));
    if (it == groups.end()) groups.push_back(g);
  }
  struct Tally {
    int trials = 0, errors = 0, decided = 0;
    double time = 0.0;
  };
  const auto P = static_cast<std::size_t>(std::max(participants, 0));
  // tally[(technique * groups + group) * P + participant]
  std::vector<Tally> tally(techniques * groups.size() * P);
  for (const TrialRecord& r : trials) {
    if (!r.scored() || r.technique >= techniques || r.participant < 0 || static_cast<std::size_t>(r.participant) >= P ||
        r.target >= targets.size()) {
      continue;
    }
    Tally& t = tally[(r.technique * groups.size() + group_of[r.target]) * P + static_cast<std::size_t>(r.participant)];
    ++t.trials;
    t.errors += r.correct ? 0 : 1;
    t.decided += r.decided ? 1 : 0;
    t.time += r.time_s;
  }
  std::vector<GroupSummary> out;
  for (std::size_t ti = 0; ti < techniques; ++ti) {
    for (std::size_t g = 0; g < groups.size(); ++g) {
      GroupSummary s;
      s.technique = ti;
      s.grouping = grouping.name;
      s.group = groups[g];
      std::vector<double> errors, times;
      int decided = 0;
      for (std::size_t p = 0; p < P; ++p) {
        const Tally& t = tally[(ti * groups.size() + g) * P + p];
        if (t.trials == 0) continue;
        s.trials += t.trials;
        decided += t.decided;
        errors.push_back(100.0 * t.errors / t.trials);
        times.push_back(t.time / t.trials);
      }
      s.error_pct = mean_ci(errors, 0.0, 100.0);
      s.time_s = mean_ci(times, 0.0, time_limit_s);
      s.decided_pct = s.trials > 0 ? 100.0 * decided / s.trials : 0.0;
      out.push_back(std::move(s));
    }
  }
  return out;
}

}  // namespace ph
