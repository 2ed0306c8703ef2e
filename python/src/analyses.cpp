// Any registered analysis (chaos, monitoring, surface metrology) on a numpy array, through the
// analysis registry: the same plugin, parameters and messages as a study's [analysis] table.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <span>
#include <string>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"
#include "chatterlab/errors.hpp"
#include "convert.hpp"

namespace chatterlab::python {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The result as Python objects: the JSON part through to_python_with_arrays (curves whose length
// the parameters bound become arrays there), each long series of an analysis with arrays
// (chatterlab/analysis_arrays.hpp) moved into a numpy array in its place: no JSON value per number.
py::object result_to_python(ResultWithArrays&& result) {
  py::object out = to_python_with_arrays(result.result);
  for (ResultArray& a : result.arrays) {
    if (a.boolean) {
      py::array_t<bool> flags(static_cast<py::ssize_t>(a.values.size()));
      bool* data = flags.mutable_data();
      for (std::size_t i = 0; i < a.values.size(); ++i) data[i] = a.values[i] != 0.0;
      out[py::str(a.key)] = std::move(flags);
    } else {
      out[py::str(a.key)] = to_numpy(std::move(a.values));
    }
  }
  return out;
}

// Returns (result, timing): timing holds the seconds spent handing the samples to the analysis
// (wrapping the numpy buffer in the series: no copy), in the analysis itself and in turning its
// result into Python objects, so callers can see what the call costs beyond the analysis.
py::tuple analyse(const std::string& name, py::handle values, double sample_interval, const std::string& sample_unit,
                  bool closed, py::handle params, py::handle context, const std::string& series_name,
                  py::handle plot_dir) {
  const auto& entry = analysis_registry().at(name);  // InputError listing the registered analyses
  const Json table = params.is_none() ? Json::object() : to_json(params, name);
  const Json earlier = context.is_none() ? Json::object() : to_json(context, "context");
  // A C-contiguous float64 array is used as it is (numpy converts other dtypes and strides once);
  // `samples` holds a reference to it, so the buffer outlives the GIL-free analysis below.
  const auto samples = as_series(values, "analyse: values");
  const bool converted = !samples.is(values);  // numpy made a float64 C-contiguous copy
  if (!(sample_interval > 0.0) || !std::isfinite(sample_interval))
    throw InputError("analyse: sample_interval = " + std::to_string(sample_interval) + ": must be > 0 (" +
                     sample_unit + " between samples)");
  const std::string plots = plot_dir.is_none() ? std::string() : py::str(plot_dir).cast<std::string>();

  ResultWithArrays result;
  double input_s = 0.0, analyse_s = 0.0;
  {
    py::gil_scoped_release release;
    CallSourceMap sources("analyse");
    // Keys as a study's [analysis.<name>] table names them, so messages read as the command line's.
    const Json validated = validate_params(table, entry.info.params, "analysis." + name, sources);
    const auto analysis = entry.create(ParamValues(validated));
    SampledSeries series;
    const Clock::time_point input_start = Clock::now();
    // Analyses read the samples through a view (SampledSeries::values): the numpy buffer itself.
    series.values = std::span<const double>(samples.data(), static_cast<std::size_t>(samples.size()));
    input_s = seconds_since(input_start);
    series.sample_interval = sample_interval;
    series.sample_unit = sample_unit;
    series.closed = closed;
    series.name = series_name;
    const Clock::time_point start = Clock::now();
    if (const auto* with_arrays = dynamic_cast<const AnalysisWithArrays*>(analysis.get()))
      result = with_arrays->analyse_with_arrays(series, earlier);
    else
      result.result = analysis->analyse(series, earlier);
    analyse_s = seconds_since(start);
    if (!plots.empty()) {
      std::filesystem::create_directories(plots);
      analysis->plot(ResultWithArrays(result).merged(), series, plots);  // a copy: plots read JSON
    }
  }
  const Clock::time_point result_start = Clock::now();
  py::object converted_result = result_to_python(std::move(result));
  result = {};  // the JSON part freed inside the measured time
  const double result_s = seconds_since(result_start);
  py::dict timing;
  timing["input_s"] = input_s;
  timing["input_converted"] = converted;
  timing["analyse_s"] = analyse_s;
  timing["result_s"] = result_s;
  return py::make_tuple(std::move(converted_result), timing);
}

}  // namespace

void bind_analyses(py::module_& m) {
  m.def("analyse", &analyse, py::arg("name"), py::arg("values"), py::arg("sample_interval"),
        py::arg("sample_unit") = "s", py::arg("closed") = false, py::arg("params") = py::none(),
        py::arg("context") = py::none(), py::arg("series_name") = "", py::arg("plot_dir") = py::none(),
        "Runs the registered analysis `name` on a one-dimensional array; returns (result, timing).");
}

}  // namespace chatterlab::python
