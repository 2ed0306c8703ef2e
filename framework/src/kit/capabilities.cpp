// Study kit: plugins by capability (chatterlab/kit/capabilities.hpp).
#include "chatterlab/kit/capabilities.hpp"

#include <stdexcept>

#include "chatterlab/errors.hpp"

namespace chatterlab::kit {

namespace {
class PluginSource final : public SourceMap {
 public:
  explicit PluginSource(std::string what) : what_(std::move(what)) {}
  SourceLocation locate(std::string_view) const override { return {what_, 0}; }

 private:
  std::string what_;
};
}  // namespace

Json plugin_parameters(const PluginInfo& info, const Json& table) {
  return validate_params(table, info.params, info.name, PluginSource("parameters of " + info.name));
}

Json example_parameters(const PluginInfo& info) {
  try {
    return validate_params(info.example_params, info.params, info.name, PluginSource("example_params of " + info.name));
  } catch (const InputError& e) {
    throw std::logic_error(e.what());
  }
}

}  // namespace chatterlab::kit
