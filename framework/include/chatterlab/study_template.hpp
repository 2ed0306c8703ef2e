#pragma once
// `chatterlab init KIND`: a complete, commented study file for a study kind, from what the kind
// and its plugins declare (tables, parameter specs, examples). Every key the kind reads is written
// with its default or example value and a comment (description, unit, limits, default).
#include <map>
#include <string>
#include <vector>

namespace chatterlab {

struct StudyTemplateOptions {
  // The plugin to put in a component table ("model" -> "plunge_regenerative", "machine" -> ...);
  // absent: the first registered plugin the kind accepts, preferring the kind's own library.
  std::map<std::string, std::string> components;
  std::string name;  // [study] name; default "<kind> study"
};

struct StudyTemplate {
  std::string toml;
  // The kind accepted the document (what `chatterlab validate` will say); when false, `error`
  // says why (e.g. a kind that reads a data file, which init cannot invent).
  bool validated = false;
  std::string error;
};

// Throws InputError for an unknown kind or an unknown or refused component choice.
StudyTemplate study_template(const std::string& kind, const StudyTemplateOptions& options = {});

}  // namespace chatterlab
