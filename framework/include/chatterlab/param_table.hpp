#pragma once
// Parameters declared once. A plugin or study kind keeps its settings in a plain struct whose
// member initialisers are the defaults, and declares each member ONCE in a ParamTable: key, unit,
// description and limits. From that one declaration the table gives the ParamSpecs (what
// `chatterlab describe` prints and validate_params checks, defaults taken from the struct), reads
// a validated table into the struct, and writes a struct back as a table (examples, summaries):
//
//     struct Settings {
//       double duration_s = 1.0;
//       std::optional<double> fit_start_s;     // optional: absent means "the plugin decides"
//       Shape shape = Shape::sine;
//     };
//     const ParamTable<Settings>& settings_table() {
//       static const ParamTable<Settings> table = [] {
//         ParamTable<Settings> t;
//         t.add(&Settings::duration_s, "duration_s", "s", "simulated time").positive();
//         t.add(&Settings::fit_start_s, "fit_start_s", "s", "start of the fit").non_negative();
//         t.add_choice(&Settings::shape, "shape", "wave form", {{"sine", Shape::sine}, ...});
//         return t;
//       }();
//       return table;
//     }
//     ...  PluginInfo::params = settings_table().specs();   Settings s = settings_table().read(json);
//
// Member types and the value kinds they declare: double (real), integral types (integer), bool,
// std::string, std::vector<double> (real_list), std::vector<std::vector<double>> (real_matrix),
// an enum through add_choice (string with choices), a struct with its own ParamTable (table,
// add_table), std::vector of such structs (table_list, add_tables); std::optional<T> of any of
// the scalar ones is an optional parameter (null when absent). add_fields embeds a sub-struct's
// table flat (its keys at this table's level).
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

namespace detail {

template <class T> struct is_optional : std::false_type {};
template <class T> struct is_optional<std::optional<T>> : std::true_type {};

template <class T>
constexpr ValueKind value_kind_of() {
  if constexpr (std::is_same_v<T, bool>) return ValueKind::boolean;
  else if constexpr (std::is_floating_point_v<T>) return ValueKind::real;
  else if constexpr (std::is_integral_v<T>) return ValueKind::integer;
  else if constexpr (std::is_same_v<T, std::string>) return ValueKind::string;
  else if constexpr (std::is_same_v<T, std::vector<double>>) return ValueKind::real_list;
  else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>>) return ValueKind::real_matrix;
  else static_assert(sizeof(T) == 0, "ParamTable: no value kind for this member type");
}

}  // namespace detail

template <class S>
class ParamTable {
 public:
  // The declaration of one member, returned by add() so that limits can be chained.
  class Field {
   public:
    Field& positive() { return above(0.0); }
    Field& non_negative() { return at_least(0.0); }
    Field& above(double v) { spec_->min = v; spec_->min_exclusive = true; return *this; }
    Field& at_least(double v) { spec_->min = v; spec_->min_exclusive = false; return *this; }
    Field& below(double v) { spec_->max = v; spec_->max_exclusive = true; return *this; }
    Field& at_most(double v) { spec_->max = v; spec_->max_exclusive = false; return *this; }
    // [0, 1], or [0, 1) when one is excluded (a damping ratio of 1 is no longer a mode; a
    // modulation depth of 1 stops the spindle).
    Field& fraction(bool one_excluded = false) { non_negative(); return one_excluded ? below(1.0) : at_most(1.0); }
    Field& choices(std::vector<std::string> names) { spec_->choices = std::move(names); return *this; }
    Field& min_items(std::size_t n) { spec_->min_items = n; return *this; }
    // A data file name, relative to the study file (ParamSpec::data_file).
    Field& data_file() { spec_->data_file = true; return *this; }
    // No default: the study must give it (the struct's initialiser is then only a placeholder).
    Field& required() { *required_ = true; return *this; }

   private:
    friend class ParamTable;
    Field(ParamSpec* spec, bool* required) : spec_(spec), required_(required) {}
    ParamSpec* spec_;
    bool* required_;
  };

  // A scalar, list or matrix member (or std::optional of one).
  template <class T>
  Field add(T S::*member, std::string key, std::string unit, std::string description) {
    using Value = typename unwrap<T>::type;
    Entry& e = push(param_spec(key, detail::value_kind_of<Value>(), std::move(unit), std::move(description)));
    e.optional = detail::is_optional<T>::value;
    e.read = [member, key](S& s, const Json& table) {
      const Json* found = find(table, key);
      if (!found) return;  // absent: the member keeps its default
      const Json& v = *found;
      if constexpr (detail::is_optional<T>::value) {
        if (v.is_null()) s.*member = std::nullopt;
        else s.*member = v.template get<Value>();
      } else {
        s.*member = v.template get<Value>();
      }
    };
    e.write = [member, key](const S& s, Json& table) {
      if constexpr (detail::is_optional<T>::value) {
        table[key] = (s.*member) ? Json(*(s.*member)) : Json(nullptr);
      } else {
        table[key] = s.*member;
      }
    };
    return Field(&e.spec, &e.required);
  }

  // An enum member written as one of the given names.
  template <class E>
  Field add_choice(E S::*member, std::string key, std::string description,
                   std::vector<std::pair<std::string, E>> names) {
    Entry& e = push(param_spec(key, ValueKind::string, "", std::move(description)));
    for (const auto& [name, value] : names) e.spec.choices.push_back(name);
    e.read = [member, key, names](S& s, const Json& table) {
      const Json* found = find(table, key);
      if (!found) return;
      const std::string text = found->template get<std::string>();
      for (const auto& [name, value] : names)
        if (name == text) { s.*member = value; return; }
      throw std::logic_error("ParamTable: '" + text + "' is no choice of " + key);
    };
    e.write = [member, key, names](const S& s, Json& table) {
      for (const auto& [name, value] : names)
        if (value == s.*member) { table[key] = name; return; }
      throw std::logic_error("ParamTable: a value of " + key + " has no name");
    };
    return Field(&e.spec, &e.required);
  }

  // A nested table [<table>.<key>] whose fields are declared by `fields`.
  template <class Sub>
  Field add_table(Sub S::*member, std::string key, std::string description,
                  const ParamTable<Sub>& fields) {
    Entry& e = push(param_spec(key, ValueKind::table, "", std::move(description)));
    e.spec.fields = fields.specs();
    e.read = [member, key, fields](S& s, const Json& table) {
      if (const Json* found = find(table, key)) s.*member = fields.read(*found);
    };
    e.write = [member, key, fields](const S& s, Json& table) { table[key] = fields.write(s.*member); };
    return Field(&e.spec, &e.required);
  }

  // An optional nested table: null (std::nullopt) when left out, e.g. one of two ways to give a
  // setting (a list of values or a range table).
  template <class Sub>
  Field add_optional_table(std::optional<Sub> S::*member, std::string key, std::string description,
                           const ParamTable<Sub>& fields) {
    Entry& e = push(param_spec(key, ValueKind::table, "", std::move(description)));
    e.spec.fields = fields.specs();
    e.optional = true;
    e.read = [member, key, fields](S& s, const Json& table) {
      const Json* found = find(table, key);
      if (!found) return;
      if (found->is_null()) s.*member = std::nullopt;
      else s.*member = fields.read(*found);
    };
    e.write = [member, key, fields](const S& s, Json& table) {
      table[key] = (s.*member) ? fields.write(*(s.*member)) : Json(nullptr);
    };
    return Field(&e.spec, &e.required);
  }

  // A list of tables ([[<table>.<key>]] or key = [{...}, ...]), each declared by `fields`.
  template <class Sub>
  Field add_tables(std::vector<Sub> S::*member, std::string key, std::string description,
                   const ParamTable<Sub>& fields) {
    Entry& e = push(param_spec(key, ValueKind::table_list, "", std::move(description)));
    e.spec.fields = fields.specs();
    e.read = [member, key, fields](S& s, const Json& table) {
      const Json* found = find(table, key);
      if (!found) return;
      (s.*member).clear();
      for (const Json& item : *found) (s.*member).push_back(fields.read(item));
    };
    e.write = [member, key, fields](const S& s, Json& table) {
      Json list = Json::array();
      for (const Sub& item : s.*member) list.push_back(fields.write(item));
      table[key] = std::move(list);
    };
    return Field(&e.spec, &e.required);
  }

  // The members of a sub-struct declared by its own table, flat in this one: a plugin whose
  // parameters extend another parameter set (G1's plus one coefficient) declares the common part
  // once and keeps it as one member.
  template <class Sub>
  void add_fields(Sub S::*member, const ParamTable<Sub>& fields) {
    for (const auto& sub : fields.entries_) {
      Entry& e = push(sub.spec);
      e.required = sub.required;
      e.optional = sub.optional;
      e.read = [member, read = sub.read](S& s, const Json& table) { read(s.*member, table); };
      e.write = [member, write = sub.write](const S& s, Json& table) { write(s.*member, table); };
    }
  }

  // The declared parameters, in declaration order, defaults from a default-constructed S.
  std::vector<ParamSpec> specs() const {
    const Json defaults = write(S{});
    std::vector<ParamSpec> out;
    out.reserve(entries_.size());
    for (const Entry& e : entries_) {
      ParamSpec spec = e.spec;
      spec.optional = e.optional;
      if (!e.required) spec.default_value = defaults.at(spec.key);
      out.push_back(std::move(spec));
    }
    return out;
  }

  // The struct from a table validated against specs(). A key the table lacks keeps the struct's
  // default (the value specs() declares), so a kind or test that builds a plugin from a partial
  // table gets what validation would have filled in; a null or absent table gives every default.
  // A missing required key is a programming error (validation reports it to the user first).
  S read(const Json& validated_table) const {
    if (!validated_table.is_null() && !validated_table.is_object())
      throw std::logic_error("ParamTable: expected a table, got " + validated_table.dump());
    S s{};
    for (const Entry& e : entries_) {
      if (e.required && !find(validated_table, e.spec.key))
        throw std::logic_error("ParamTable: required parameter '" + e.spec.key + "' missing");
      e.read(s, validated_table);
    }
    return s;
  }
  S read(const ParamValues& values) const { return read(values.json()); }

  // The table of a struct's values (keys in declaration order).
  Json write(const S& s) const {
    Json table = Json::object();
    for (const Entry& e : entries_) e.write(s, table);
    return table;
  }

 private:
  template <class> friend class ParamTable;  // add_fields reads another table's entries
  // The value at key, or nullptr when the table (or the key) is absent.
  static const Json* find(const Json& table, const std::string& key) {
    if (!table.is_object()) return nullptr;
    const auto it = table.find(key);
    return it == table.end() ? nullptr : &*it;
  }

  template <class T> struct unwrap { using type = T; };
  template <class T> struct unwrap<std::optional<T>> { using type = T; };

  struct Entry {
    ParamSpec spec;
    bool required = false;
    bool optional = false;
    std::function<void(S&, const Json&)> read;
    std::function<void(const S&, Json&)> write;
  };

  Entry& push(ParamSpec spec) {
    for (const Entry& e : entries_)
      if (e.spec.key == spec.key) throw std::logic_error("ParamTable: key declared twice: " + spec.key);
    entries_.push_back(Entry{std::move(spec), false, false, {}, {}});
    return entries_.back();
  }

  std::deque<Entry> entries_;  // a deque: Field keeps pointers into it while more are added
};

}  // namespace chatterlab
