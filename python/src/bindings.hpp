#pragma once
// The parts of the compiled module _chatterlab (module.cpp puts them together). Each binds the
// functions of one area; the pure-Python package chatterlab (python/chatterlab/) wraps them in
// the documented API (docs/python.md).
#include <pybind11/pybind11.h>

namespace chatterlab::python {

namespace py = pybind11;

void bind_catalog(py::module_& m);   // plugins, describe, load_plugin, init, shipped studies
void bind_models(py::module_& m);    // validate_model, rightmost_root, simulate, fit_envelope
void bind_analyses(py::module_& m);  // analyse: any registered analysis on a numpy array
void bind_studies(py::module_& m);   // load_study, run_study

}  // namespace chatterlab::python
