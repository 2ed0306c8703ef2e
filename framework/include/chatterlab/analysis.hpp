#pragma once
// Base class of analysis plugins. The registry exists from the start so that plugin authors and
// `chatterlab list` see every kind; the kind's interface is filled in by the capability that
// first needs it (see docs/architecture.md).
#include "chatterlab/registry.hpp"

namespace chatterlab {

class Analysis {
 public:
  virtual ~Analysis() = default;
};

}  // namespace chatterlab
