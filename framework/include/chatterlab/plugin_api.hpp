#pragma once
// Out-of-tree plugins: a shared library with two extern "C" symbols, both written by one macro.
// A study names it with `plugins = ["path/to/libx.so"]`; list, describe, validate and run take
// `--plugin path/to/libx.so`. Write in the library's .cpp:
//
//     #include <chatterlab/plugin_api.hpp>
//     CHATTERLAB_PLUGIN_ENTRY(registries) {
//       chatterlab::add_plugin<MyModel>(registries.models, registries.origin);
//       chatterlab::add_study_kind<MySweep>(registries.study_kinds, registries.origin);
//     }
//
// and build it with chatterlab_add_plugin() of the CMake package (find_package(chatterlab)).
// The host first reads chatterlab_plugin_build(): the plugin API version and the chatterlab
// version the library was compiled for. It refuses (bad input, exit 2) a library built for
// another plugin API or another major.minor version, naming the library, what it was built for and
// what the host is; only then does it call chatterlab_plugin_entry(host_api_version, &registries),
// which registers only when the versions agree and returns the library's API version.
#include <string>

#include "chatterlab/analysis.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/suppression.hpp"
#include "chatterlab/version.hpp"

// Raised whenever a change of the public headers would make an existing library misbehave (a
// new virtual function, a changed struct layout, a new registry in Registries). 2: study kinds.
// 3: SampledSeries::values is a read-only view (std::span), no longer a std::vector.
// 4: CharacteristicFunction::newton_form (a new virtual function).
#define CHATTERLAB_PLUGIN_API_VERSION 4

namespace chatterlab {

struct Registries {
  Registry<Model>& models;
  Registry<Kinematics>& kinematics;
  Registry<Suppression>& suppression;
  Registry<Analysis>& analysis;
  Registry<StudyKind>& study_kinds;
  std::string origin;  // the library path, recorded as each entry's origin
};

// Loads a plugin library into the global registries. Throws InputError (missing file, dlopen
// failure, missing entry symbol, another plugin API or chatterlab version, duplicate plugin name).
// Each entry it registers has the library's canonical path as its origin.
void load_plugin_library(const std::string& path);

// The out-of-tree plugins a study document chooses (every `type = "<name>"`, at any depth, that
// names a plugin loaded from a library), as "model plugin 'x' (library /p/libx.so)", comma
// separated; "" when it uses built-in plugins only. Failure messages name them.
std::string out_of_tree_plugins_in(const Json& document);

// What a loaded (or refused) library says it was built for.
struct PluginLibraryBuild {
  int plugin_api_version = 0;
  std::string chatterlab_version;  // "" when the library does not say (plugin API 1)
  std::string compiler;
};
// Reads chatterlab_plugin_build() of a library without registering anything (check-plugin).
// Throws InputError as load_plugin_library does for a file that is not a loadable plugin.
PluginLibraryBuild plugin_library_build(const std::string& path);

}  // namespace chatterlab

extern "C" {
// What a library was built for. Its layout never changes (fields may only be appended), so any
// host can read it from any library before it trusts anything else in it.
struct chatterlab_plugin_build_info {
  int plugin_api_version;
  const char* chatterlab_version;  // CHATTERLAB_VERSION of the headers it was compiled with
  const char* compiler;
};
using chatterlab_plugin_build_fn = const chatterlab_plugin_build_info* (*)();
using chatterlab_plugin_entry_fn = int (*)(int host_api_version, chatterlab::Registries* registries);
}

#define CHATTERLAB_PLUGIN_ENTRY(registries_name)                                                  \
  extern "C" __attribute__((visibility("default"))) const chatterlab_plugin_build_info*           \
  chatterlab_plugin_build() {                                                                     \
    static const chatterlab_plugin_build_info build{                                              \
        CHATTERLAB_PLUGIN_API_VERSION, CHATTERLAB_VERSION, CHATTERLAB_COMPILER};            \
    return &build;                                                                                \
  }                                                                                               \
  static void chatterlab_plugin_register(chatterlab::Registries& registries_name);                \
  extern "C" __attribute__((visibility("default"))) int chatterlab_plugin_entry(                  \
      int host_api_version, chatterlab::Registries* registries) {                                 \
    if (host_api_version == CHATTERLAB_PLUGIN_API_VERSION && registries != nullptr)               \
      chatterlab_plugin_register(*registries);                                                    \
    return CHATTERLAB_PLUGIN_API_VERSION;                                                         \
  }                                                                                               \
  static void chatterlab_plugin_register(chatterlab::Registries& registries_name)
