// One small interface for every way of turning a texel step into a C/D ratio. The traversal knows
// nothing else about a method, so new methods plug in without touching it (docs/DESIGN.md, "One file per method").
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>

#include "core/field.hpp"
#include "core/geometry.hpp"

namespace ph {

// What a method reads from one texel for one motion direction; the meaning of the two numbers is private
// to the method (curvature: a = n''_x and the slope angle; depth: the height, and its change per px along
// the motion).
struct TexelSample {
  double v0 = 0.0;
  double v1 = 0.0;
};

// The intermediate quantities of one step, for traces and tests. Fields a method does not use stay NaN
// (a trace writes them as empty cells; they never reach an event).
struct StepDetail {
  double cos_alpha;
  double delta_beta_deg;
  double kmax;
  double kmin;
  double dh;
};
StepDetail empty_step_detail();

// The built-in methods, which the traversal calls without a virtual call per texel. Any other method
// (BuiltinMethod::none) goes through the virtual interface, unchanged.
enum class BuiltinMethod : std::uint8_t { none, curvature, depth };

class Method {
 public:
  virtual ~Method() = default;
  BuiltinMethod builtin() const { return builtin_; }

  virtual std::string_view name() const = 0;
  virtual FieldNeeds needs() const = 0;

  // Sample of texel `local` of a region's fields; a region whose fields lack what this method reads
  // (or a texel outside every region, `fields == nullptr`) gives the flat surface's sample.
  virtual TexelSample sample(const RegionFields* fields, Texel local, Vec2 direction) const = 0;

  // Sample at a continuous position `at` (region-local px) inside texel `local`, for Sampling::bilinear.
  // A method that has no interpolated reading keeps the texel's: the default is sample(fields, local, m).
  virtual TexelSample sample_at(const RegionFields* fields, Texel local, Vec2 at, Vec2 direction) const {
    static_cast<void>(at);
    return sample(fields, local, direction);
  }

  // C/D ratio of the segment inside the texel `to`, entered from the neighbour texel `from`, whose
  // centres are `step_px` apart. Always finite and within the method's documented bounds.
  virtual double cd(const TexelSample& from, const TexelSample& to, double step_px, StepDetail* detail) const = 0;

  // The range every value of cd() lies in.
  virtual double cd_lower_bound() const = 0;
  virtual double cd_upper_bound() const = 0;

 protected:
  explicit Method(BuiltinMethod builtin = BuiltinMethod::none) : builtin_(builtin) {}

 private:
  BuiltinMethod builtin_;
};

using MethodPtr = std::shared_ptr<const Method>;

}  // namespace ph
