#include <algorithm>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/study_kind.hpp"
#include "study/messages.hpp"

namespace chatterlab::detail {

Json validate_component(const Json& document, const std::string& table,
                        const std::string& registry_kind, const std::vector<const PluginInfo*>& plugins,
                        const SourceMap& sources) {
  std::vector<std::string> names;
  for (const auto* info : plugins) names.push_back(info->name);
  std::string choice = fmt::format("one of: {}", messages::sorted_list(names));

  auto where = [&](const std::string& path) { return sources.locate(path).str(); };
  auto it = document.find(table);
  if (it == document.end())
    throw InputError(fmt::format("{}: missing table [{}]; it needs type = the {} to use, {}",
                                 where(table), table, registry_kind, choice));
  if (!it->is_object())
    throw InputError(fmt::format("{}: {} = {}: expected a table [{}]", where(table), table,
                                 messages::show(*it), table));
  std::string type_path = table + ".type";
  auto type = it->find("type");
  if (type == it->end())
    throw InputError(fmt::format("{}: missing required key '{}' (the {} to use, {})", where(table),
                                 type_path, registry_kind, choice));
  if (!type->is_string())
    throw InputError(fmt::format("{}: {} = {}: expected a string naming a {}, {}", where(type_path),
                                 type_path, messages::show(*type), registry_kind, choice));
  const std::string name = type->get<std::string>();
  auto found = std::find_if(plugins.begin(), plugins.end(),
                            [&](const PluginInfo* info) { return info->name == name; });
  if (found == plugins.end())
    throw InputError(fmt::format("{}: {} = \"{}\": unknown {} '{}'{}; valid names: {}", where(type_path),
                                 type_path, name, registry_kind, name,
                                 messages::did_you_mean(name, names), messages::sorted_list(names)));

  Json parameters = *it;
  parameters.erase("type");
  Json out = Json::object();
  out["type"] = name;
  Json validated = validate_params(parameters, (*found)->params, table, sources);
  for (auto& [key, value] : validated.items()) out[key] = std::move(value);
  return out;
}

}  // namespace chatterlab::detail
