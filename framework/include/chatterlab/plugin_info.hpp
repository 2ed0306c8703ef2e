#pragma once
// Declaring a plugin in one expression, for `static PluginInfo info()` (chatterlab/registry.hpp):
//
//     return plugin_info("xc_cam", "K2", parameters_table().specs(), {{"wheel_radius_mm", 200.0}},
//                        "X-C cam grinder: ...", ThreadSafety::shareable);
//
// name and MODELS.md ids first, then the parameters, the example, the one-line description (often
// the longest) and the thread safety (default copy_per_thread, as PluginInfo's; a study kind
// leaves it out: every kind is shareable, set at registration). Filling a PluginInfo field by
// field declares the same plugin.
#include <string>
#include <utility>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

inline PluginInfo plugin_info(std::string name, std::string models_md_ids, std::vector<ParamSpec> params,
                              Json example_params, std::string description,
                              ThreadSafety thread_safety = ThreadSafety::copy_per_thread) {
  PluginInfo info;
  info.name = std::move(name);
  info.description = std::move(description);
  info.params = std::move(params);
  info.thread_safety = thread_safety;
  info.models_md_ids = std::move(models_md_ids);
  info.example_params = std::move(example_params);
  return info;
}

}  // namespace chatterlab
