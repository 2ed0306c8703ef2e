// A plugin library as if built against a future chatterlab whose plugin API is 999 (same
// chatterlab version): its build record says so, and its entry follows the protocol of
// CHATTERLAB_PLUGIN_ENTRY (register only when the host's version equals its own, always report
// its own). The host must refuse it from the record alone, with a "rebuild" message.
#include <chatterlab/plugin_api.hpp>

namespace {
constexpr int library_api_version = 999;
}

extern "C" __attribute__((visibility("default"))) const chatterlab_plugin_build_info*
chatterlab_plugin_build() {
  static const chatterlab_plugin_build_info build{library_api_version, CHATTERLAB_VERSION, "GCC"};
  return &build;
}

extern "C" __attribute__((visibility("default"))) int chatterlab_plugin_entry(
    int host_api_version, chatterlab::Registries* /*registries*/) {
  // host_api_version != 999 here, so nothing is registered.
  (void)host_api_version;
  return library_api_version;
}
