#pragma once
// Study kit: the plots every study kind draws the same way. Figures collects failures so that one
// failing figure does not hide the others; axis_label turns a key into words with a unit; the grid
// helpers draw one result column over a study's grid (a curve over one varying axis, a map over
// two), which is what a kind's write_artifacts mostly needs.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "chatterlab/plot.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {
class MeasuredMachine;  // chatterlab/modal_fit.hpp
}

namespace chatterlab::kit {

// Draws every figure even when one fails (gnuplot rejects a title, ...), then reports all
// failures together in one PlotError (the runner records it in meta.json).
class Figures {
 public:
  template <class Figure>
  void render(const Figure& figure, const std::filesystem::path& out_dir, const std::string& stem) {
    try {
      plot::render(figure, out_dir, stem);
    } catch (const std::exception& e) {
      add_error(stem, e.what());
    }
  }
  void add_error(const std::string& stem, const std::string& message);
  void finish() const;  // throws plot::PlotError naming every failed figure

 private:
  std::string errors_;
};

// Runs every figure-drawing action (stem, action) the same way: all run, the failures are
// reported together in one PlotError.
void render_all(const std::vector<std::pair<std::string, std::function<void()>>>& figures);

// The study's name for plot titles: [study] name, else the study file's stem.
std::string study_title(const Json& document, const std::filesystem::path& study_file);
std::string study_title(const Study& study);

// Words and unit of a parameter key or dotted path, for an axis: "wheel_speed_rpm" -> "wheel
// speed [rpm]", "model.modes.0.damping_ratio" -> "mode 1 damping ratio", "growth_rate_per_s" ->
// "growth rate [1/s]". The unit comes from the key's suffix (the project's naming convention).
std::string axis_label(std::string_view key);

// A grid axis as a plot axis: its values, its label and whether it is log-spaced (declared
// `log = true` in [grid], or a geometric and not arithmetic progression).
struct PlotAxis {
  std::size_t grid_index = 0;
  std::string label;
  std::vector<double> values;
  bool log = false;
};

// The axes a picture can show: the numeric grid axes with more than one value (an axis with one
// value is a fixed parameter). Empty when any varying axis is not numeric.
std::vector<PlotAxis> varying_axes(const Study& study);

// Position of an output column in ResultTable rows (logic_error if absent).
std::size_t column_index(const ResultTable& results, const std::string& name);
// A numeric cell; NaN for a failed point or a non-number (a grey cell / gap in plots).
double cell(const ResultTable& results, std::size_t row, std::size_t column);

// A large grid's plots draw a decimated table (ResultTable::strides): the words a title gets
// for it, short enough for a title line: " (every 4th value)", " (every 4th x 2nd value)";
// empty for a whole table.
std::string decimation_note(const std::vector<PlotAxis>& axes, const ResultTable& results);

// One result column drawn over the grid.
struct ColumnFigure {
  ColumnFigure(std::string column_name, std::string figure_title, std::string label)
      : column(std::move(column_name)), title(std::move(figure_title)), value_label(std::move(label)) {}
  std::string column;       // output column
  std::string title;        // full title
  std::string value_label;  // y axis (one varying axis) or colour bar (two)
  std::optional<double> reference;  // a level drawn as a line (1-D) or contour (2-D), e.g. 0
  std::string reference_label;
  bool diverging = false;            // 2-D: palette centred on `reference`
  std::string low_label, high_label;  // 2-D: words at the ends of the colour bar
  // 1-D: rows whose `flag_column` is false are drawn again as points labelled `flag_label`
  // (e.g. the points without a root certificate).
  std::string flag_column, flag_label;
};

// A curve (one varying axis) or a heat map (two); nothing for a single point or 3+ axes (the
// results table holds every number). `axes` = varying_axes(study).
void plot_column(const std::vector<PlotAxis>& axes, const ResultTable& results,
                 const ColumnFigure& figure, const std::filesystem::path& out_dir,
                 const std::string& stem, Figures& figures);

// The plots of a machine given by a measured FRF (Model::measured_machine()), for any kind whose
// model has one: frf_fit (|H| measured and synthesised from the fit, log scale), frf_fit_parts
// (real and imaginary parts) and, when the model uses a modal fit, stabilisation_diagram (every
// pole of every order by its label, the selected modes, |H| scaled behind).
void plot_measured_machine(const MeasuredMachine& machine, const std::string& title,
                           const std::filesystem::path& out_dir, Figures& figures);

// At most ~2 x buckets points of a long series, for a plot: the minimum and maximum of each
// bucket in time order, so the envelope of a fast oscillation stays visible (taking every n-th
// sample instead would let a short wave or a spike vanish from the picture).
plot::Series decimated(std::string label, const std::vector<double>& x, const std::vector<double>& y,
                       std::size_t buckets = 2000);

// The same for a series given by accessors x_at(i), y_at(i), i < n, evaluated once per sample,
// for series that are computed on the fly (a profile of 10^7 samples is not copied to be drawn).
template <class XAt, class YAt>
plot::Series decimated(std::string label, std::size_t n, XAt&& x_at, YAt&& y_at,
                       std::size_t buckets = 2000) {
  plot::Series s{std::move(label), {}, {}, "lines"};
  const std::size_t per = n / buckets > 1 ? n / buckets : 1;
  for (std::size_t i = 0; i < n; i += per) {
    const std::size_t end = i + per < n ? i + per : n;
    std::size_t lo = i, hi = i;
    double y_lo = y_at(i), y_hi = y_lo;
    for (std::size_t j = i + 1; j < end; ++j) {
      const double y = y_at(j);
      if (y < y_lo) lo = j, y_lo = y;
      if (y > y_hi) hi = j, y_hi = y;
    }
    const bool lo_first = lo <= hi;
    s.x.push_back(x_at(lo_first ? lo : hi));
    s.y.push_back(lo_first ? y_lo : y_hi);
    if (lo != hi) {
      s.x.push_back(x_at(lo_first ? hi : lo));
      s.y.push_back(lo_first ? y_hi : y_lo);
    }
  }
  return s;
}

}  // namespace chatterlab::kit
