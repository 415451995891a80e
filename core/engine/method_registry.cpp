#include "core/engine/method_registry.hpp"

#include <stdexcept>

namespace ph {

void MethodRegistry::add(MethodEntry entry) {
  if (find(entry.name) != nullptr) throw std::invalid_argument("method '" + entry.name + "' is already registered");
  entries_.push_back(std::make_shared<const MethodEntry>(std::move(entry)));
}

const MethodEntry* MethodRegistry::find(std::string_view name) const {
  for (const auto& entry : entries_) {
    if (entry->name == name) return entry.get();
  }
  return nullptr;
}

std::string MethodRegistry::names() const {
  std::string out;
  for (const auto& entry : entries_) out += (out.empty() ? "" : ", ") + entry->name;
  return out;
}

MethodPtr make_default_method(const MethodRegistry& registry, std::string_view name) {
  const MethodEntry* entry = registry.find(name);
  if (entry == nullptr) {
    throw std::invalid_argument("unknown method '" + std::string(name) + "' (allowed: " + registry.names() + ")");
  }
  return entry->make(entry->defaults());
}

}  // namespace ph
