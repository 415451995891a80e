// Decoding of normal and depth images and resampling to a region's size, as docs/METHODS.md specifies in
// "Screen, regions and fields".
#include "core/engine/decode.hpp"
#include "tests/band_agreement.hpp"
#include "tests/thrown_message.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace ph {
namespace {

constexpr float nan_value = std::numeric_limits<float>::quiet_NaN();
constexpr float inf_value = std::numeric_limits<float>::infinity();
constexpr NormalDecodeOptions unorm_options{GreenConvention::opengl, NormalEncoding::unorm};
constexpr NormalDecodeOptions signed_options{GreenConvention::opengl, NormalEncoding::signed_values};

RawImage raw(std::int32_t width, std::int32_t height, std::int32_t channels, bool is_float, std::vector<float> pixels) {
  return RawImage{width, height, channels, is_float, std::move(pixels)};
}

// One texel per entry, signed float RGB.
RawImage signed_rgb(std::int32_t width, std::int32_t height, const std::vector<Normal>& tangent_normals) {
  std::vector<float> pixels;
  for (const Normal& n : tangent_normals) pixels.insert(pixels.end(), {n.x, n.y, n.z});
  return raw(width, height, 3, true, std::move(pixels));
}

// A hemisphere of radius `radius` texels centred in a side x side unorm image, tangent space with
// +green toward the top of the image; flat outside. Returns the expected screen-frame normals too.
struct Hemisphere {
  RawImage image;
  NormalImage screen;
};

Hemisphere make_hemisphere(std::int32_t side, double radius) {
  Hemisphere h{raw(side, side, 3, false, {}), NormalImage(side, side)};
  const double centre = side / 2.0;
  for (std::int32_t y = 0; y < side; ++y) {
    for (std::int32_t x = 0; x < side; ++x) {
      const double u = (x + 0.5 - centre) / radius;
      const double v = (y + 0.5 - centre) / radius;  // screen y, down
      const double r2 = u * u + v * v;
      const double nx = r2 < 1.0 ? u : 0.0;
      const double ny = r2 < 1.0 ? v : 0.0;
      const double nz = r2 < 1.0 ? std::sqrt(1.0 - r2) : 1.0;
      h.screen.at(x, y) = {static_cast<float>(nx), static_cast<float>(ny), static_cast<float>(nz)};
      const double green = -ny;  // tangent space: up
      h.image.pixels.insert(
          h.image.pixels.end(),
          {static_cast<float>((nx + 1) / 2), static_cast<float>((green + 1) / 2), static_cast<float>((nz + 1) / 2)});
    }
  }
  return h;
}

void expect_unit_and_finite(const NormalImage& normals) {
  for (const Normal& n : normals.values) {
    ASSERT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
    ASSERT_NEAR(std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z), 1.0, 1e-5);
    ASSERT_GT(n.z, 0.0f);
  }
}

void expect_normal_near(Normal actual, Normal expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

// --- Normals: conventions -------------------------------------------------------------------------

// A float depth map may hold heights up to 3.4e38: the slopes between them stay finite and within the
// bound that slopes from normals have (what the daemon's image reader hands back must pass its checks).
TEST(GradientFromDepth, HugeHeightsGiveBoundedFiniteSlopes) {
  DepthField depth(3, 2);
  depth.values = {-3.0e38f, 3.0e38f, 0.0f, 1.0f, 2.0e18f, 2.0e18f};
  const GradientField g = gradient_from_depth(depth);
  for (const Gradient& s : g.values) {
    EXPECT_TRUE(std::isfinite(s.x) && std::isfinite(s.y));
    EXPECT_LE(std::abs(s.x), kMaxSlope);
    EXPECT_LE(std::abs(s.y), kMaxSlope);
  }
  EXPECT_EQ(g.at(0, 0).x, kMaxSlope);   // -3e38 to 3e38: steeply up, clamped
  EXPECT_EQ(g.at(0, 1).x, kMaxSlope);   // 1 to 2e18 over two texels
  EXPECT_EQ(g.at(2, 0).y, kMaxSlope);   // 0 to 2e18
  EXPECT_EQ(g.at(1, 0).y, -kMaxSlope);  // 3e38 to 2e18
}

// In bands of rows on threads (a load's) the slopes are those of one band, to the bit, the band's first and last rows
// (which read the rows either side, in the band before and after) included.
TEST(GradientFromDepth, InBandsAgreesWithOneBandToTheBit) {
  DepthField depth(97, 300);
  std::uint32_t state = 4321;
  for (float& h : depth.values) {
    state = state * 1664525u + 1013904223u;
    h = static_cast<float>(state >> 8) / 65536.0f;  // 0-256 px, every texel its own
  }
  expect_bands_agree_with_one([&](unsigned threads) { return gradient_from_depth(depth, threads); });
}

TEST(DecodeNormals, OpenGlHemisphereGivesScreenFrameNormals) {
  const Hemisphere hemisphere = make_hemisphere(33, 14.0);
  DecodeReport report;
  const NormalImage normals = decode_normals(hemisphere.image, {}, report);
  EXPECT_EQ(report.texels, 33u * 33u);
  EXPECT_EQ(report.invalid_texels, 0u);
  ASSERT_EQ(normals.width, 33);
  ASSERT_EQ(normals.height, 33);
  for (std::size_t i = 0; i < normals.values.size(); ++i) {
    expect_normal_near(normals.values[i], hemisphere.screen.values[i], 1e-5);
  }
  // Near the top of the image the dome faces up the screen (-y), near the left it faces left.
  EXPECT_LT(normals.at(16, 4).y, -0.5f);
  EXPECT_GT(normals.at(16, 28).y, 0.5f);
  EXPECT_LT(normals.at(4, 16).x, -0.5f);
  EXPECT_NEAR(normals.at(16, 16).z, 1.0f, 1e-3);
}

TEST(DecodeNormals, DirectXFlipsGreen) {
  const Hemisphere hemisphere = make_hemisphere(33, 14.0);
  DecodeReport report;
  const NormalImage opengl =
      decode_normals(hemisphere.image, {GreenConvention::opengl, NormalEncoding::automatic}, report);
  const NormalImage directx =
      decode_normals(hemisphere.image, {GreenConvention::directx, NormalEncoding::automatic}, report);
  EXPECT_GT(directx.at(16, 4).y, 0.5f);
  for (std::size_t i = 0; i < opengl.values.size(); ++i) {
    EXPECT_FLOAT_EQ(directx.values[i].x, opengl.values[i].x);
    EXPECT_FLOAT_EQ(directx.values[i].y, -opengl.values[i].y);
    EXPECT_FLOAT_EQ(directx.values[i].z, opengl.values[i].z);
  }
}

TEST(DecodeNormals, UnormMidGreyIsFlat) {
  DecodeReport report;
  const NormalImage n = decode_normals(raw(1, 1, 3, false, {0.5f, 0.5f, 1.0f}), {}, report);
  expect_normal_near(n.at(0, 0), {0, 0, 1}, 1e-6);
}

TEST(DecodeNormals, FloatImagesHoldSignedValues) {
  DecodeReport report;
  const float s = static_cast<float>(std::sqrt(0.5));
  const NormalImage n = decode_normals(raw(1, 1, 3, true, {s, 0.0f, s}), {}, report);
  expect_normal_near(n.at(0, 0), {s, 0, s}, 1e-6);
  // The same values read as unorm would be a different normal.
  const NormalImage as_unorm = decode_normals(raw(1, 1, 3, true, {s, 0.0f, s}), unorm_options, report);
  const double nx = 2 * s - 1, ny = 1.0, nz = 2 * s - 1;  // green -1 in tangent space = screen +1
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  expect_normal_near(as_unorm.at(0, 0),
                     {static_cast<float>(nx / len), static_cast<float>(ny / len), static_cast<float>(nz / len)}, 1e-6);
}

TEST(DecodeNormals, SignedEncodingOverridesIntegerImages) {
  DecodeReport report;
  const NormalImage n = decode_normals(raw(1, 1, 3, false, {0.0f, 0.6f, 0.8f}), signed_options, report);
  expect_normal_near(n.at(0, 0), {0.0f, -0.6f, 0.8f}, 1e-6);
}

TEST(DecodeNormals, Renormalises) {
  DecodeReport report;
  const NormalImage n = decode_normals(raw(2, 1, 3, true, {0.6f, 0.0f, 0.6f, 0.0f, 0.0f, 7.0f}), {}, report);
  const float s = static_cast<float>(std::sqrt(0.5));
  expect_normal_near(n.at(0, 0), {s, 0, s}, 1e-6);
  expect_normal_near(n.at(1, 0), {0, 0, 1}, 1e-6);
  EXPECT_EQ(report.invalid_texels, 0u);
}

TEST(DecodeNormals, AlphaIsIgnored) {
  DecodeReport report;
  const NormalImage n = decode_normals(raw(1, 1, 4, false, {0.5f, 0.5f, 1.0f, 0.0f}), {}, report);
  expect_normal_near(n.at(0, 0), {0, 0, 1}, 1e-6);
  EXPECT_EQ(report.invalid_texels, 0u);
}

// --- Normals: invalid texels ----------------------------------------------------------------------

TEST(DecodeNormals, InvalidTexelsAreCountedAndTakeTheNearestValid) {
  // Row of 7: left end tilted right, right end tilted left, invalid texels between.
  const float s = static_cast<float>(std::sqrt(0.5));
  const Normal left{s, 0, s};
  const Normal right{-s, 0, s};
  const std::vector<Normal> row{left,
                                {0, 0, 0},          // zero length
                                {0.1f, 0, 0.2f},    // length < 0.5
                                {0, 0, -1},         // n_z < 0
                                {1, 0, 0},          // n_z = 0
                                {nan_value, 0, 1},  // not finite
                                right};
  DecodeReport report;
  const NormalImage n = decode_normals(signed_rgb(7, 1, row), {}, report);
  EXPECT_EQ(report.texels, 7u);
  EXPECT_EQ(report.invalid_texels, 5u);
  expect_normal_near(n.at(1, 0), left, 1e-6);
  expect_normal_near(n.at(2, 0), left, 1e-6);
  expect_normal_near(n.at(4, 0), right, 1e-6);
  expect_normal_near(n.at(5, 0), right, 1e-6);
  expect_unit_and_finite(n);
}

// A unorm map decoded in bands of rows on several threads: every gradient the same to the bit as in one band, and
// the invalid texels (black pixels beside the cuts between bands, and a whole row of them) counted and repaired alike.
TEST(DecodeNormals, ToGradientInBandsAgreesWithOneBandToTheBit) {
  const std::int32_t width = 97, height = 300;
  RawImage image = raw(width, height, 3, false, std::vector<float>(static_cast<std::size_t>(width) * height * 3));
  image.code_max = 255;
  std::uint32_t state = 12345;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {  // tilted every way, n_z > 0
    state = state * 1664525u + 1013904223u;
    const std::uint32_t code = i % 3 == 2 ? 192 + (state >> 24) % 64 : 64 + (state >> 24) % 128;
    image.pixels[i] = static_cast<float>(code) / 255.0f;
  }
  auto blacken = [&](std::int32_t x, std::int32_t y) {
    for (std::int32_t c = 0; c < 3; ++c) image.pixels[(static_cast<std::size_t>(y) * width + x) * 3 + c] = 0.0f;
  };
  for (const std::int32_t y : {74, 75, 149, 150, 224, 225}) blacken(y % width, y);
  for (std::int32_t x = 0; x < width; ++x) blacken(x, 100);
  DecodeReport one_report;
  const GradientField one = decode_normals_to_gradient(image, unorm_options, one_report, 1);
  EXPECT_EQ(one_report.invalid_texels, 6u + static_cast<std::size_t>(width));
  for (const unsigned threads : {2u, 3u, 4u}) {
    SCOPED_TRACE(threads);
    DecodeReport report;
    const GradientField banded = decode_normals_to_gradient(image, unorm_options, report, threads);
    EXPECT_EQ(report.invalid_texels, one_report.invalid_texels);
    ASSERT_EQ(banded.values.size(), one.values.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < one.values.size(); ++i) {
      differing += std::memcmp(&banded.values[i], &one.values[i], sizeof(Gradient)) != 0 ? 1 : 0;
    }
    EXPECT_EQ(differing, 0u);
  }
}

TEST(DecodeNormals, RepairReachesDiagonally) {
  // 5 x 5, only the top-left corner valid: every texel takes its value.
  std::vector<Normal> texels(25, Normal{0, 0, -1});
  texels[0] = {0.6f, 0, 0.8f};
  DecodeReport report;
  const NormalImage n = decode_normals(signed_rgb(5, 5, texels), {}, report);
  EXPECT_EQ(report.invalid_texels, 24u);
  for (const Normal& v : n.values) expect_normal_near(v, {0.6f, 0, 0.8f}, 1e-6);
}

TEST(DecodeNormals, UnormBlackAndInfinityAreInvalid) {
  DecodeReport report;
  const NormalImage n =
      decode_normals(raw(3, 1, 3, false, {0.5f, 0.5f, 0.5f, inf_value, 0.5f, 1.0f, 0.5f, 0.5f, 1.0f}), {}, report);
  EXPECT_EQ(report.invalid_texels, 2u);
  for (const Normal& v : n.values) expect_normal_near(v, {0, 0, 1}, 1e-6);
}

TEST(DecodeNormals, NoValidTexelGivesFlat) {
  DecodeReport report;
  const NormalImage n =
      decode_normals(signed_rgb(3, 2, std::vector<Normal>(6, Normal{nan_value, nan_value, nan_value})), {}, report);
  EXPECT_EQ(report.invalid_texels, 6u);
  for (const Normal& v : n.values) expect_normal_near(v, {0, 0, 1}, 0.0);
}

// --- Normals: channel counts ----------------------------------------------------------------------

TEST(DecodeNormals, WrongChannelCountsThrowSayingWhatIsNeeded) {
  DecodeReport report;
  for (const std::int32_t channels : {1, 2, 5}) {
    const RawImage image = raw(2, 2, channels, false, std::vector<float>(4 * channels, 0.5f));
    const std::string message = thrown_message<FieldError>([&] { decode_normals(image, {}, report); });
    EXPECT_NE(message.find("3 (RGB) or 4 (RGBA)"), std::string::npos) << message;
    EXPECT_NE(message.find("has " + std::to_string(channels)), std::string::npos) << message;
  }
}

TEST(DecodeNormals, InconsistentPixelCountThrows) {
  DecodeReport report;
  EXPECT_THROW(decode_normals(raw(2, 2, 3, false, std::vector<float>(5, 0.5f)), {}, report), FieldError);
  EXPECT_THROW(decode_normals(raw(0, 2, 3, false, {}), {}, report), FieldError);
}

// --- Depth ----------------------------------------------------------------------------------------

TEST(DecodeDepth, ScalesAroundDepthZero) {
  DecodeReport report;
  const DepthField d = decode_depth(raw(3, 1, 1, false, {0.0f, 0.5f, 1.0f}), {0.5, 40.0}, report);
  EXPECT_FLOAT_EQ(d.at(0, 0), -20.0f);
  EXPECT_FLOAT_EQ(d.at(1, 0), 0.0f);
  EXPECT_FLOAT_EQ(d.at(2, 0), 20.0f);
  EXPECT_EQ(report.texels, 3u);
  EXPECT_EQ(report.invalid_texels, 0u);
}

TEST(DecodeDepth, GreyAlphaIgnoresAlpha) {
  DecodeReport report;
  const DepthField d = decode_depth(raw(2, 1, 2, false, {0.25f, 0.0f, 1.0f, 0.5f}), {}, report);
  EXPECT_FLOAT_EQ(d.at(0, 0), 25.0f);
  EXPECT_FLOAT_EQ(d.at(1, 0), 100.0f);
}

TEST(DecodeDepth, WrongChannelCountsThrow) {
  DecodeReport report;
  for (const std::int32_t channels : {3, 4}) {
    const RawImage image = raw(1, 1, channels, false, std::vector<float>(channels, 0.5f));
    const std::string message = thrown_message<FieldError>([&] { decode_depth(image, {}, report); });
    EXPECT_NE(message.find("1 channel"), std::string::npos) << message;
    EXPECT_NE(message.find("has " + std::to_string(channels)), std::string::npos) << message;
  }
}

TEST(DecodeDepth, NonFiniteTexelsTakeTheNearestValid) {
  DecodeReport report;
  const DepthField d = decode_depth(raw(5, 1, 1, true, {1.0f, nan_value, inf_value, -inf_value, 2.0f}), {}, report);
  EXPECT_EQ(report.invalid_texels, 3u);
  EXPECT_FLOAT_EQ(d.at(1, 0), 100.0f);
  EXPECT_FLOAT_EQ(d.at(3, 0), 200.0f);
  for (const float h : d.values) EXPECT_TRUE(std::isfinite(h));
}

TEST(DecodeDepth, OverflowingHeightIsInvalid) {
  DecodeReport report;
  const DepthField d = decode_depth(raw(2, 1, 1, true, {1.0f, 3.0e38f}), {}, report);
  EXPECT_EQ(report.invalid_texels, 1u);
  EXPECT_FLOAT_EQ(d.at(1, 0), 100.0f);
}

TEST(DecodeDepth, NoValidTexelGivesZero) {
  DecodeReport report;
  const DepthField d = decode_depth(raw(2, 2, 1, true, std::vector<float>(4, nan_value)), {}, report);
  EXPECT_EQ(report.invalid_texels, 4u);
  for (const float h : d.values) EXPECT_EQ(h, 0.0f);
}

// --- Resampling -----------------------------------------------------------------------------------

struct Size {
  std::int32_t width;
  std::int32_t height;
};

// Enlarging, shrinking, by integer and fractional factors, and both at once.
const std::vector<Size> target_sizes{{7, 5}, {16, 10}, {23, 17}, {3, 2}, {5, 4}, {1, 1}, {20, 3}, {2, 13}, {7, 1}};

DepthField ramp(std::int32_t width, std::int32_t height, double a, double b, double c) {
  DepthField d(width, height);
  for (std::int32_t y = 0; y < height; ++y) {
    for (std::int32_t x = 0; x < width; ++x) d.at(x, y) = static_cast<float>(a * (x + 0.5) + b * (y + 0.5) + c);
  }
  return d;
}

TEST(Resample, ConstantDepthStaysConstant) {
  const DepthField constant(7, 5, 12.5f);
  for (const Size size : target_sizes) {
    const DepthField r = resample_depth(constant, size.width, size.height);
    ASSERT_EQ(r.width, size.width);
    ASSERT_EQ(r.height, size.height);
    ASSERT_EQ(r.values.size(), static_cast<std::size_t>(size.width * size.height));
    for (const float h : r.values) EXPECT_NEAR(h, 12.5f, 1e-5);
  }
}

TEST(Resample, ConstantNormalsStayConstantAndUnit) {
  const Normal tilted{0.36f, -0.48f, 0.8f};
  const NormalImage constant(7, 5, tilted);
  for (const Size size : target_sizes) {
    const NormalImage r = resample_normals(constant, size.width, size.height);
    ASSERT_EQ(r.width, size.width);
    ASSERT_EQ(r.height, size.height);
    for (const Normal& n : r.values) expect_normal_near(n, tilted, 1e-6);
  }
}

TEST(Resample, SameSizeIsACopy) {
  const DepthField d = ramp(4, 3, 1.0, 2.0, 0.0);
  EXPECT_EQ(resample_depth(d, 4, 3).values, d.values);
  const Hemisphere h = make_hemisphere(9, 4.0);
  const NormalImage r = resample_normals(h.screen, 9, 9);
  for (std::size_t i = 0; i < r.values.size(); ++i) expect_normal_near(r.values[i], h.screen.values[i], 0.0);
}

// Shrinking by an integer factor averages whole texels, so a ramp stays exactly linear; a fractional
// factor weighs partly covered texels by coverage, which bends it by at most half a source texel's step.
void expect_shrunk_ramp(Size size, double tolerance) {
  const double a = 1.5, b = -0.75, c = 3.0;
  const DepthField r = resample_depth(ramp(24, 18, a, b, c), size.width, size.height);
  const double sx = 24.0 / size.width;
  const double sy = 18.0 / size.height;
  for (std::int32_t y = 0; y < size.height; ++y) {
    for (std::int32_t x = 0; x < size.width; ++x) {
      const double expected = a * (x + 0.5) * sx + b * (y + 0.5) * sy + c;
      EXPECT_NEAR(r.at(x, y), expected, tolerance) << size.width << "x" << size.height << " at " << x << "," << y;
    }
  }
}

TEST(Resample, ShrinkingByIntegerFactorsKeepsARampLinear) {
  for (const Size size : std::vector<Size>{{12, 9}, {8, 6}, {6, 3}, {24, 2}, {1, 1}}) expect_shrunk_ramp(size, 1e-4);
}

TEST(Resample, ShrinkingByFractionalFactorsKeepsARampNearlyLinear) {
  for (const Size size : std::vector<Size>{{7, 5}, {5, 11}, {23, 17}}) expect_shrunk_ramp(size, 0.5 * (1.5 + 0.75));
}

// Enlarging bilinearly keeps a ramp linear between the outermost source texel centres.
TEST(Resample, EnlargingKeepsARampLinearInside) {
  const DepthField d = ramp(6, 4, 2.0, 1.0, -1.0);
  for (const Size size : std::vector<Size>{{12, 8}, {17, 9}, {6, 10}}) {
    const DepthField r = resample_depth(d, size.width, size.height);
    const double sx = 6.0 / size.width;
    const double sy = 4.0 / size.height;
    for (std::int32_t y = 0; y < size.height; ++y) {
      for (std::int32_t x = 0; x < size.width; ++x) {
        const double u = (x + 0.5) * sx;  // source coordinate of the texel centre
        const double v = (y + 0.5) * sy;
        if (u < 0.5 || u > 5.5 || v < 0.5 || v > 3.5) continue;  // the border holds the edge texels' values
        EXPECT_NEAR(r.at(x, y), 2.0 * u + v - 1.0, 1e-4) << size.width << "x" << size.height << " at " << x << "," << y;
      }
    }
  }
}

TEST(Resample, NormalsStayUnitAndFinite) {
  const Hemisphere h = make_hemisphere(32, 15.0);
  DecodeReport report;
  const NormalImage decoded = decode_normals(h.image, {}, report);
  for (const Size size : std::vector<Size>{{64, 64}, {100, 37}, {13, 13}, {7, 90}, {1, 1}, {31, 33}}) {
    const NormalImage r = resample_normals(decoded, size.width, size.height);
    ASSERT_EQ(r.values.size(), static_cast<std::size_t>(size.width * size.height));
    expect_unit_and_finite(r);
  }
}

TEST(Resample, OppositeNormalsAveragingToZeroBecomeFlatNotNaN) {
  NormalImage n(2, 1);
  n.at(0, 0) = {1, 0, 0};
  n.at(1, 0) = {-1, 0, 0};
  const NormalImage r = resample_normals(n, 1, 1);
  expect_normal_near(r.at(0, 0), {0, 0, 1}, 0.0);
}

TEST(Resample, RefusesEmptySizes) {
  const DepthField d(3, 3, 1.0f);
  EXPECT_THROW(resample_depth(d, 0, 3), FieldError);
  EXPECT_THROW(resample_depth(d, 3, -1), FieldError);
  EXPECT_THROW(resample_normals(NormalImage(3, 3), 3, 0), FieldError);
  EXPECT_THROW(resample_depth(DepthField{}, 3, 3), FieldError);
}

}  // namespace
}  // namespace ph

namespace ph {
namespace {

// A unorm map cannot store 0: the codes around it decode to +-1/cmax. They must come out exactly flat,
// or every flat area of an 8-bit map would be a 0.4% slope with C/D != 1.
TEST(DecodeNormals, QuantisedZeroIsExactlyFlat) {
  for (std::uint32_t cmax : {255u, 65535u}) {
    const float below = static_cast<float>((cmax / 2) / static_cast<double>(cmax));
    const float above = static_cast<float>((cmax / 2 + 1) / static_cast<double>(cmax));
    RawImage image{2, 1, 3, false, {below, above, 1.0f, above, below, 1.0f}, cmax};
    DecodeReport report;
    const NormalImage n = decode_normals(image, {}, report);
    for (const Normal& v : n.values) {
      EXPECT_EQ(v.x, 0.0f) << cmax;
      EXPECT_EQ(v.y, 0.0f) << cmax;
      EXPECT_EQ(v.z, 1.0f) << cmax;
    }
    // One code further from 0 is a real slope and stays.
    const float next = static_cast<float>((cmax / 2 + 2) / static_cast<double>(cmax));
    image.pixels = {next, above, 1.0f, above, above, 1.0f};
    const NormalImage m = decode_normals(image, {}, report);
    EXPECT_GT(m.values[0].x, 0.0f);
  }
}

}  // namespace
}  // namespace ph
