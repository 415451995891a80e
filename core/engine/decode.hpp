// Decoding of normal and depth images into fields (docs/METHODS.md, "Screen, regions and fields"), and the one-time
// resampling to a region's on-screen size. Pure functions: the pixels come from config/image_io.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/engine/field.hpp"

namespace ph {

// Pixels as read from an image file, before any interpretation.
struct RawImage {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t channels = 0;
  bool is_float = false;       // float/half pixels hold signed values as stored
  std::vector<float> pixels;   // row-major, channels interleaved; integer formats scaled to [0, 1]
  std::uint32_t code_max = 0;  // largest code of an integer format (255, 65535); 0 when unknown or float
};

// Raised for an image or field that cannot be used; the message names the file when one is known.
class FieldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class GreenConvention { opengl, directx };  // OpenGL: +green points to the top of the image (screen -y)
enum class NormalEncoding { automatic, unorm, signed_values };  // automatic: unorm for integer images

struct NormalDecodeOptions {
  GreenConvention green = GreenConvention::opengl;
  NormalEncoding encoding = NormalEncoding::automatic;
};

// The largest |relief_px|: a million screen px of height per unit of value is far beyond any screen's relief, and
// beyond it the heights of a unorm map no longer fit in a float.
inline constexpr double kMaxReliefPx = 1e6;
// The largest |depth_zero|: a float map's values (elevations, say) are far below it, and beyond it the difference
// v - depth_zero keeps none of a float's precision for v, so that every height is the same, or infinite.
inline constexpr double kMaxDepthZero = 1e6;

struct DepthDecodeOptions {
  double depth_zero = 0.0;   // stored value that means height 0, |depth_zero| <= kMaxDepthZero
  double relief_px = 100.0;  // screen px of height per unit of stored value, |relief_px| <= kMaxReliefPx
};

// What decoding found; invalid texels were repaired.
struct DecodeReport {
  std::size_t texels = 0;
  std::size_t invalid_texels = 0;
  // The step between neighbouring stored values in what was decoded: 2 / code_max of a normal component from a
  // unorm map (1 / code_max from a signed one), relief_px / code_max px of height from a depth map; 0 for float.
  double value_step = 0.0;
  // The image's own size (texels = width x height); a region of another size gets it resampled.
  std::int32_t width = 0;
  std::int32_t height = 0;
};

// The standard deviation of a gradient's rounding error from the storage of its map, given the map's value_step:
// a normal component rounded to steps q errs uniformly within +-q/2 (q / sqrt(12); in slope, near flat), and a
// central difference (h(x+1) - h(x-1)) / 2 of heights rounded to steps q errs by q / sqrt(24). 0 for a float map.
double gradient_rounding_of_normals(double value_step);
double gradient_rounding_of_depth(double value_step);
// The standard deviation of a height's rounding error from a depth map's storage: value_step / sqrt(12). 0 for float.
double height_rounding_of_depth(double value_step);
// Its inverse: the step between a depth map's stored heights (px) whose rounding has that standard deviation, for
// fields that keep only the deviation (RegionFields::depth_rounding).
double depth_step_of_rounding(double height_rounding);

// Unit normals in the screen frame. A unorm image cannot store 0 (2c/cmax - 1 is +-1/cmax around it), so
// tangent components within one code of 0 are taken as 0: a flat area of an 8- or 16-bit map is exactly
// flat (C/D exactly 1) rather than tilted by 1/cmax. Invalid texels (length < 0.5, n_z <= 0, non-finite) take the value
// of the nearest valid texel, or flat when there is none. Throws FieldError on a wrong channel count.
NormalImage decode_normals(const RawImage& image, const NormalDecodeOptions& options, DecodeReport& report);

// The same normals as height gradients, gradient_from_normals(decode_normals(...)) in one pass and without the
// image of normals: what a region whose map already has its size needs. A unorm map's rows are decoded in bands on
// `threads` threads (0: one per core, at most kMaxRowBandThreads; bands of kMinRowBandRows rows at least), each
// gradient the same whatever the number; the repair of invalid texels follows on the caller's thread.
GradientField decode_normals_to_gradient(const RawImage& image, const NormalDecodeOptions& options,
                                         DecodeReport& report, unsigned threads = 0);

// Heights in screen px, h = (v - depth_zero) * relief_px. Non-finite texels are repaired like normals.
DepthField decode_depth(const RawImage& image, const DepthDecodeOptions& options, DecodeReport& report);

// Resampling to w x h texels: bilinear when enlarging, area average when shrinking.
// Normals are renormalised afterwards. Same size returns a copy.
NormalImage resample_normals(const NormalImage& image, std::int32_t width, std::int32_t height);
DepthField resample_depth(const DepthField& depth, std::int32_t width, std::int32_t height);

}  // namespace ph
