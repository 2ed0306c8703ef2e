#pragma once
// TOML text of parameter tables, shared by `chatterlab describe` (catalog.cpp) and
// `chatterlab init` (sdk/study_template.cpp).
#include <string>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

std::string toml_key(const std::string& key);  // bare when possible, else quoted
// Shortest text that reads back as the same double ("5e9", not "5000000000").
std::string readable_number(double v);
// `declared_real`: numbers written as TOML floats ("1450.0"), which also teaches the type.
std::string toml_value(const Json& v, bool declared_real);
bool is_table_array(const Json& v);
const ParamSpec* find_spec(const std::vector<ParamSpec>& specs, const std::string& key);
bool is_real_kind(const ParamSpec* spec);
std::string limits_text(const ParamSpec& spec);   // "[0, 1)", "> 0", "-"
std::string default_text(const ParamSpec& spec);  // "required", "optional" or the value
std::string spec_comment(const ParamSpec& spec);  // "# description [unit]; limits; default: x\n"

// Appends `table` below the header `header`: plain keys, then nested tables [header.key], then
// arrays of tables [[header.key]] (the order TOML requires). `specs` decide number types; with
// `comments`, each key whose spec is known gets spec_comment() above it.
void append_toml_table(std::string& out, const Json& table, const std::string& header,
                       const std::vector<ParamSpec>& specs, bool comments = false);

}  // namespace chatterlab
