#pragma once
// Base class of kinematics plugins. The registry exists from the start so that plugin authors and
// `chatterlab list` see every kind; the kind's interface is filled in by the capability that
// first needs it (see docs/architecture.md).
#include "chatterlab/registry.hpp"

namespace chatterlab {

class Kinematics {
 public:
  virtual ~Kinematics() = default;
};

}  // namespace chatterlab
