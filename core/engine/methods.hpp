// The list of methods. Adding a method is its own file (a Method subclass with kName, kParamKeys, Params,
// parse_params and sample_exact) and one line here: the scene file, trace, the accuracy command and the
// ground truth then know it by its registry entry, and the walkers call it without a virtual call per texel
// (one visit per region a frame meets). A method outside this list (a test's, a registry entry added at run
// time) still works everywhere, through the virtual interface.
#pragma once

#include "core/engine/method_curvature.hpp"
#include "core/engine/method_depth.hpp"
#include "core/engine/method_flat.hpp"
#include "core/engine/method_hybrid.hpp"
#include "core/engine/method_registry.hpp"

namespace ph {

template <typename... M>
struct MethodList {};

using Methods = MethodList<CurvatureMethod, DepthMethod, FlatMethod, HybridMethod>;

namespace detail {

template <typename F>
decltype(auto) visit_in(const Method& method, F& f, MethodList<>) {
  return f(method);
}

template <typename F, typename First, typename... Rest>
decltype(auto) visit_in(const Method& method, F& f, MethodList<First, Rest...>) {
  if (method.tag() == method_tag<First>()) return f(static_cast<const First&>(method));
  return visit_in(method, f, MethodList<Rest...>{});
}

template <typename... M>
MethodRegistry registry_of(MethodList<M...>) {
  MethodRegistry registry;
  (registry.add(method_entry<M>()), ...);
  return registry;
}

}  // namespace detail

// Calls f with the method as its concrete class when it is one of Methods (its calls then inline), else as
// Method (virtual calls). f must return the same type for every class.
template <typename F>
decltype(auto) visit_method(const Method& method, F&& f) {
  return detail::visit_in(method, f, Methods{});
}

// The registry of the listed methods, in their order (the scene file's "allowed: ..." order).
inline MethodRegistry builtin_methods() { return detail::registry_of(Methods{}); }

}  // namespace ph
