#include "study_kinds/compliance_chart/compliance_chart.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;

constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr const char* kColumns[] = {"leftmost_real_compliance_m_per_n", "leftmost_frequency_hz",
                                    "process_line_m_per_n", "line_depth_ratio", "intersects"};

// The model of a point and the two capabilities the chart reads.
struct ChartModel {
  std::unique_ptr<Model> model;
  StiffnessChain chain;
  const StructuralCompliance* compliance = nullptr;
};

ChartModel chart_model(const Json& model_table) {
  ChartModel m{kit::build_model(model_table), {}, nullptr};
  auto chain = m.model->stiffness_chain();
  m.compliance = m.model->structural_compliance();
  if (!chain || !m.compliance)
    throw PointFailure("compliance_chart: the model has no stiffness chain or no structural compliance");
  m.chain = std::move(*chain);
  return m;
}

double band_hz(const ComplianceChartSettings& settings, const StiffnessChain& chain) {
  if (settings.max_frequency_hz) return *settings.max_frequency_hz;
  double highest = 0.0;
  for (const ModeView& m : chain.modes) highest = std::max(highest, m.frequency_hz);
  return kit::default_band_multiple * highest;
}

// The chart figure of one point: the compliance curve, the process line, the leftmost point.
plot::Curves chart_figure(const ComplianceChart& c, const StructuralCompliance& compliance, double band) {
  plot::Curves fig;
  fig.title = fmt::format("Stability chart (fig 2-4): {}", c.intersects ? "curve and line meet, chatter possible"
                                                                         : "curve and line apart, stable at all speeds");
  fig.x_label = "Re H(jw) [m/N]";
  fig.y_label = "Im H(jw) [m/N]";
  fig.series.push_back({"machine compliance H(jw), 0.." + fmt::format("{:.0f}", band) + " Hz", c.real_m_per_n,
                        c.imag_m_per_n, "lines"});
  const auto [lowest, highest] = std::minmax_element(c.imag_m_per_n.begin(), c.imag_m_per_n.end());
  fig.series.push_back(
      {fmt::format("process line eta: Re = -(1/2)(2/kc + 1/kg + 1/kw) = {:.3g}", c.process_line_m_per_n),
       {c.process_line_m_per_n, c.process_line_m_per_n},
       {*lowest - 0.1 * (*highest - *lowest), *highest + 0.1 * (*highest - *lowest)},
       "lines"});
  fig.series.push_back({fmt::format("leftmost point, {:.1f} Hz", c.leftmost_frequency_hz),
                        {c.leftmost_real_m_per_n},
                        {std::imag(compliance.compliance_m_per_n(Complex(0.0, kTwoPi * c.leftmost_frequency_hz)))},
                        "points"});
  return fig;
}

}  // namespace

ComplianceChart compliance_chart(const StiffnessChain& chain, const StructuralCompliance& compliance,
                                 double max_frequency_hz, int points) {
  ComplianceChart out;
  // A chain that is off has an infinite stiffness: its 1/k is 0.
  out.process_line_m_per_n = -0.5 * (2.0 / chain.contact_stiffness_n_per_m + 1.0 / chain.wheel_wear_stiffness_n_per_m +
                                     1.0 / chain.work_removal_stiffness_n_per_m);
  auto re = [&](double f) { return compliance.compliance_m_per_n(Complex(0.0, kTwoPi * f)).real(); };
  std::size_t best = 0;
  for (int i = 0; i < points; ++i) {
    const double f = max_frequency_hz * i / (points - 1);
    const Complex h = compliance.compliance_m_per_n(Complex(0.0, kTwoPi * f));
    out.frequency_hz.push_back(f);
    out.real_m_per_n.push_back(h.real());
    out.imag_m_per_n.push_back(h.imag());
    if (h.real() < out.real_m_per_n[best]) best = out.frequency_hz.size() - 1;
  }
  // Golden-section refinement between the neighbours of the smallest sample.
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

const ParamTable<ComplianceChartSettings>& compliance_chart_settings_table() {
  using S = ComplianceChartSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::max_frequency_hz, "max_frequency_hz", "Hz",
          "the curve is drawn for 0 <= f <= this (default: 4 x the highest mode)")
        .positive();
    t.add(&S::points, "points", "1", "frequency samples of the curve").at_least(100).at_most(10000000);
    return t;
  }();
  return table;
}

PluginInfo ComplianceChartKind::info() {
  return plugin_info("compliance_chart", "G1 (eq 2-21), G2",
                     compliance_chart_settings_table().specs(),
                     {{"max_frequency_hz", 1000.0}},
                     "stability chart of book fig 2-4: machine compliance curve H(jw) against the process line "
                     "Re = -(1/2)(2/kc + 1/kg + 1/kw) (G1 eq 2-21)");
}

void ComplianceChartKind::validate(Json& document, const SourceMap& sources) const {
  auto model = kit::validate_model(document, kit::ModelNeeds::nothing, "compliance_chart", sources);
  kit::validate_settings(document, "chart", compliance_chart_settings_table(), sources);
  const auto chain = model->stiffness_chain();
  const std::string type = document.at("model").at("type").get<std::string>();
  if (!chain || !model->structural_compliance())
    throw InputError(fmt::format(
        "{}: model.type = \"{}\": compliance_chart needs a model with a G1 stiffness chain and a "
        "structural compliance (e.g. plunge_regenerative, thompson)",
        sources.locate("model.type").str(), type));
  if (chain->penetration_damping_n_s_per_m > 0.0)
    throw InputError(fmt::format(
        "{}: model.penetration_damping_n_s_per_m = {}: the process line of eq 2-21 needs a purely "
        "regenerating work chain (with kd > 0 the work term's real part on s = jw is not 1/(2 kw)); "
        "draw the chart with kd = 0 or work_regeneration = false",
        sources.locate("model.penetration_damping_n_s_per_m").str(), chain->penetration_damping_n_s_per_m));
}

std::vector<std::string> ComplianceChartKind::output_columns(const Json&) const {
  return {std::begin(kColumns), std::end(kColumns)};
}

std::vector<Json> ComplianceChartKind::run_point(const Json& document, const PointContext& context) const {
  const ChartModel m = chart_model(document.at("model"));
  const ComplianceChartSettings settings = kit::read_settings(document, "chart", compliance_chart_settings_table());
  const double band = band_hz(settings, m.chain);
  const ComplianceChart c = compliance_chart(m.chain, *m.compliance, band, settings.points);
  if (context.single_point()) {
    kit::write_table(context, "chart.csv", {"frequency_hz", "real_compliance_m_per_n", "imag_compliance_m_per_n"},
                     {c.frequency_hz, c.real_m_per_n, c.imag_m_per_n});
    if (context.plots && !context.artifact_dir.empty())
      plot::render(chart_figure(c, *m.compliance, band), context.artifact_dir, "stability_chart");
  }
  return {c.leftmost_real_m_per_n, c.leftmost_frequency_hz, c.process_line_m_per_n,
          c.leftmost_real_m_per_n / c.process_line_m_per_n, c.intersects};
}

void ComplianceChartKind::write_artifacts(const Study& study, const ResultTable& results,
                                          const fs::path& out_dir) const {
  // The depth ratio (leftmost point / line; > 1: they meet) over the grid: a curve over one
  // varying axis, a map over two.
  const std::vector<kit::PlotAxis> axes = kit::varying_axes(study);
  kit::ColumnFigure figure{"line_depth_ratio",
                           kit::study_title(study) + ": leftmost Re H over the process line",
                           "leftmost Re H / process line (> 1: they meet)"};
  figure.reference = 1.0;
  figure.reference_label = "line touches the curve";
  figure.diverging = true;
  figure.low_label = "apart: stable at all speeds";
  figure.high_label = "they meet: chatter possible";
  kit::Figures figures;
  kit::plot_column(axes, results, figure, out_dir, "line_depth_ratio", figures);
  figures.finish();
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::ComplianceChartKind);
