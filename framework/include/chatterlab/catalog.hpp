#pragma once
// Text for `chatterlab list` and `chatterlab describe NAME`.
#include <string>
#include <string_view>

namespace chatterlab {

// Every registered plugin of every kind (and every study kind), sorted, one line each:
// "<kind>  <name>  <one-line description>".
std::string format_plugin_list();

// Parameters of one plugin or study kind: key, type, unit, limits, default, description, thread
// safety, MODELS.md ids and a TOML example. Throws InputError listing valid names if unknown.
std::string describe_plugin(std::string_view name);

}  // namespace chatterlab
