#include "chatterlab/registry.hpp"

#include "chatterlab/analysis.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/suppression.hpp"

namespace chatterlab {

std::string_view to_string(ThreadSafety safety) {
  switch (safety) {
    case ThreadSafety::shareable: return "shareable";
    case ThreadSafety::copy_per_thread: return "copy per thread";
    case ThreadSafety::serial: return "serial";
  }
  return "?";
}

namespace detail {
std::string join_names(const std::vector<std::string>& names) {
  if (names.empty()) return "(none registered)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}
}  // namespace detail

// Function-local statics: constructed on first use, so registration lines in any translation
// unit can run during static initialisation without ordering problems.
Registry<Model>& model_registry() {
  static Registry<Model> registry("model");
  return registry;
}
Registry<Kinematics>& kinematics_registry() {
  static Registry<Kinematics> registry("kinematics");
  return registry;
}
Registry<Suppression>& suppression_registry() {
  static Registry<Suppression> registry("suppression");
  return registry;
}
Registry<Analysis>& analysis_registry() {
  static Registry<Analysis> registry("analysis");
  return registry;
}

}  // namespace chatterlab
