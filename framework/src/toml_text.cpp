// TOML text of parameter tables: `chatterlab describe` prints a plugin's example with it and
// `chatterlab init` a whole study, with each key's description, unit, limits and default as a
// comment above it.
#include "toml_text.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace chatterlab {

// Interval notation for two-sided limits ("[0, 1)"), a comparison for one-sided ones ("> 0").
std::string limits_text(const ParamSpec& spec) {
  std::vector<std::string> parts;
  bool has_min = std::isfinite(spec.min), has_max = std::isfinite(spec.max);
  if (has_min && has_max) {
    parts.push_back(fmt::format("{}{}, {}{}", spec.min_exclusive ? '(' : '[',
                                readable_number(spec.min), readable_number(spec.max),
                                spec.max_exclusive ? ')' : ']'));
  } else if (has_min) {
    parts.push_back(
        fmt::format("{} {}", spec.min_exclusive ? ">" : ">=", readable_number(spec.min)));
  } else if (has_max) {
    parts.push_back(
        fmt::format("{} {}", spec.max_exclusive ? "<" : "<=", readable_number(spec.max)));
  }
  if (!spec.choices.empty())
    parts.push_back(fmt::format("one of {}", fmt::join(spec.choices, ", ")));
  if (spec.min_items > 0)
    parts.push_back(
        fmt::format("at least {} {}", spec.min_items, spec.min_items == 1 ? "entry" : "entries"));
  return parts.empty() ? "-" : fmt::format("{}", fmt::join(parts, "; "));
}

std::string default_text(const ParamSpec& spec) {
  if (spec.kind == ValueKind::table) return spec.optional ? "optional" : "-";  // fields below
  if (spec.required()) return "required";
  if (spec.default_value.is_null()) return "optional";
  return toml_value(spec.default_value, is_real_kind(&spec));
}


// "# natural frequency of the mode [Hz]; > 0; required" above a key.
std::string spec_comment(const ParamSpec& spec) {
  std::string text = "# " + spec.description;
  if (!spec.unit.empty() && spec.unit != "1") text += " [" + spec.unit + "]";
  const std::string limits = limits_text(spec);
  if (limits != "-") text += "; " + limits;
  text += "; default: " + default_text(spec);
  return text + "\n";
}


std::string toml_key(const std::string& key) {
  bool bare = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
  return bare ? key : Json(key).dump();
}

bool is_table_array(const Json& v) {
  return v.is_array() && !v.empty() &&
         std::all_of(v.begin(), v.end(), [](const Json& e) { return e.is_object(); });
}

// Shortest text that reads back as the same double, in scientific notation for very large or
// small magnitudes ("5e9", not "5000000000"; stiffnesses and tolerances are read at a glance).
std::string readable_number(double v) {
  const double magnitude = std::abs(v);
  if (!std::isfinite(v) || magnitude == 0.0 || (magnitude >= 1e-4 && magnitude < 1e6))
    return fmt::format("{}", v);
  for (int digits = 0; digits <= 17; ++digits) {
    std::string text = fmt::format("{:.{}e}", v, digits);
    if (std::stod(text) != v) continue;
    // "5e+09" -> "5e9", "1.5e-05" -> "1.5e-5"
    const std::size_t e = text.find('e');
    std::string exponent = text.substr(e + 1);
    const bool negative = exponent.front() == '-';
    exponent.erase(0, exponent.find_first_not_of("+-0"));
    return text.substr(0, e + 1) + (negative ? "-" : "") + exponent;
  }
  return fmt::format("{}", v);
}

// `declared_real`: the spec says real, so numbers are shown as TOML floats ("1450.0", not
// "1450") and the example also teaches the type.
std::string toml_value(const Json& v, bool declared_real) {
  if (v.is_number() && (v.is_number_float() || declared_real)) {
    std::string s = readable_number(v.get<double>());
    if (s.find_first_of(".en") == std::string::npos) s += ".0";
    return s;
  }
  if (v.is_array()) {
    std::vector<std::string> items;
    for (const auto& e : v) items.push_back(toml_value(e, declared_real));
    return fmt::format("[{}]", fmt::join(items, ", "));
  }
  if (v.is_object()) {
    std::vector<std::string> items;
    for (const auto& [k, e] : v.items())
      items.push_back(toml_key(k) + " = " + toml_value(e, false));
    return items.empty() ? "{}" : fmt::format("{{ {} }}", fmt::join(items, ", "));
  }
  // Strings: JSON escapes are valid TOML basic-string escapes. Booleans and integers are alike.
  return v.dump();
}

const ParamSpec* find_spec(const std::vector<ParamSpec>& specs, const std::string& key) {
  auto it =
      std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& p) { return p.key == key; });
  return it == specs.end() ? nullptr : &*it;
}

bool is_real_kind(const ParamSpec* spec) {
  return spec != nullptr && (spec->kind == ValueKind::real || spec->kind == ValueKind::real_list ||
                             spec->kind == ValueKind::real_matrix);
}

// A table's plain keys first, then its arrays of tables as [[header.key]] sections (TOML requires
// that order: keys after a [[...]] header belong to that element). `specs` decide number types.
void append_toml_table(std::string& out, const Json& table, const std::string& header,
                       const std::vector<ParamSpec>& specs, bool comments) {
  for (const auto& [key, value] : table.items()) {
    if (value.is_null() || is_table_array(value) || value.is_object()) continue;
    const ParamSpec* spec = find_spec(specs, key);
    if (comments && spec != nullptr) out += spec_comment(*spec);
    out += toml_key(key) + " = " + toml_value(value, is_real_kind(spec)) + '\n';
  }
  // Nested tables ([header.key]) after the plain keys, as TOML needs.
  for (const auto& [key, value] : table.items()) {
    if (!value.is_object()) continue;
    const ParamSpec* spec = find_spec(specs, key);
    const std::string nested = header + "." + toml_key(key);
    out += fmt::format("\n[{}]\n", nested);
    append_toml_table(out, value, nested, spec != nullptr ? spec->fields : std::vector<ParamSpec>{}, comments);
  }
  for (const auto& [key, value] : table.items()) {
    if (!is_table_array(value)) continue;
    const ParamSpec* spec = find_spec(specs, key);
    const std::vector<ParamSpec> no_fields;
    std::string element_header = header + "." + toml_key(key);
    for (const auto& element : value) {
      out += fmt::format("\n[[{}]]\n", element_header);
      append_toml_table(out, element, element_header, spec != nullptr ? spec->fields : no_fields, comments);
    }
  }
}

}  // namespace chatterlab
