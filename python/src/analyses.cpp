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
#include "chatterlab/errors.hpp"
#include "convert.hpp"

namespace chatterlab::python {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Returns (result, timing): timing holds the seconds spent handing the samples to the analysis
// (wrapping the numpy buffer in the series: no copy) and in the analysis itself, so callers can
// see what the call costs beyond it.
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

  Json result;
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
    result = analysis->analyse(series, earlier);
    analyse_s = seconds_since(start);
    if (!plots.empty()) {
      std::filesystem::create_directories(plots);
      analysis->plot(result, series, plots);
    }
  }
  py::dict timing;
  timing["input_s"] = input_s;
  timing["input_converted"] = converted;
  timing["analyse_s"] = analyse_s;
  return py::make_tuple(to_python_with_arrays(result), timing);
}

}  // namespace

void bind_analyses(py::module_& m) {
  m.def("analyse", &analyse, py::arg("name"), py::arg("values"), py::arg("sample_interval"),
        py::arg("sample_unit") = "s", py::arg("closed") = false, py::arg("params") = py::none(),
        py::arg("context") = py::none(), py::arg("series_name") = "", py::arg("plot_dir") = py::none(),
        "Runs the registered analysis `name` on a one-dimensional array; returns (result, timing).");
}

}  // namespace chatterlab::python
