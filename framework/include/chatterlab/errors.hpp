#pragma once
// Error kinds that decide the exit code of `chatterlab` (see docs/architecture.md):
//   InputError  -> exit 2, nothing written. The message names file, line, key, value and limit.
//   PointFailure -> recorded in that grid point's status; the run goes on and exits 1.
#include <stdexcept>
#include <string>

namespace chatterlab {

// Bad user input (study file, grid, plugin library, output directory). Always thrown, never
// asserted: users must get the message in release builds too.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A numerical failure confined to one grid point (root search did not converge, integrator
// failed). The runner catches it per point, records the reason and continues.
class PointFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace chatterlab
