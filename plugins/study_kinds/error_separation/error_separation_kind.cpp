#include "study_kinds/error_separation/error_separation_kind.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>

#include "study_kinds/error_separation/cylindricity.hpp"
#include "study_kinds/error_separation/error_separation.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;
namespace es = error_separation;
namespace ss = kit;

constexpr double deg = std::numbers::pi / 180.0;
constexpr std::size_t max_probes = 8;
const std::vector<std::string> methods{"frequency", "time_recursion", "two_point", "n_point"};

// ------------------------------------------------------------------ table specs
std::vector<ParamSpec> input_specs() {
  ParamSpec spr = param_spec("samples_per_rev", ValueKind::integer, "1",
                             "samples per revolution N (default: all rows are one revolution)");
  spr.min = 8;
  spr.optional = true;
  ParamSpec unit = param_spec("unit_um", ValueKind::real, "um",
                              "micrometres per unit of the probe data (1 for um, 1000 for mm)");
  unit.default_value = 1.0;
  unit.min = 0.0;
  unit.min_exclusive = true;
  ParamSpec average = param_spec("average_revolutions", ValueKind::boolean, "",
                                 "ensemble-average all revolutions (E3); false: the first only");
  average.default_value = true;
  ParamSpec section = param_spec("section_column", ValueKind::string, "",
                                 "column holding the axial position of each row: cylindricity "
                                 "mode (E6), one block of whole revolutions per section");
  section.optional = true;
  return {spr, unit, average, section};
}

std::vector<ParamSpec> probe_specs() {
  ParamSpec angles = param_spec("angles_deg", ValueKind::real_list, "deg",
                                "probe angles phi_q, one per input column, e.g. [0, a, a + b]");
  angles.min = -360.0;
  angles.max = 720.0;
  angles.min_items = 2;
  ParamSpec method =
      param_spec("method", ValueKind::string, "",
                 "frequency (E1/E2), time_recursion (E4), two_point or n_point (E5)");
  method.default_value = "frequency";
  method.choices = methods;
  ParamSpec weights = param_spec("weights", ValueKind::real_list, "1",
                                 "n_point only: probe weights c_q (default: balanced by least "
                                 "squares over the harmonics)");
  weights.optional = true;
  ParamSpec on_suppressed =
      param_spec("on_suppressed", ValueKind::string, "",
                 "suppressed harmonics in 2..max_harmonic: warn (listed in summary.json) or "
                 "error (exit 2)");
  on_suppressed.default_value = "warn";
  on_suppressed.choices = {"warn", "error"};
  ParamSpec opt_lo = param_spec("optimise_min_harmonic", ValueKind::integer, "1",
                                "probe-angle optimisation: lowest harmonic of the band that must be seen");
  opt_lo.default_value = 2;
  opt_lo.min = 2;
  opt_lo.max = 10000;
  ParamSpec opt_h = param_spec("optimise_max_harmonic", ValueKind::integer, "1",
                               "probe-angle optimisation: no suppressed harmonic up to this order");
  opt_h.default_value = 50;
  opt_h.min = 2;
  opt_h.max = 10000;
  ParamSpec opt_span = param_spec("optimise_max_span_deg", ValueKind::real, "deg",
                                  "probe-angle optimisation: largest angle between first and last "
                                  "probe");
  opt_span.default_value = 180.0;
  opt_span.min = 0.0;
  opt_span.min_exclusive = true;
  opt_span.max = 360.0;
  return {angles, method, weights, on_suppressed, opt_lo, opt_h, opt_span};
}

std::vector<ParamSpec> separation_specs() {
  ParamSpec max_h = param_spec("max_harmonic", ValueKind::integer, "1",
                               "highest harmonic kept and checked for suppression (default N/2)");
  max_h.min = 2;
  max_h.optional = true;
  ParamSpec tol = param_spec("suppression_tolerance", ValueKind::real, "1",
                             "harmonic l counts as suppressed when |G(l)| <= this x sum |c_q|");
  tol.default_value = 1e-6;
  tol.min = 0.0;
  tol.min_exclusive = true;
  tol.max = 0.1;
  ParamSpec validity = param_spec("validity_fraction", ValueKind::real, "1",
                                  "first-harmonic check: |S_1| must stay below this fraction of "
                                  "the range of S (book: 3-5 %)");
  validity.default_value = 0.05;
  validity.min = 0.0;
  validity.min_exclusive = true;
  validity.max = 1.0;
  ParamSpec pass = param_spec("fir_passband_upr", ValueKind::real, "1/rev",
                              "zero-phase FIR smoothing: passband edge in undulations per "
                              "revolution (0: no smoothing)");
  pass.default_value = 0.0;
  pass.min = 0.0;
  ParamSpec stop = param_spec("fir_stopband_upr", ValueKind::real, "1/rev",
                              "zero-phase FIR: stopband edge (default 2 x passband)");
  stop.optional = true;
  stop.min = 0.0;
  stop.min_exclusive = true;
  ParamSpec passes = param_spec("max_recursion_passes", ValueKind::integer, "1",
                                "time recursion: passes around the revolution before giving up");
  passes.default_value = 20;
  passes.min = 1;
  passes.max = 1000;
  return {max_h, tol, validity, pass, stop, passes};
}

// ------------------------------------------------------------------ configuration
struct Config {
  std::vector<fs::path> files;  // one, or one per probe
  std::vector<std::string> columns;
  std::optional<std::size_t> samples_per_rev;
  double unit_um = 1.0;
  bool average = true;
  std::string section_column;
  std::vector<double> angles_deg;
  std::string method;
  std::vector<double> weights;
  std::string on_suppressed;
  int optimise_min_harmonic = 2, optimise_max_harmonic = 50;
  double optimise_max_span_deg = 180;
  std::optional<int> max_harmonic;
  double suppression_tolerance = 1e-6, validity_fraction = 0.05;
  double fir_passband_upr = 0;
  std::optional<double> fir_stopband_upr;
  int max_recursion_passes = 20;
};

Config read_config(const Json& document) {
  const Json& input = document.at("input");
  const Json& probes = document.at("probes");
  const Json& sep = document.at("separation");
  Config c;
  if (input.contains("files"))
    for (const Json& f : input.at("files")) c.files.emplace_back(f.get<std::string>());
  else
    c.files.emplace_back(input.at("file").get<std::string>());
  for (const Json& col : input.at("columns")) c.columns.push_back(col.get<std::string>());
  if (!input.at("samples_per_rev").is_null())
    c.samples_per_rev = input.at("samples_per_rev").get<std::size_t>();
  c.unit_um = input.at("unit_um").get<double>();
  c.average = input.at("average_revolutions").get<bool>();
  if (!input.at("section_column").is_null())
    c.section_column = input.at("section_column").get<std::string>();
  c.angles_deg = probes.at("angles_deg").get<std::vector<double>>();
  c.method = probes.at("method").get<std::string>();
  if (!probes.at("weights").is_null()) c.weights = probes.at("weights").get<std::vector<double>>();
  c.on_suppressed = probes.at("on_suppressed").get<std::string>();
  c.optimise_min_harmonic = probes.at("optimise_min_harmonic").get<int>();
  c.optimise_max_harmonic = probes.at("optimise_max_harmonic").get<int>();
  c.optimise_max_span_deg = probes.at("optimise_max_span_deg").get<double>();
  if (!sep.at("max_harmonic").is_null()) c.max_harmonic = sep.at("max_harmonic").get<int>();
  c.suppression_tolerance = sep.at("suppression_tolerance").get<double>();
  c.validity_fraction = sep.at("validity_fraction").get<double>();
  c.fir_passband_upr = sep.at("fir_passband_upr").get<double>();
  if (!sep.at("fir_stopband_upr").is_null())
    c.fir_stopband_upr = sep.at("fir_stopband_upr").get<double>();
  c.max_recursion_passes = sep.at("max_recursion_passes").get<int>();
  return c;
}

// ------------------------------------------------------------------ data
struct ProbeData {
  std::size_t n = 0;            // samples per revolution
  std::size_t revolutions = 1;  // per section, as measured (averaged when average = true)
  std::vector<double> z;        // per section (one section without a section column)
  std::vector<std::vector<std::vector<double>>> sections;  // [section][probe][sample], um
};

// Reads and checks the probe data (also what validate() uses to refuse bad input).
ProbeData load_probe_data(const Config& c, const SourceMap& sources) {
  const std::string file_key = c.files.size() > 1 ? "input.files" : "input.file";
  std::vector<DataTable> tables;
  for (const fs::path& f : c.files) tables.push_back(ss::read_table_at(f, file_key, sources));
  std::vector<std::vector<double>> signals;
  std::vector<std::string> origin;  // "column "A" of file" for messages
  for (std::size_t q = 0; q < c.columns.size(); ++q) {
    const DataTable& t = tables[c.files.size() > 1 ? q : 0];
    signals.push_back(ss::column_at(t, c.columns[q], "input.columns", sources));
    origin.push_back(fmt::format("column \"{}\" of {}", c.columns[q], t.file.filename().string()));
  }
  for (std::size_t q = 1; q < signals.size(); ++q)
    if (signals[q].size() != signals[0].size())
      throw InputError(
          fmt::format("{}: {}: probe signals differ in length: {} has {} rows, {} has {} rows",
                      sources.locate(file_key).str(), file_key, origin[0], signals[0].size(),
                      origin[q], signals[q].size()));
  for (auto& s : signals)
    for (double& v : s) v *= c.unit_um;

  // Sections: consecutive rows with the same value of the section column.
  std::vector<std::size_t> starts{0};
  std::vector<double> z{0.0};
  if (!c.section_column.empty()) {
    const auto& column =
        ss::column_at(tables[0], c.section_column, "input.section_column", sources);
    z = {column.front()};
    for (std::size_t r = 1; r < column.size(); ++r)
      if (column[r] != column[r - 1]) {
        starts.push_back(r);
        z.push_back(column[r]);
      }
    if (starts.size() < 2)
      throw InputError(fmt::format(
          "{}: input.section_column = \"{}\": all rows hold one section (z = {}); cylindricity "
          "needs at least two sections",
          sources.locate("input.section_column").str(), c.section_column, z.front()));
  }
  starts.push_back(signals[0].size());

  ProbeData data;
  data.z = z;
  const std::size_t first_rows = starts[1] - starts[0];
  data.n = c.samples_per_rev.value_or(first_rows);
  if (data.n < 8)
    throw InputError(fmt::format("{}: input: {} rows per revolution, at least 8 needed",
                                 sources.locate("input").str(), data.n));
  for (std::size_t j = 0; j + 1 < starts.size(); ++j) {
    const std::size_t rows = starts[j + 1] - starts[j];
    if (rows % data.n != 0 || rows == 0) {
      const std::string where = c.section_column.empty()
                                    ? std::string("the data have")
                                    : fmt::format("section {} = {} has", c.section_column, z[j]);
      throw InputError(fmt::format(
          "{}: input.samples_per_rev = {}: {} {} rows, not a whole number of revolutions (a "
          "multiple of {})",
          sources.locate(c.samples_per_rev ? "input.samples_per_rev" : "input").str(), data.n,
          where, rows, data.n));
    }
    if (j > 0 && rows / data.n != data.revolutions)
      throw InputError(fmt::format(
          "{}: input.section_column = \"{}\": sections hold different numbers of revolutions "
          "({} and {})",
          sources.locate("input.section_column").str(), c.section_column, data.revolutions,
          rows / data.n));
    data.revolutions = rows / data.n;
    std::vector<std::vector<double>> section;
    for (const auto& s : signals) {
      std::span<const double> block(s.data() + starts[j], c.average ? rows : data.n);
      section.push_back(es::average_revolutions(block, data.n));
    }
    data.sections.push_back(std::move(section));
  }
  return data;
}

// ------------------------------------------------------------------ layout and method
struct Method {
  es::ProbeLayout layout;  // the layout whose G(l) governs the result (3 probes for two_point)
  es::SeparationOptions options;
  int max_harmonic = 0;  // resolved
};

Method build_method(const Config& c, std::size_t n, const SourceMap& sources) {
  Method m;
  const std::string angles_where = sources.locate("probes.angles_deg").str();
  const std::string angles_text = fmt::format("[{}]", fmt::join(c.angles_deg, ", "));
  m.max_harmonic = c.max_harmonic ? *c.max_harmonic : static_cast<int>(n / 2);
  if (m.max_harmonic > static_cast<int>(n / 2))
    throw InputError(fmt::format(
        "{}: separation.max_harmonic = {}: out of range, must be <= N/2 = {} (samples_per_rev {})",
        sources.locate("separation.max_harmonic").str(), m.max_harmonic, n / 2, n));
  m.options.max_harmonic = m.max_harmonic;
  m.options.suppression_tolerance = c.suppression_tolerance;
  m.options.validity_fraction = c.validity_fraction;
  m.options.max_recursion_passes = c.max_recursion_passes;
  if (c.fir_passband_upr > 0) {
    try {
      m.options.fir = es::design_zero_phase_lowpass(
          c.fir_passband_upr, c.fir_stopband_upr.value_or(2 * c.fir_passband_upr), n);
    } catch (const std::invalid_argument& e) {
      throw InputError(fmt::format("{}: separation.fir_passband_upr = {}: {}",
                                   sources.locate("separation.fir_passband_upr").str(),
                                   c.fir_passband_upr, e.what()));
    }
  }

  auto need = [&](bool ok, const std::string& what) {
    if (!ok)
      throw InputError(fmt::format("{}: probes.angles_deg = {}: {} (method \"{}\")", angles_where,
                                   angles_text, what, c.method));
  };
  std::vector<double> angles;
  for (double a : c.angles_deg) angles.push_back(a * deg);
  try {
    if (c.method == "frequency") {
      need(angles.size() == 3, fmt::format("{} angles; the three-point method takes 3 (use "
                                           "method = \"n_point\" for more)",
                                           angles.size()));
      m.layout = {angles, es::three_point_weights(angles)};
    } else if (c.method == "time_recursion") {
      need(angles.size() == 3, fmt::format("{} angles; the time recursion takes 3", angles.size()));
      const double samples_per_rad = static_cast<double>(n) / (2 * std::numbers::pi);
      const double p = (angles[1] - angles[0]) * samples_per_rad;
      const double p0 = angles[0] * samples_per_rad;
      const double two_cos = 2.0 * std::cos(angles[1] - angles[0]);
      m.layout = {angles, {1.0, -two_cos, 1.0}};
      need(std::abs(p - std::round(p)) < 1e-6 && std::abs(p0 - std::round(p0)) < 1e-6 &&
               std::abs((angles[2] - angles[1]) - (angles[1] - angles[0])) < 1e-9,
           fmt::format("the time recursion needs equally spaced probes 0, p, 2p whole samples "
                       "apart (one sample = {:.6g} deg)",
                       360.0 / static_cast<double>(n)));
      const auto spacing = static_cast<long>(std::llround(std::abs(p)));
      need(std::gcd(spacing, static_cast<long>(n)) == 1,
           fmt::format("the probe spacing p = {} samples shares the factor {} with "
                       "samples_per_rev = {} (the recursion needs gcd(p, N) = 1)",
                       spacing, std::gcd(spacing, static_cast<long>(n)), n));
    } else if (c.method == "two_point") {
      need(angles.size() == 2,
           fmt::format("{} angles; the two-point approximation takes 2", angles.size()));
      const double gap = c.angles_deg[1] - c.angles_deg[0];
      const double want = 180.0 - 360.0 / static_cast<double>(n);
      need(std::abs(gap - want) < 1e-6,
           fmt::format("the two probes must be 180 - 360/N = {} deg apart (N = {}), not {}", want,
                       n, gap));
      m.layout = es::two_point_layout(angles[0], n);
    } else {  // n_point
      need(angles.size() >= 3,
           fmt::format("{} angles; the n-point method takes at least 3", angles.size()));
      if (!c.weights.empty()) {
        if (c.weights.size() != angles.size())
          throw InputError(fmt::format("{}: probes.weights: {} weights for {} probes",
                                       sources.locate("probes.weights").str(), c.weights.size(),
                                       angles.size()));
        m.layout = {angles, c.weights};
        const double residual = es::spindle_residual(m.layout);
        if (!(residual <= 1e-9))
          throw InputError(fmt::format(
              "{}: probes.weights = [{}]: they do not cancel spindle motion (|sum c cos phi|, "
              "|sum c sin phi| = {:.3g} x sum |c|, must be 0)",
              sources.locate("probes.weights").str(), fmt::join(c.weights, ", "), residual));
      } else {
        m.layout = {angles, es::balanced_weights(angles, m.max_harmonic)};
      }
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(
        fmt::format("{}: probes.angles_deg = {}: {}", angles_where, angles_text, e.what()));
  }
  if (c.method != "n_point" && !c.weights.empty())
    throw InputError(
        fmt::format("{}: probes.weights: only method = \"n_point\" takes weights "
                    "(this study uses \"{}\")",
                    sources.locate("probes.weights").str(), c.method));
  return m;
}

es::Separation run_method(const Config& c, const Method& m,
                          std::span<const std::vector<double>> probes) {
  if (c.method == "time_recursion") return es::separate_time_recursion(probes, m.layout, m.options);
  if (c.method == "two_point")
    return es::separate_two_point(probes, m.layout.angles_rad[0], m.options);
  return es::separate_frequency(probes, m.layout, m.options);
}

std::string harmonic_list(const std::vector<int>& h) {
  constexpr std::size_t shown = 20;
  std::vector<int> head(h.begin(), h.begin() + static_cast<long>(std::min(h.size(), shown)));
  return fmt::format("{}{}", fmt::join(head, ", "),
                     h.size() > shown ? fmt::format(", ... ({} in all)", h.size()) : "");
}

std::string suppression_message(const Config& c, const std::vector<int>& suppressed, int top) {
  return fmt::format(
      "probes.angles_deg = [{}]: harmonics {} of 2..{} are suppressed (|G(l)| = 0): the probes "
      "cannot see them and profile.csv lacks them (probe offsets sharing a factor with "
      "samples_per_rev suppress l = k N/d +/- 1)",
      fmt::join(c.angles_deg, ", "), harmonic_list(suppressed), top);
}

// What the layout cannot see in the evaluated band 2..max_harmonic: the run is `degraded` when
// it loses a harmonic there, with the lost harmonics, their share of the probe signals' power
// and an infinite worst error transfer.
struct Degradation {
  std::string status = "ok";  // ok | degraded
  es::WorstTransfer worst;
  es::LostSpectrum lost;
  bool degraded() const { return status == "degraded"; }
};

// An error transfer factor for JSON and CSV: "inf" where it is infinite (JSON has no infinity).
Json transfer_factor(double q) { return std::isfinite(q) ? Json(q) : Json("inf"); }

std::string degradation_message(const Config& c, const Degradation& d, int top,
                                const es::AngleOptimum& proposal, int band_lo, int band_hi) {
  std::string message = fmt::format(
      "probes.angles_deg = [{}]: degraded: harmonics {} of 2..{} are lost ({} harmonics, |G(l)| = "
      "0): they hold {:.1f} % of the probe signals' power in that band, the separated profile "
      "lacks them (its roundness can be low by as much) and the worst error transfer is infinite",
      fmt::join(c.angles_deg, ", "), harmonic_list(d.lost.harmonics), top, d.lost.harmonics.size(),
      100.0 * d.lost.lost_share);
  if (proposal.found) {
    std::vector<double> a;
    for (double r : proposal.angles_rad) a.push_back(std::round(r * 180.0 / std::numbers::pi * 1e6) / 1e6);
    message += fmt::format("; probes at [{}] deg see every harmonic {}..{} (worst Q {:.3g} at l = {})",
                           fmt::join(a, ", "), band_lo, band_hi, proposal.worst.q, proposal.worst.harmonic);
  }
  return message;
}

// ------------------------------------------------------------------ outputs
std::vector<double> angles_deg_of(std::size_t n) {
  std::vector<double> a(n);
  for (std::size_t i = 0; i < n; ++i)
    a[i] = 360.0 * static_cast<double>(i) / static_cast<double>(n);
  return a;
}

// Worst Q over the band (infinite when a harmonic is lost), the worst over the harmonics the
// layout sees, and the smallest |G| there.
Json transfer_json(const es::Transfer& t, const Degradation& d, int top) {
  double min_g = std::numeric_limits<double>::infinity();
  for (std::size_t l = 2; l < t.g_abs.size() && static_cast<int>(l) <= top; ++l)
    if (t.g_abs[l] > 0) min_g = std::min(min_g, t.g_abs[l]);
  Json j;
  j["worst_error_transfer_q"] = transfer_factor(d.worst.q);
  j["harmonic_of_worst_q"] = d.worst.harmonic;
  j["worst_error_transfer_q_seen"] = d.worst.seen_q;
  j["harmonic_of_worst_q_seen"] = d.worst.seen_harmonic;
  j["min_abs_g"] = std::isfinite(min_g) ? Json(min_g) : Json();
  j["band"] = {2, top};
  return j;
}

void plot_figures(const std::string& title, const Method& m, const es::Separation& sep,
                  const es::Transfer& t, const Degradation& d, const fs::path& dir) {
  namespace pl = plot;
  const std::size_t n = sep.profile.size();
  const std::vector<double> angle = angles_deg_of(n);
  std::vector<std::pair<std::string, std::function<void()>>> figures;
  // Every profile figure says what it cannot show: "DEGRADED" in the title, what is lost in the
  // key (the title has no room for it).
  const std::string lost_note = d.degraded() ? " - DEGRADED" : "";
  const std::string lost_detail =
      d.degraded() ? fmt::format(", without its {} lost harmonics ({:.1f} % of the probe power)",
                                 d.lost.harmonics.size(), 100.0 * d.lost.lost_share)
                   : std::string();

  figures.emplace_back("profile_linear", [&] {
    pl::Curves f;
    f.title =
        fmt::format("{}: profile, RONt {:.4g} um (LS centre){}", title, sep.roundness(), lost_note);
    f.x_label = "angle [deg]";
    f.y_label = "radius deviation [um]";
    f.series.push_back(
        {"profile r(theta) - mean, 1st harmonic removed" + lost_detail, angle, sep.profile, "lines"});
    f.reference_y = 0.0;
    f.reference_label = "least-squares circle";
    pl::render(f, dir, "profile_linear");
  });
  figures.emplace_back("profile_polar", [&] {
    const double rng = std::max(sep.roundness(), 1e-12);
    const double base = 2.0 * rng;  // deviation drawn around a base circle of twice its P-V
    pl::Curves f;
    f.title = fmt::format("{}: polar profile{}", title, lost_note);
    f.x_label = fmt::format("x = (base circle {:.3g} + deviation) cos(theta) [um]", base);
    f.y_label = "y [um]";
    f.equal_aspect = true;  // a round part must look round
    pl::Series profile{"separated profile" + lost_detail, {}, {}, "lines"},
        circle{"least-squares circle", {}, {}, "lines"};
    for (std::size_t i = 0; i <= n; ++i) {
      const double th = 2 * std::numbers::pi * static_cast<double>(i % n) / static_cast<double>(n);
      profile.x.push_back((base + sep.profile[i % n]) * std::cos(th));
      profile.y.push_back((base + sep.profile[i % n]) * std::sin(th));
      circle.x.push_back(base * std::cos(th));
      circle.y.push_back(base * std::sin(th));
    }
    f.series = {profile, circle};
    pl::render(f, dir, "profile_polar");
  });
  figures.emplace_back("spindle_motion", [&] {
    pl::Curves f;
    f.title = fmt::format("{}: spindle error motion (with the part's eccentricity)", title);
    f.x_label = "angle [deg]";
    f.y_label = "displacement [um]";
    f.series.push_back({"dx", angle, sep.dx, "lines"});
    f.series.push_back({"dy", angle, sep.dy, "lines"});
    pl::render(f, dir, "spindle_motion");
  });
  figures.emplace_back("transfer_g", [&] {
    pl::Curves f;
    f.title = fmt::format("{}: |G(l)|, {} lost harmonics", title, sep.suppressed.size());
    f.x_label = "harmonic l [undulations per revolution]";
    f.y_label = "|G(l)|";
    pl::Series g{"|G(l)|", {}, {}, "impulses"},
        zero{"lost harmonics (G = 0: not measured)", {}, {}, "points"};
    for (std::size_t l = 2; l < t.g_abs.size(); ++l) {
      g.x.push_back(static_cast<double>(l));
      g.y.push_back(t.g_abs[l]);
    }
    for (int l : sep.suppressed) {
      zero.x.push_back(l);
      zero.y.push_back(0.0);
    }
    f.series.push_back(g);
    if (!zero.x.empty()) f.series.push_back(zero);
    pl::render(f, dir, "transfer_g");
  });
  figures.emplace_back("transfer_q", [&] {
    pl::Curves f;
    f.title = fmt::format("{}: amplitude transfer W(l) = 1/|G| and error transfer Q(l)", title);
    f.x_label = "harmonic l [undulations per revolution]";
    f.y_label = "transfer factor";
    f.log_y = true;
    pl::Series q{"Q(l) = sqrt(sum c^2)/|G(l)|", {}, {}, "lines"},
        w{"W(l) = 1/|G(l)|", {}, {}, "lines"};
    double top = 1.0;
    for (std::size_t l = 2; l < t.q.size(); ++l) {
      if (!std::isfinite(t.q[l])) continue;  // lost: marked at the top below
      q.x.push_back(static_cast<double>(l));
      q.y.push_back(t.q[l]);
      w.x.push_back(static_cast<double>(l));
      w.y.push_back(t.w[l]);
      top = std::max({top, t.q[l], t.w[l]});
    }
    // A lost harmonic has Q = W = infinity: marked above every finite value.
    pl::Series lost{"lost harmonic: Q infinite (drawn at the top)", {}, {}, "points"};
    for (int l : sep.suppressed) {
      lost.x.push_back(l);
      lost.y.push_back(2.0 * top);
    }
    if (q.x.empty() && lost.x.empty()) return;
    f.title = fmt::format("{}: transfer W = 1/|G|, Q (worst Q {})", title,
                          std::isfinite(d.worst.q) ? fmt::format("{:.3g}", d.worst.q) : "infinite");
    if (!q.x.empty()) f.series = {q, w};
    if (!lost.x.empty()) f.series.push_back(lost);
    pl::render(f, dir, "transfer_q");
  });
  figures.emplace_back("probe_spectrum", [&] {
    // What the probes measured per harmonic, and which of it the layout cannot separate.
    pl::Curves f;
    f.title = fmt::format("{}: probe amplitude per harmonic{}", title, lost_note);
    f.x_label = "harmonic l [undulations per revolution]";
    f.y_label = "mean probe amplitude [um]";
    pl::Series seen{"amplitude (mean over the probes)", {}, {}, "impulses"},
        lost{fmt::format("lost harmonic (not separable from spindle motion): {:.1f} % of the band's power",
                         100.0 * d.lost.lost_share), {}, {}, "points"};
    for (std::size_t l = 2; l < d.lost.amplitude.size(); ++l) {
      seen.x.push_back(static_cast<double>(l));
      seen.y.push_back(d.lost.amplitude[l]);
    }
    for (int l : d.lost.harmonics) {
      lost.x.push_back(l);
      lost.y.push_back(d.lost.amplitude[static_cast<std::size_t>(l)]);
    }
    f.series.push_back(seen);
    if (!lost.x.empty()) f.series.push_back(lost);
    pl::render(f, dir, "probe_spectrum");
  });
  figures.emplace_back("suppression_map", [&] {
    // |G(l)|/sum|c| of three-probe layouts (0, alpha, phi2) with this study's alpha.
    const auto& a = m.layout.angles_rad;
    const double alpha = a[1] - a[0];
    const int top = std::min(m.max_harmonic, 100);
    const std::size_t rows = std::min<std::size_t>(n, 360);
    pl::Heatmap h;
    h.title = fmt::format("{}: |G(l)|/sum|c|, probes 0, {:.4g} deg, phi2", title, alpha / deg);
    h.x_label = "harmonic l";
    h.y_label = "third probe angle phi2 [deg]";
    h.z_label = "|G(l)| / sum |c_q|";
    std::vector<double> phi2;
    for (std::size_t k = 1; k < rows; ++k) {
      const double p = 2 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(rows);
      if (std::abs(std::sin(p - alpha)) < 1e-9 || std::abs(std::sin(0.5 * p)) < 1e-9) continue;
      phi2.push_back(p);
      h.y.push_back(p / deg);
    }
    for (int l = 2; l <= top; ++l) h.x.push_back(l);
    h.z = es::suppression_map(alpha, phi2, top);
    h.low_label = "suppressed";
    h.high_label = "well seen";
    pl::render(h, dir, "suppression_map");
  });
  ss::render_all(figures);
}

void plot_cylinder(const std::string& title, const std::string& z_name, const es::Cylinder& cyl,
                   const fs::path& dir) {
  namespace pl = plot;
  std::vector<std::pair<std::string, std::function<void()>>> figures;
  figures.emplace_back("cylinder_sections", [&] {
    pl::Curves f;
    f.title =
        fmt::format("{}: sections, cylindricity {:.4g} um (LS cylinder)", title, cyl.cylindricity);
    f.x_label = z_name;
    f.y_label = "[um]";
    pl::Series dr{"mean radius difference dr", {}, {}, "linespoints"},
        u{"slide straightness u", {}, {}, "linespoints"},
        v{"slide straightness v", {}, {}, "linespoints"},
        cx{"section centre x", {}, {}, "linespoints"},
        cy{"section centre y", {}, {}, "linespoints"};
    for (const auto& s : cyl.sections) {
      for (auto* series : {&dr, &u, &v, &cx, &cy}) series->x.push_back(s.z);
      dr.y.push_back(s.mean_radius_difference);
      u.y.push_back(s.straightness_u);
      v.y.push_back(s.straightness_v);
      cx.y.push_back(s.centre_x);
      cy.y.push_back(s.centre_y);
    }
    f.series = {dr, u, v, cx, cy};
    pl::render(f, dir, "cylinder_sections");
  });
  figures.emplace_back("cylinder_form", [&] {
    pl::Heatmap h;
    h.title = fmt::format("{}: 3-D form about the least-squares cylinder", title);
    h.x_label = "angle [deg]";
    h.y_label = z_name;
    h.z_label = "radial deviation [um]";
    h.x = angles_deg_of(cyl.residual.front().size());
    for (std::size_t j = 0; j < cyl.sections.size(); ++j) {
      h.y.push_back(cyl.sections[j].z);
      h.z.insert(h.z.end(), cyl.residual[j].begin(), cyl.residual[j].end());
    }
    pl::render(h, dir, "cylinder_form");
  });
  ss::render_all(figures);
}

}  // namespace

PluginInfo ErrorSeparationKind::info() {
  PluginInfo info;
  info.name = "error_separation";
  info.description =
      "roundness and spindle error motion from 2-8 probes by error separation (three-point, time "
      "recursion, n-point, two-point), cylindricity with a section column";
  info.models_md_ids = "E1, E2, E3, E4, E5, E6";
  info.params = separation_specs();
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_harmonic", 64}, {"fir_passband_upr", 32.0}};
  return info;
}

void ErrorSeparationKind::validate(Json& document, const SourceMap& sources) const {
  // [input]: file / files and columns by hand (lists of strings), the rest by spec.
  Json input = ss::table_or_empty(document, "input", sources);
  ss::integer_columns_as_names(input, {"columns", "section_column"});
  std::vector<std::string> input_keys{"file", "files", "columns"};
  for (const ParamSpec& s : input_specs()) input_keys.push_back(s.key);
  ss::check_known_keys(input, input_keys, "input", sources);
  if (input.contains("file") == input.contains("files"))
    throw InputError(fmt::format(
        "{}: [input] needs exactly one of 'file' (one table with every probe column) or 'files' "
        "(one table per probe)",
        sources.locate("input").str()));
  if (!input.contains("columns"))
    throw InputError(
        fmt::format("{}: missing required key 'input.columns' (one data column per "
                    "probe, e.g. [\"A\", \"B\", \"C\"])",
                    sources.locate("input").str()));
  // With one table per probe the same column name in each is natural.
  const auto columns = ss::string_list(input["columns"], "input.columns", sources, 2, max_probes,
                                       input.contains("files"));
  if (input.contains("file")) {
    input["file"] = ss::resolve_data_file(input["file"], "input.file", sources).string();
  } else {
    const auto names = ss::string_list(input["files"], "input.files", sources, columns.size(),
                                       columns.size(), true);
    Json resolved = Json::array();
    for (const auto& f : names)
      resolved.push_back(ss::resolve_data_file(Json(f), "input.files", sources).string());
    input["files"] = resolved;
  }
  Json scalars = input;
  for (const char* k : {"file", "files", "columns"}) scalars.erase(k);
  scalars = validate_params(scalars, input_specs(), "input", sources);
  for (auto& [k, v] : scalars.items()) input[k] = v;

  Json probes = validate_params(ss::table_or_empty(document, "probes", sources), probe_specs(),
                                "probes", sources);
  Json separation = validate_params(ss::table_or_empty(document, "separation", sources),
                                    separation_specs(), "separation", sources);
  document["input"] = input;
  document["probes"] = probes;
  document["separation"] = separation;

  const Config c = read_config(document);
  if (c.angles_deg.size() != c.columns.size())
    throw InputError(fmt::format("{}: probes.angles_deg = [{}]: {} angles for {} input.columns",
                                 sources.locate("probes.angles_deg").str(),
                                 fmt::join(c.angles_deg, ", "), c.angles_deg.size(),
                                 c.columns.size()));
  const ProbeData data = load_probe_data(c, sources);
  const Method m = build_method(c, data.n, sources);
  const auto suppressed =
      es::suppressed_harmonics(m.layout, m.max_harmonic, c.suppression_tolerance);
  if (!suppressed.empty() && c.on_suppressed == "error")
    throw InputError(fmt::format("{}: {} (probes.on_suppressed = \"error\")",
                                 sources.locate("probes.angles_deg").str(),
                                 suppression_message(c, suppressed, m.max_harmonic)));
}

std::vector<std::string> ErrorSeparationKind::output_columns(const Json& document) const {
  std::vector<std::string> columns{"roundness_um", "mean_radius_offset_um",
                                   "suppressed_harmonic_count", "worst_error_transfer_q",
                                   "first_harmonic_valid", "separation_status",
                                   "lost_share_percent"};
  if (!document.at("input").at("section_column").is_null()) columns.push_back("cylindricity_um");
  return columns;
}

std::vector<Json> ErrorSeparationKind::run_point(const Json& point_document,
                                                 const PointContext& context) const {
  const SourceMap& sources = ss::no_sources();  // validated already: no line numbers needed
  const Config c = read_config(point_document);
  const ProbeData data = load_probe_data(c, sources);
  const Method m = build_method(c, data.n, sources);
  const es::Transfer t = es::transfer(m.layout, m.max_harmonic);
  const bool cylinder = !c.section_column.empty();

  auto separate = [&](std::span<const std::vector<double>> probes) {
    try {
      return run_method(c, m, probes);
    } catch (const std::exception& e) {
      throw PointFailure(e.what());
    }
  };
  std::optional<es::Cylinder> cyl;
  es::Separation first;
  if (cylinder) {
    try {
      cyl = es::reconstruct_cylinder(data.sections, data.z, separate);
    } catch (const std::invalid_argument& e) {
      throw PointFailure(e.what());
    }
    first = cyl->sections.front().separation;
  } else {
    first = separate(data.sections.front());
  }

  // Optimal probe angles for this N and the band (E2): proposed where this layout loses harmonics.
  const int band_hi = std::min(c.optimise_max_harmonic, static_cast<int>(data.n / 2));
  const int band_lo = std::min(c.optimise_min_harmonic, band_hi);
  const es::AngleOptimum best = es::optimise_three_point_angles(
      data.n, band_hi, c.optimise_max_span_deg * deg, c.suppression_tolerance, band_lo);

  // Degraded: the layout loses harmonics of the evaluated band 2..max_harmonic.
  Degradation degradation;
  degradation.worst = es::worst_q(m.layout, m.max_harmonic, c.suppression_tolerance);
  degradation.lost = es::lost_spectrum(data.sections.front(), first.suppressed, 2, m.max_harmonic);
  if (!first.suppressed.empty()) degradation.status = "degraded";

  std::vector<std::string> warnings;
  if (degradation.degraded())
    warnings.push_back(degradation_message(c, degradation, m.max_harmonic, best, band_lo, band_hi));
  bool all_valid = true;
  std::vector<const es::Separation*> seps;
  if (cyl)
    for (const auto& s : cyl->sections) seps.push_back(&s.separation);
  else
    seps.push_back(&first);
  for (std::size_t j = 0; j < seps.size(); ++j)
    if (!seps[j]->first_harmonic.valid) {
      all_valid = false;
      warnings.push_back(fmt::format(
          "first-harmonic check failed{}: |S_1| = {:.4g} um > {:.4g} um ({} of the range of S): "
          "the signals do not fit the probe angles (misalignment, unsynchronised sampling, drift)",
          cyl ? fmt::format(" in section z = {}", data.z[j]) : std::string(),
          seps[j]->first_harmonic.amplitude, seps[j]->first_harmonic.limit, c.validity_fraction));
    }
  for (const auto& w : warnings) ss::warn(w);

  double roundness = 0.0;
  for (const auto* s : seps) roundness = std::max(roundness, s->roundness());

  if (!context.artifact_dir.empty()) {
    const fs::path dir = context.artifact_dir;
    const std::vector<double> angle = angles_deg_of(data.n);
    if (!cyl) {
      write_file_atomically(dir / "profile.csv",
                            csv_text({"angle_deg", "deviation_um"}, {angle, first.profile}));
      write_file_atomically(dir / "spindle.csv",
                            csv_text({"angle_deg", "dx_um", "dy_um"}, {angle, first.dx, first.dy}));
    } else {
      std::vector<std::vector<double>> prof(4), spin(5), form(5), sections(9);
      for (std::size_t j = 0; j < cyl->sections.size(); ++j) {
        const auto& s = cyl->sections[j];
        for (std::size_t i = 0; i < data.n; ++i) {
          for (auto* v : {&prof, &spin, &form}) {
            (*v)[0].push_back(static_cast<double>(j));
            (*v)[1].push_back(s.z);
            (*v)[2].push_back(angle[i]);
          }
          prof[3].push_back(s.separation.profile[i]);
          spin[3].push_back(s.separation.dx[i]);
          spin[4].push_back(s.separation.dy[i]);
          form[3].push_back(cyl->form[j][i]);
          form[4].push_back(cyl->residual[j][i]);
        }
        const double values[] = {static_cast<double>(j),
                                 s.z,
                                 s.mean_radius_difference,
                                 s.straightness_u,
                                 s.straightness_v,
                                 s.centre_x,
                                 s.centre_y,
                                 s.separation.roundness(),
                                 s.separation.first_harmonic.valid ? 1.0 : 0.0};
        for (std::size_t k = 0; k < 9; ++k) sections[k].push_back(values[k]);
      }
      const std::string z_name = c.section_column;
      write_file_atomically(dir / "profile.csv",
                            csv_text({"section", z_name, "angle_deg", "deviation_um"}, prof));
      write_file_atomically(dir / "spindle.csv",
                            csv_text({"section", z_name, "angle_deg", "dx_um", "dy_um"}, spin));
      write_file_atomically(
          dir / "cylinder.csv",
          csv_text({"section", z_name, "angle_deg", "form_um", "residual_um"}, form));
      write_file_atomically(dir / "sections.csv",
                            csv_text({"section", z_name, "mean_radius_difference_um",
                                      "straightness_u_um", "straightness_v_um", "centre_x_um",
                                      "centre_y_um", "roundness_um", "first_harmonic_valid"},
                                     sections));
    }
    // Harmonics 2..max_harmonic; a lost one (G = 0) has infinite W and Q and lost = 1.
    std::vector<std::vector<double>> tcols(5);
    const double inf = std::numeric_limits<double>::infinity();
    for (std::size_t l = 2; l < t.harmonic.size(); ++l) {
      const bool lost = std::binary_search(first.suppressed.begin(), first.suppressed.end(), t.harmonic[l]);
      tcols[0].push_back(t.harmonic[l]);
      tcols[1].push_back(t.g_abs[l]);
      tcols[2].push_back(lost ? inf : t.w[l]);
      tcols[3].push_back(lost ? inf : t.q[l]);
      tcols[4].push_back(lost ? 1.0 : 0.0);
    }
    write_file_atomically(
        dir / "transfer.csv",
        csv_text({"harmonic", "abs_g", "amplitude_transfer_w", "error_transfer_q", "lost"}, tcols));

    Json summary;
    summary["status"] = degradation.status;
    summary["status_meaning"] =
        degradation.degraded()
            ? "degraded: the probe layout loses harmonics of the evaluated band (2..max_harmonic); "
              "the profile lacks them and the worst error transfer is infinite"
            : "ok: the probe layout sees every harmonic of the evaluated band";
    summary["lost_harmonics"] = {
        {"count", degradation.lost.harmonics.size()},
        {"harmonics", degradation.lost.harmonics},
        {"band", {2, m.max_harmonic}},
        {"lost_share_of_probe_power", degradation.lost.lost_share},
        {"note", "share of the probe signals' power (mean over the probes) in the band at the lost "
                 "harmonics: the form there cannot be told from spindle motion"}};
    summary["method"] = c.method;
    summary["samples_per_rev"] = data.n;
    summary["revolutions"] = data.revolutions;
    summary["revolutions_averaged"] = c.average ? data.revolutions : 1;
    summary["angles_deg"] = c.angles_deg;
    std::vector<double> offsets;
    for (double a : c.angles_deg) offsets.push_back(a * static_cast<double>(data.n) / 360.0);
    summary["offsets_samples"] = offsets;
    summary["layout_angles_deg"] = [&] {
      std::vector<double> a;
      for (double r : m.layout.angles_rad) a.push_back(r / deg);
      return a;
    }();
    summary["weights"] = m.layout.weights;
    summary["max_harmonic"] = m.max_harmonic;
    summary["suppressed_harmonics"] = first.suppressed;
    // Cylinder mode: the largest section roundness (as in results.csv); per section in
    // sections.csv. Peak, valley and mean offset belong to one profile: the first section's.
    summary["roundness_um"] = roundness;
    summary["roundness_reference"] =
        cyl ? "least-squares centre per section, peak-to-valley, largest over the sections"
            : "least-squares centre (first harmonic removed), peak-to-valley";
    summary["peak_um"] = *std::max_element(first.profile.begin(), first.profile.end());
    summary["valley_um"] = *std::min_element(first.profile.begin(), first.profile.end());
    summary["mean_radius_offset_um"] = first.mean_radius_known ? Json(first.mean_radius) : Json();
    summary["first_harmonic_check"] = {{"amplitude_um", first.first_harmonic.amplitude},
                                       {"limit_um", first.first_harmonic.limit},
                                       {"validity_fraction", c.validity_fraction},
                                       {"valid", all_valid}};
    Json transfer = transfer_json(t, degradation, m.max_harmonic);
    summary["transfer"] = transfer;
    if (c.method == "time_recursion") summary["recursion_passes"] = first.recursion_passes;
    if (m.options.fir)
      summary["fir"] = {{"passband_upr", m.options.fir->passband_upr},
                        {"stopband_upr", m.options.fir->stopband_upr},
                        {"taps", m.options.fir->taps.size()},
                        {"design", "Hamming-windowed sinc, symmetric (zero phase), unit DC gain"}};
    Json opt;
    opt["min_harmonic"] = band_lo;
    opt["max_harmonic"] = band_hi;
    opt["max_span_deg"] = c.optimise_max_span_deg;
    opt["layouts_checked"] = best.layouts_checked;
    opt["found"] = best.found;
    if (best.found) {
      std::vector<double> a;  // whole samples: 360 p / N, not a rounded radian value
      for (double r : best.angles_rad)
        a.push_back(std::round(r / (2 * std::numbers::pi) * static_cast<double>(data.n)) * 360.0 /
                    static_cast<double>(data.n));
      opt["angles_deg"] = a;
      opt["worst_error_transfer_q"] = best.worst.q;
      opt["harmonic_of_worst_q"] = best.worst.harmonic;
    }
    const es::WorstTransfer this_worst = es::worst_q(m.layout, band_hi, c.suppression_tolerance, band_lo);
    opt["this_layout_worst_q"] = transfer_factor(this_worst.q);
    opt["this_layout_lost_harmonics"] = this_worst.lost;
    summary["angle_optimisation"] = opt;
    if (cyl) {
      Json cj;
      cj["sections"] = cyl->sections.size();
      cj["cylindricity_um"] = cyl->cylindricity;
      cj["cylindricity_reference"] = "least-squares cylinder, peak-to-valley of the residual";
      cj["ls_radius_offset_um"] = cyl->ls_radius;
      cj["axis"] = {{"x0_um", cyl->axis_x0},
                    {"x_slope_um_per_unit", cyl->axis_x_slope},
                    {"y0_um", cyl->axis_y0},
                    {"y_slope_um_per_unit", cyl->axis_y_slope}};
      cj["max_section_roundness_um"] = roundness;
      summary["cylinder"] = cj;
    }
    summary["warnings"] = warnings;
    if (context.plots) {
      try {
        const std::string title =
            fmt::format("{} ({})", ss::study_title(point_document, "error_separation"), c.method);
        plot_figures(title, m, first, t, degradation, dir);
        if (cyl) plot_cylinder(title, c.section_column, *cyl, dir);
      } catch (const plot::PlotError& e) {
        summary["plot_errors"] = e.what();
      }
    }
    write_json_file(dir / "summary.json", summary);
  }

  std::vector<Json> out{roundness,
                        first.mean_radius_known ? Json(first.mean_radius) : Json(),
                        first.suppressed.size(),
                        transfer_factor(degradation.worst.q),
                        all_valid,
                        degradation.status,
                        100.0 * degradation.lost.lost_share};
  if (cyl) out.emplace_back(cyl->cylindricity);
  return out;
}

void ErrorSeparationKind::write_artifacts(const Study& /*study*/, const ResultTable& /*results*/,
                                          const fs::path& /*out_dir*/) const {
  // Every figure belongs to one point and is drawn by run_point into its artefact directory.
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::ErrorSeparationKind);
