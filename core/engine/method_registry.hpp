// One entry per method: its name, the keys of its parameter table and their parser, and its factory. The
// scene file, the tools and the ground truth know the methods through these entries only; the walkers'
// fast path is the list in core/engine/methods.hpp, which also builds the registry of the built-in methods.
#pragma once

#include <any>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/engine/method.hpp"

namespace ph {

// Where a method reads its parameters from: the scene file's [region.NAME] table (config/scene_file.cpp),
// or a tool's options. Keeps the parsers free of any file format.
class ParamReader {
 public:
  virtual ~ParamReader() = default;
  // The number under `key`; nullopt when the key is absent. A value that is not a number is rejected.
  virtual std::optional<double> number(std::string_view key) const = 0;
  // A [lower, upper] pair of numbers under `key`; nullopt when absent.
  virtual std::optional<std::pair<double, double>> pair(std::string_view key) const = 0;
  // Rejects the value under `key` (the table itself for an empty key): throws, saying where it is written.
  [[noreturn]] virtual void reject(std::string_view key, std::string_view message) const = 0;
};

// A method's parameters, of the type its entry knows (its Params).
using MethodParams = std::any;

struct MethodEntry {
  std::string name;               // method = "NAME" in a scene file; its parameters in [region.NAME]
  std::vector<std::string> keys;  // the keys that table may hold (none: the method has no table)
  std::function<MethodParams()> defaults;
  // Parses the table; rejects (through the reader) a value out of range, naming its key.
  std::function<MethodParams(const ParamReader&)> parse;
  // Throws std::invalid_argument for parameters that are not valid (or not this method's Params).
  std::function<MethodPtr(const MethodParams&)> make;
};

// The entry of a method class M, from what M declares: kName, kParamKeys, Params, parse_params(const
// ParamReader&) and a constructor from Params.
template <typename M>
MethodEntry method_entry() {
  using Params = typename M::Params;
  MethodEntry e;
  e.name = std::string(M::kName);
  for (std::string_view key : M::kParamKeys) e.keys.emplace_back(key);
  e.defaults = [] { return MethodParams(Params{}); };
  e.parse = [](const ParamReader& reader) { return MethodParams(M::parse_params(reader)); };
  e.make = [](const MethodParams& params) -> MethodPtr {
    const Params* p = std::any_cast<Params>(&params);
    if (p == nullptr) throw std::invalid_argument(std::string(M::kName) + " method: parameters of another method");
    return std::make_shared<const M>(*p);
  };
  return e;
}

// The methods a scene file may name, in the order they are listed.
class MethodRegistry {
 public:
  // Throws std::invalid_argument when a method of that name is already registered.
  void add(MethodEntry entry);
  const MethodEntry* find(std::string_view name) const;
  const std::vector<std::shared_ptr<const MethodEntry>>& entries() const { return entries_; }
  std::string names() const;  // "curvature, depth, none"

 private:
  std::vector<std::shared_ptr<const MethodEntry>> entries_;
};

// The method `name` with its default parameters; throws std::invalid_argument for an unknown name.
MethodPtr make_default_method(const MethodRegistry& registry, std::string_view name);

}  // namespace ph
