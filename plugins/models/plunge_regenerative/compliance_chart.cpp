#include "models/plunge_regenerative/compliance_chart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "models/thompson/thompson.hpp"

namespace chatterlab {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDefaultBandMultiple = 4.0;  // as stability_map: 4 x the highest mode

// The G1 parameters behind a [model] table, or nothing for a model this chart cannot draw.
std::optional<PlungeRegenerativeParameters> g1_parameters(const Json& model_table) {
  Json params = model_table;
  const std::string type = params.at("type").get<std::string>();
  params.erase("type");
  auto model = model_registry().at(type).create(ParamValues(std::move(params)));
  if (const auto* plunge = dynamic_cast<const PlungeRegenerative*>(model.get())) return plunge->parameters();
  if (const auto* thompson = dynamic_cast<const Thompson*>(model.get()))
    return thompson::equivalent_g1(thompson->parameters());
  return std::nullopt;
}

double band_hz(const Json& chart, const PlungeRegenerativeParameters& p) {
  if (!chart.at("max_frequency_hz").is_null()) return chart.at("max_frequency_hz").get<double>();
  double highest = 0.0;
  for (const StructuralMode& m : p.modes) highest = std::max(highest, m.frequency_hz);
  return kDefaultBandMultiple * highest;
}

constexpr const char* kColumns[] = {"leftmost_real_compliance_m_per_n", "leftmost_frequency_hz",
                                    "process_line_m_per_n", "line_depth_ratio", "intersects"};

}  // namespace

ComplianceChart compliance_chart(const PlungeRegenerativeParameters& p, double max_frequency_hz,
                                 int points) {
  const PlungeCharacteristic e(p);
  ComplianceChart out;
  out.process_line_m_per_n = -0.5 * (2.0 / p.contact_stiffness_n_per_m +
                                     (p.wheel_regeneration ? 1.0 / p.wheel_wear_stiffness_n_per_m : 0.0) +
                                     (p.work_regeneration ? 1.0 / p.work_removal_stiffness_n_per_m : 0.0));
  std::size_t best = 0;
  for (int i = 0; i < points; ++i) {
    const double f = max_frequency_hz * i / (points - 1);
    const Complex h = e.structural_compliance(Complex(0.0, kTwoPi * f));
    out.frequency_hz.push_back(f);
    out.real_m_per_n.push_back(h.real());
    out.imag_m_per_n.push_back(h.imag());
    if (h.real() < out.real_m_per_n[best]) best = out.frequency_hz.size() - 1;
  }
  // Golden-section refinement between the neighbours of the smallest sample.
  auto re = [&](double f) { return e.structural_compliance(Complex(0.0, kTwoPi * f)).real(); };
  double lo = out.frequency_hz[best == 0 ? 0 : best - 1];
  double hi = out.frequency_hz[std::min(best + 1, out.frequency_hz.size() - 1)];
  for (int it = 0; it < 100 && hi - lo > 1e-12 * max_frequency_hz; ++it) {
    const double a = lo + 0.381966 * (hi - lo), b = hi - 0.381966 * (hi - lo);
    if (re(a) < re(b))
      hi = b;
    else
      lo = a;
  }
  out.leftmost_frequency_hz = 0.5 * (lo + hi);
  out.leftmost_real_m_per_n = std::min(re(out.leftmost_frequency_hz), out.real_m_per_n[best]);
  out.intersects = out.leftmost_real_m_per_n < out.process_line_m_per_n;
  return out;
}

PluginInfo ComplianceChartKind::info() {
  PluginInfo info;
  info.name = "compliance_chart";
  info.description =
      "stability chart of book fig 2-4: machine compliance curve H(jw) against the process line "
      "Re = -(1/2)(2/kc + 1/kg + 1/kw) (G1 eq 2-21)";
  info.models_md_ids = "G1 (eq 2-21), G2";
  ParamSpec band = param_spec("max_frequency_hz", ValueKind::real, "Hz",
                              "the curve is drawn for 0 <= f <= this (default: 4 x the highest mode)");
  band.min = 0.0;
  band.min_exclusive = true;
  band.optional = true;
  ParamSpec points = param_spec("points", ValueKind::integer, "1", "frequency samples of the curve");
  points.default_value = 20000;
  points.min = 100;
  points.max = 10000000;
  info.params = {band, points};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_frequency_hz", 1000.0}};
  return info;
}

void ComplianceChartKind::validate(Json& document, const SourceMap& sources) const {
  Json model = validate_component(document, "model", model_registry(), sources);
  Json chart = document.contains("chart") ? document["chart"] : Json::object();
  if (!chart.is_object())
    throw InputError(fmt::format("{}: chart = {}: expected a table [chart]", sources.locate("chart").str(),
                                 chart.dump()));
  chart = validate_params(chart, info().params, "chart", sources);
  if (!g1_parameters(model))
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": compliance_chart draws G1-type models only "
        "(plunge_regenerative, thompson)",
        sources.locate("model.type").str(), model["type"].get<std::string>()));
  document["model"] = std::move(model);
  document["chart"] = std::move(chart);
}

std::vector<std::string> ComplianceChartKind::output_columns(const Json&) const {
  return {std::begin(kColumns), std::end(kColumns)};
}

std::vector<Json> ComplianceChartKind::run_point(const Json& document, const PointContext& context) const {
  const auto p = g1_parameters(document.at("model"));
  if (!p) throw PointFailure("compliance_chart: not a G1-type model");
  const Json& settings = document.at("chart");
  const double band = band_hz(settings, *p);
  const ComplianceChart c = compliance_chart(*p, band, settings.at("points").get<int>());
  if (context.single_point() && !context.artifact_dir.empty()) {
    write_file_atomically(context.artifact_dir / "chart.csv",
                          csv_text({"frequency_hz", "real_compliance_m_per_n", "imag_compliance_m_per_n"},
                                   {c.frequency_hz, c.real_m_per_n, c.imag_m_per_n}));
    if (context.plots) {
      plot::Curves fig;
      fig.title = fmt::format("Stability chart (fig 2-4): {}",
                              c.intersects ? "curve and line meet, chatter possible"
                                           : "curve and line apart, stable at all speeds");
      fig.x_label = "Re H(jw) [m/N]";
      fig.y_label = "Im H(jw) [m/N]";
      fig.series.push_back({"machine compliance H(jw), 0.." + fmt::format("{:.0f}", band) + " Hz", c.real_m_per_n,
                            c.imag_m_per_n, "lines"});
      const auto [lowest, highest] = std::minmax_element(c.imag_m_per_n.begin(), c.imag_m_per_n.end());
      fig.series.push_back({fmt::format("process line eta: Re = -(1/2)(2/kc + 1/kg + 1/kw) = {:.3g}",
                                        c.process_line_m_per_n),
                            {c.process_line_m_per_n, c.process_line_m_per_n},
                            {*lowest - 0.1 * (*highest - *lowest), *highest + 0.1 * (*highest - *lowest)},
                            "lines"});
      fig.series.push_back({fmt::format("leftmost point, {:.1f} Hz", c.leftmost_frequency_hz),
                            {c.leftmost_real_m_per_n},
                            {std::imag(PlungeCharacteristic(*p).structural_compliance(
                                Complex(0.0, kTwoPi * c.leftmost_frequency_hz)))},
                            "points"});
      plot::render(fig, context.artifact_dir, "stability_chart");
    }
  }
  return {c.leftmost_real_m_per_n, c.leftmost_frequency_hz, c.process_line_m_per_n,
          c.leftmost_real_m_per_n / c.process_line_m_per_n, c.intersects};
}

void ComplianceChartKind::write_artifacts(const Study& study, const ResultTable& results,
                                          const std::filesystem::path& out_dir) const {
  // 1-D grid: the depth ratio (leftmost point / line; > 1: they meet) against the grid key.
  std::vector<std::size_t> varying;
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    if (study.grid[a].values.size() > 1) varying.push_back(a);
  if (varying.size() != 1) return;
  const std::size_t axis = varying[0];
  const std::size_t ratio = results.grid_columns.size() + 3;
  plot::Curves fig;
  fig.title = "Stability chart: depth of the compliance curve beyond the process line";
  fig.x_label = study.grid[axis].key;
  fig.y_label = "leftmost Re H / process line (> 1: they meet)";
  plot::Series s{"line_depth_ratio", {}, {}, "linespoints"};
  for (const auto& row : results.rows) {
    if (!row[axis].is_number() || !row[ratio].is_number()) continue;
    s.x.push_back(row[axis].get<double>());
    s.y.push_back(row[ratio].get<double>());
  }
  // Log x for a geometric progression of positive values (e.g. a kc sweep).
  fig.log_x = s.x.size() > 2 && s.x.front() > 0 &&
              std::abs(s.x[2] / s.x[1] - s.x[1] / s.x[0]) < 1e-9 * (s.x[1] / s.x[0]);
  fig.series.push_back(std::move(s));
  fig.reference_y = 1.0;
  fig.reference_label = "line touches the curve";
  plot::render(fig, out_dir, "line_depth_ratio");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::ComplianceChartKind);
