// Loading out-of-tree plugin libraries (plugin_api.hpp). A library registers first into private
// staging registries; only when the entry succeeded, reported the host's API version and none of
// its names collides with a registered plugin are its entries moved into the global registries.
// A failed load therefore leaves the registries exactly as they were.
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
};

}  // namespace

void load_plugin_library(const std::string& path) {
  // Study loading is single-threaded today, but a library must never be half-registered by two
  // callers at once, and the set of loaded paths is shared.
  static std::mutex mutex;
  static std::set<std::string> loaded;
  std::lock_guard lock(mutex);

  std::error_code ec;
  const fs::path given(path);
  if (!fs::exists(given, ec)) throw InputError(fmt::format("plugin library '{}' not found", path));
  if (!fs::is_regular_file(given, ec))
    throw InputError(fmt::format("plugin library '{}' is not a file", path));
  // The canonical path identifies the library: loading it again under another spelling (relative
  // path, symlink) is the same no-op, and it is what `chatterlab list` shows as the origin.
  const std::string library = fs::canonical(given, ec).string();
  if (ec) throw InputError(fmt::format("plugin library '{}': {}", path, ec.message()));
  if (loaded.count(library) != 0) return;

  // RTLD_NOW: an unresolved symbol is reported here, not as a crash in the middle of a run.
  // RTLD_LOCAL: two plugin libraries cannot interpose each other's symbols.
  dlerror();
  LibraryHandle handle(dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL));
  if (handle.get() == nullptr)
    throw InputError(fmt::format("cannot load plugin library '{}': {}", library, dl_error_text()));

  void* symbol = dlsym(handle.get(), "chatterlab_plugin_entry");
  if (symbol == nullptr) {
    throw InputError(fmt::format(
        "'{}' is not a chatterlab plugin: it has no symbol chatterlab_plugin_entry (define it "
        "with CHATTERLAB_PLUGIN_ENTRY from <chatterlab/plugin_api.hpp>)",
        library));
  }
  // POSIX guarantees that a dlsym() result converts to a function pointer.
  auto entry = reinterpret_cast<chatterlab_plugin_entry_fn>(symbol);

  StagingRegistries staging;
  Registries registries{staging.models, staging.kinematics, staging.suppression, staging.analysis,
                        library};
  int library_version = 0;
  try {
    library_version = entry(CHATTERLAB_PLUGIN_API_VERSION, &registries);
  } catch (...) {
    // Registry::add throws std::logic_error for a name registered twice inside the library; the
    // library's own code may throw anything, which must not end the process ("terminate called").
    throw InputError(fmt::format("plugin library '{}' failed to register: {}", library,
                                 describe_current_exception()));
  }
  if (library_version != CHATTERLAB_PLUGIN_API_VERSION) {
    throw InputError(fmt::format(
        "plugin library '{}' was built for plugin API {}, this chatterlab has {}: rebuild it "
        "against this version",
        library, library_version, CHATTERLAB_PLUGIN_API_VERSION));
  }

  for (const std::string& clash : {first_clash(staging.models, model_registry()),
                                   first_clash(staging.kinematics, kinematics_registry()),
                                   first_clash(staging.suppression, suppression_registry()),
                                   first_clash(staging.analysis, analysis_registry())}) {
    if (!clash.empty())
      throw InputError(fmt::format("plugin library '{}' cannot be loaded: {}", library, clash));
  }
  move_entries(staging.models, model_registry());
  move_entries(staging.kinematics, kinematics_registry());
  move_entries(staging.suppression, suppression_registry());
  move_entries(staging.analysis, analysis_registry());
  handle.keep_loaded();
  loaded.insert(library);
}

namespace {

template <class Product>
void note_plugin(const Registry<Product>& registry, const std::string& name,
                 std::vector<std::string>& found) {
  const auto* entry = registry.find(name);
  if (entry == nullptr || entry->origin == "built-in") return;
  std::string text = fmt::format("{} plugin '{}' (library {})", registry.kind(), name, entry->origin);
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
  collect_plugins(document, found);
  return fmt::format("{}", fmt::join(found, ", "));
}

}  // namespace chatterlab
