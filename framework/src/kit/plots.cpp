// Study kit: plots drawn the same way by every study kind (chatterlab/kit/plots.hpp).
#include "chatterlab/kit/plots.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace chatterlab::kit {

namespace fs = std::filesystem;

void Figures::add_error(const std::string& stem, const std::string& message) {
  errors_ += fmt::format("{}{}: {}", errors_.empty() ? "" : "; ", stem, message);
}

void Figures::finish() const {
  if (!errors_.empty()) throw plot::PlotError(errors_);
}

void render_all(const std::vector<std::pair<std::string, std::function<void()>>>& figures) {
  Figures out;
  for (const auto& [stem, draw] : figures) {
    try {
      draw();
    } catch (const std::exception& e) {
      out.add_error(stem, e.what());
    }
  }
  out.finish();
}

std::string study_title(const Json& document, const fs::path& study_file) {
  auto it = document.find("study");
  if (it != document.end() && it->is_object() && it->contains("name") && (*it)["name"].is_string())
    return (*it)["name"].get<std::string>();
  return study_file.stem().string();
}

std::string study_title(const Study& study) { return study_title(study.document, study.file); }

// ---------------------------------------------------------------- axis labels
namespace {

struct UnitSuffix {
  const char* suffix;  // after the last word of the quantity
  const char* unit;    // as printed; empty: dimensionless, no brackets
};

// Longest suffixes first: "_n_s_per_m" before "_per_m", "_m_per_s" before "_per_s" and "_s".
constexpr std::array<UnitSuffix, 27> unit_suffixes{{
    {"_n_s_per_m", "N s/m"}, {"_m_per_n", "m/N"},   {"_n_per_m", "N/m"},
    {"_mm_per_s", "mm/s"},   {"_um_per_s", "µm/s"}, {"_m_per_s", "m/s"},
    {"_per_wheel_rev", "1/wheel rev"},               {"_per_rev", "1/rev"},
    {"_per_sample", "1/sample"},                     {"_per_s", "1/s"},
    {"_rpm", "rpm"},         {"_hz", "Hz"},         {"_khz", "kHz"},
    {"_deg", "deg"},         {"_rad", "rad"},       {"_mm", "mm"},
    {"_um", "µm"},           {"_nm", "nm"},         {"_m", "m"},
    {"_s", "s"},             {"_ms", "ms"},         {"_n", "N"},
    {"_kg", "kg"},           {"_pct", "%"},         {"_percent", "%"},
    {"_mv", "mV"},           {"_ratio", ""},
}};

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() > suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::string words(std::string_view snake) {
  std::string out(snake);
  std::replace(out.begin(), out.end(), '_', ' ');
  return out;
}

}  // namespace

std::string axis_label(std::string_view key) {
  // Dotted paths: the model's keys are the study's parameters and need no prefix; another table
  // names what the key belongs to ("suppression.amplitude_ratio" -> "suppression amplitude
  // ratio"); an index follows a plural ("modes.0" -> "mode 1").
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const std::size_t dot = key.find('.', start);
    parts.push_back(key.substr(start, dot == std::string_view::npos ? std::string_view::npos : dot - start));
    if (dot == std::string_view::npos) break;
    start = dot + 1;
  }
  if (parts.size() > 1 && parts.front() == "model") parts.erase(parts.begin());
  std::string prefix;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    if (all_digits(parts[i])) continue;
    std::string name = words(parts[i]);
    if (all_digits(parts[i + 1])) {
      if (ends_with(name, "s")) name.pop_back();
      name += fmt::format(" {}", std::stoul(std::string(parts[i + 1])) + 1);
    }
    prefix += name + " ";
  }
  std::string_view last = parts.back();
  std::string unit;
  for (const UnitSuffix& u : unit_suffixes) {
    if (!ends_with(last, u.suffix)) continue;
    if (std::string_view(u.suffix) != "_ratio") last.remove_suffix(std::string_view(u.suffix).size());
    unit = u.unit;
    break;
  }
  std::string label = prefix + words(last);
  return unit.empty() ? label : fmt::format("{} [{}]", label, unit);
}

// ---------------------------------------------------------------- grid axes
namespace {

bool numeric(const GridAxis& axis) {
  return std::all_of(axis.values.begin(), axis.values.end(), [](const Json& v) { return v.is_number(); });
}

// A log axis when the values are a geometric, not an arithmetic, progression (what
// `{ from, to, steps, log = true }` produces, or a hand-written 1, 10, 100).
bool log_spaced(const std::vector<double>& v) {
  if (v.size() < 3) return false;
  auto same = [](double a, double b) {
    return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
  };
  bool geometric = true, arithmetic = true;
  for (std::size_t i = 0; i + 1 < v.size(); ++i) {
    if (v[i] <= 0 || v[i + 1] <= 0) return false;
    geometric = geometric && same(v[i + 1] / v[i], v[1] / v[0]);
    arithmetic = arithmetic && same(v[i + 1] - v[i], v[1] - v[0]);
  }
  return geometric && !arithmetic;
}

// `log = true` as written in the study's [grid] table (Study::document keeps that table).
bool declared_log(const Study& study, const GridAxis& axis) {
  auto grid = study.document.find("grid");
  if (grid == study.document.end() || !grid->is_object()) return false;
  auto range = grid->find(axis.key);
  if (range == grid->end() || !range->is_object()) return false;
  auto log = range->find("log");
  return log != range->end() && *log == Json(true);
}

}  // namespace

std::vector<PlotAxis> varying_axes(const Study& study) {
  std::vector<PlotAxis> axes;
  for (std::size_t a = 0; a < study.grid.size(); ++a) {
    const GridAxis& axis = study.grid[a];
    if (axis.values.size() < 2) continue;
    if (!numeric(axis)) return {};
    PlotAxis p{a, axis_label(axis.key), {}, false};
    for (const Json& v : axis.values) p.values.push_back(v.get<double>());
    p.log = declared_log(study, axis) || log_spaced(p.values);
    axes.push_back(std::move(p));
  }
  return axes;
}

std::size_t column_index(const ResultTable& results, const std::string& name) {
  for (std::size_t c = 0; c < results.output_columns.size(); ++c)
    if (results.output_columns[c] == name) return results.grid_columns.size() + c;
  throw std::logic_error("no output column " + name);
}

double cell(const ResultTable& results, std::size_t row, std::size_t column) {
  const Json& v = results.rows[row][column];
  return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

std::string decimation_note(const std::vector<PlotAxis>& axes, const ResultTable& results) {
  if (!results.decimated()) return {};
  auto ordinal = [](std::size_t n) {
    const std::size_t tens = n % 100, ones = n % 10;
    const char* suffix = tens >= 11 && tens <= 13 ? "th"
                         : ones == 1              ? "st"
                         : ones == 2              ? "nd"
                         : ones == 3              ? "rd"
                                                  : "th";
    return std::to_string(n) + suffix;
  };
  std::vector<std::string> strides;
  bool same = true;
  for (const PlotAxis& axis : axes) {
    strides.push_back(ordinal(results.strides[axis.grid_index]));
    same = same && strides.back() == strides.front();
  }
  if (same && !strides.empty()) strides.resize(1);
  return fmt::format(" (every {} value)", fmt::join(strides, " x "));
}

void plot_column(const std::vector<PlotAxis>& axes, const ResultTable& results,
                 const ColumnFigure& figure, const fs::path& out_dir, const std::string& stem,
                 Figures& figures) {
  const std::size_t column = column_index(results, figure.column);
  const std::string title = figure.title + decimation_note(axes, results);
  if (axes.size() == 1) {
    const PlotAxis& axis = axes[0];
    plot::Curves curves;
    curves.title = title;
    curves.x_label = axis.label;
    curves.y_label = figure.value_label;
    curves.log_x = axis.log;
    curves.reference_y = figure.reference;
    curves.reference_label = figure.reference_label;
    plot::Series main{figure.value_label, {}, {}, "linespoints"};
    plot::Series flagged{figure.flag_label, {}, {}, "points"};
    const std::size_t flag =
        figure.flag_column.empty() ? 0 : column_index(results, figure.flag_column);
    for (std::size_t r = 0; r < results.rows.size(); ++r) {
      const double y = cell(results, r, column);
      if (!std::isfinite(y)) continue;  // failed point: listed in the results table and meta.json
      const double x = results.rows[r][axis.grid_index].get<double>();
      main.x.push_back(x);
      main.y.push_back(y);
      if (!figure.flag_column.empty() && results.rows[r][flag] == Json(false)) {
        flagged.x.push_back(x);
        flagged.y.push_back(y);
      }
    }
    curves.series.push_back(std::move(main));
    if (!flagged.x.empty()) curves.series.push_back(std::move(flagged));
    figures.render(curves, out_dir, stem);
  } else if (axes.size() == 2) {
    // x = the faster (later) axis, so results rows are already in z's order.
    const PlotAxis& x = axes[1];
    const PlotAxis& y = axes[0];
    plot::Heatmap h;
    h.title = title;
    h.x_label = x.label;
    h.y_label = y.label;
    h.z_label = figure.value_label;
    h.x = x.values;
    h.y = y.values;
    h.log_x = x.log;
    h.log_y = y.log;
    for (std::size_t r = 0; r < results.rows.size(); ++r) h.z.push_back(cell(results, r, column));
    h.contour_level = figure.reference;
    h.contour_label = figure.reference_label;
    h.diverging = figure.diverging;
    h.low_label = figure.low_label;
    h.high_label = figure.high_label;
    figures.render(h, out_dir, stem);
  }
}

plot::Series decimated(std::string label, const std::vector<double>& x, const std::vector<double>& y,
                       std::size_t buckets) {
  return decimated(std::move(label), x.size(), [&](std::size_t i) { return x[i]; },
                   [&](std::size_t i) { return y[i]; }, buckets);
}

}  // namespace chatterlab::kit
