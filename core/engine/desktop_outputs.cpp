#include "core/engine/desktop_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ph {

namespace {

bool on_output(const Rect& r, Vec2 p) {
  return p.x >= r.x && p.x < static_cast<double>(r.x) + r.w && p.y >= r.y && p.y < static_cast<double>(r.y) + r.h;
}

// `p` clamped into `r`, short of its far edges.
Vec2 clamped_into(const Rect& r, Vec2 p) {
  const double right = std::nextafter(static_cast<double>(r.x) + r.w, r.x);
  const double bottom = std::nextafter(static_cast<double>(r.y) + r.h, r.y);
  return {std::clamp(p.x, static_cast<double>(r.x), right), std::clamp(p.y, static_cast<double>(r.y), bottom)};
}

}  // namespace

bool output_within(const Rect& output, const Rect& desktop) {
  return output.w >= 1 && output.h >= 1 && output.x >= desktop.x && output.y >= desktop.y &&
         std::int64_t{output.x} + output.w <= std::int64_t{desktop.x} + desktop.w &&
         std::int64_t{output.y} + output.h <= std::int64_t{desktop.y} + desktop.h;
}

bool on_an_output(const std::vector<Rect>& outputs, Vec2 p) {
  return std::any_of(outputs.begin(), outputs.end(), [p](const Rect& r) { return on_output(r, p); });
}

Vec2 stop_on_outputs(const std::vector<Rect>& outputs, Vec2 from, Vec2 to) {
  for (const Rect& r : outputs) {
    if (on_output(r, from)) return clamped_into(r, to);
  }
  Vec2 nearest = to;
  double best = std::numeric_limits<double>::infinity();
  for (const Rect& r : outputs) {
    const Vec2 p = clamped_into(r, to);
    const double d = length(p - to);
    if (d < best) {
      best = d;
      nearest = p;
    }
  }
  return nearest;
}

bool outputs_cover(const std::vector<Rect>& outputs, Rect area) {
  // The area cut along every output's edges: each cell lies wholly on an output or wholly off all of them.
  std::vector<std::int64_t> xs{area.x, std::int64_t{area.x} + area.w}, ys{area.y, std::int64_t{area.y} + area.h};
  for (const Rect& r : outputs) {
    xs.push_back(r.x);
    xs.push_back(std::int64_t{r.x} + r.w);
    ys.push_back(r.y);
    ys.push_back(std::int64_t{r.y} + r.h);
  }
  for (auto* cuts : {&xs, &ys}) {
    std::sort(cuts->begin(), cuts->end());
    cuts->erase(std::unique(cuts->begin(), cuts->end()), cuts->end());
  }
  for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
    for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
      const double cx = (static_cast<double>(xs[i]) + static_cast<double>(xs[i + 1])) / 2.0;
      const double cy = (static_cast<double>(ys[j]) + static_cast<double>(ys[j + 1])) / 2.0;
      const bool in_area = on_output(area, {cx, cy});
      if (in_area && !on_an_output(outputs, {cx, cy})) return false;
    }
  }
  return true;
}

bool outputs_contiguous(const std::vector<Rect>& outputs) {
  if (outputs.empty()) return true;
  const auto touch = [](const Rect& a, const Rect& b) {
    return std::int64_t{a.x} <= std::int64_t{b.x} + b.w && std::int64_t{a.x} + a.w >= b.x &&
           std::int64_t{a.y} <= std::int64_t{b.y} + b.h && std::int64_t{a.y} + a.h >= b.y;
  };
  std::vector<bool> reached(outputs.size(), false);
  std::vector<std::size_t> next{0};
  reached[0] = true;
  while (!next.empty()) {
    const std::size_t i = next.back();
    next.pop_back();
    for (std::size_t j = 0; j < outputs.size(); ++j) {
      if (!reached[j] && touch(outputs[i], outputs[j])) {
        reached[j] = true;
        next.push_back(j);
      }
    }
  }
  return std::all_of(reached.begin(), reached.end(), [](bool r) { return r; });
}

std::vector<Rect> pointer_outputs(Rect desktop, std::vector<Rect> outputs) {
  const auto inside = [&desktop](const Rect& r) { return output_within(r, desktop); };
  if (outputs.size() > kMaxOutputs || !std::all_of(outputs.begin(), outputs.end(), inside) ||
      !outputs_contiguous(outputs) || outputs_cover(outputs, desktop)) {
    return {};
  }
  return outputs;
}

}  // namespace ph
