#pragma once
// Study kit: choosing plugins by what they can do, not by their names. A capability is a typed
// interface a plugin class also derives from and returns through an accessor of its base class
// (Model::process_conditions(), Analysis::profile_quality(), ...); plugins_with finds the
// registered plugins that have one, so a plugin loaded from outside the tree that declares it is
// found like the built-in ones.
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab::kit {

// A parameter table validated against a plugin's specs (defaults filled in), for building a
// plugin from a table the study already validated against (part of) them. Throws InputError
// naming the plugin and the key.
Json plugin_parameters(const PluginInfo& info, const Json& table);

// A plugin's example_params validated against its own specs (defaults filled in). Throws
// std::logic_error when they fail them (a packaging error; the conformance test reports it).
Json example_parameters(const PluginInfo& info);

// The registered plugins whose instance, built from its example parameters, has the capability
// (the accessor returns non-null), sorted by name. A plugin whose example cannot be built is
// left out (the conformance test fails it).
template <class Product, class Capability>
std::vector<const typename Registry<Product>::Entry*> plugins_with(const Registry<Product>& registry,
                                                                  const Capability* (Product::*accessor)() const) {
  std::vector<const typename Registry<Product>::Entry*> found;
  for (const auto* entry : registry.sorted()) {
    try {
      const auto product = entry->create(ParamValues(example_parameters(entry->info)));
      if (product && ((*product).*accessor)() != nullptr) found.push_back(entry);
    } catch (const std::exception&) {
      // not buildable from its example: not a candidate
    }
  }
  return found;
}

}  // namespace chatterlab::kit
