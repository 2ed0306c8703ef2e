#pragma once
// Plugin registries, one per kind (model, kinematics, suppression, analysis). Each registry lives
// inside a function (no static-initialisation-order problems). An in-tree plugin registers with
// one line in its .cpp:
//
//     CHATTERLAB_REGISTER_MODEL(PlungeRegenerative);
//
// where the class has `static PluginInfo info()` and a constructor taking `const ParamValues&`.
// Duplicate names are a hard error; an unknown name is answered with the sorted valid names.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

// How the runner may use one plugin instance across OpenMP threads.
enum class ThreadSafety {
  shareable,        // one instance may be used by all threads at once
  copy_per_thread,  // each thread builds its own instance (the default)
  serial,           // the grid loop runs on one thread when this plugin is used
};
std::string_view to_string(ThreadSafety safety);

struct PluginInfo {
  std::string name;         // registry key, snake_case
  std::string description;  // one line for `chatterlab list`
  std::vector<ParamSpec> params;
  ThreadSafety thread_safety = ThreadSafety::copy_per_thread;
  std::string models_md_ids;  // MODELS.md sections implemented, e.g. "G1"; shown by describe
  // A small valid parameter table: printed by `chatterlab describe` as a TOML example and run by
  // the conformance test that loops over every registered plugin.
  Json example_params = Json::object();
};

template <class Product>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Product>(const ParamValues&)>;
  struct Entry {
    PluginInfo info;
    Factory create;
    std::string origin;  // "built-in" or the shared library path
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  // Throws std::logic_error on a duplicate name (a programming or packaging error).
  void add(PluginInfo info, Factory create, std::string origin = "built-in");
  // Throws InputError naming the kind and listing the sorted valid names.
  const Entry& at(std::string_view name) const;
  const Entry* find(std::string_view name) const;
  std::vector<const Entry*> sorted() const;  // by name
  const std::string& kind() const { return kind_; }

 private:
  std::string kind_;
  std::map<std::string, Entry, std::less<>> entries_;
};

class Model;
class Kinematics;
class Suppression;
class Analysis;

Registry<Model>& model_registry();
Registry<Kinematics>& kinematics_registry();
Registry<Suppression>& suppression_registry();
Registry<Analysis>& analysis_registry();

// Adds plugin class T (static info(), constructor from ParamValues) to a registry.
template <class T, class Product>
void add_plugin(Registry<Product>& registry, std::string origin = "built-in") {
  registry.add(T::info(), [](const ParamValues& p) -> std::unique_ptr<Product> {
    return std::make_unique<T>(p);
  }, std::move(origin));
}

}  // namespace chatterlab

#define CHATTERLAB_DETAIL_CAT2(a, b) a##b
#define CHATTERLAB_DETAIL_CAT(a, b) CHATTERLAB_DETAIL_CAT2(a, b)
#define CHATTERLAB_DETAIL_REGISTER(registry_fn, Type)                                   \
  namespace {                                                                            \
  [[maybe_unused]] const bool CHATTERLAB_DETAIL_CAT(chatterlab_registered_, __LINE__) = \
      (::chatterlab::add_plugin<Type>(registry_fn()), true);                             \
  }
#define CHATTERLAB_REGISTER_MODEL(Type) CHATTERLAB_DETAIL_REGISTER(::chatterlab::model_registry, Type)
#define CHATTERLAB_REGISTER_KINEMATICS(Type) \
  CHATTERLAB_DETAIL_REGISTER(::chatterlab::kinematics_registry, Type)
#define CHATTERLAB_REGISTER_SUPPRESSION(Type) \
  CHATTERLAB_DETAIL_REGISTER(::chatterlab::suppression_registry, Type)
#define CHATTERLAB_REGISTER_ANALYSIS(Type) \
  CHATTERLAB_DETAIL_REGISTER(::chatterlab::analysis_registry, Type)

#include "chatterlab/detail/registry_impl.hpp"
