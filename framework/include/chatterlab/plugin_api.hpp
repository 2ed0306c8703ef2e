#pragma once
// Out-of-tree plugins: a shared library with ONE versioned extern "C" entry point. A study names
// it with `plugins = ["path/to/libx.so"]`. Write in the library's .cpp:
//
//     #include <chatterlab/plugin_api.hpp>
//     CHATTERLAB_PLUGIN_ENTRY(registries) {
//       chatterlab::add_plugin<MyModel>(registries.models, registries.origin);
//     }
//
// The host calls chatterlab_plugin_entry(host_api_version, &registries). The entry returns the
// API version the library was compiled with and registers only when it equals the host's; the
// host reports a mismatch or a missing symbol as bad input (exit 2).
#include <string>

#include "chatterlab/analysis.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/suppression.hpp"

#define CHATTERLAB_PLUGIN_API_VERSION 1

namespace chatterlab {

struct Registries {
  Registry<Model>& models;
  Registry<Kinematics>& kinematics;
  Registry<Suppression>& suppression;
  Registry<Analysis>& analysis;
  std::string origin;  // the library path, recorded as each entry's origin
};

// Loads a plugin library into the global registries. Throws InputError (missing file, dlopen
// failure, missing entry symbol, API version mismatch, duplicate plugin name).
void load_plugin_library(const std::string& path);

// The out-of-tree plugins a study document chooses (every `type = "<name>"`, at any depth, that
// names a plugin loaded from a library), as "model plugin 'x' (library /p/libx.so)", comma
// separated; "" when it uses built-in plugins only. Failure messages name them.
std::string out_of_tree_plugins_in(const Json& document);

}  // namespace chatterlab

extern "C" {
using chatterlab_plugin_entry_fn = int (*)(int host_api_version, chatterlab::Registries* registries);
}

#define CHATTERLAB_PLUGIN_ENTRY(registries_name)                                                  \
  static void chatterlab_plugin_register(chatterlab::Registries& registries_name);                \
  extern "C" __attribute__((visibility("default"))) int chatterlab_plugin_entry(                  \
      int host_api_version, chatterlab::Registries* registries) {                                 \
    if (host_api_version == CHATTERLAB_PLUGIN_API_VERSION && registries != nullptr)               \
      chatterlab_plugin_register(*registries);                                                    \
    return CHATTERLAB_PLUGIN_API_VERSION;                                                         \
  }                                                                                               \
  static void chatterlab_plugin_register(chatterlab::Registries& registries_name)
