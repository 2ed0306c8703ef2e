// A plugin library with a packaging error: it registers the same model name twice. The host must
// refuse the whole library (nothing of it registered) and name it.
#include <chatterlab/plugin_api.hpp>

namespace {

class TwiceModel final : public chatterlab::Model {
 public:
  explicit TwiceModel(const chatterlab::ParamValues&) {}
  static chatterlab::PluginInfo info() {
    chatterlab::PluginInfo info;
    info.name = "twice_registered_model";
    info.description = "registered twice by its library (plugin loader test)";
    return info;
  }
};

}  // namespace

CHATTERLAB_PLUGIN_ENTRY(registries) {
  chatterlab::add_plugin<TwiceModel>(registries.models, registries.origin);
  chatterlab::add_plugin<TwiceModel>(registries.models, registries.origin);
}
