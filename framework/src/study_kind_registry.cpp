#include "chatterlab/study_kind.hpp"

#include "chatterlab/model.hpp"

namespace chatterlab {

// Function-local static, like the plugin registries (registry.cpp): kinds register from static
// initialisers in any translation unit without ordering problems.
Registry<StudyKind>& study_kind_registry() {
  static Registry<StudyKind> registry("study kind");
  return registry;
}

bool model_is_serial(const Json& model_table) {
  const auto& entry = model_registry().at(model_table.at("type").get<std::string>());
  return entry.info.thread_safety == ThreadSafety::serial;
}

}  // namespace chatterlab
