#include "chatterlab/study_kind.hpp"

namespace chatterlab {

// Function-local static, like the plugin registries (registry.cpp): kinds register from static
// initialisers in any translation unit without ordering problems.
Registry<StudyKind>& study_kind_registry() {
  static Registry<StudyKind> registry("study kind");
  return registry;
}

}  // namespace chatterlab
