#pragma once
// Study kit: kinds that read a measured data file (signal_analysis, chatter_monitor, surface, doe,
// error_separation). Strict checks of the non-scalar keys ParamSpec does not cover (lists of
// column names, files relative to the study file) and reading the data with the study's line in
// every message. Data files are read through the read-once input service
// (chatterlab/input_files.hpp, via read_data_table): every grid point of a run sees the bytes the
// run first read, and the file's hash goes into meta.json.
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab::kit {

// Rejects keys of `table` (at dotted `path`) not in `allowed`, listing the valid ones.
void check_known_keys(const Json& table, const std::vector<std::string>& allowed,
                      const std::string& path, const SourceMap& sources);

// `value` as a list of non-empty strings with min_items..max_items entries, distinct unless
// `allow_repeats`.
std::vector<std::string> string_list(const Json& value, const std::string& path,
                                     const SourceMap& sources, std::size_t min_items,
                                     std::size_t max_items, bool allow_repeats = false);

// A data file path: relative paths are taken relative to the study file's directory (as
// `plugins`); returns the absolute path (stored back into the document, so validation stays
// idempotent).
std::filesystem::path resolve_data_file(const Json& value, const std::string& path,
                                        const SourceMap& sources);

// read_data_table (read once per run) with the study's file:line and key in front of its messages.
DataTable read_table_at(const std::filesystem::path& file, const std::string& path,
                        const SourceMap& sources);
// The same without a copy: the run's parsed table itself (read_shared_data_table), for inputs of
// 10^7 rows where a copy would cost 8 bytes per value.
std::shared_ptr<const DataTable> read_shared_table_at(const std::filesystem::path& file,
                                                      const std::string& path,
                                                      const SourceMap& sources);

// A column by header name or 1-based index ("2"), or InputError "<study>:<line>: <path>: no
// column "<name>" in <file> (columns: ...)".
const std::vector<double>& column_at(const DataTable& table, const std::string& name,
                                     const std::string& path, const SourceMap& sources);

// Column keys given as TOML integers (`column = 2`, `columns = [1, 2, 3]`) mean 1-based column
// indices, the same as "2": rewritten in place as strings in table[key] for each key (a list's
// integer items too) before the string-typed checks see them. Absent keys are left alone.
void integer_columns_as_names(Json& table, const std::vector<std::string>& keys);

// A SourceMap that locates nothing: for re-reading input in run_point (validated before).
const SourceMap& no_sources();

// Locates every path in one file, at no line: parameters given in code (plugin tests, examples),
// whose messages then name that source ("test: model.mass_kg = -1: ...").
class FileSourceMap final : public SourceMap {
 public:
  explicit FileSourceMap(std::string file) : file_(std::move(file)) {}
  SourceLocation locate(std::string_view) const override { return {file_, 0}; }

 private:
  std::string file_;
};

// "chatterlab: warning: <message>" on stderr.
void warn(const std::string& message);

}  // namespace chatterlab::kit
