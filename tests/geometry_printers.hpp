// Readable test failures: gtest prints rectangles and points by these instead of their bytes.
#pragma once

#include <ostream>

#include "core/engine/geometry.hpp"

namespace ph {

inline void PrintTo(const Rect& r, std::ostream* os) { *os << r.w << "x" << r.h << "+" << r.x << "+" << r.y; }
inline void PrintTo(const Vec2& v, std::ostream* os) { *os << "(" << v.x << ", " << v.y << ")"; }

}  // namespace ph
