// Studies from Python: load (a file, or a dict read as if it were one) and run through the same
// runner as `chatterlab run` (threads, resume, results.csv, meta.json, plots). The run goes on in
// a worker thread without the GIL while the calling thread reports progress to Python.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "convert.hpp"

namespace chatterlab::python {
namespace {

namespace fs = std::filesystem;

Study load_file(const std::string& path, bool allow_large) {
  py::gil_scoped_release release;
  return load_study(path, {.allow_large = allow_large});
}

Study load_dict(py::handle document, const std::string& origin, bool allow_large) {
  Json study = to_json(document, origin);
  py::gil_scoped_release release;
  return load_study_document(std::move(study), origin, {.allow_large = allow_large});
}

py::list grid_axes(const Study& study) {
  py::list axes;
  for (const GridAxis& axis : study.grid) {
    py::dict a;
    a["key"] = axis.key;
    a["path"] = axis.path;
    a["values"] = to_python(Json(axis.values));
    axes.append(std::move(a));
  }
  return axes;
}

// `progress(done, total)` is called from this thread every `interval_s` while the run goes on
// and once at the end; an exception it raises (KeyboardInterrupt included) is raised after the
// run, which the runner cannot stop midway (`resume=True` completes an interrupted run from the
// command line's journal).
py::dict run(const Study& study, const std::string& out_dir, int threads, bool resume, bool plots,
             py::object progress, double interval_s) {
  RunOptions options;
  options.out_dir = out_dir;
  options.threads = threads;
  options.resume = resume;
  options.plots = plots;
  options.progress = false;  // the terminal bar would write into a notebook's stderr
  std::atomic<std::size_t> done{0}, total{0};
  options.on_point_done = [&done, &total](std::size_t d, std::size_t t) {
    total.store(t, std::memory_order_relaxed);
    std::size_t seen = done.load(std::memory_order_relaxed);  // threads finish out of order
    while (seen < d && !done.compare_exchange_weak(seen, d, std::memory_order_relaxed)) {
    }
  };

  RunSummary summary;
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable finished_cv;
  bool finished = false;
  std::optional<py::error_already_set> callback_error;
  auto report = [&] {
    if (progress.is_none() || callback_error) return;
    py::gil_scoped_acquire acquire;
    try {
      progress(done.load(), total.load());
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    } catch (py::error_already_set& e) {
      callback_error.emplace(std::move(e));
    }
  };
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        summary = run_study(study, options);
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard lock(mutex);
      finished = true;
      finished_cv.notify_all();
    });
    const auto interval = std::chrono::duration<double>(interval_s);
    for (;;) {
      {
        std::unique_lock lock(mutex);
        if (finished_cv.wait_for(lock, interval, [&] { return finished; })) break;
      }
      report();
    }
    worker.join();
  }
  if (failure) std::rethrow_exception(failure);
  report();
  if (callback_error) throw std::move(*callback_error);
  py::dict out;
  out["points"] = summary.points;
  out["failed"] = summary.failed;
  out["resumed"] = summary.resumed;
  out["exit_code"] = summary.exit_code();
  return out;
}

py::array object_array(const py::list& items) {
  return py::module_::import("numpy").attr("array")(items, py::arg("dtype") = "O");
}

// One column of a result table typed as python/chatterlab/_tables.py types a results.csv column:
// booleans only -> bool; numbers and empty cells -> float64 (empty: NaN); anything else -> text
// as results.csv writes it (object array of str, empty cells ""). Built here, straight into the
// arrays: results.h5 is written for grids of 10^5 points and more.
py::array column_array(const ResultTable& table, std::size_t column) {
  const std::size_t n = table.rows.size();
  auto cell = [&](std::size_t row) -> const Json& { return table.rows[row][column]; };
  bool booleans = true, numbers = true;
  for (std::size_t i = 0; i < n; ++i) {
    const Json& v = cell(i);
    booleans = booleans && v.is_boolean();
    numbers = numbers && (v.is_number() || v.is_null());
  }
  if (booleans && n > 0) {
    py::array_t<bool> out(static_cast<py::ssize_t>(n));
    bool* data = out.mutable_data();
    for (std::size_t i = 0; i < n; ++i) data[i] = cell(i).get<bool>();
    return out;
  }
  if (numbers) {
    py::array_t<double> out(static_cast<py::ssize_t>(n));
    double* data = out.mutable_data();
    for (std::size_t i = 0; i < n; ++i)
      data[i] = cell(i).is_null() ? std::numeric_limits<double>::quiet_NaN() : cell(i).get<double>();
    return out;
  }
  py::list text;
  for (std::size_t i = 0; i < n; ++i) {
    const Json& v = cell(i);
    if (v.is_string())
      text.append(py::str(v.get_ref<const std::string&>()));
    else if (v.is_boolean())
      text.append(py::str(v.get<bool>() ? "true" : "false"));
    else if (v.is_null())
      text.append(py::str(""));
    else
      text.append(py::str(to_python(v)));
  }
  return object_array(text);
}

// results.h5 of a run of `study` as (column names, arrays), the columns of results.csv.
py::tuple read_results_h5(const Study& study, const std::string& path) {
  ResultTable table;
  {
    py::gil_scoped_release release;
    table = chatterlab::read_results_h5(study, path);
  }
  py::list names, columns;
  const std::size_t grid = table.grid_columns.size();
  for (std::size_t c = 0; c < grid + table.output_columns.size(); ++c) {
    names.append(c < grid ? table.grid_columns[c] : table.output_columns[c - grid]);
    columns.append(column_array(table, c));
  }
  names.append("status");
  py::list status;
  for (const std::string& s : table.status) status.append(py::str(s));
  columns.append(object_array(status));
  return py::make_tuple(std::move(names), std::move(columns));
}

}  // namespace

void bind_studies(py::module_& m) {
  py::class_<Study>(m, "_Study", "A loaded, validated study (chatterlab.load_study)")
      .def_property_readonly("file", [](const Study& s) { return s.file.string(); })
      .def_property_readonly("kind", [](const Study& s) { return s.kind; })
      .def_property_readonly("document", [](const Study& s) { return to_python(s.document); })
      .def_property_readonly("point_count", &Study::point_count)
      .def_property_readonly("grid", &grid_axes)
      .def_property_readonly("plugin_libraries", [](const Study& s) { return s.plugin_libraries; })
      .def("point_document", [](const Study& s, std::size_t point) { return to_python(s.point_document(point)); },
           py::arg("point"));
  m.def("load_study_file", &load_file, py::arg("path"), py::arg("allow_large") = false);
  m.def("load_study_dict", &load_dict, py::arg("document"), py::arg("origin"), py::arg("allow_large") = false);
  m.def("run_study", &run, py::arg("study"), py::arg("out_dir"), py::arg("threads") = 0,
        py::arg("resume") = false, py::arg("plots") = true, py::arg("progress") = py::none(),
        py::arg("interval_s") = 0.2);
  m.def("read_results_h5", &read_results_h5, py::arg("study"), py::arg("path"),
        "results.h5 of a run of `study` as (column names, numpy arrays): results.csv's columns.");
}

}  // namespace chatterlab::python
