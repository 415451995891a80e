// Sets (or unsets) an environment variable for one scope, and puts back what was there: a test that changes the
// environment leaves the tests after it in the same process as they would be alone.
#pragma once

#include <cstdlib>
#include <optional>
#include <string>

namespace ph {

class ScopedEnv {
 public:
  // `value` empty (std::nullopt): the variable is unset for the scope.
  ScopedEnv(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      ::setenv(name, value->c_str(), 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

}  // namespace ph
