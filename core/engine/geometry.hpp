// Screen geometry shared by the whole core: vectors in screen pixels (x right, y down),
// integer texel coordinates and axis-aligned integer rectangles.
#pragma once

#include <cmath>
#include <cstdint>

namespace ph {

// A point or displacement in screen pixels (float precision kept in double).
struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

constexpr Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
constexpr Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
constexpr Vec2 operator*(Vec2 a, double s) { return {a.x * s, a.y * s}; }
constexpr bool operator==(Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }
inline double length(Vec2 v) { return std::hypot(v.x, v.y); }
inline bool is_finite(Vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

// Integer index of one screen pixel (= one texel of any region covering it).
struct Texel {
  std::int32_t x = 0;
  std::int32_t y = 0;
};

constexpr bool operator==(Texel a, Texel b) { return a.x == b.x && a.y == b.y; }
constexpr bool operator!=(Texel a, Texel b) { return !(a == b); }
constexpr Texel operator+(Texel a, Texel b) { return {a.x + b.x, a.y + b.y}; }

// Texel containing a point; a point on a boundary belongs to the texel on its +x/+y side.
inline Texel texel_at(Vec2 p) {
  return {static_cast<std::int32_t>(std::floor(p.x)), static_cast<std::int32_t>(std::floor(p.y))};
}

// Screen rectangle [x, x + w) x [y, y + h) in whole pixels.
struct Rect {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t w = 0;
  std::int32_t h = 0;

  constexpr bool contains(Texel t) const { return t.x >= x && t.x < x + w && t.y >= y && t.y < y + h; }
  constexpr std::int64_t area() const { return std::int64_t{w} * h; }
  constexpr bool operator==(const Rect&) const = default;
};

// Coordinates and sizes past this are not a desktop: the scene file, the control socket's layout and a replay's
// --desktop refuse them (absolute output counts half pixels of the desktop in 32-bit axis ranges).
inline constexpr std::int32_t kMaxDesktopCoordinate = 1 << 20;

// Sides from 1 to kMaxDesktopCoordinate px, the corner within +-kMaxDesktopCoordinate.
constexpr bool is_valid_desktop(const Rect& d) {
  return d.w >= 1 && d.h >= 1 && d.w <= kMaxDesktopCoordinate && d.h <= kMaxDesktopCoordinate &&
         d.x >= -kMaxDesktopCoordinate && d.x <= kMaxDesktopCoordinate && d.y >= -kMaxDesktopCoordinate &&
         d.y <= kMaxDesktopCoordinate;
}

// The cursor model never leaves [-kWorldLimitPx, kWorldLimitPx]^2, so texel indices always fit.
inline constexpr double kWorldLimitPx = 1.0e9;

// Time of an input event, microseconds on the source's clock. The core never reads a clock itself.
using TimeUs = std::int64_t;

}  // namespace ph
