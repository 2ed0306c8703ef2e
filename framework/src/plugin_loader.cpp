// Loading out-of-tree plugin libraries (plugin_api.hpp). The library's build record is read first:
// a library built for another plugin API or another chatterlab major.minor version is refused
// before any of its code is called. It then registers into private staging registries; only when
// the entry succeeded, reported the host's API version and none of its names collides with a
// registered plugin are its entries moved into the global registries. A failed load therefore
// leaves the registries exactly as they were.
#include <dlfcn.h>

#include <algorithm>
#include <filesystem>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/version.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;

// dlclose()s a handle unless released. Declared before the staging registries so that on an
// error they (holding factories whose code lives in the library) are destroyed first.
class LibraryHandle {
 public:
  explicit LibraryHandle(void* handle) : handle_(handle) {}
  LibraryHandle(const LibraryHandle&) = delete;
  LibraryHandle& operator=(const LibraryHandle&) = delete;
  ~LibraryHandle() {
    if (handle_ != nullptr) dlclose(handle_);
  }
  void* get() const { return handle_; }
  // A registered plugin's code lives in the library: it must stay mapped for the process.
  void keep_loaded() { handle_ = nullptr; }

 private:
  void* handle_;
};

std::string dl_error_text() {
  const char* text = dlerror();
  return text != nullptr ? text : "unknown dynamic loader error";
}

// The name clash a move into `target` would cause, or "" when there is none.
template <class Product>
std::string first_clash(const Registry<Product>& staged, const Registry<Product>& target) {
  for (const auto* entry : staged.sorted()) {
    if (const auto* existing = target.find(entry->info.name)) {
      return fmt::format("duplicate {} plugin name '{}' (already registered by {})", target.kind(),
                         entry->info.name, existing->origin);
    }
  }
  return {};
}

// Moves a library's entries into the global registry with their factories wrapped: whatever a
// plugin's constructor throws (its own class, an int) leaves as an exception that names the
// plugin and its library. InputError and PointFailure keep their type (bad parameters at load
// time, a failed point at run time); anything else becomes PluginError.
template <class Product>
void move_entries(const Registry<Product>& staged, Registry<Product>& target) {
  for (const auto* entry : staged.sorted()) {
    auto factory = [create = entry->create, name = entry->info.name, library = entry->origin,
                    kind = target.kind()](const ParamValues& params) -> std::unique_ptr<Product> {
      const std::string who = fmt::format("{} plugin '{}' (library {})", kind, name, library);
      try {
        return create(params);
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}: {}", who, e.what()));
      } catch (const PointFailure& e) {
        throw PointFailure(fmt::format("{}: {}", who, e.what()));
      } catch (...) {
        throw PluginError(
            fmt::format("{}: its constructor threw {}", who, describe_current_exception()), name,
            library);
      }
    };
    target.add(entry->info, std::move(factory), entry->origin);
  }
}

// Same kind names as the global registries, so messages read the same.
struct StagingRegistries {
  Registry<Model> models{model_registry().kind()};
  Registry<Kinematics> kinematics{kinematics_registry().kind()};
  Registry<Suppression> suppression{suppression_registry().kind()};
  Registry<Analysis> analysis{analysis_registry().kind()};
  Registry<StudyKind> study_kinds{study_kind_registry().kind()};
};

// The library's path as it is identified from now on: the canonical path, so that loading it
// again under another spelling (relative path, symlink) is the same no-op, and what
// `chatterlab list` shows as the origin.
std::string canonical_library(const std::string& path) {
  std::error_code ec;
  const fs::path given(path);
  if (!fs::exists(given, ec)) throw InputError(fmt::format("plugin library '{}' not found", path));
  if (!fs::is_regular_file(given, ec))
    throw InputError(fmt::format("plugin library '{}' is not a file", path));
  std::string library = fs::canonical(given, ec).string();
  if (ec) throw InputError(fmt::format("plugin library '{}': {}", path, ec.message()));
  return library;
}

void* open_library(const std::string& library) {
  // RTLD_NOW: an unresolved symbol is reported here, not as a crash in the middle of a run.
  // RTLD_LOCAL: two plugin libraries cannot interpose each other's symbols.
  dlerror();
  void* handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr)
    throw InputError(fmt::format("cannot load plugin library '{}': {}", library, dl_error_text()));
  return handle;
}

chatterlab_plugin_entry_fn entry_point(void* handle, const std::string& library) {
  void* symbol = dlsym(handle, "chatterlab_plugin_entry");
  if (symbol == nullptr) {
    throw InputError(fmt::format(
        "'{}' is not a chatterlab plugin: it has no symbol chatterlab_plugin_entry (define it "
        "with CHATTERLAB_PLUGIN_ENTRY from <chatterlab/plugin_api.hpp>)",
        library));
  }
  // POSIX guarantees that a dlsym() result converts to a function pointer.
  return reinterpret_cast<chatterlab_plugin_entry_fn>(symbol);
}

// The build record. A library of plugin API 1 has none; its entry, called with this host's
// version and no registries, registers nothing and reports the version it was built for (the
// API 1 protocol).
PluginLibraryBuild read_build(void* handle, chatterlab_plugin_entry_fn entry) {
  PluginLibraryBuild build;
  if (void* symbol = dlsym(handle, "chatterlab_plugin_build")) {
    const chatterlab_plugin_build_info* info =
        reinterpret_cast<chatterlab_plugin_build_fn>(symbol)();
    if (info != nullptr) {
      build.plugin_api_version = info->plugin_api_version;
      build.chatterlab_version = info->chatterlab_version ? info->chatterlab_version : "";
      build.compiler = info->compiler ? info->compiler : "";
      return build;
    }
  }
  build.plugin_api_version = entry(CHATTERLAB_PLUGIN_API_VERSION, nullptr);
  return build;
}

// "0.1.3" -> "0.1": libraries of one major.minor version share the C++ ABI.
std::string major_minor(const std::string& version) {
  const std::size_t first = version.find('.');
  if (first == std::string::npos) return version;
  return version.substr(0, version.find('.', first + 1));
}

std::string describe_build(const PluginLibraryBuild& build) {
  if (build.chatterlab_version.empty())
    return fmt::format("plugin API {} (a chatterlab that records no version)",
                       build.plugin_api_version);
  return fmt::format("chatterlab {} (plugin API {})", build.chatterlab_version,
                     build.plugin_api_version);
}

void check_compatible(const PluginLibraryBuild& build, const std::string& library) {
  if (build.plugin_api_version == CHATTERLAB_PLUGIN_API_VERSION &&
      major_minor(build.chatterlab_version) == major_minor(CHATTERLAB_VERSION))
    return;
  throw InputError(fmt::format(
      "plugin library '{}' was built for {}; this chatterlab is {} (plugin API {}): rebuild the "
      "library against this version",
      library, describe_build(build), CHATTERLAB_VERSION, CHATTERLAB_PLUGIN_API_VERSION));
}

}  // namespace

void load_plugin_library(const std::string& path) {
  // Study loading is single-threaded today, but a library must never be half-registered by two
  // callers at once, and the set of loaded paths is shared.
  static std::mutex mutex;
  static std::set<std::string> loaded;
  std::lock_guard lock(mutex);

  const std::string library = canonical_library(path);
  if (loaded.count(library) != 0) return;

  LibraryHandle handle(open_library(library));
  const chatterlab_plugin_entry_fn entry = entry_point(handle.get(), library);
  const PluginLibraryBuild build = read_build(handle.get(), entry);
  check_compatible(build, library);

  StagingRegistries staging;
  Registries registries{staging.models,   staging.kinematics,  staging.suppression,
                        staging.analysis, staging.study_kinds, library};
  int library_version = 0;
  try {
    library_version = entry(CHATTERLAB_PLUGIN_API_VERSION, &registries);
  } catch (...) {
    // Registry::add throws std::logic_error for a name registered twice inside the library; the
    // library's own code may throw anything, which must not end the process ("terminate called").
    throw InputError(fmt::format("plugin library '{}' failed to register: {}", library,
                                 describe_current_exception()));
  }
  // The record said the API agrees, so the entry must have registered; if it reports another
  // version after all, nothing it did can be trusted.
  if (library_version != CHATTERLAB_PLUGIN_API_VERSION) {
    PluginLibraryBuild reported = build;
    reported.plugin_api_version = library_version;
    check_compatible(reported, library);
  }

  for (const std::string& clash : {first_clash(staging.models, model_registry()),
                                   first_clash(staging.kinematics, kinematics_registry()),
                                   first_clash(staging.suppression, suppression_registry()),
                                   first_clash(staging.analysis, analysis_registry()),
                                   first_clash(staging.study_kinds, study_kind_registry())}) {
    if (!clash.empty())
      throw InputError(fmt::format("plugin library '{}' cannot be loaded: {}", library, clash));
  }
  move_entries(staging.models, model_registry());
  move_entries(staging.kinematics, kinematics_registry());
  move_entries(staging.suppression, suppression_registry());
  move_entries(staging.analysis, analysis_registry());
  move_entries(staging.study_kinds, study_kind_registry());
  handle.keep_loaded();
  loaded.insert(library);
}

namespace {

template <class Product>
void note_plugin(const Registry<Product>& registry, const std::string& name,
                 std::vector<std::string>& found) {
  const auto* entry = registry.find(name);
  if (entry == nullptr || entry->origin == "built-in") return;
  std::string text =
      fmt::format("{} plugin '{}' (library {})", registry.kind(), name, entry->origin);
  if (std::find(found.begin(), found.end(), text) == found.end()) found.push_back(std::move(text));
}

void collect_plugins(const Json& value, std::vector<std::string>& found) {
  if (value.is_array()) {
    for (const Json& item : value) collect_plugins(item, found);
    return;
  }
  if (!value.is_object()) return;
  for (const auto& [key, item] : value.items()) {
    if (key == "type" && item.is_string()) {
      const std::string& name = item.get_ref<const std::string&>();
      note_plugin(model_registry(), name, found);
      note_plugin(kinematics_registry(), name, found);
      note_plugin(suppression_registry(), name, found);
      note_plugin(analysis_registry(), name, found);
    } else {
      collect_plugins(item, found);
    }
  }
}

}  // namespace

std::string out_of_tree_plugins_in(const Json& document) {
  std::vector<std::string> found;
  // A study kind may come from a library too (plugin API 2); it is chosen by [study] kind.
  if (const auto study = document.find("study"); study != document.end() && study->is_object())
    if (const auto kind = study->find("kind"); kind != study->end() && kind->is_string())
      note_plugin(study_kind_registry(), kind->get<std::string>(), found);
  collect_plugins(document, found);
  return fmt::format("{}", fmt::join(found, ", "));
}

PluginLibraryBuild plugin_library_build(const std::string& path) {
  const std::string library = canonical_library(path);
  LibraryHandle handle(open_library(library));
  return read_build(handle.get(), entry_point(handle.get(), library));
}

}  // namespace chatterlab
