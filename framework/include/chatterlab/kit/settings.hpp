#pragma once
// Study kit: a study kind's settings tables ([stability], [simulation], [lobes], ...) bound to
// structs through their ParamTable (chatterlab/param_table.hpp), so that a kind declares each
// setting once and reads typed values at every grid point.
#include <string>

#include "chatterlab/param_table.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::kit {

// The top-level table `name` of the document: an empty table when absent; InputError naming the
// file and line when it is not a table.
Json table_or_empty(const Json& document, const std::string& name, const SourceMap& sources);

// For StudyKind::validate: validates the table `name` (absent: all defaults) against `table`'s
// specs, writes it back into the document with its defaults filled in, and returns the struct.
template <class S>
S validate_settings(Json& document, const std::string& name, const ParamTable<S>& table,
                    const SourceMap& sources) {
  Json validated = validate_params(table_or_empty(document, name, sources), table.specs(), name, sources);
  S settings = table.read(validated);
  document[name] = std::move(validated);
  return settings;
}

// For StudyKind::run_point: the settings of one point's (validated) document.
template <class S>
S read_settings(const Json& point_document, const std::string& name, const ParamTable<S>& table) {
  return table.read(point_document.at(name));
}

}  // namespace chatterlab::kit
