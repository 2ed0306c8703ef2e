#include "chatterlab/study_kind.hpp"

#include <algorithm>

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

bool StudyKind::requires_serial(const Json& document) const {
  const std::vector<std::string> read = tables();
  if (std::find(read.begin(), read.end(), "model") == read.end()) return false;
  const auto model = document.find("model");
  return model != document.end() && model->is_object() && model->contains("type") &&
         model_is_serial(*model);
}

}  // namespace chatterlab
