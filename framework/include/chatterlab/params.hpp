#pragma once
// Typed plugin parameters: every plugin declares its parameters (unit, limits, default,
// description) as a list of ParamSpec. The framework validates a study's table against that list
// (unknown keys, missing keys, types, limits, NaN/inf) before the plugin ever sees the values, so a
// plugin reads already-checked values through ParamValues.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace chatterlab {

using Json = nlohmann::ordered_json;

enum class ValueKind {
  real,         // double; must be finite
  integer,      // int64
  boolean,
  string,       // optionally restricted to `choices`
  real_list,    // [1.0, 2.0, ...]
  real_matrix,  // [[...], [...]] rectangular
  table_list,   // [{...}, {...}] each element validated against `fields`
  table,        // a nested table [<table>.<key>] validated against `fields`; left out, it is
                // the table of its fields' defaults (default_value {}) or null (optional)
};

std::string_view to_string(ValueKind kind);

struct ParamSpec {
  std::string key;
  ValueKind kind = ValueKind::real;
  std::string unit;         // SI unit or "1" for dimensionless; also in the key name where possible
  std::string description;  // one line, shown by `chatterlab describe`
  Json default_value;       // null => required
  // Limits for reals/integers (and every element of lists/matrices).
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool max_exclusive = false;
  std::vector<std::string> choices;  // allowed strings (empty: any)
  std::vector<ParamSpec> fields;     // element fields for table_list, the fields of a table
  std::size_t min_items = 0;         // for lists/matrices/table_list
  bool optional = false;             // absent and no default: left null, plugin decides
  // A string naming a data file: a relative name is taken relative to the directory of the study
  // file it is written in (as `plugins`), validation writes the absolute path back and refuses a
  // file that does not exist.
  bool data_file = false;
  bool required() const { return default_value.is_null() && !optional; }
};

// A spec with its key, kind, unit and description; set limits, default etc. on the result.
// (Designated initialisers would read better, but GCC 12 warns under -Wextra about every field
// they leave out, and assigning string literals to the fields trips a false -Wrestrict at -O3.)
ParamSpec param_spec(std::string key, ValueKind kind, std::string unit, std::string description);

// Read access to a validated parameter table (defaults already filled in). The accessors assume
// validation passed; a wrong key here is a programming error in the plugin (std::logic_error).
class ParamValues {
 public:
  ParamValues() = default;
  explicit ParamValues(Json table) : table_(std::move(table)) {}

  double real(std::string_view key) const;
  std::int64_t integer(std::string_view key) const;
  bool boolean(std::string_view key) const;
  std::string string(std::string_view key) const;
  std::vector<double> reals(std::string_view key) const;
  std::vector<std::vector<double>> matrix(std::string_view key) const;
  std::vector<ParamValues> tables(std::string_view key) const;
  bool has(std::string_view key) const;

  const Json& json() const { return table_; }

 private:
  const Json& at(std::string_view key) const;
  Json table_;
};

// Where a value came from, for error messages: "study.toml:12".
struct SourceLocation {
  std::string file;
  int line = 0;  // 0: unknown
  std::string str() const;
};

// Looks up the source line of a dotted parameter path ("model.modes.0.damping_ratio").
class SourceMap {
 public:
  virtual ~SourceMap() = default;
  virtual SourceLocation locate(std::string_view dotted_path) const = 0;
};

// Validates `table` (the contents of e.g. [model], without the `type` key) against `specs`.
// `path` is the dotted prefix used in messages ("model"). Returns the table with defaults filled.
// Throws InputError: "<file>:<line>: <path.key> = <value>: <what is wrong> (<limit>)", and for
// unknown keys the sorted list of valid keys.
Json validate_params(const Json& table, const std::vector<ParamSpec>& specs, std::string_view path,
                     const SourceMap& sources);

}  // namespace chatterlab
