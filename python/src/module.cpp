// The compiled part of the Python module `chatterlab` (docs/python.md): _chatterlab. A thin layer
// over the public headers: plugins through their registries, studies through load_study and
// run_study, errors as the command line words them. The documented API, with docstrings, result
// classes, DataFrames and progress bars, is the package python/chatterlab/ around it.
#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/catalog.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/study_template.hpp"
#include "chatterlab/suppression.hpp"
#include "chatterlab/version.hpp"
#include "convert.hpp"

namespace chatterlab::python {
namespace {

namespace fs = std::filesystem;

py::dict spec_dict(const ParamSpec& spec) {
  py::dict d;
  d["key"] = spec.key;
  d["kind"] = std::string(to_string(spec.kind));
  d["unit"] = spec.unit;
  d["description"] = spec.description;
  d["default"] = to_python(spec.default_value);
  d["min"] = spec.min;
  d["max"] = spec.max;
  d["min_exclusive"] = spec.min_exclusive;
  d["max_exclusive"] = spec.max_exclusive;
  d["choices"] = spec.choices;
  d["required"] = spec.required();
  py::list fields;
  for (const ParamSpec& f : spec.fields) fields.append(spec_dict(f));
  d["fields"] = std::move(fields);
  return d;
}

template <class Product>
void add_entries(py::list& out, const Registry<Product>& registry, const std::string& origin_filter) {
  for (const auto* entry : registry.sorted()) {
    if (!origin_filter.empty() && entry->origin != origin_filter) continue;
    py::dict d;
    d["registry"] = registry.kind();
    d["name"] = entry->info.name;
    d["description"] = entry->info.description;
    d["origin"] = entry->origin;
    d["models_md_ids"] = entry->info.models_md_ids;
    d["thread_safety"] = std::string(to_string(entry->info.thread_safety));
    py::list params;
    for (const ParamSpec& spec : entry->info.params) params.append(spec_dict(spec));
    d["params"] = std::move(params);
    d["example_params"] = to_python(entry->info.example_params);
    out.append(std::move(d));
  }
}

// Every registered plugin and study kind (only those of one library with `origin`).
py::list plugins(const std::string& origin) {
  py::list out;
  add_entries(out, model_registry(), origin);
  add_entries(out, kinematics_registry(), origin);
  add_entries(out, suppression_registry(), origin);
  add_entries(out, analysis_registry(), origin);
  add_entries(out, study_kind_registry(), origin);
  return out;
}

bool has_origin(const std::string& origin) {
  auto in = [&](const auto& registry) {
    const auto entries = registry.sorted();
    return std::any_of(entries.begin(), entries.end(), [&](const auto* e) { return e->origin == origin; });
  };
  return in(model_registry()) || in(kinematics_registry()) || in(suppression_registry()) ||
         in(analysis_registry()) || in(study_kind_registry());
}

// Loads an out-of-tree plugin library (what a study's `plugins = [...]` does); loading the same
// library again is a no-op, so a notebook cell can be re-run. Returns what the library registered.
py::list load_plugin(const std::string& path) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(path);
  const fs::path canonical = fs::canonical(absolute, ec);
  if (ec || !has_origin(canonical.string())) {
    py::gil_scoped_release release;
    load_plugin_library(absolute.lexically_normal().string());  // InputError names what is wrong
  }
  return plugins(fs::canonical(absolute).string());
}

py::dict init_study(const std::string& kind, const std::string& example, const std::string& name,
                    const std::map<std::string, std::string>& components) {
  StudyTemplateOptions options;
  options.example = example;
  options.name = name;
  options.components = components;
  StudyTemplate study;
  {
    py::gil_scoped_release release;
    study = study_template(kind, options);
  }
  py::dict out;
  out["toml"] = study.toml;
  out["validated"] = study.validated;
  out["error"] = study.error;
  out["based_on"] = study.based_on ? py::object(py::str(study.based_on->string())) : py::object(py::none());
  return out;
}

py::list shipped() {
  py::list out;
  for (const ShippedStudy& s : shipped_studies()) out.append(py::make_tuple(s.file.string(), s.kind));
  return out;
}

}  // namespace
}  // namespace chatterlab::python

PYBIND11_MODULE(_chatterlab, m) {
  using namespace chatterlab;
  using namespace chatterlab::python;
  m.doc() = "chatterlab's compiled core (use the package `chatterlab`, docs/python.md)";
  m.attr("__version__") = CHATTERLAB_VERSION;
  // The command line's exit-code classes as Python exceptions, with its messages.
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<PointFailure>(m, "PointFailure", PyExc_RuntimeError);
  py::register_exception<plot::PlotError>(m, "PlotError", PyExc_RuntimeError);

  m.def("plugins", &plugins, py::arg("origin") = "");
  m.def("describe", [](const std::string& name) { return describe_plugin(name); }, py::arg("name"));
  m.def("load_plugin", &load_plugin, py::arg("path"));
  m.def("init_study", &init_study, py::arg("kind"), py::arg("example") = "", py::arg("name") = "",
        py::arg("components") = std::map<std::string, std::string>{});
  m.def("shipped_studies", &shipped);
  m.def("shipped_studies_dir", [] {
    const auto dir = shipped_studies_dir();
    return dir ? py::object(py::str(dir->string())) : py::object(py::none());
  });
  bind_models(m);
  bind_analyses(m);
  bind_studies(m);
}
