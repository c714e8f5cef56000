#pragma once
// The one exception hierarchy of mbsflow. Every error the library throws derives from Error.
#include <stdexcept>
#include <string>

namespace mbsflow {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Bad input: a model, a setting or a command-line value. The CLI exits with code 2.
struct InputError : Error {
  using Error::Error;
};

// A run that could not be completed (diverged, step too small, peer lost). Exit code 1.
struct RunError : Error {
  using Error::Error;
};

}  // namespace mbsflow
