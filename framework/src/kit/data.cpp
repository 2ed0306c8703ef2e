#include "chatterlab/kit/data.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstdint>
#include <iostream>
#include <set>

#include "chatterlab/errors.hpp"

namespace chatterlab::kit {

namespace fs = std::filesystem;

void check_known_keys(const Json& table, const std::vector<std::string>& allowed,
                      const std::string& path, const SourceMap& sources) {
  for (const auto& [key, value] : table.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::vector<std::string> sorted = allowed;
    std::sort(sorted.begin(), sorted.end());
    throw InputError(fmt::format("{}: unknown key '{}.{}'; valid keys: {}",
                                 sources.locate(path + "." + key).str(), path, key,
                                 fmt::join(sorted, ", ")));
  }
}

std::vector<std::string> string_list(const Json& value, const std::string& path,
                                     const SourceMap& sources, std::size_t min_items,
                                     std::size_t max_items, bool allow_repeats) {
  const std::string where = sources.locate(path).str();
  if (!value.is_array())
    throw InputError(fmt::format("{}: {} = {}: expected a list of strings, e.g. [\"A\", \"B\"]",
                                 where, path, value.dump()));
  std::vector<std::string> out;
  std::set<std::string> seen;
  for (const Json& item : value) {
    if (!item.is_string() || item.get<std::string>().empty())
      throw InputError(fmt::format("{}: {} = {}: every entry must be a non-empty string", where,
                                   path, value.dump()));
    if (!seen.insert(item.get<std::string>()).second && !allow_repeats)
      throw InputError(fmt::format("{}: {} = {}: \"{}\" is listed twice", where, path, value.dump(),
                                   item.get<std::string>()));
    out.push_back(item.get<std::string>());
  }
  if (out.size() < min_items || out.size() > max_items)
    throw InputError(fmt::format("{}: {} = {}: {} entries, must be {} to {}", where, path,
                                 value.dump(), out.size(), min_items, max_items));
  return out;
}

fs::path resolve_data_file(const Json& value, const std::string& path, const SourceMap& sources) {
  const SourceLocation where = sources.locate(path);
  if (!value.is_string() || value.get<std::string>().empty())
    throw InputError(
        fmt::format("{}: {} = {}: expected a file name (string)", where.str(), path, value.dump()));
  fs::path file = value.get<std::string>();
  if (file.is_relative() && !where.file.empty())
    file = fs::absolute(fs::path(where.file)).parent_path() / file;
  return file.lexically_normal();
}

DataTable read_table_at(const fs::path& file, const std::string& path, const SourceMap& sources) {
  return *read_shared_table_at(file, path, sources);
}

std::shared_ptr<const DataTable> read_shared_table_at(const fs::path& file, const std::string& path,
                                                      const SourceMap& sources) {
  try {
    return read_shared_data_table(file);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}: {}", sources.locate(path).str(), path, e.what()));
  }
}

const std::vector<double>& column_at(const DataTable& table, const std::string& name,
                                     const std::string& path, const SourceMap& sources) {
  try {
    return table.column(name);  // a header name or a 1-based index written as digits
  } catch (const std::exception&) {  // InputError, or out_of_range for an absurd index
    throw InputError(fmt::format("{}: {}: no column \"{}\" in {} (columns: {})",
                                 sources.locate(path).str(), path, name, table.file.string(),
                                 fmt::join(table.names, ", ")));
  }
}

void integer_columns_as_names(Json& table, const std::vector<std::string>& keys) {
  if (!table.is_object()) return;
  auto as_name = [](Json& value) {
    if (value.is_number_integer()) value = std::to_string(value.get<std::int64_t>());
  };
  for (const std::string& key : keys) {
    if (!table.contains(key)) continue;
    Json& value = table[key];
    if (value.is_array())
      for (Json& item : value) as_name(item);
    else
      as_name(value);
  }
}

const SourceMap& no_sources() {
  struct NoSources final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  };
  static const NoSources sources;
  return sources;
}

void warn(const std::string& message) { std::cerr << "chatterlab: warning: " << message << '\n'; }

}  // namespace chatterlab::kit
