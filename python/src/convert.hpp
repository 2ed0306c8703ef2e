#pragma once
// Plain Python data <-> chatterlab's JSON documents, numpy arrays <-> C++ vectors, and the
// SourceMap that names the calling function in messages (a dict has no file and line).
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "chatterlab/params.hpp"

namespace chatterlab::python {

namespace py = pybind11;

// dict (str keys, insertion order kept), list/tuple, bool, int, float, str, None, os.PathLike,
// numpy scalars and arrays (as nested lists). Anything else: TypeError naming `where`.
Json to_json(py::handle object, const std::string& where);
py::object to_python(const Json& value);
// The same, but every non-empty array of numbers (booleans excluded) becomes a float64 numpy array
// in one pass: analysis results hold curves of 10^5 and more values, which as Python lists and
// then arrays cost more than many analyses themselves.
py::object to_python_with_arrays(const Json& value);

// A C-contiguous float64 view of `values` (no copy when it already is one; numpy converts
// other dtypes and strides once). ValueError unless it is one-dimensional.
py::array_t<double, py::array::c_style | py::array::forcecast> as_series(py::handle values,
                                                                        const std::string& where);

// A numpy array that owns `values` (moved, not copied): numpy frees the vector with the array.
py::array_t<double> to_numpy(std::vector<double>&& values);

// Messages about a Python call: "<function>: model.wheel_speed_rpm = -1: ..." (the command line
// writes "<file>:<line>: " in the same place).
class CallSourceMap final : public SourceMap {
 public:
  explicit CallSourceMap(std::string function) : function_(std::move(function)) {}
  SourceLocation locate(std::string_view /*dotted_path*/) const override { return {function_, 0}; }

 private:
  std::string function_;
};

}  // namespace chatterlab::python
