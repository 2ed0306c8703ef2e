#include "study_kinds/doe/doe_kind.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>

#include "study_kinds/doe/doe.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;
namespace ss = kit;

constexpr std::size_t max_factors = 26;
const double alphas[] = {0.25, 0.10, 0.05, 0.01};  // the book's F table levels (Table 5-4)

// [doe] and [regression], declared once ([input] holds lists of column names: checked by hand).
struct DoeSettings {
  std::string goal = "minimize";
};

const ParamTable<DoeSettings>& doe_table() {
  static const ParamTable<DoeSettings> table = [] {
    ParamTable<DoeSettings> t;
    t.add(&DoeSettings::goal, "goal", "",
          "best level = the one with the smallest (minimize, e.g. chatter) or largest (maximize) "
          "mean response")
        .choices({"minimize", "maximize"});
    return t;
  }();
  return table;
}

struct RegressionSettings {
  std::string file, x, y;
  std::optional<double> x0;                                  // absent: mean of x
  std::optional<std::vector<double>> two_point_parabola;     // x of the vertex and a second point
  std::optional<std::vector<double>> two_point_exponential;  // x of two data points
};

const ParamTable<RegressionSettings>& regression_table() {
  static const ParamTable<RegressionSettings> table = [] {
    ParamTable<RegressionSettings> t;
    t.add(&RegressionSettings::file, "file", "", "single-factor data table").required();
    t.add(&RegressionSettings::x, "x", "", "column of the factor (e.g. vf_um_per_s)").required();
    t.add(&RegressionSettings::y, "y", "", "column of the response").required();
    t.add(&RegressionSettings::x0, "x0", "as x",
          "reference of the exponential y = a b^(x - x0) (default: mean of x)");
    t.add(&RegressionSettings::two_point_parabola, "two_point_parabola", "as x",
          "x of the vertex point and of a second point: the book's parabola through two data "
          "points (5-46)");
    t.add(&RegressionSettings::two_point_exponential, "two_point_exponential", "as x",
          "x of two data points: the book's exponential through them (5-47)");
    return t;
  }();
  return table;
}

struct Design {
  std::string response;
  std::vector<std::string> factors, errors;
  std::vector<double> y;
  std::vector<std::vector<double>> factor_levels, error_levels;
  std::string array;  // matching standard array, "" if none
  bool orthogonal = true;
};

// Level labels as indices 0, 1, ... of the distinct values (ascending), for the balance check.
std::vector<int> as_levels(const std::vector<double>& v) {
  const std::set<double> distinct(v.begin(), v.end());
  std::vector<int> out;
  for (double x : v)
    out.push_back(static_cast<int>(std::distance(distinct.begin(), distinct.find(x))));
  return out;
}

// Reads and checks the design table (validate() and run_point()).
Design load_design(const Json& input, const SourceMap& sources) {
  Design d;
  const fs::path file = input.at("file").get<std::string>();
  const DataTable table = ss::read_table_at(file, "input.file", sources);
  d.response = input.at("response").get<std::string>();
  d.y = ss::column_at(table, d.response, "input.response", sources);
  for (const Json& f : input.at("factors")) d.factors.push_back(f.get<std::string>());
  for (const Json& e : input.at("error_columns")) d.errors.push_back(e.get<std::string>());
  auto levels_of = [&](const std::string& name, const std::string& key) {
    const auto& column = ss::column_at(table, name, key, sources);
    std::set<double> distinct(column.begin(), column.end());
    if (distinct.size() < 2)
      throw InputError(
          fmt::format("{}: {}: column \"{}\" has a single level ({}); a factor needs "
                      "at least two",
                      sources.locate(key).str(), key, name, *distinct.begin()));
    if (distinct.size() == column.size())
      throw InputError(fmt::format(
          "{}: {}: column \"{}\" has a different value in every run; it is not a level column",
          sources.locate(key).str(), key, name));
    return column;
  };
  for (const auto& f : d.factors) d.factor_levels.push_back(levels_of(f, "input.factors"));
  for (const auto& e : d.errors) d.error_levels.push_back(levels_of(e, "input.error_columns"));
  for (const auto& f : d.factors)
    if (f == d.response || std::find(d.errors.begin(), d.errors.end(), f) != d.errors.end())
      throw InputError(
          fmt::format("{}: input.factors: \"{}\" is also the response or an error "
                      "column",
                      sources.locate("input.factors").str(), f));
  if (std::find(d.errors.begin(), d.errors.end(), d.response) != d.errors.end())
    throw InputError(fmt::format("{}: input.error_columns: \"{}\" is the response",
                                 sources.locate("input.error_columns").str(), d.response));
  const std::size_t runs = d.y.size();
  const std::size_t used_df = [&] {
    std::size_t df = 0;
    for (const auto* group : {&d.factor_levels, &d.error_levels})
      for (const auto& c : *group) df += std::set<double>(c.begin(), c.end()).size() - 1;
    return df;
  }();
  if (used_df > runs - 1)
    throw InputError(fmt::format(
        "{}: input: the factor and error columns need {} degrees of freedom, but {} runs give "
        "only {}",
        sources.locate("input.factors").str(), used_df, runs, runs - 1));

  std::vector<std::vector<int>> columns;
  for (const auto* group : {&d.factor_levels, &d.error_levels})
    for (const auto& c : *group) columns.push_back(as_levels(c));
  d.orthogonal = doe::is_orthogonal(columns);
  for (const auto& name : doe::orthogonal_array_names()) {
    const doe::OrthogonalArray oa = doe::orthogonal_array(name);
    const auto levels =
        std::set<double>(d.factor_levels[0].begin(), d.factor_levels[0].end()).size();
    if (oa.rows() == runs && static_cast<std::size_t>(oa.levels) == levels &&
        columns.size() <= oa.columns() && d.orthogonal)
      d.array = oa.name;
  }
  return d;
}

struct Regression {
  std::vector<double> x, y;
  std::string x_name, y_name;
  std::vector<doe::Fit> fits;
};

std::size_t index_of_x(const std::vector<double>& x, double value, const std::string& key,
                       const SourceMap& sources) {
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i] - value) <= 1e-9 * std::max(1.0, std::abs(value))) return i;
  throw InputError(
      fmt::format("{}: {}: no data point with x = {}", sources.locate(key).str(), key, value));
}

// The validated-table check of one two-point key: the x of two different data points.
std::optional<std::pair<std::size_t, std::size_t>> two_points(
    const std::optional<std::vector<double>>& given, const std::vector<double>& x, const char* key,
    const SourceMap& sources) {
  if (!given) return std::nullopt;
  const std::vector<double>& v = *given;
  const std::string path = std::string("regression.") + key;
  if (v.size() != 2 || v[0] == v[1])
    throw InputError(fmt::format("{}: {} = [{}]: give the x of two different data points",
                                 sources.locate(path).str(), path, fmt::join(v, ", ")));
  return std::pair{index_of_x(x, v[0], path, sources), index_of_x(x, v[1], path, sources)};
}

std::optional<Regression> load_regression(const Json& table, const SourceMap& sources) {
  if (table.empty()) return std::nullopt;
  const RegressionSettings settings = regression_table().read(table);
  Regression r;
  const DataTable data = ss::read_table_at(settings.file, "regression.file", sources);
  r.x_name = settings.x;
  r.y_name = settings.y;
  r.x = ss::column_at(data, r.x_name, "regression.x", sources);
  r.y = ss::column_at(data, r.y_name, "regression.y", sources);
  if (r.x.size() < 4)
    throw InputError(
        fmt::format("{}: regression.file: {} points, at least 4 needed (quadratic "
                    "fit with a residual)",
                    sources.locate("regression.file").str(), r.x.size()));
  const double x0 = settings.x0.value_or(std::accumulate(r.x.begin(), r.x.end(), 0.0) /
                                         static_cast<double>(r.x.size()));
  const bool positive = std::all_of(r.y.begin(), r.y.end(), [](double v) { return v > 0; });
  r.fits.push_back(doe::fit_linear(r.x, r.y));
  r.fits.push_back(doe::fit_quadratic(r.x, r.y));
  if (positive) {
    r.fits.push_back(doe::fit_exponential_log_linear(r.x, r.y, x0));
    r.fits.push_back(doe::fit_exponential_nonlinear(r.x, r.y, x0));
  }
  if (auto p = two_points(settings.two_point_parabola, r.x, "two_point_parabola", sources))
    r.fits.push_back(doe::fit_two_point_parabola(r.x, r.y, p->first, p->second));
  if (auto p = two_points(settings.two_point_exponential, r.x, "two_point_exponential", sources)) {
    if (!(r.y[p->first] > 0 && r.y[p->second] > 0))
      throw InputError(
          fmt::format("{}: regression.two_point_exponential: the two points need y > 0",
                      sources.locate("regression.two_point_exponential").str()));
    r.fits.push_back(doe::fit_two_point_exponential(r.x, r.y, p->first, p->second));
  }
  return r;
}

Json optional_number(const std::optional<double>& v) { return v ? Json(*v) : Json(); }

std::string level_text(double level) { return fmt::format("{}", level); }

void plot_doe(const std::string& title, const Design& d,
              const std::vector<doe::FactorRange>& ranges, const doe::Anova& anova,
              const std::optional<Regression>& regression, const fs::path& dir) {
  namespace pl = plot;
  std::vector<std::pair<std::string, std::function<void()>>> figures;
  const double grand_mean =
      std::accumulate(d.y.begin(), d.y.end(), 0.0) / static_cast<double>(d.y.size());
  for (std::size_t f = 0; f < d.factors.size(); ++f) {
    const std::string stem = "effect_" + d.factors[f];
    figures.emplace_back(stem, [&, f, stem] {
      pl::Curves c;
      c.title =
          fmt::format("{}: level means of {} (R = {:.4g})", title, d.factors[f], ranges[f].range);
      c.x_label = fmt::format("level of {}", d.factors[f]);
      c.y_label = fmt::format("mean {}", d.response);
      c.series.push_back({"level mean", ranges[f].levels, ranges[f].means, "linespoints"});
      c.reference_y = grand_mean;
      c.reference_label = "grand mean";
      pl::render(c, dir, stem);
    });
  }
  figures.emplace_back("effects", [&] {
    pl::Curves c;
    c.title = fmt::format("{}: level means of every factor", title);
    c.x_label = "level";
    c.y_label = fmt::format("mean {}", d.response);
    for (std::size_t f = 0; f < d.factors.size(); ++f)
      c.series.push_back({d.factors[f], ranges[f].levels, ranges[f].means, "linespoints"});
    c.reference_y = grand_mean;
    c.reference_label = "grand mean";
    pl::render(c, dir, "effects");
  });
  figures.emplace_back("anova", [&] {
    pl::Curves c;
    c.title = fmt::format("{}: sums of squares (1..{} factors, {} error)", title, d.factors.size(),
                          d.factors.size() + 1);
    c.x_label = fmt::format("source: {}, error", fmt::join(d.factors, ", "));
    c.y_label = "sum of squares S";
    pl::Series bars{"factor S", {}, {}, "impulses"}, error{"error S", {}, {}, "impulses"};
    for (std::size_t f = 0; f < anova.factors.size(); ++f) {
      bars.x.push_back(static_cast<double>(f + 1));
      bars.y.push_back(anova.factors[f].s);
    }
    error.x.push_back(static_cast<double>(anova.factors.size() + 1));
    error.y.push_back(anova.error.s);
    // Zero-height ends keep the outer bars off the frame.
    pl::Series ends{"", {0.0, static_cast<double>(anova.factors.size() + 2)}, {0.0, 0.0}, "points"};
    c.series = {bars, error, ends};
    pl::render(c, dir, "anova");
  });
  if (regression) {
    figures.emplace_back("regression", [&] {
      pl::Curves c;
      c.title = fmt::format("{}: fits of {} over {} (SSE in the key)", title, regression->y_name,
                            regression->x_name);
      c.x_label = regression->x_name;
      c.y_label = regression->y_name;
      c.series.push_back({"data", regression->x, regression->y, "points"});
      const auto [lo, hi] = std::minmax_element(regression->x.begin(), regression->x.end());
      for (const auto& fit : regression->fits) {
        pl::Series s{fmt::format("{}: SSE {:.4g}", fit.label, fit.sse), {}, {}, "lines"};
        for (int k = 0; k <= 200; ++k) {
          const double x = *lo + (*hi - *lo) * k / 200.0;
          s.x.push_back(x);
          s.y.push_back(fit.at(x));
        }
        c.series.push_back(std::move(s));
      }
      pl::render(c, dir, "regression");
    });
  }
  ss::render_all(figures);
}

}  // namespace

PluginInfo DoeKind::info() {
  return plugin_info("doe", "S4",
                     doe_table().specs(),
                     {{"goal", "minimize"}},
                     "orthogonal-array experiment: range analysis, ANOVA with F tests and p-values, regression "
                     "fits with SSE");
}

void DoeKind::validate(Json& document, const SourceMap& sources) const {
  Json input = ss::table_or_empty(document, "input", sources);
  ss::check_known_keys(input, {"file", "response", "factors", "error_columns"}, "input", sources);
  for (const char* key : {"file", "response", "factors"})
    if (!input.contains(key))
      throw InputError(
          fmt::format("{}: missing required key 'input.{}'", sources.locate("input").str(), key));
  input["file"] = ss::resolve_data_file(input["file"], "input.file", sources).string();
  if (!input["response"].is_string() || input["response"].get<std::string>().empty())
    throw InputError(fmt::format("{}: input.response = {}: expected a column name (string)",
                                 sources.locate("input.response").str(), input["response"].dump()));
  ss::string_list(input["factors"], "input.factors", sources, 1, max_factors);
  if (!input.contains("error_columns")) input["error_columns"] = Json::array();
  ss::string_list(input["error_columns"], "input.error_columns", sources, 0, max_factors);

  Json doe =
      validate_params(ss::table_or_empty(document, "doe", sources), doe_table().specs(), "doe", sources);
  Json regression = ss::table_or_empty(document, "regression", sources);
  if (!regression.empty()) {
    regression = validate_params(regression, regression_table().specs(), "regression", sources);
    regression["file"] =
        ss::resolve_data_file(regression["file"], "regression.file", sources).string();
  }
  document["input"] = input;
  document["doe"] = doe;
  document["regression"] = regression;
  load_design(input, sources);
  load_regression(regression, sources);
}

std::vector<std::string> DoeKind::output_columns(const Json& document) const {
  std::vector<std::string> columns;
  for (const Json& f : document.at("input").at("factors")) {
    const std::string name = f.get<std::string>();
    for (const char* what : {"S_", "F_", "p_"}) columns.push_back(what + name);
  }
  columns.push_back("S_error");
  columns.push_back("S_total");
  columns.push_back("best_combination");
  return columns;
}

namespace {

std::vector<std::string> design_warnings(const Design& d, const doe::Anova& anova) {
  std::vector<std::string> warnings;
  if (!d.orthogonal)
    warnings.push_back(
        "the factor and error columns are not pairwise balanced (not an orthogonal "
        "design): the sums of squares overlap and the ANOVA is approximate");
  if (anova.error.df <= 0)
    warnings.push_back(
        "no degrees of freedom left for the error: no F values (add error_columns "
        "or runs)");
  return warnings;
}

// The ANOVA table of summary.json: per factor S, df, MS, F, p, significance and the F table's
// critical values; the error and total rows.
Json anova_json(const doe::Anova& anova, const Design& d) {
  Json a = Json::object();
  for (const auto& row : anova.factors) {
    Json entry = {{"S", row.s},
                  {"df", row.df},
                  {"MS", row.ms},
                  {"F", optional_number(row.f)},
                  {"p", optional_number(row.p)}};
    entry["significance"] = row.p ? Json(doe::significance(*row.p)) : Json();
    if (anova.error.df > 0) {
      Json critical;
      for (double alpha : alphas)
        critical[fmt::format("{}", alpha)] = doe::f_critical(alpha, row.df, anova.error.df);
      entry["F_critical"] = critical;
    }
    a[row.source] = entry;
  }
  a["error"] = {
      {"S", anova.error.s},   {"df", anova.error.df},
      {"MS", anova.error.ms}, {"F", nullptr},
      {"p", nullptr},         {"columns", d.errors.empty() ? Json("residual") : Json(d.errors)}};
  a["total"] = {{"S", anova.total.s}, {"df", anova.total.df}, {"F", nullptr}, {"p", nullptr}};
  return a;
}

Json ranges_json(const Design& d, const std::vector<doe::FactorRange>& ranges) {
  Json r = Json::object();
  for (std::size_t f = 0; f < d.factors.size(); ++f) {
    r[d.factors[f]] = {{"levels", ranges[f].levels}, {"sums", ranges[f].sums},
                       {"counts", ranges[f].counts}, {"means", ranges[f].means},
                       {"R", ranges[f].range},       {"best_level", ranges[f].best_level}};
  }
  return r;
}

// Factor names by decreasing range R (the most influential first).
std::vector<std::string> factors_by_range(const Design& d, const std::vector<doe::FactorRange>& ranges) {
  std::vector<std::size_t> order(d.factors.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t i, std::size_t j) { return ranges[i].range > ranges[j].range; });
  std::vector<std::string> by_range;
  for (std::size_t i : order) by_range.push_back(d.factors[i]);
  return by_range;
}

Json regression_json(const Regression& regression) {
  Json fits = Json::array();
  for (const auto& fit : regression.fits)
    fits.push_back({{"model", fit.model},
                    {"formula", fit.formula},
                    {"coefficients", fit.coefficients},
                    {"sse", fit.sse}});
  return {{"x", regression.x_name}, {"y", regression.y_name}, {"fits", fits}};
}

}  // namespace

std::vector<Json> DoeKind::run_point(const Json& point_document,
                                     const PointContext& context) const {
  const SourceMap& sources = ss::no_sources();  // validated already: no line numbers needed
  const Design d = load_design(point_document.at("input"), sources);
  const auto regression = load_regression(point_document.at("regression"), sources);
  const std::string goal = doe_table().read(point_document.at("doe")).goal;
  const bool minimise = goal == "minimize";

  std::vector<doe::FactorRange> ranges;
  for (const auto& levels : d.factor_levels)
    ranges.push_back(doe::range_analysis(levels, d.y, minimise));
  const doe::Anova anova = doe::analyse_variance(d.factor_levels, d.factors, d.error_levels, d.y);
  std::string best;
  for (std::size_t f = 0; f < d.factors.size(); ++f)
    best += fmt::format("{}{}{}", f ? " " : "", d.factors[f], level_text(ranges[f].best_level));
  const std::vector<std::string> warnings = design_warnings(d, anova);
  for (const auto& w : warnings) ss::warn(w);

  if (!context.artifact_dir.empty()) {
    Json summary;
    summary["response"] = d.response;
    summary["goal"] = goal;
    summary["best_is"] = minimise ? "minimum of the level means" : "maximum of the level means";
    summary["runs"] = d.y.size();
    summary["array"] = d.array.empty() ? Json() : Json(d.array);
    summary["design_orthogonal"] = d.orthogonal;
    summary["anova"] = anova_json(anova, d);
    summary["correction_term"] = anova.correction_term;
    summary["unassigned_S"] = anova.unassigned;
    summary["ranges"] = ranges_json(d, ranges);
    summary["factors_by_range"] = factors_by_range(d, ranges);
    summary["best_combination"] = best;
    if (regression) summary["regression"] = regression_json(*regression);
    summary["warnings"] = warnings;
    if (context.plots) {
      try {
        plot_doe(ss::study_title(point_document, "doe"), d, ranges, anova, regression,
                 context.artifact_dir);
      } catch (const plot::PlotError& e) {
        summary["plot_errors"] = e.what();
      }
    }
    write_json_file(context.artifact_dir / "summary.json", summary);
  }

  std::vector<Json> out;
  for (const auto& row : anova.factors) {
    out.emplace_back(row.s);
    out.push_back(optional_number(row.f));
    out.push_back(optional_number(row.p));
  }
  out.emplace_back(anova.error.s);
  out.emplace_back(anova.total.s);
  out.emplace_back(best);
  return out;
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::DoeKind);
