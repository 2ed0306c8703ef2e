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
namespace es = error_separation;
namespace ss = kit;

constexpr double deg = std::numbers::pi / 180.0;
constexpr std::size_t max_probes = 8;
const std::vector<std::string> methods{"frequency", "time_recursion", "two_point", "n_point"};

// ------------------------------------------------------------------ tables, declared once
// [input] scalars (file / files and columns are lists of names, checked by hand), [probes],
// [separation].
struct InputSettings {
  std::optional<std::size_t> samples_per_rev;  // absent: all rows are one revolution
  double unit_um = 1.0;
  bool average_revolutions = true;
  std::optional<std::string> section_column;  // cylindricity mode (E6)
};

const ParamTable<InputSettings>& input_table() {
  static const ParamTable<InputSettings> table = [] {
    ParamTable<InputSettings> t;
    t.add(&InputSettings::samples_per_rev, "samples_per_rev", "1",
          "samples per revolution N (default: all rows are one revolution)")
        .at_least(8);
    t.add(&InputSettings::unit_um, "unit_um", "um",
          "micrometres per unit of the probe data (1 for um, 1000 for mm)")
        .positive();
    t.add(&InputSettings::average_revolutions, "average_revolutions", "",
          "ensemble-average all revolutions (E3); false: the first only");
    t.add(&InputSettings::section_column, "section_column", "",
          "column holding the axial position of each row: cylindricity mode (E6), one block of "
          "whole revolutions per section");
    return t;
  }();
  return table;
}

struct ProbeSettings {
  std::vector<double> angles_deg;
  std::string method = "frequency";
  std::optional<std::vector<double>> weights;  // n_point only
  std::string on_suppressed = "warn";
  int optimise_min_harmonic = 2, optimise_max_harmonic = 50;
  double optimise_max_span_deg = 180.0;
};

const ParamTable<ProbeSettings>& probe_table() {
  static const ParamTable<ProbeSettings> table = [] {
    ParamTable<ProbeSettings> t;
    t.add(&ProbeSettings::angles_deg, "angles_deg", "deg",
          "probe angles phi_q, one per input column, e.g. [0, a, a + b]")
        .at_least(-360.0)
        .at_most(720.0)
        .min_items(2)
        .required();
    t.add(&ProbeSettings::method, "method", "",
          "frequency (E1/E2), time_recursion (E4), two_point or n_point (E5)")
        .choices(methods);
    t.add(&ProbeSettings::weights, "weights", "1",
          "n_point only: probe weights c_q (default: balanced by least squares over the "
          "harmonics)");
    t.add(&ProbeSettings::on_suppressed, "on_suppressed", "",
          "suppressed harmonics in 2..max_harmonic: warn (listed in summary.json) or error (exit "
          "2)")
        .choices({"warn", "error"});
    t.add(&ProbeSettings::optimise_min_harmonic, "optimise_min_harmonic", "1",
          "probe-angle optimisation: lowest harmonic of the band that must be seen")
        .at_least(2)
        .at_most(10000);
    t.add(&ProbeSettings::optimise_max_harmonic, "optimise_max_harmonic", "1",
          "probe-angle optimisation: no suppressed harmonic up to this order")
        .at_least(2)
        .at_most(10000);
    t.add(&ProbeSettings::optimise_max_span_deg, "optimise_max_span_deg", "deg",
          "probe-angle optimisation: largest angle between first and last probe")
        .positive()
        .at_most(360.0);
    return t;
  }();
  return table;
}

struct SeparationSettings {
  std::optional<int> max_harmonic;  // absent: N/2
  double suppression_tolerance = 1e-6, validity_fraction = 0.05;
  double fir_passband_upr = 0.0;
  std::optional<double> fir_stopband_upr;  // absent: 2 x passband
  int max_recursion_passes = 20;
};

const ParamTable<SeparationSettings>& separation_table() {
  static const ParamTable<SeparationSettings> table = [] {
    ParamTable<SeparationSettings> t;
    t.add(&SeparationSettings::max_harmonic, "max_harmonic", "1",
          "highest harmonic kept and checked for suppression (default N/2)")
        .at_least(2);
    t.add(&SeparationSettings::suppression_tolerance, "suppression_tolerance", "1",
          "harmonic l counts as suppressed when |G(l)| <= this x sum |c_q|")
        .positive()
        .at_most(0.1);
    t.add(&SeparationSettings::validity_fraction, "validity_fraction", "1",
          "first-harmonic check: |S_1| must stay below this fraction of the range of S (book: "
          "3-5 %)")
        .positive()
        .at_most(1.0);
    t.add(&SeparationSettings::fir_passband_upr, "fir_passband_upr", "1/rev",
          "zero-phase FIR smoothing: passband edge in undulations per revolution (0: no "
          "smoothing)")
        .non_negative();
    t.add(&SeparationSettings::fir_stopband_upr, "fir_stopband_upr", "1/rev",
          "zero-phase FIR: stopband edge (default 2 x passband)")
        .positive();
    t.add(&SeparationSettings::max_recursion_passes, "max_recursion_passes", "1",
          "time recursion: passes around the revolution before giving up")
        .at_least(1)
        .at_most(1000);
    return t;
  }();
  return table;
}

// ------------------------------------------------------------------ configuration
struct Config {
  std::vector<fs::path> files;  // one, or one per probe
  std::vector<std::string> columns;
  InputSettings input;
  ProbeSettings probes;
  SeparationSettings separation;
};

Config read_config(const Json& document) {
  const Json& input = document.at("input");
  Config c;
  if (input.contains("files"))
    for (const Json& f : input.at("files")) c.files.emplace_back(f.get<std::string>());
  else
    c.files.emplace_back(input.at("file").get<std::string>());
  for (const Json& col : input.at("columns")) c.columns.push_back(col.get<std::string>());
  c.input = input_table().read(input);  // the scalars; file(s) and columns read above
  c.probes = probe_table().read(document.at("probes"));
  c.separation = separation_table().read(document.at("separation"));
  return c;
}

// The section column's name, "" without one (no cylindricity); the n_point weights, empty when
// not given.
std::string section_column_of(const Config& c) { return c.input.section_column.value_or(""); }
std::vector<double> weights_of(const Config& c) {
  return c.probes.weights.value_or(std::vector<double>{});
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
    for (double& v : s) v *= c.input.unit_um;

  // Sections: consecutive rows with the same value of the section column.
  std::vector<std::size_t> starts{0};
  std::vector<double> z{0.0};
  if (!section_column_of(c).empty()) {
    const auto& column =
        ss::column_at(tables[0], section_column_of(c), "input.section_column", sources);
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
          sources.locate("input.section_column").str(), section_column_of(c), z.front()));
  }
  starts.push_back(signals[0].size());

  ProbeData data;
  data.z = z;
  const std::size_t first_rows = starts[1] - starts[0];
  data.n = c.input.samples_per_rev.value_or(first_rows);
  if (data.n < 8)
    throw InputError(fmt::format("{}: input: {} rows per revolution, at least 8 needed",
                                 sources.locate("input").str(), data.n));
  for (std::size_t j = 0; j + 1 < starts.size(); ++j) {
    const std::size_t rows = starts[j + 1] - starts[j];
    if (rows % data.n != 0 || rows == 0) {
      const std::string where = section_column_of(c).empty()
                                    ? std::string("the data have")
                                    : fmt::format("section {} = {} has", section_column_of(c), z[j]);
      throw InputError(fmt::format(
          "{}: input.samples_per_rev = {}: {} {} rows, not a whole number of revolutions (a "
          "multiple of {})",
          sources.locate(c.input.samples_per_rev ? "input.samples_per_rev" : "input").str(), data.n,
          where, rows, data.n));
    }
    if (j > 0 && rows / data.n != data.revolutions)
      throw InputError(fmt::format(
          "{}: input.section_column = \"{}\": sections hold different numbers of revolutions "
          "({} and {})",
          sources.locate("input.section_column").str(), section_column_of(c), data.revolutions,
          rows / data.n));
    data.revolutions = rows / data.n;
    std::vector<std::vector<double>> section;
    for (const auto& s : signals) {
      std::span<const double> block(s.data() + starts[j], c.input.average_revolutions ? rows : data.n);
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

// The probe layout of the method: angles (and weights) checked against what the method needs.
es::ProbeLayout probe_layout(const Config& c, std::size_t n, int max_harmonic,
                             const SourceMap& sources) {
  const std::string angles_where = sources.locate("probes.angles_deg").str();
  const std::string angles_text = fmt::format("[{}]", fmt::join(c.probes.angles_deg, ", "));
  es::ProbeLayout layout;
  auto need = [&](bool ok, const std::string& what) {
    if (!ok)
      throw InputError(fmt::format("{}: probes.angles_deg = {}: {} (method \"{}\")", angles_where,
                                   angles_text, what, c.probes.method));
  };
  std::vector<double> angles;
  for (double a : c.probes.angles_deg) angles.push_back(a * deg);
  try {
    if (c.probes.method == "frequency") {
      need(angles.size() == 3, fmt::format("{} angles; the three-point method takes 3 (use "
                                           "method = \"n_point\" for more)",
                                           angles.size()));
      layout = {angles, es::three_point_weights(angles)};
    } else if (c.probes.method == "time_recursion") {
      need(angles.size() == 3, fmt::format("{} angles; the time recursion takes 3", angles.size()));
      const double samples_per_rad = static_cast<double>(n) / (2 * std::numbers::pi);
      const double p = (angles[1] - angles[0]) * samples_per_rad;
      const double p0 = angles[0] * samples_per_rad;
      const double two_cos = 2.0 * std::cos(angles[1] - angles[0]);
      layout = {angles, {1.0, -two_cos, 1.0}};
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
    } else if (c.probes.method == "two_point") {
      need(angles.size() == 2,
           fmt::format("{} angles; the two-point approximation takes 2", angles.size()));
      const double gap = c.probes.angles_deg[1] - c.probes.angles_deg[0];
      const double want = 180.0 - 360.0 / static_cast<double>(n);
      need(std::abs(gap - want) < 1e-6,
           fmt::format("the two probes must be 180 - 360/N = {} deg apart (N = {}), not {}", want,
                       n, gap));
      layout = es::two_point_layout(angles[0], n);
    } else {  // n_point
      need(angles.size() >= 3,
           fmt::format("{} angles; the n-point method takes at least 3", angles.size()));
      if (!weights_of(c).empty()) {
        if (weights_of(c).size() != angles.size())
          throw InputError(fmt::format("{}: probes.weights: {} weights for {} probes",
                                       sources.locate("probes.weights").str(), weights_of(c).size(),
                                       angles.size()));
        layout = {angles, weights_of(c)};
        const double residual = es::spindle_residual(layout);
        if (!(residual <= 1e-9))
          throw InputError(fmt::format(
              "{}: probes.weights = [{}]: they do not cancel spindle motion (|sum c cos phi|, "
              "|sum c sin phi| = {:.3g} x sum |c|, must be 0)",
              sources.locate("probes.weights").str(), fmt::join(weights_of(c), ", "), residual));
      } else {
        layout = {angles, es::balanced_weights(angles, max_harmonic)};
      }
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(
        fmt::format("{}: probes.angles_deg = {}: {}", angles_where, angles_text, e.what()));
  }
  return layout;
}

Method build_method(const Config& c, std::size_t n, const SourceMap& sources) {
  Method m;
  m.max_harmonic = c.separation.max_harmonic ? *c.separation.max_harmonic : static_cast<int>(n / 2);
  if (m.max_harmonic > static_cast<int>(n / 2))
    throw InputError(fmt::format(
        "{}: separation.max_harmonic = {}: out of range, must be <= N/2 = {} (samples_per_rev {})",
        sources.locate("separation.max_harmonic").str(), m.max_harmonic, n / 2, n));
  m.options.max_harmonic = m.max_harmonic;
  m.options.suppression_tolerance = c.separation.suppression_tolerance;
  m.options.validity_fraction = c.separation.validity_fraction;
  m.options.max_recursion_passes = c.separation.max_recursion_passes;
  if (c.separation.fir_passband_upr > 0) {
    try {
      m.options.fir = es::design_zero_phase_lowpass(
          c.separation.fir_passband_upr, c.separation.fir_stopband_upr.value_or(2 * c.separation.fir_passband_upr), n);
    } catch (const std::invalid_argument& e) {
      throw InputError(fmt::format("{}: separation.fir_passband_upr = {}: {}",
                                   sources.locate("separation.fir_passband_upr").str(),
                                   c.separation.fir_passband_upr, e.what()));
    }
  }

  m.layout = probe_layout(c, n, m.max_harmonic, sources);
  if (c.probes.method != "n_point" && !weights_of(c).empty())
    throw InputError(
        fmt::format("{}: probes.weights: only method = \"n_point\" takes weights "
                    "(this study uses \"{}\")",
                    sources.locate("probes.weights").str(), c.probes.method));
  return m;
}

es::Separation run_method(const Config& c, const Method& m,
                          std::span<const std::vector<double>> probes) {
  if (c.probes.method == "time_recursion") return es::separate_time_recursion(probes, m.layout, m.options);
  if (c.probes.method == "two_point")
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
      fmt::join(c.probes.angles_deg, ", "), harmonic_list(suppressed), top);
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
      fmt::join(c.probes.angles_deg, ", "), harmonic_list(d.lost.harmonics), top, d.lost.harmonics.size(),
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

// What every figure of one separated profile needs (plot_figures draws them one by one).
struct ProfileFigures {
  const std::string& title;
  const Method& m;
  const es::Separation& sep;
  const es::Transfer& t;
  const Degradation& d;
  const fs::path& dir;
  std::size_t n;
  std::vector<double> angle;
  // Every profile figure says what it cannot show: "DEGRADED" in the title, what is lost in the
  // key (the title has no room for it).
  std::string lost_note;
  std::string lost_detail;
};

void figure_profile_linear(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void figure_profile_polar(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void figure_spindle_motion(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
  pl::Curves f;
  f.title = fmt::format("{}: spindle error motion (with the part's eccentricity)", title);
  f.x_label = "angle [deg]";
  f.y_label = "displacement [um]";
  f.series.push_back({"dx", angle, sep.dx, "lines"});
  f.series.push_back({"dy", angle, sep.dy, "lines"});
  pl::render(f, dir, "spindle_motion");
}

void figure_transfer_g(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void figure_transfer_q(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void figure_probe_spectrum(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void figure_suppression_map(const ProfileFigures& in) {
  [[maybe_unused]] const auto& [title, m, sep, t, d, dir, n, angle, lost_note, lost_detail] = in;
  namespace pl = plot;
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
}

void plot_figures(const std::string& title, const Method& m, const es::Separation& sep,
                  const es::Transfer& t, const Degradation& d, const fs::path& dir) {
  const std::size_t n = sep.profile.size();
  const ProfileFigures in{
      title, m, sep, t, d, dir, n, angles_deg_of(n), d.degraded() ? " - DEGRADED" : "",
      d.degraded() ? fmt::format(", without its {} lost harmonics ({:.1f} % of the probe power)",
                                 d.lost.harmonics.size(), 100.0 * d.lost.lost_share)
                   : std::string()};
  std::vector<std::pair<std::string, std::function<void()>>> figures;
  figures.emplace_back("profile_linear", [&] { figure_profile_linear(in); });
  figures.emplace_back("profile_polar", [&] { figure_profile_polar(in); });
  figures.emplace_back("spindle_motion", [&] { figure_spindle_motion(in); });
  figures.emplace_back("transfer_g", [&] { figure_transfer_g(in); });
  figures.emplace_back("transfer_q", [&] { figure_transfer_q(in); });
  figures.emplace_back("probe_spectrum", [&] { figure_probe_spectrum(in); });
  figures.emplace_back("suppression_map", [&] { figure_suppression_map(in); });
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
  return plugin_info("error_separation", "E1, E2, E3, E4, E5, E6",
                     separation_table().specs(),
                     {{"max_harmonic", 64}, {"fir_passband_upr", 32.0}},
                     "roundness and spindle error motion from 2-8 probes by error separation (three-point, time "
                     "recursion, n-point, two-point), cylindricity with a section column");
}

void ErrorSeparationKind::validate(Json& document, const SourceMap& sources) const {
  // [input]: file / files and columns by hand (lists of strings), the rest by spec.
  Json input = ss::table_or_empty(document, "input", sources);
  ss::integer_columns_as_names(input, {"columns", "section_column"});
  std::vector<std::string> input_keys{"file", "files", "columns"};
  for (const ParamSpec& s : input_table().specs()) input_keys.push_back(s.key);
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
  scalars = validate_params(scalars, input_table().specs(), "input", sources);
  for (auto& [k, v] : scalars.items()) input[k] = v;

  Json probes = validate_params(ss::table_or_empty(document, "probes", sources), probe_table().specs(),
                                "probes", sources);
  Json separation = validate_params(ss::table_or_empty(document, "separation", sources),
                                    separation_table().specs(), "separation", sources);
  document["input"] = input;
  document["probes"] = probes;
  document["separation"] = separation;

  const Config c = read_config(document);
  if (c.probes.angles_deg.size() != c.columns.size())
    throw InputError(fmt::format("{}: probes.angles_deg = [{}]: {} angles for {} input.columns",
                                 sources.locate("probes.angles_deg").str(),
                                 fmt::join(c.probes.angles_deg, ", "), c.probes.angles_deg.size(),
                                 c.columns.size()));
  const ProbeData data = load_probe_data(c, sources);
  const Method m = build_method(c, data.n, sources);
  const auto suppressed =
      es::suppressed_harmonics(m.layout, m.max_harmonic, c.separation.suppression_tolerance);
  if (!suppressed.empty() && c.probes.on_suppressed == "error")
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

namespace {

// Everything one point computes: the files, summary.json and the result row are drawn from it.
struct SeparatedPoint {
  Config c;
  ProbeData data;
  Method m;
  es::Transfer t;
  std::optional<es::Cylinder> cyl;  // cylindricity mode (section column)
  es::Separation first;             // the (first section's) separation
  int band_lo = 0, band_hi = 0;     // probe-angle optimisation band
  es::AngleOptimum best;
  Degradation degradation;
  std::vector<std::string> warnings;
  bool all_valid = true;  // every section passed the first-harmonic check
  double roundness = 0.0;  // largest over the sections
};

// The separation of every section (a cylinder with a section column, else one profile); a
// failure of the method is this point's failure.
void separate_sections(SeparatedPoint& p) {
  auto separate = [&](std::span<const std::vector<double>> probes) {
    try {
      return run_method(p.c, p.m, probes);
    } catch (const std::exception& e) {
      throw PointFailure(e.what());
    }
  };
  if (!section_column_of(p.c).empty()) {
    try {
      p.cyl = es::reconstruct_cylinder(p.data.sections, p.data.z, separate);
    } catch (const std::invalid_argument& e) {
      throw PointFailure(e.what());
    }
    p.first = p.cyl->sections.front().separation;
  } else {
    p.first = separate(p.data.sections.front());
  }
}

// Optimal probe angles for this N and the band (E2), proposed where this layout loses
// harmonics; degraded when the layout loses harmonics of the evaluated band 2..max_harmonic.
void rate_layout(SeparatedPoint& p) {
  const Config& c = p.c;
  p.band_hi = std::min(c.probes.optimise_max_harmonic, static_cast<int>(p.data.n / 2));
  p.band_lo = std::min(c.probes.optimise_min_harmonic, p.band_hi);
  p.best = es::optimise_three_point_angles(p.data.n, p.band_hi, c.probes.optimise_max_span_deg * deg,
                                           c.separation.suppression_tolerance, p.band_lo);
  p.degradation.worst = es::worst_q(p.m.layout, p.m.max_harmonic, c.separation.suppression_tolerance);
  p.degradation.lost =
      es::lost_spectrum(p.data.sections.front(), p.first.suppressed, 2, p.m.max_harmonic);
  if (!p.first.suppressed.empty()) p.degradation.status = "degraded";
  if (p.degradation.degraded())
    p.warnings.push_back(
        degradation_message(c, p.degradation, p.m.max_harmonic, p.best, p.band_lo, p.band_hi));
}

// The first-harmonic check of every section, and the roundness (largest over the sections).
void check_sections(SeparatedPoint& p) {
  std::vector<const es::Separation*> seps;
  if (p.cyl)
    for (const auto& s : p.cyl->sections) seps.push_back(&s.separation);
  else
    seps.push_back(&p.first);
  for (std::size_t j = 0; j < seps.size(); ++j)
    if (!seps[j]->first_harmonic.valid) {
      p.all_valid = false;
      p.warnings.push_back(fmt::format(
          "first-harmonic check failed{}: |S_1| = {:.4g} um > {:.4g} um ({} of the range of S): "
          "the signals do not fit the probe angles (misalignment, unsynchronised sampling, drift)",
          p.cyl ? fmt::format(" in section z = {}", p.data.z[j]) : std::string(),
          seps[j]->first_harmonic.amplitude, seps[j]->first_harmonic.limit,
          p.c.separation.validity_fraction));
    }
  for (const auto& w : p.warnings) ss::warn(w);
  for (const auto* s : seps) p.roundness = std::max(p.roundness, s->roundness());
}

SeparatedPoint compute_point(const Json& point_document) {
  const SourceMap& sources = ss::no_sources();  // validated already: no line numbers needed
  SeparatedPoint p;
  p.c = read_config(point_document);
  p.data = load_probe_data(p.c, sources);
  p.m = build_method(p.c, p.data.n, sources);
  p.t = es::transfer(p.m.layout, p.m.max_harmonic);
  separate_sections(p);
  rate_layout(p);
  check_sections(p);
  return p;
}

// cylinder mode: profile.csv, spindle.csv, cylinder.csv (form and residual) per section and
// angle, sections.csv one row per section.
void write_cylinder_csvs(const SeparatedPoint& p, const std::vector<double>& angle, const fs::path& dir) {
  const es::Cylinder& cyl = *p.cyl;
  std::vector<std::vector<double>> prof(4), spin(5), form(5), sections(9);
  for (std::size_t j = 0; j < cyl.sections.size(); ++j) {
    const auto& s = cyl.sections[j];
    for (std::size_t i = 0; i < p.data.n; ++i) {
      for (auto* v : {&prof, &spin, &form}) {
        (*v)[0].push_back(static_cast<double>(j));
        (*v)[1].push_back(s.z);
        (*v)[2].push_back(angle[i]);
      }
      prof[3].push_back(s.separation.profile[i]);
      spin[3].push_back(s.separation.dx[i]);
      spin[4].push_back(s.separation.dy[i]);
      form[3].push_back(cyl.form[j][i]);
      form[4].push_back(cyl.residual[j][i]);
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
  const std::string z_name = section_column_of(p.c);
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

// profile.csv and spindle.csv (or the cylinder's files) and transfer.csv: harmonics
// 2..max_harmonic; a lost one (G = 0) has infinite W and Q and lost = 1.
void write_csvs(const SeparatedPoint& p, const fs::path& dir) {
  const std::vector<double> angle = angles_deg_of(p.data.n);
  if (!p.cyl) {
    write_file_atomically(dir / "profile.csv",
                          csv_text({"angle_deg", "deviation_um"}, {angle, p.first.profile}));
    write_file_atomically(dir / "spindle.csv", csv_text({"angle_deg", "dx_um", "dy_um"},
                                                        {angle, p.first.dx, p.first.dy}));
  } else {
    write_cylinder_csvs(p, angle, dir);
  }
  const es::Transfer& t = p.t;
  std::vector<std::vector<double>> tcols(5);
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t l = 2; l < t.harmonic.size(); ++l) {
    const bool lost =
        std::binary_search(p.first.suppressed.begin(), p.first.suppressed.end(), t.harmonic[l]);
    tcols[0].push_back(t.harmonic[l]);
    tcols[1].push_back(t.g_abs[l]);
    tcols[2].push_back(lost ? inf : t.w[l]);
    tcols[3].push_back(lost ? inf : t.q[l]);
    tcols[4].push_back(lost ? 1.0 : 0.0);
  }
  write_file_atomically(
      dir / "transfer.csv",
      csv_text({"harmonic", "abs_g", "amplitude_transfer_w", "error_transfer_q", "lost"}, tcols));
}

// summary.json, first part: status, lost harmonics, method and the probe layout.
void add_layout_summary(const SeparatedPoint& p, Json& summary) {
  const Degradation& degradation = p.degradation;
  summary["status"] = degradation.status;
  summary["status_meaning"] =
      degradation.degraded()
          ? "degraded: the probe layout loses harmonics of the evaluated band (2..max_harmonic); "
            "the profile lacks them and the worst error transfer is infinite"
          : "ok: the probe layout sees every harmonic of the evaluated band";
  summary["lost_harmonics"] = {
      {"count", degradation.lost.harmonics.size()},
      {"harmonics", degradation.lost.harmonics},
      {"band", {2, p.m.max_harmonic}},
      {"lost_share_of_probe_power", degradation.lost.lost_share},
      {"note", "share of the probe signals' power (mean over the probes) in the band at the lost "
               "harmonics: the form there cannot be told from spindle motion"}};
  summary["method"] = p.c.probes.method;
  summary["samples_per_rev"] = p.data.n;
  summary["revolutions"] = p.data.revolutions;
  summary["revolutions_averaged"] = p.c.input.average_revolutions ? p.data.revolutions : 1;
  summary["angles_deg"] = p.c.probes.angles_deg;
  std::vector<double> offsets;
  for (double a : p.c.probes.angles_deg) offsets.push_back(a * static_cast<double>(p.data.n) / 360.0);
  summary["offsets_samples"] = offsets;
  std::vector<double> layout_angles;
  for (double r : p.m.layout.angles_rad) layout_angles.push_back(r / deg);
  summary["layout_angles_deg"] = layout_angles;
  summary["weights"] = p.m.layout.weights;
  summary["max_harmonic"] = p.m.max_harmonic;
  summary["suppressed_harmonics"] = p.first.suppressed;
}

// summary.json, second part: roundness, first-harmonic check, transfer, recursion and FIR.
void add_result_summary(const SeparatedPoint& p, Json& summary) {
  const es::Separation& first = p.first;
  // Cylinder mode: the largest section roundness (as in results.csv); per section in
  // sections.csv. Peak, valley and mean offset belong to one profile: the first section's.
  summary["roundness_um"] = p.roundness;
  summary["roundness_reference"] =
      p.cyl ? "least-squares centre per section, peak-to-valley, largest over the sections"
            : "least-squares centre (first harmonic removed), peak-to-valley";
  summary["peak_um"] = *std::max_element(first.profile.begin(), first.profile.end());
  summary["valley_um"] = *std::min_element(first.profile.begin(), first.profile.end());
  summary["mean_radius_offset_um"] = first.mean_radius_known ? Json(first.mean_radius) : Json();
  summary["first_harmonic_check"] = {{"amplitude_um", first.first_harmonic.amplitude},
                                     {"limit_um", first.first_harmonic.limit},
                                     {"validity_fraction", p.c.separation.validity_fraction},
                                     {"valid", p.all_valid}};
  summary["transfer"] = transfer_json(p.t, p.degradation, p.m.max_harmonic);
  if (p.c.probes.method == "time_recursion") summary["recursion_passes"] = first.recursion_passes;
  if (p.m.options.fir)
    summary["fir"] = {{"passband_upr", p.m.options.fir->passband_upr},
                      {"stopband_upr", p.m.options.fir->stopband_upr},
                      {"taps", p.m.options.fir->taps.size()},
                      {"design", "Hamming-windowed sinc, symmetric (zero phase), unit DC gain"}};
}

// summary.json's angle_optimisation: the best three-probe layout for the band, and this one's.
Json angle_optimisation_json(const SeparatedPoint& p) {
  Json opt;
  opt["min_harmonic"] = p.band_lo;
  opt["max_harmonic"] = p.band_hi;
  opt["max_span_deg"] = p.c.probes.optimise_max_span_deg;
  opt["layouts_checked"] = p.best.layouts_checked;
  opt["found"] = p.best.found;
  if (p.best.found) {
    std::vector<double> a;  // whole samples: 360 p / N, not a rounded radian value
    for (double r : p.best.angles_rad)
      a.push_back(std::round(r / (2 * std::numbers::pi) * static_cast<double>(p.data.n)) * 360.0 /
                  static_cast<double>(p.data.n));
    opt["angles_deg"] = a;
    opt["worst_error_transfer_q"] = p.best.worst.q;
    opt["harmonic_of_worst_q"] = p.best.worst.harmonic;
  }
  const es::WorstTransfer this_worst =
      es::worst_q(p.m.layout, p.band_hi, p.c.separation.suppression_tolerance, p.band_lo);
  opt["this_layout_worst_q"] = transfer_factor(this_worst.q);
  opt["this_layout_lost_harmonics"] = this_worst.lost;
  return opt;
}

Json cylinder_json(const es::Cylinder& cyl, double max_section_roundness) {
  Json cj;
  cj["sections"] = cyl.sections.size();
  cj["cylindricity_um"] = cyl.cylindricity;
  cj["cylindricity_reference"] = "least-squares cylinder, peak-to-valley of the residual";
  cj["ls_radius_offset_um"] = cyl.ls_radius;
  cj["axis"] = {{"x0_um", cyl.axis_x0},
                {"x_slope_um_per_unit", cyl.axis_x_slope},
                {"y0_um", cyl.axis_y0},
                {"y_slope_um_per_unit", cyl.axis_y_slope}};
  cj["max_section_roundness_um"] = max_section_roundness;
  return cj;
}

// The point's files: CSVs, figures (failures recorded in summary.json) and summary.json.
void write_point_files(const Json& point_document, const SeparatedPoint& p, const PointContext& context) {
  const fs::path dir = context.artifact_dir;
  write_csvs(p, dir);
  Json summary;
  add_layout_summary(p, summary);
  add_result_summary(p, summary);
  summary["angle_optimisation"] = angle_optimisation_json(p);
  if (p.cyl) summary["cylinder"] = cylinder_json(*p.cyl, p.roundness);
  summary["warnings"] = p.warnings;
  if (context.plots) {
    try {
      const std::string title = fmt::format(
          "{} ({})", ss::study_title(point_document, "error_separation"), p.c.probes.method);
      plot_figures(title, p.m, p.first, p.t, p.degradation, dir);
      if (p.cyl) plot_cylinder(title, section_column_of(p.c), *p.cyl, dir);
    } catch (const plot::PlotError& e) {
      summary["plot_errors"] = e.what();
    }
  }
  write_json_file(dir / "summary.json", summary);
}

}  // namespace

std::vector<Json> ErrorSeparationKind::run_point(const Json& point_document,
                                                 const PointContext& context) const {
  const SeparatedPoint p = compute_point(point_document);
  if (!context.artifact_dir.empty()) write_point_files(point_document, p, context);
  std::vector<Json> out{p.roundness,
                        p.first.mean_radius_known ? Json(p.first.mean_radius) : Json(),
                        p.first.suppressed.size(),
                        transfer_factor(p.degradation.worst.q),
                        p.all_valid,
                        p.degradation.status,
                        100.0 * p.degradation.lost.lost_share};
  if (p.cyl) out.emplace_back(p.cyl->cylindricity);
  return out;
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::ErrorSeparationKind);
