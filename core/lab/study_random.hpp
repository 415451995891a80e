// Random numbers for the simulated study (docs/STUDY.md: "the same seed gives the same files"): the same seed gives the
// same study on any standard library. std::mt19937_64's output is fixed by the C++ standard, but
// std::uniform_real_distribution and std::normal_distribution are not (libstdc++ and libc++ give different numbers), so
// the distributions are ours.
#pragma once

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <random>

namespace ph {

// SplitMix64's finaliser: a well-mixed 64-bit value from another, to derive independent streams from keys.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The seed of a stream named by a list of keys (seed, participant, block, ...): a different list, a different
// and unrelated stream, whatever order the streams are drawn in.
constexpr std::uint64_t stream_seed(std::initializer_list<std::uint64_t> keys) {
  std::uint64_t h = 0x6a09e667f3bcc909ULL;
  for (std::uint64_t k : keys) h = mix64(h ^ mix64(k));
  return h;
}

class StudyRng {
 public:
  explicit StudyRng(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1), 53 bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n), n > 0 (a modulo: its bias, of order n / 2^64, does not matter here).
  std::uint64_t below(std::uint64_t n) { return engine_() % n; }
  // Standard normal, Box-Muller (both values of a pair are used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]: the log is finite
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * std::numbers::pi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * std::numbers::pi * u2);
  }
  double normal(double mean, double sd) { return mean + sd * normal(); }
  // Log-normal with median `median` and sd `sigma` of its logarithm.
  double log_normal(double median, double sigma) { return median * std::exp(sigma * normal()); }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace ph
