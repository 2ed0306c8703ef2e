// load_study: the generic part of reading a study (plugins, [study], top-level keys, [grid]);
// the kind validates its own tables.
#include <algorithm>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "study/grid.hpp"
#include "study/messages.hpp"
#include "study/toml_reader.hpp"

namespace chatterlab {
namespace {

// Keys every study may have, whatever its kind.
const std::vector<std::string>& generic_keys() {
  static const std::vector<std::string> keys = {"plugins", "study", "grid", "run", "output"};
  return keys;
}

// [run]: how the runner treats the points (docs/studies.md, "[run]"). Not seen by the kind and
// not part of the resume fingerprint: these settings never change an ok point's numbers.
std::vector<ParamSpec> run_table_specs() {
  std::vector<ParamSpec> specs = {
      param_spec("point_timeout_s", ValueKind::real, "s",
                 "time limit of one grid point; a point still running then is killed and "
                 "recorded as timeout (points run in worker processes); absent: no limit"),
      param_spec("isolate", ValueKind::boolean, "1",
                 "run every point in a worker process, so that a crashing plugin fails only its "
                 "point (as --isolate)")};
  specs[0].min = 0.0;
  specs[0].min_exclusive = true;
  specs[0].optional = true;
  specs[1].default_value = false;
  return specs;
}

// [output]: how the runner writes the results (docs/studies.md, "[output]"). Like [run], not seen
// by the kind and not part of the resume fingerprint: the numbers are the same in every format.
std::vector<ParamSpec> output_table_specs() {
  std::vector<ParamSpec> specs = {
      param_spec("format", ValueKind::string, "1",
                 "results file: \"csv\" (results.csv), \"hdf5\" (results.h5: compressed, one "
                 "dataset per output column over the grid axes) or \"auto\" (hdf5 for grids of "
                 "more than 100,000 points, else csv)"),
      param_spec("keep_journal", ValueKind::boolean, "1",
                 "keep journal/ after a complete hdf5 run (by default it is removed then: "
                 "results.h5 holds every point, and --resume reads it)")};
  specs[0].default_value = std::string("csv");
  specs[0].choices = {"csv", "hdf5", "auto"};
  specs[1].default_value = false;
  return specs;
}

std::vector<std::string> study_kind_names() {
  std::vector<std::string> names;
  for (const auto* entry : study_kind_registry().sorted()) names.push_back(entry->info.name);
  return names;
}

std::vector<ParamSpec> study_table_specs(const std::filesystem::path& file) {
  std::vector<ParamSpec> specs = {
      param_spec("kind", ValueKind::string, "1",
                 "what the study computes, one of: " + messages::sorted_list(study_kind_names())),
      param_spec("name", ValueKind::string, "1",
                 "name shown in plots and meta.json (default: the file name without .toml)"),
      param_spec("description", ValueKind::string, "1", "free text, copied to meta.json")};
  specs[1].default_value = file.stem().string();
  specs[2].default_value = std::string();
  return specs;
}

// `plugins = [...]`: resolves each path against the study file's directory and loads it, before
// any table is validated, so that the libraries' plugins are known by then.
std::vector<std::string> load_plugins(Json& document, const std::filesystem::path& file,
                                      const SourceMap& sources) {
  auto it = document.find("plugins");
  if (it == document.end()) return {};
  auto fail = [&](const std::string& path, const std::string& what) {
    throw InputError(fmt::format("{}: {}", sources.locate(path).str(), what));
  };
  if (!it->is_array())
    fail("plugins", fmt::format("plugins = {}: expected a list of shared library paths, e.g. "
                                "plugins = [\"lib/libmy_model.so\"]", messages::show(*it)));
  std::filesystem::path base = std::filesystem::absolute(file).parent_path();
  std::vector<std::string> resolved;
  for (std::size_t i = 0; i < it->size(); ++i) {
    const Json& entry = (*it)[i];
    std::string path = fmt::format("plugins.{}", i);
    if (!entry.is_string() || entry.get<std::string>().empty())
      fail(path, fmt::format("{} = {}: expected the path of a shared library (a non-empty string)",
                             path, messages::show(entry)));
    std::filesystem::path library = entry.get<std::string>();
    if (library.is_relative()) library = base / library;
    std::string absolute = library.lexically_normal().string();
    try {
      load_plugin_library(absolute);
    } catch (const InputError& e) {
      fail(path, fmt::format("{} = {} ({}): {}", path, messages::show(entry), absolute, e.what()));
    }
    // Its hash goes into meta.json and the resume fingerprint (the library decides results).
    if (auto snapshot = current_input_snapshot())
      snapshot->read(absolute, InputRole::plugin, /*keep_bytes=*/false);
    resolved.push_back(absolute);
  }
  *it = resolved;
  return resolved;
}

// [study]: validated in place; returns the kind.
std::string validate_study_table(Json& document, const std::filesystem::path& file,
                                 const SourceMap& sources) {
  Json& table = document["study"];  // absent: validated as empty, so "missing key study.kind"
  if (table.is_null()) table = Json::object();
  table = validate_params(table, study_table_specs(file), "study", sources);
  std::string kind = table["kind"].get<std::string>();
  try {
    study_kind_registry().at(kind);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: study.kind = \"{}\": {}{}", sources.locate("study.kind").str(),
                                 kind, e.what(), messages::did_you_mean(kind, study_kind_names())));
  }
  return kind;
}

// Top-level keys: the generic ones and the kind's tables, nothing else.
void check_top_level(const Json& document, const StudyKind& kind, const SourceMap& sources) {
  std::vector<std::string> tables = kind.tables();
  std::vector<std::string> valid = generic_keys();
  valid.insert(valid.end(), tables.begin(), tables.end());
  for (const auto& [key, value] : document.items()) {
    std::string where = sources.locate(key).str();
    if (std::find(valid.begin(), valid.end(), key) == valid.end())
      throw InputError(fmt::format("{}: unknown top-level key '{}'{}; valid: {}", where, key,
                                   messages::did_you_mean(key, valid), messages::sorted_list(valid)));
    bool is_table = key != "plugins";
    if (is_table && !value.is_object())
      throw InputError(fmt::format("{}: {} = {}: expected a table [{}]", where, key,
                                   messages::show(value), key));
  }
}

// The document a kind sees: without [grid], [run] and [output] (the runner's tables).
Json without_grid(const Json& document) {
  Json out = Json::object();
  for (const auto& [key, value] : document.items())
    if (key != "grid" && key != "run" && key != "output") out[key] = value;
  return out;
}

// "<file>:<line>" of the table that chose `plugin` (type = "<plugin>"), or the file alone.
std::string plugin_table_location(const Json& document, const std::string& plugin,
                                  const SourceMap& sources, const std::filesystem::path& file) {
  // A study kind from a library (plugin API 2) is chosen by [study] kind.
  if (const auto study = document.find("study"); study != document.end() && study->is_object() &&
                                                  study->value("kind", Json()) == Json(plugin))
    return sources.locate("study.kind").str();
  for (const auto& [key, value] : document.items())
    if (value.is_object() && value.value("type", Json()) == Json(plugin))
      return sources.locate(key + ".type").str();
  return file.string();
}

// Runs the kind's checks. Whatever a plugin throws while being built or asked during validation
// is bad input (exit 2) with the study file, the table's line and the plugin named; only
// InputError passes unchanged (it carries its own location).
template <class Check>
void with_plugin_errors_as_input_errors(const Json& document, const SourceMap& sources,
                                        const std::filesystem::path& file, Check&& check) {
  try {
    check();
  } catch (const InputError&) {
    throw;
  } catch (const PluginError& e) {
    throw InputError(fmt::format("{}: {}", plugin_table_location(document, e.plugin(), sources, file),
                                 e.what()));
  } catch (...) {
    std::string plugins = out_of_tree_plugins_in(document);
    throw InputError(fmt::format("{}: checking the study failed: {}{}", file.string(),
                                 describe_current_exception(),
                                 plugins.empty() ? "" : " (out-of-tree plugins: " + plugins + ")"));
  }
}

}  // namespace

namespace {

// The caller has an InputScope of `snapshot` open: every file read while the study is checked
// (its plugin libraries, its data files) is recorded with its hash, and its bytes are what the
// run's points will see.
Study load_parsed(Json document, const std::filesystem::path& file, std::shared_ptr<const SourceMap> source_map,
                  std::shared_ptr<InputSnapshot> snapshot, const LoadOptions& options) {
  const SourceMap& sources = *source_map;
  Study study;
  study.file = file;
  study.sources = std::move(source_map);
  study.inputs = std::move(snapshot);
  study.plugin_libraries = load_plugins(document, file, sources);
  study.kind = validate_study_table(document, file, sources);
  std::unique_ptr<StudyKind> kind;  // from a library, its constructor is plugin code too
  with_plugin_errors_as_input_errors(document, sources, file, [&] {
    kind = study_kind_registry().at(study.kind).create(ParamValues());
  });
  check_top_level(document, *kind, sources);
  if (document.contains("run"))
    document["run"] = validate_params(document["run"], run_table_specs(), "run", sources);
  if (document.contains("output"))
    document["output"] = validate_params(document["output"], output_table_specs(), "output", sources);

  Json grid = document.contains("grid") ? document["grid"] : Json::object();
  Json validated = without_grid(document);
  with_plugin_errors_as_input_errors(document, sources, file, [&] {
    kind->validate(validated, sources);
    study.output_columns = kind->output_columns(validated);
    study.grid =
        build_grid(grid, validated, *kind, sources, options, study.output_columns.size());
  });

  // The resolved study in the order the file was written; [grid] as written (flat).
  study.document = Json::object();
  for (const auto& [key, value] : document.items())
    study.document[key] = key == "grid" || !validated.contains(key) ? value : validated[key];
  for (const auto& [key, value] : validated.items())  // tables the kind added (defaults)
    if (!study.document.contains(key)) study.document[key] = value;
  return study;
}

}  // namespace

Study load_study(const std::filesystem::path& file, const LoadOptions& options) {
  auto snapshot = std::make_shared<InputSnapshot>();
  InputScope reads_through(snapshot);  // the study file itself is an input too
  TomlDocument toml = read_toml_study(file);
  return load_parsed(std::move(toml.document), file, std::move(toml.sources), std::move(snapshot), options);
}

Study load_study_document(Json document, const std::filesystem::path& origin, const LoadOptions& options) {
  if (!document.is_object())
    throw InputError(fmt::format("{}: a study is a table of tables ([study], [model], ...), not {}",
                                 origin.string(), messages::show(document)));
  auto snapshot = std::make_shared<InputSnapshot>();
  InputScope reads_through(snapshot);
  return load_parsed(std::move(document), origin, std::make_shared<LineSourceMap>(origin.string()),
                     std::move(snapshot), options);
}

std::size_t Study::point_count() const {
  std::vector<std::size_t> sizes;
  for (const auto& axis : grid) sizes.push_back(axis.values.size());
  return grid_point_count(sizes).value();  // load_study rejected grids that overflow
}

std::vector<std::size_t> Study::point_indices(std::size_t point) const {
  if (point >= point_count())
    throw std::out_of_range(fmt::format("grid point {} of {}", point, point_count()));
  std::vector<std::size_t> indices(grid.size());
  for (std::size_t a = grid.size(); a-- > 0;) {
    indices[a] = point % grid[a].values.size();
    point /= grid[a].values.size();
  }
  return indices;
}

Json Study::point_document(std::size_t point) const {
  std::vector<std::size_t> indices = point_indices(point);
  Json out = without_grid(document);
  for (std::size_t a = 0; a < grid.size(); ++a) set_at_path(out, grid[a].path, grid[a].values[indices[a]]);
  return out;
}

}  // namespace chatterlab
