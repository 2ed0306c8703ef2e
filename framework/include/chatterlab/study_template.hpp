#pragma once
// `chatterlab init KIND`: a complete, commented study file for a study kind, from what the kind
// and its plugins declare (tables, parameter specs, examples). Every key the kind reads is written
// with its default or example value and a comment (description, unit, limits, default).
//
// A kind whose tables need what no parameter default can supply (a measured data file, a
// machine's process settings) starts from one of the studies shipped with chatterlab instead
// (studies/*.toml, installed in <prefix>/share/chatterlab/studies): its data files are written
// by absolute path, so the study validates wherever it is written. Every registered kind must
// either validate from its own example or have a shipped study (sdk.commands checks it).
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace chatterlab {

struct StudyTemplateOptions {
  // The plugin to put in a component table ("model" -> "plunge_regenerative", "machine" -> ...);
  // absent: the first registered plugin the kind accepts, preferring the kind's own library.
  std::map<std::string, std::string> components;
  std::string name;  // [study] name; default "<kind> study"
  // Start from this shipped study (file name with or without .toml; shipped_studies()) instead
  // of the kind's own example.
  std::string example;
};

struct StudyTemplate {
  std::string toml;
  // The kind accepted the document (what `chatterlab validate` will say); when false, `error`
  // says why (e.g. a kind that reads a data file, which init cannot invent).
  bool validated = false;
  std::string error;
  std::optional<std::filesystem::path> based_on;  // the shipped study it started from
};

// Throws InputError for an unknown kind or an unknown or refused component choice.
StudyTemplate study_template(const std::string& kind, const StudyTemplateOptions& options = {});

// The studies shipped with chatterlab, found relative to libchatterlab (installed:
// <prefix>/<datadir>/chatterlab/studies; a build tree links its source tree's studies/ into the
// same place); nullopt when there are none (e.g. a library copied on its own).
std::optional<std::filesystem::path> shipped_studies_dir();

struct ShippedStudy {
  std::filesystem::path file;  // absolute
  std::string kind;            // its [study] kind
};
// Every readable study of shipped_studies_dir(), by file name.
std::vector<ShippedStudy> shipped_studies();

}  // namespace chatterlab
