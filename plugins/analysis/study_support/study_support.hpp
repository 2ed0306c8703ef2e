#pragma once
// Helpers shared by the study kinds that read a measured data file (`error_separation`, `doe`):
// strict checks of the non-scalar keys that ParamSpec does not cover (lists of column names,
// input files relative to the study file), reading the data with the study's line in every
// message, and drawing a study's figures so that one failing figure does not hide the others.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab::study_support {

// Rejects keys of `table` (at dotted `path`) not in `allowed`, listing the valid ones.
void check_known_keys(const Json& table, const std::vector<std::string>& allowed,
                      const std::string& path, const SourceMap& sources);

// The table `name` of the document (an empty table when absent; InputError if not a table).
Json table_or_empty(const Json& document, const std::string& name, const SourceMap& sources);

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

// read_data_table with the study's file:line and key in front of its messages.
DataTable read_table_at(const std::filesystem::path& file, const std::string& path,
                        const SourceMap& sources);

// A column by header name or 1-based index ("2"), or InputError "<study>:<line>: <path> = "<name>": no column '<name>' in
// <file> (columns: ...)".
const std::vector<double>& column_at(const DataTable& table, const std::string& name,
                                     const std::string& path, const SourceMap& sources);

// Column keys given as TOML integers (`column = 2`, `columns = [1, 2, 3]`) mean 1-based column
// indices, the same as "2": rewritten in place as strings in table[key] for each key (a list's
// integer items too) before the string-typed checks see them. Absent keys are left alone.
void integer_columns_as_names(Json& table, const std::vector<std::string>& keys);

// The study's name for plot titles: [study] name, else the study file's stem.
std::string study_title(const Json& document, const std::filesystem::path& study_file);

// Runs every figure-drawing action; collects the failures and throws one plot::PlotError naming
// them all (the runner records it in meta.json).
void render_all(const std::vector<std::pair<std::string, std::function<void()>>>& figures);

// A SourceMap that locates nothing: for re-reading input in run_point (validated before).
const SourceMap& no_sources();

// "chatterlab: warning: <message>" on stderr.
void warn(const std::string& message);

}  // namespace chatterlab::study_support
