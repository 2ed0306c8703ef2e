// `chatterlab list` and `chatterlab describe NAME`: everything a user needs to write a study table
// for a plugin comes from its PluginInfo, so the text can never drift from the code.
#include "chatterlab/catalog.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "chatterlab/analysis.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/suppression.hpp"
#include "toml_text.hpp"

namespace chatterlab {
namespace {

using Row = std::vector<std::string>;

// Left-aligned columns separated by two spaces; the last column is not padded (it holds the
// free-text description).
std::string format_table(const std::vector<Row>& rows, std::string_view indent) {
  std::vector<std::size_t> widths;
  for (const Row& row : rows) {
    if (widths.size() < row.size()) widths.resize(row.size(), 0);
    for (std::size_t c = 0; c + 1 < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  }
  std::string out;
  for (const Row& row : rows) {
    std::string line(indent);
    for (std::size_t c = 0; c < row.size(); ++c)
      line += c + 1 < row.size() ? fmt::format("{:<{}}  ", row[c], widths[c]) : row[c];
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + '\n';
  }
  return out;
}

// ------------------------------------------------------------------ every registry, uniformly

// One registered entry seen through what the catalog needs, whatever its product type.
struct CatalogEntry {
  std::string kind;  // the registry's kind: "model", "study kind", ...
  const PluginInfo* info;
  std::string origin;
  // Study kinds only: the top-level tables the kind reads (StudyKind::tables()).
  std::vector<std::string> tables;
};

template <class Product>
void collect(const Registry<Product>& registry, std::vector<CatalogEntry>& out) {
  for (const auto* entry : registry.sorted())
    out.push_back(CatalogEntry{registry.kind(), &entry->info, entry->origin, {}});
}

// Study kinds first (a study starts with its kind), then the plugin kinds in data-flow order.
std::vector<CatalogEntry> all_entries() {
  std::vector<CatalogEntry> out;
  for (const auto* entry : study_kind_registry().sorted()) {
    CatalogEntry e{study_kind_registry().kind(), &entry->info, entry->origin, {}};
    // A kind holds no per-study state (study_kind.hpp), so building one just to ask which tables
    // it reads is harmless.
    if (auto kind = entry->create(ParamValues{})) e.tables = kind->tables();
    out.push_back(std::move(e));
  }
  collect(model_registry(), out);
  collect(kinematics_registry(), out);
  collect(suppression_registry(), out);
  collect(analysis_registry(), out);
  return out;
}

bool is_component_kind(const std::string& table) {
  return table == model_registry().kind() || table == kinematics_registry().kind() ||
         table == suppression_registry().kind() || table == analysis_registry().kind();
}

// The table holding a study kind's own settings: the one table it reads that is not a component
// table ([model], [kinematics], ...), e.g. [stability] for stability_map. Empty when ambiguous.
std::string settings_table(const CatalogEntry& e) {
  std::vector<std::string> own;
  for (const auto& t : e.tables)
    if (!is_component_kind(t)) own.push_back(t);
  return own.size() == 1 ? own.front() : std::string();
}

// Analyses are not chosen by `type =` like the other components: a study lists them by name,
// [analysis] methods = ["<name>", ...], and takes each one's parameters from [analysis.<name>].
bool is_analysis(const CatalogEntry& e) { return e.kind == analysis_registry().kind(); }
std::string analysis_table(const CatalogEntry& e) {
  return fmt::format("{}.{}", e.kind, toml_key(e.info->name));
}

// Every registered study kind, built once to ask what it reads (a kind holds no per-study
// state, study_kind.hpp), with its name.
template <class Visit>
void for_each_study_kind(Visit visit) {
  for (const auto* entry : study_kind_registry().sorted())
    if (auto kind = entry->create(ParamValues{})) visit(entry->info.name, *kind);
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// Study kinds that read a top-level table (e.g. [analysis]): where a component can be used.
std::vector<std::string> kinds_reading(const std::string& table) {
  std::vector<std::string> kinds;
  for_each_study_kind([&](const std::string& name, const StudyKind& kind) {
    if (contains(kind.tables(), table)) kinds.push_back(name);
  });
  return kinds;
}

// Study kinds that read an analysis' parameters from [<table>.<name>] of their own tables
// (StudyKind::nested_analyses), as (kind, table).
std::vector<std::pair<std::string, std::string>> kinds_nesting(const std::string& analysis) {
  std::vector<std::pair<std::string, std::string>> out;
  for_each_study_kind([&](const std::string& name, const StudyKind& kind) {
    for (const auto& nested : kind.nested_analyses())
      if (contains(nested.analyses, analysis)) out.emplace_back(name, nested.table);
  });
  return out;
}

std::string example_toml(const CatalogEntry& e) {
  std::string out;
  if (is_analysis(e)) {
    out = fmt::format("[{}]\nmethods = [{}]\n", e.kind, Json(e.info->name).dump());
    if (e.info->example_params.empty()) return out;
    out += fmt::format("\n[{}]\n", analysis_table(e));
    append_toml_table(out, e.info->example_params, analysis_table(e), e.info->params);
    return out;
  }
  if (e.kind == study_kind_registry().kind()) {
    out = fmt::format("[study]\nkind = {}\n", Json(e.info->name).dump());
    if (e.info->example_params.empty()) return out;
    std::string table = settings_table(e);
    if (table.empty()) {
      // The kind reads several tables of its own and does not say which holds these settings:
      // show them commented out rather than as keys of [study], which they are not.
      std::string settings;
      append_toml_table(settings, e.info->example_params, "settings", e.info->params);
      out += "\n# settings of this kind (in one of its tables, see its documentation):\n";
      for (std::size_t start = 0; start < settings.size();) {
        std::size_t end = settings.find('\n', start);
        out += fmt::format("# {}\n", settings.substr(start, end - start));
        start = end + 1;
      }
    } else {
      out += fmt::format("\n[{}]\n", toml_key(table));
      append_toml_table(out, e.info->example_params, toml_key(table), e.info->params);
    }
    return out;
  }
  out = fmt::format("[{}]\ntype = {}\n", e.kind, Json(e.info->name).dump());
  append_toml_table(out, e.info->example_params, e.kind, e.info->params);
  return out;
}

// ------------------------------------------------------------------ parameter table

std::string_view short_type(ValueKind kind) {
  switch (kind) {
    case ValueKind::real: return "real";
    case ValueKind::integer: return "integer";
    case ValueKind::boolean: return "boolean";
    case ValueKind::string: return "string";
    case ValueKind::real_list: return "real list";
    case ValueKind::real_matrix: return "real matrix";
    case ValueKind::table_list: return "table list";
    case ValueKind::table: return "table";
  }
  return "?";
}

void append_param_rows(const std::vector<ParamSpec>& specs, const std::string& prefix, int depth,
                       std::vector<Row>& rows) {
  for (const ParamSpec& spec : specs) {
    rows.push_back({std::string(2 * static_cast<std::size_t>(depth), ' ') + prefix + spec.key,
                    std::string(short_type(spec.kind)), spec.unit.empty() ? "-" : spec.unit,
                    limits_text(spec), default_text(spec), spec.description});
    // Fields of each element of a list of tables, e.g. modes[].frequency_hz, and of a nested
    // table, e.g. simulation.seed.
    if (spec.kind == ValueKind::table_list)
      append_param_rows(spec.fields, prefix + spec.key + "[].", depth + 1, rows);
    if (spec.kind == ValueKind::table)
      append_param_rows(spec.fields, prefix + spec.key + ".", depth + 1, rows);
  }
}

std::string_view thread_safety_meaning(ThreadSafety safety) {
  switch (safety) {
    case ThreadSafety::shareable: return "one instance is shared by all threads of a run";
    case ThreadSafety::copy_per_thread: return "each thread of a run builds its own instance";
    case ThreadSafety::serial: return "a run that uses it computes its grid on one thread";
  }
  return "?";
}

std::string describe_entry(const CatalogEntry& e) {
  const PluginInfo& info = *e.info;
  const bool is_kind = e.kind == study_kind_registry().kind();
  std::string out =
      fmt::format("{} ({}, {})\n  {}\n\n", info.name, e.kind, e.origin, info.description);
  std::vector<Row> facts;
  if (is_kind) {
    std::vector<std::string> tables;
    for (const auto& t : e.tables) tables.push_back(fmt::format("[{}]", t));
    facts.push_back({"Used as:", fmt::format("[study] kind = \"{}\"", info.name)});
    if (!tables.empty())
      facts.push_back({"Reads tables:", fmt::format("{}", fmt::join(tables, ", "))});
  } else if (is_analysis(e)) {
    const auto kinds = kinds_reading(e.kind);
    std::string usage = fmt::format("[{}] methods = [\"{}\", ...], parameters in [{}]", e.kind,
                                    info.name, analysis_table(e));
    if (!kinds.empty())
      usage += fmt::format(" (study kind{} {})", kinds.size() > 1 ? "s" : "",
                           fmt::join(kinds, ", "));
    facts.push_back({"Used as:", usage});
    for (const auto& [kind, table] : kinds_nesting(info.name))
      facts.push_back({"Also used as:",
                       fmt::format("parameters in [{}.{}] (study kind {})", table,
                                   toml_key(info.name), kind)});
  } else {
    facts.push_back({"Used as:", fmt::format("[{}] type = \"{}\"", e.kind, info.name)});
  }
  facts.push_back({"MODELS.md:", info.models_md_ids.empty() ? "-" : info.models_md_ids});
  facts.push_back({"Thread safety:", fmt::format("{} ({})", to_string(info.thread_safety),
                                                 thread_safety_meaning(info.thread_safety))});
  out += format_table(facts, "  ");

  std::string table = is_kind ? settings_table(e) : is_analysis(e) ? analysis_table(e) : e.kind;
  out += table.empty() ? "\nParameters:\n" : fmt::format("\nParameters ([{}]):\n", table);
  if (info.params.empty()) {
    out += "  (none)\n";
  } else {
    std::vector<Row> rows{{"key", "type", "unit", "limits", "default", "description"}};
    append_param_rows(info.params, "", 0, rows);
    out += format_table(rows, "  ");
  }

  out += "\nExample:\n";
  std::string example = example_toml(e);
  for (std::size_t start = 0; start < example.size();) {
    std::size_t end = example.find('\n', start);
    std::string line = example.substr(start, end - start);
    out += line.empty() ? std::string("\n") : fmt::format("  {}\n", line);
    start = end == std::string::npos ? example.size() : end + 1;
  }
  return out;
}

}  // namespace

std::string format_plugin_list() {
  std::vector<Row> rows;
  for (const CatalogEntry& e : all_entries()) {
    std::string description = e.info->description;
    if (e.origin != "built-in") description += fmt::format("  (from {})", e.origin);
    rows.push_back({e.kind, e.info->name, description});
  }
  return format_table(rows, "");
}

std::string describe_plugin(std::string_view name) {
  const std::vector<CatalogEntry> entries = all_entries();
  std::string out;
  // Registries are per kind, so one name may exist in two kinds: describe every match.
  for (const CatalogEntry& e : entries) {
    if (e.info->name != name) continue;
    // (Appended piecewise: `"literal" + std::string` trips a false GCC 12 -Wrestrict at -O3.)
    if (!out.empty()) out += '\n';
    out += describe_entry(e);
  }
  if (!out.empty()) return out;
  std::vector<std::string> names;
  for (const CatalogEntry& e : entries) names.push_back(e.info->name);
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  throw InputError(fmt::format("unknown plugin or study kind '{}'; valid names: {}", name,
                               detail::join_names(names)));
}

}  // namespace chatterlab
