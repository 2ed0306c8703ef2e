// `chatterlab init KIND` (chatterlab/study_template.hpp). The kind's own validate() decides what is
// complete: the template is the document it accepted, so every default it fills in is written
// down, and `chatterlab validate` accepts the file by construction.
#include "chatterlab/study_template.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/suppression.hpp"
#include "chatterlab/version.hpp"
#include "study/source_map.hpp"
#include "toml_text.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;

// A component table of a study ([model] type = ...) and the plugins that can fill it.
struct Component {
  std::string table;
  std::string registry_kind;
  std::vector<const PluginInfo*> plugins;  // in preference order
  std::vector<std::string> origins;
};

// The component tables of docs/studies.md: [model], [machine] (kinematics), [suppression].
template <class Product>
Component component(const std::string& table, const Registry<Product>& registry,
                    const std::string& preferred_origin) {
  Component c{table, registry.kind(), {}, {}};
  for (int pass = 0; pass < 2; ++pass)  // the kind's own library first, then the rest by name
    for (const auto* entry : registry.sorted())
      if ((entry->origin == preferred_origin) == (pass == 0)) {
        c.plugins.push_back(&entry->info);
        c.origins.push_back(entry->origin);
      }
  return c;
}

std::optional<Component> component_of(const std::string& table, const std::string& origin) {
  if (table == "model") return component(table, model_registry(), origin);
  if (table == "machine" || table == "kinematics") return component(table, kinematics_registry(), origin);
  if (table == "suppression") return component(table, suppression_registry(), origin);
  return std::nullopt;
}

Json component_table(const PluginInfo& plugin) {
  Json table = Json::object();
  table["type"] = plugin.name;
  for (const auto& [key, value] : plugin.example_params.items()) table[key] = value;
  return table;
}

// How much of a model's interface a plugin implements: the example of a kind shows the most
// capable model it accepts (its outputs then include closed forms, wheel revolutions, ...).
int capability_score(const std::string& registry_kind, const PluginInfo& plugin) {
  if (registry_kind != model_registry().kind()) return 0;
  try {
    LineSourceMap sources("example of " + plugin.name);
    const auto model = model_registry().at(plugin.name).create(
        ParamValues(validate_params(plugin.example_params, plugin.params, "model", sources)));
    return (model->characteristic() ? 1 : 0) + (model->time_domain() ? 1 : 0) +
           (model->wheel_period_s() ? 1 : 0) + (model->closed_forms() ? 1 : 0) +
           (model->process_conditions() ? 1 : 0) + (model->stiffness_chain() ? 1 : 0);
  } catch (const std::exception&) {
    return -1;
  }
}

// The kind's validate() on a copy; "" when it accepts the document.
std::string refusal(const StudyKind& kind, const Json& document, const std::string& kind_name) {
  Json copy = document;
  LineSourceMap sources("`chatterlab init " + kind_name + "`");
  try {
    kind.validate(copy, sources);
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

const PluginInfo* find_plugin(const Component& c, const std::string& name) {
  for (const PluginInfo* p : c.plugins)
    if (p->name == name) return p;
  return nullptr;
}

// A commented-out [grid] over the first real parameter of the model's example: +/- 20 %.
std::string grid_suggestion(const Json& document) {
  std::string text =
      "\n# [grid] varies parameters over a grid of points (a bare key is a [model] parameter;\n"
      "# dotted paths reach any table, e.g. \"model.modes.0.damping_ratio\"). For example:\n";
  if (document.contains("model"))
    for (const auto& [key, value] : document["model"].items())
      if (value.is_number_float() && value.get<double>() > 0.0) {
        const double v = value.get<double>();
        return text + fmt::format("# [grid]\n# {} = {{ from = {}, to = {}, steps = 11 }}\n", key,
                                  toml_value(0.8 * v, true), toml_value(1.2 * v, true));
      }
  return text + "# [grid]\n# \"<table>.<key>\" = [value1, value2, value3]\n";
}

// The kind's own example: [study], each component with the plugin whose example the kind accepts
// (the kind's own library first, then the most capable), the kind's example_params in the
// settings table that takes them. `accepted` and `example_table` are filled for the comments.
Json generated_document(const StudyKind& kind, const PluginInfo& info, const std::string& origin,
                        const std::vector<Component>& components, const std::vector<std::string>& settings_tables,
                        const StudyTemplateOptions& options, std::vector<std::vector<std::string>>& accepted,
                        std::string& example_table, const std::string& kind_name) {
  Json document = Json::object();
  document["study"] = {{"kind", kind_name}, {"name", options.name.empty() ? kind_name + " study" : options.name},
                       {"description", ""}};
  for (const std::string& table : kind.tables()) document[table] = Json::object();  // the kind's order
  // The kind's example_params belong to one of its settings tables: the only one, or the one
  // where the kind accepts them (placed in another table they are unknown keys).
  example_table = settings_tables.size() == 1 ? settings_tables.front() : std::string();
  if (example_table.empty() && !info.example_params.empty()) {
    for (const Component& c : components)
      if (!c.plugins.empty()) document[c.table] = component_table(*c.plugins.front());
    for (const std::string& table : settings_tables) {
      Json trial = document;
      trial[table] = info.example_params;
      const std::string why = refusal(kind, trial, kind_name);
      if (why.find("unknown key") == std::string::npos) {
        example_table = table;
        break;
      }
    }
  }
  if (!example_table.empty()) document[example_table] = info.example_params;
  for (const Component& c : components)
    if (!c.plugins.empty()) document[c.table] = component_table(*c.plugins.front());
  for (std::size_t i = 0; i < components.size(); ++i) {
    const Component& c = components[i];
    if (auto chosen = options.components.find(c.table); chosen != options.components.end()) {
      document[c.table] = component_table(*find_plugin(c, chosen->second));
      continue;
    }
    const PluginInfo* best = nullptr;
    int best_score = -2;
    bool best_own = false;
    for (std::size_t p = 0; p < c.plugins.size(); ++p) {
      const PluginInfo* plugin = c.plugins[p];
      Json trial = document;
      trial[c.table] = component_table(*plugin);
      if (!refusal(kind, trial, kind_name).empty()) continue;
      accepted[i].push_back(plugin->name);
      const bool own = c.origins[p] == origin && origin != "built-in";
      const int score = capability_score(c.registry_kind, *plugin);
      if (best == nullptr || (own && !best_own) || (own == best_own && score > best_score)) {
        best = plugin;
        best_score = score;
        best_own = own;
      }
    }
    if (best) {
      document[c.table] = component_table(*best);
      continue;
    }
    // No plugin fits, but the kind reads this table only optionally (stability_map's
    // [suppression] with a model that has no linearisation): leave it out.
    Json without = document;
    without.erase(c.table);
    if (refusal(kind, without, kind_name).empty()) document.erase(c.table);
  }
  return document;
}

// What the text is made of: the validated document and where its keys' comments come from.
struct TemplateParts {
  const std::string& kind_name;
  const PluginInfo& info;
  const std::string& origin;  // the kind's library, or "built-in"
  const std::vector<Component>& components;
  std::vector<std::vector<std::string>> accepted;  // per component: the plugins the kind accepts
  std::string example_table;                       // the table info.params describe ("" none)
  Json document;                                   // without [grid]
  std::optional<Json> grid;                        // a shipped study's [grid], as written
  std::string preamble;                            // comment lines after the generic header
};

std::string render(const TemplateParts& parts, const StudyTemplate& out) {
  const Json& validated = parts.document;
  std::string t;
  t += fmt::format("# A {} study: {}\n", parts.kind_name, parts.info.description);
  t += fmt::format("# Written by `chatterlab init {}` (chatterlab {}). Every key the kind reads is set to its\n"
                   "# default or an example value; the comment above a key gives its meaning, unit, limits\n"
                   "# and default. `chatterlab describe <name>` documents any kind or plugin.\n",
                   parts.kind_name, CHATTERLAB_VERSION);
  t += "#   chatterlab validate <this file>\n#   chatterlab run <this file> --out out/<name>\n";
  t += parts.preamble;
  if (!out.validated)
    t += "#\n# NOT YET VALID: " + out.error + "\n# Fill in what it names, then validate.\n";
  std::vector<std::string> libraries;
  if (parts.origin != "built-in") libraries.push_back(parts.origin);
  for (const Component& c : parts.components) {
    const std::string type = validated.contains(c.table) ? validated[c.table].value("type", "") : "";
    for (std::size_t p = 0; p < c.plugins.size(); ++p)
      if (c.plugins[p]->name == type && c.origins[p] != "built-in" &&
          std::find(libraries.begin(), libraries.end(), c.origins[p]) == libraries.end())
        libraries.push_back(c.origins[p]);
  }
  if (!libraries.empty()) {
    std::vector<std::string> quoted;
    for (const auto& l : libraries) quoted.push_back(Json(l).dump());
    t += fmt::format("\n# Out-of-tree plugin libraries, loaded before any table is read.\nplugins = [{}]\n",
                     fmt::join(quoted, ", "));
  }
  t += "\n[study]\n";
  append_toml_table(t, validated["study"], "study", {}, false);
  for (const auto& [table, value] : validated.items()) {
    if (table == "study" || table == "plugins" || !value.is_object()) continue;
    t += fmt::format("\n[{}]\n", toml_key(table));
    std::vector<ParamSpec> specs;
    auto c = std::find_if(parts.components.begin(), parts.components.end(),
                          [&](const Component& x) { return x.table == table; });
    if (c != parts.components.end()) {
      const PluginInfo* plugin = find_plugin(*c, value.value("type", ""));
      if (plugin) {
        t += fmt::format("# {} ({}): `chatterlab describe {}`\n", plugin->name, plugin->description, plugin->name);
        specs = plugin->params;
      }
      const auto& others = parts.accepted[static_cast<std::size_t>(c - parts.components.begin())];
      if (others.size() > 1)
        t += fmt::format("# {} plugins this kind accepts: {}\n", c->registry_kind, fmt::join(others, ", "));
    } else if (table == parts.example_table) {
      specs = parts.info.params;  // the kind's own settings
    }
    append_toml_table(t, value, toml_key(table), specs, true);
  }
  if (parts.grid && !parts.grid->empty()) {
    t += "\n# The shipped study's grid (a bare key is a [model] parameter; dotted paths reach any table).\n[grid]\n";
    for (const auto& [key, value] : parts.grid->items())
      t += fmt::format("{} = {}\n", toml_key(key), toml_value(value, false));
  } else {
    t += grid_suggestion(validated);
  }
  return t;
}

// The rendered text read back the way `chatterlab validate` reads it: written to a private
// temporary file, loaded (plugins, tables, grid), removed. "" when it loads.
std::string round_trip_refusal(const std::string& toml) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("chatterlab-init-{}", ::getpid());
  std::error_code ec;
  fs::create_directories(dir, ec);
  const fs::path file = dir / "study.toml";
  std::string why;
  try {
    write_file_atomically(file, toml);
    load_study(file);
  } catch (const std::exception& e) {
    why = e.what();
  }
  fs::remove_all(dir, ec);
  return why;
}

// The leading comment block of a shipped study (its sources and assumptions), as comment lines.
std::string leading_comments(const fs::path& file) {
  std::ifstream in(file);
  std::string line, out;
  while (std::getline(in, line) && (line.empty() || line.front() == '#'))
    if (!line.empty()) out += line + '\n';
  return out;
}

// True when a string anywhere in `value` is a path below `dir` (a data file the kind resolved).
bool names_file_in(const Json& value, const std::string& dir) {
  if (value.is_string()) return value.get_ref<const std::string&>().rfind(dir, 0) == 0;
  if (value.is_structured())
    for (const auto& item : value)
      if (names_file_in(item, dir)) return true;
  return false;
}

std::vector<ShippedStudy> shipped_studies_of(const std::string& kind_name) {
  std::vector<ShippedStudy> out;
  for (auto& study : shipped_studies())
    if (study.kind == kind_name) out.push_back(std::move(study));
  return out;
}

std::string stems(const std::vector<ShippedStudy>& studies) {
  std::vector<std::string> names;
  for (const auto& s : studies) names.push_back(s.file.stem().string());
  return fmt::format("{}", fmt::join(names, ", "));
}

const ShippedStudy& chosen_example(const std::vector<ShippedStudy>& examples, const std::string& kind_name,
                                   const std::string& name) {
  const std::string stem = fs::path(name).stem().string();
  for (const auto& s : examples)
    if (s.file.stem() == stem) return s;
  if (examples.empty())
    throw InputError(fmt::format("init --example {}: no study of kind '{}' is shipped{}", name, kind_name,
                                 shipped_studies_dir() ? "" : " (no shipped studies found beside libchatterlab)"));
  throw InputError(fmt::format("init --example {}: no shipped study of kind '{}' has that name; shipped: {}",
                               name, kind_name, stems(examples)));
}

// The first of the kind's settings tables that accepts the kind's example_params merged in:
// the table info.params describes (for the comments).
std::string settings_table_of(const StudyKind& kind, const PluginInfo& info, const Json& document,
                              const std::vector<std::string>& settings_tables, const std::string& kind_name) {
  if (settings_tables.size() == 1) return settings_tables.front();
  if (info.example_params.empty()) return {};
  for (const std::string& table : settings_tables) {
    Json trial = document;
    if (!trial[table].is_object()) trial[table] = Json::object();
    trial[table].update(info.example_params);
    if (refusal(kind, trial, kind_name).empty()) return table;
  }
  return {};
}

}  // namespace

StudyTemplate study_template(const std::string& kind_name, const StudyTemplateOptions& options) {
  const auto& entry = study_kind_registry().at(kind_name);
  const auto kind = entry.create(ParamValues{});
  const PluginInfo& info = entry.info;
  const std::vector<ShippedStudy> examples = shipped_studies_of(kind_name);
  const ShippedStudy* example =
      options.example.empty() ? nullptr : &chosen_example(examples, kind_name, options.example);

  // The kind's own settings table: the one table it reads that is not a component.
  std::vector<Component> components;
  std::vector<std::string> settings_tables;
  for (const std::string& table : kind->tables()) {
    if (auto c = component_of(table, entry.origin)) components.push_back(std::move(*c));
    else settings_tables.push_back(table);
  }
  for (const auto& [table, plugin] : options.components) {
    auto it = std::find_if(components.begin(), components.end(), [&](const Component& c) { return c.table == table; });
    if (it == components.end())
      throw InputError(fmt::format("study kind '{}' has no component table [{}]", kind_name, table));
    if (!find_plugin(*it, plugin))
      throw InputError(fmt::format("unknown {} '{}' for [{}]", it->registry_kind, plugin, table));
  }

  TemplateParts parts{kind_name, info, entry.origin, components, std::vector<std::vector<std::string>>(components.size()),
                      {}, Json::object(), std::nullopt, {}};
  StudyTemplate out;
  if (!example) {
    parts.document = generated_document(*kind, info, entry.origin, components, settings_tables, options,
                                        parts.accepted, parts.example_table, kind_name);
    out.error = refusal(*kind, parts.document, kind_name);
    // A kind that needs what no default supplies starts from its first shipped study instead.
    if (!out.error.empty() && !examples.empty()) example = &examples.front();
  }
  if (example) {
    out.based_on = example->file;
    Study study = load_study(example->file);  // a shipped study that does not load is a packaging bug
    Json document = study.document;
    if (document.contains("grid")) {
      parts.grid = document["grid"];
      document.erase("grid");
    }
    if (!options.name.empty()) document["study"]["name"] = options.name;
    for (const auto& [table, plugin] : options.components) {
      const auto& c = *std::find_if(components.begin(), components.end(), [&](const Component& x) { return x.table == table; });
      document[table] = component_table(*find_plugin(c, plugin));
    }
    for (std::size_t i = 0; i < components.size(); ++i)
      for (const PluginInfo* plugin : components[i].plugins) {
        Json trial = document;
        trial[components[i].table] = component_table(*plugin);
        if (refusal(*kind, trial, kind_name).empty()) parts.accepted[i].push_back(plugin->name);
      }
    parts.example_table = settings_table_of(*kind, info, document, settings_tables, kind_name);
    parts.document = std::move(document);
    out.error = refusal(*kind, parts.document, kind_name);
    parts.preamble = fmt::format("#\n# Started from the shipped study {}{}; its notes:\n", example->file.string(),
                                 examples.size() > 1 ? fmt::format(" (shipped studies of this kind: {}; "
                                                                   "`chatterlab init {} --example NAME` starts from another)",
                                                                   stems(examples), kind_name)
                                                     : "");
    parts.preamble += leading_comments(example->file);
    if (names_file_in(parts.document, example->file.parent_path().string() + "/"))
      parts.preamble += "# Its data files are named by absolute path: point them at your own measurements.\n";
  } else if (!examples.empty()) {
    parts.preamble = fmt::format("#\n# Shipped studies of this kind (`chatterlab init {} --example NAME`): {}\n",
                                 kind_name, stems(examples));
  }
  if (out.error.empty()) {
    LineSourceMap sources("`chatterlab init " + kind_name + "`");
    kind->validate(parts.document, sources);  // defaults filled in: every key is written
  }
  out.validated = out.error.empty();
  out.toml = render(parts, out);
  if (out.validated) {
    // What init calls valid must load as `chatterlab validate` loads it (grid and all).
    out.error = round_trip_refusal(out.toml);
    if (!out.error.empty()) {
      out.validated = false;
      out.toml = render(parts, out);
    }
  }
  return out;
}

}  // namespace chatterlab
