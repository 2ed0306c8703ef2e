// A plugin library built by a future chatterlab 9.9.0 that happens to have the same plugin API:
// the C++ ABI of another minor version cannot be trusted, so the host refuses it, naming both
// versions. Its entry would register a model; the host must never call it.
#include <chatterlab/plugin_api.hpp>

#include <stdexcept>

extern "C" __attribute__((visibility("default"))) const chatterlab_plugin_build_info*
chatterlab_plugin_build() {
  static const chatterlab_plugin_build_info build{CHATTERLAB_PLUGIN_API_VERSION, "9.9.0",
                                                  "GCC 99"};
  return &build;
}

extern "C" __attribute__((visibility("default"))) int chatterlab_plugin_entry(
    int /*host_api_version*/, chatterlab::Registries* /*registries*/) {
  throw std::logic_error("the entry of a library built for another version was called");
}
