// A plugin library built by a chatterlab of plugin API 1, which wrote no build record: only the
// entry, which registers nothing when the host's version differs and reports its own (1). The
// host must refuse it with a "rebuild" message naming API 1.
#include <chatterlab/plugin_api.hpp>

extern "C" __attribute__((visibility("default"))) int chatterlab_plugin_entry(
    int host_api_version, chatterlab::Registries* registries) {
  if (host_api_version == 1 && registries != nullptr) {
    // (An API 1 library would register here; this host is never API 1.)
  }
  return 1;
}
