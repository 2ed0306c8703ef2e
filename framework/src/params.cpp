#include "chatterlab/params.hpp"

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "study/messages.hpp"

namespace chatterlab {

std::string_view to_string(ValueKind kind) {
  switch (kind) {
    case ValueKind::real: return "real number";
    case ValueKind::integer: return "integer";
    case ValueKind::boolean: return "boolean";
    case ValueKind::string: return "string";
    case ValueKind::real_list: return "list of real numbers";
    case ValueKind::real_matrix: return "matrix (list of equal-length lists of real numbers)";
    case ValueKind::table_list: return "list of tables";
    case ValueKind::table: return "table";
  }
  return "?";
}

ParamSpec param_spec(std::string key, ValueKind kind, std::string unit, std::string description) {
  ParamSpec spec;
  spec.key = std::move(key);
  spec.kind = kind;
  spec.unit = std::move(unit);
  spec.description = std::move(description);
  return spec;
}

std::string SourceLocation::str() const {
  if (file.empty()) return "<study>";
  return line > 0 ? fmt::format("{}:{}", file, line) : file;
}

// ---------------------------------------------------------------- ParamValues accessors
const Json& ParamValues::at(std::string_view key) const {
  auto it = table_.find(std::string(key));
  if (it == table_.end())
    throw std::logic_error(fmt::format("plugin read undeclared parameter '{}'", key));
  return *it;
}
bool ParamValues::has(std::string_view key) const {
  return table_.contains(std::string(key)) && !table_.at(std::string(key)).is_null();
}
double ParamValues::real(std::string_view key) const { return at(key).get<double>(); }
std::int64_t ParamValues::integer(std::string_view key) const { return at(key).get<std::int64_t>(); }
bool ParamValues::boolean(std::string_view key) const { return at(key).get<bool>(); }
std::string ParamValues::string(std::string_view key) const { return at(key).get<std::string>(); }
std::vector<double> ParamValues::reals(std::string_view key) const {
  return at(key).get<std::vector<double>>();
}
std::vector<std::vector<double>> ParamValues::matrix(std::string_view key) const {
  return at(key).get<std::vector<std::vector<double>>>();
}
std::vector<ParamValues> ParamValues::tables(std::string_view key) const {
  std::vector<ParamValues> out;
  for (const auto& t : at(key)) out.emplace_back(t);
  return out;
}

// ---------------------------------------------------------------- validation
namespace {

using messages::show;

// "a real number", "an integer": the kind names read as the object of "expected".
std::string with_article(ValueKind kind) {
  std::string_view name = to_string(kind);
  bool vowel = name.find_first_of("aeiou") == 0;
  return fmt::format("{} {}", vowel ? "an" : "a", name);
}

std::string limit_text(const ParamSpec& spec) {
  std::string lo, hi;
  if (std::isfinite(spec.min)) lo = fmt::format("{} {}", spec.min_exclusive ? ">" : ">=", spec.min);
  if (std::isfinite(spec.max)) hi = fmt::format("{} {}", spec.max_exclusive ? "<" : "<=", spec.max);
  if (!lo.empty() && !hi.empty()) return "must be " + lo + " and " + hi;
  return "must be " + lo + hi;
}

std::string unit_suffix(const ParamSpec& spec) {
  return spec.unit.empty() || spec.unit == "1" ? std::string() : fmt::format(" [{}]", spec.unit);
}

struct Checker {
  const SourceMap& sources;

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InputError(fmt::format("{}: {}", sources.locate(path).str(), what));
  }

  double number(const Json& v, const ParamSpec& spec, const std::string& path) const {
    if (!v.is_number() || v.is_boolean())
      fail(path, fmt::format("{} = {}: expected {}", path, show(v),
                             with_article(spec.kind == ValueKind::integer ? ValueKind::integer
                                                                          : ValueKind::real)));
    double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, fmt::format("{} = {}: must be finite", path, show(v)));
    bool below = spec.min_exclusive ? d <= spec.min : d < spec.min;
    bool above = spec.max_exclusive ? d >= spec.max : d > spec.max;
    if (below || above)
      fail(path, fmt::format("{} = {}{}: out of range, {} ({})", path, show(v), unit_suffix(spec),
                             limit_text(spec), spec.description));
    return d;
  }

  Json value(const Json& v, const ParamSpec& spec, const std::string& path) const {
    auto type_error = [&] {
      fail(path, fmt::format("{} = {}: expected {}", path, show(v), with_article(spec.kind)));
    };
    switch (spec.kind) {
      case ValueKind::real: return number(v, spec, path);
      case ValueKind::integer: {
        double d = number(v, spec, path);
        if (v.is_number_integer()) return v.get<std::int64_t>();  // exact, even beyond 2^53
        // A whole real (2.0, or a generated grid value) is accepted; 2^63 itself does not fit.
        if (d != std::floor(d) || std::fabs(d) >= 9.2233720368547758e18) type_error();
        return static_cast<std::int64_t>(d);
      }
      case ValueKind::boolean:
        if (!v.is_boolean()) type_error();
        return v;
      case ValueKind::string: {
        if (!v.is_string()) type_error();
        if (!spec.choices.empty() &&
            std::find(spec.choices.begin(), spec.choices.end(), v.get<std::string>()) ==
                spec.choices.end()) {
          fail(path, fmt::format("{} = {}: not one of: {}{}", path, show(v),
                                 messages::sorted_list(spec.choices),
                                 messages::did_you_mean(v.get<std::string>(), spec.choices)));
        }
        if (spec.data_file) return data_file(v, path);
        return v;
      }
      case ValueKind::real_list: {
        if (!v.is_array()) type_error();
        count(v, spec, path);
        Json out = Json::array();
        for (std::size_t i = 0; i < v.size(); ++i)
          out.push_back(number(v[i], spec, fmt::format("{}.{}", path, i)));
        return out;
      }
      case ValueKind::real_matrix: {
        if (!v.is_array()) type_error();
        count(v, spec, path);
        Json out = Json::array();
        for (std::size_t i = 0; i < v.size(); ++i) {
          std::string row_path = fmt::format("{}.{}", path, i);
          if (!v[i].is_array()) fail(row_path, fmt::format("{} = {}: expected a list of real numbers (a matrix row)", row_path, show(v[i])));
          if (v[i].size() != v[0].size())
            fail(row_path, fmt::format("{} has {} entries but row 0 has {}: a matrix must be rectangular",
                                       row_path, v[i].size(), v[0].size()));
          Json row = Json::array();
          for (std::size_t j = 0; j < v[i].size(); ++j)
            row.push_back(number(v[i][j], spec, fmt::format("{}.{}", row_path, j)));
          out.push_back(std::move(row));
        }
        return out;
      }
      case ValueKind::table_list: {
        if (!v.is_array()) type_error();
        count(v, spec, path);
        Json out = Json::array();
        for (std::size_t i = 0; i < v.size(); ++i) {
          std::string item = fmt::format("{}.{}", path, i);
          if (!v[i].is_object()) fail(item, fmt::format("{} = {}: expected a table", item, show(v[i])));
          out.push_back(validate_params(v[i], spec.fields, item, sources));
        }
        return out;
      }
      case ValueKind::table:
        if (!v.is_object()) type_error();
        return validate_params(v, spec.fields, path, sources);
    }
    fail(path, "unsupported parameter kind");
  }

  // A data file name resolved against the directory of the study file that names it.
  Json data_file(const Json& v, const std::string& path) const {
    std::filesystem::path file = v.get<std::string>();
    if (file.empty()) fail(path, fmt::format("{} = \"\": expected a file name", path));
    const SourceLocation where = sources.locate(path);
    if (file.is_relative() && where.line > 0)
      file = std::filesystem::absolute(std::filesystem::path(where.file)).parent_path() / file;
    file = file.lexically_normal();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
      fail(path, fmt::format("{} = {}: no such file{}", path, show(v),
                             file.string() == v.get<std::string>() ? "" : fmt::format(" ({})", file.string())));
    return file.string();
  }

  void count(const Json& v, const ParamSpec& spec, const std::string& path) const {
    if (v.size() < spec.min_items)
      fail(path, fmt::format("{} has {} entries: needs at least {} ({})", path, v.size(),
                             spec.min_items, spec.description));
  }
};

}  // namespace

Json validate_params(const Json& table, const std::vector<ParamSpec>& specs, std::string_view path,
                     const SourceMap& sources) {
  Checker check{sources};
  std::string prefix = path.empty() ? std::string() : std::string(path) + ".";
  if (!table.is_object())
    check.fail(std::string(path), fmt::format("{} = {}: expected a table", path, show(table)));
  Json out = Json::object();
  for (const auto& [key, value] : table.items()) {
    auto it = std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.key == key; });
    if (it == specs.end()) {
      std::vector<std::string> valid;
      for (const auto& s : specs) valid.push_back(s.key);
      check.fail(prefix + key, fmt::format("unknown key '{}{}'{}; valid keys: {}", prefix, key,
                                           messages::did_you_mean(key, valid),
                                           messages::sorted_list(valid)));
    }
  }
  for (const auto& spec : specs) {
    std::string key_path = prefix + spec.key;
    auto it = table.find(spec.key);
    // null: an optional parameter left out, as a previous validation wrote it (validating a
    // validated table again must succeed: grid values are checked that way).
    if (it == table.end() || it->is_null()) {
      // A nested table left out is the table of its fields' defaults (and a required field
      // in it is reported as missing).
      if (spec.kind == ValueKind::table && spec.default_value.is_object()) {
        out[spec.key] = validate_params(spec.default_value, spec.fields, key_path, sources);
        continue;
      }
      if (spec.required())
        check.fail(std::string(path), fmt::format("missing required key '{}' ({}{})", key_path,
                                                  spec.description, unit_suffix(spec)));
      out[spec.key] = spec.default_value;
      continue;
    }
    out[spec.key] = check.value(*it, spec, key_path);
  }
  return out;
}

}  // namespace chatterlab
