// Exceptions the core throws. The bindings map InvalidArgument to Python's
// ValueError and BackendUnavailable to glint_core.BackendUnavailable, so the
// message must name the argument and what was expected: it is what a user sees.
#pragma once
#include <stdexcept>
#include <string>

namespace glint {

// Base of everything Glint throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A caller passed something the core cannot use. `argument` is the caller's
// name for it ("position", "max_distance", ...).
class InvalidArgument : public Error {
 public:
  InvalidArgument(std::string argument, const std::string& expected)
      : Error(argument + ": " + expected), argument_(std::move(argument)) {}
  const std::string& argument() const { return argument_; }

 private:
  std::string argument_;
};

// A backend cannot run here (no EGL library, no display, GL too old).
class BackendUnavailable : public Error {
 public:
  using Error::Error;
};

}  // namespace glint
