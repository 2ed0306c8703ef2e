#include "shared/metrology/surface_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <span>

#include "chatterlab/errors.hpp"
#include "chatterlab/fft.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/plot.hpp"
#include "shared/metrology/waviness.hpp"

namespace chatterlab::surface {

namespace fs = std::filesystem;

namespace {

ParamSpec optional_spec(std::string key, ValueKind kind, std::string unit, std::string what) {
  ParamSpec s = param_spec(std::move(key), kind, std::move(unit), std::move(what));
  s.optional = true;
  return s;
}

ParamSpec positive(ParamSpec s) {
  s.min = 0.0;
  s.min_exclusive = true;
  return s;
}

}  // namespace

ParamSpec unit_spec() {
  ParamSpec unit = param_spec("unit", ValueKind::string, "1",
                              "unit of the profile values: um (default), mm or m");
  unit.default_value = "um";
  unit.choices = {"um", "mm", "m"};
  return unit;
}

std::vector<ParamSpec> input_specs() {
  ParamSpec file = param_spec("file", ValueKind::string, "1",
                              "profile data file (CSV/whitespace table or WAV), relative to the "
                              "study file");
  ParamSpec closed = param_spec("closed", ValueKind::boolean, "1",
                                "true: one revolution of a circumferential profile (periodic)");
  closed.default_value = false;
  const ParamSpec unit = unit_spec();
  ParamSpec per_rev = optional_spec("samples_per_rev", ValueKind::integer, "1",
                                    "closed profiles: samples in one revolution (= rows)");
  per_rev.min = 4;
  return {file,
          optional_spec("column", ValueKind::string, "1",
                        "profile column (header name or 1-based index); default: the only "
                        "column besides x_column"),
          optional_spec("x_column", ValueKind::string, "mm",
                        "open profiles: column of positions in mm (must be uniformly spaced)"),
          positive(optional_spec("spacing_mm", ValueKind::real, "mm",
                                 "open profiles: sample spacing")),
          per_rev,
          closed,
          unit};
}

std::vector<ParamSpec> filter_specs() {
  ParamSpec type = param_spec("type", ValueKind::string, "1",
                              "gaussian (ISO 16610-21) or robust_gaussian (ISO 16610-31)");
  type.default_value = "gaussian";
  type.choices = {"gaussian", "robust_gaussian"};
  ParamSpec iterations = param_spec("max_iterations", ValueKind::integer, "1",
                                    "robust_gaussian: most reweighting passes");
  iterations.default_value = 50;
  iterations.min = 1;
  iterations.max = 1000;
  return {type,
          positive(optional_spec("cutoff_mm", ValueKind::real, "mm",
                                 "open profiles: cut-off wavelength lambda_c")),
          positive(optional_spec("cutoff_upr", ValueKind::real, "1/rev",
                                 "closed profiles: cut-off in undulations per revolution "
                                 "(default 50; ISO 12181-2 uses 15, 50, 150, 500)")),
          iterations};
}

std::vector<ParamSpec> process_specs() {
  ParamSpec low = optional_spec("low_band_upr", ValueKind::real_list, "1/rev",
                                "Wz|f low band [from, to] (default around Z = n_g / n_w)");
  low.min_items = 2;
  low.min = 0;
  ParamSpec high = optional_spec("high_band_upr", ValueKind::real_list, "1/rev",
                                 "Wz|f high band [from, to] (default: above the low band)");
  high.min_items = 2;
  high.min = 0;
  return {positive(optional_spec("wheel_speed_rpm", ValueKind::real, "rpm",
                                 "wheel speed n_g (with work_speed_rpm: Wz|f bands)")),
          positive(optional_spec("work_speed_rpm", ValueKind::real, "rpm", "work speed n_w")),
          low, high};
}

std::vector<ParamSpec> parameter_specs() {
  ParamSpec lengths = param_spec("sampling_lengths", ValueKind::integer, "1",
                                 "W parameters averaged over this many equal sampling lengths");
  lengths.default_value = 1;
  lengths.min = 1;
  ParamSpec a = positive(param_spec("motif_a_mm", ValueKind::real, "mm",
                                    "ISO 12085 limit A of roughness motifs"));
  a.default_value = 0.5;
  ParamSpec b = positive(param_spec("motif_b_mm", ValueKind::real, "mm",
                                    "ISO 12085 limit B of waviness motifs"));
  b.default_value = 2.5;
  return {lengths, a, b};
}

Json validated_table(const Json& document, const std::string& name,
                     const std::vector<ParamSpec>& specs, const SourceMap& sources) {
  Json table = document.contains(name) ? document.at(name) : Json::object();
  if (!table.is_object())
    throw InputError(fmt::format("{}: {} = {}: expected a table [{}]",
                                 sources.locate(name).str(), name, table.dump(), name));
  return validate_params(table, specs, name, sources);
}

double unit_to_um(const std::string& unit) {
  if (unit == "mm") return 1e3;
  if (unit == "m") return 1e6;
  return 1.0;
}

// The profile column's name: as given, or the only column that is not the x column.
std::string profile_column(const Json& input, const DataTable& table, const SourceMap* sources) {
  if (input["column"].is_string()) return input["column"].get<std::string>();
  std::vector<std::string> candidates;
  for (const auto& name : table.names)
    if (!input["x_column"].is_string() || name != input["x_column"].get<std::string>())
      candidates.push_back(name);
  if (candidates.size() == 1) return candidates.front();
  std::string list;
  for (const auto& name : table.names) list += (list.empty() ? "" : ", ") + name;
  throw InputError(fmt::format("{}: missing key 'input.column': {} has {} columns ({}); name the "
                               "profile column",
                               sources ? sources->locate("input").str() : std::string("input"),
                               table.file.string(), table.names.size(), list));
}

SampledSeries series_from(const Json& input, const DataTable& table, const std::string& column) {
  SampledSeries s;
  s.values = table.column(column);  // a view: valid while `table` lives
  s.closed = input["closed"].get<bool>();
  s.name = column;
  if (s.closed) {
    s.sample_unit = "deg";
    s.sample_interval = 360.0 / static_cast<double>(s.values.size());
  } else {
    s.sample_unit = "mm";
    if (input["spacing_mm"].is_number()) {
      s.sample_interval = input["spacing_mm"].get<double>();
    } else {
      const auto& x = table.column(input["x_column"].get<std::string>());
      s.sample_interval = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
    }
  }
  return s;
}

// `rows`: the profile's samples; for a closed profile given with spacing_mm (circumferential
// spacing) and cutoff_mm, the cut-off becomes cutoff_upr = circumference / cutoff_mm.
SurfaceSettings settings_from(const Json& document, std::size_t rows) {
  const Json& input = document.at("input");
  const Json& filter = document.at("filter");
  const Json& process = document.at("process");
  const Json& parameters = document.at("parameters");
  SurfaceSettings s;
  s.filter = filter["type"] == "robust_gaussian" ? FilterType::robust_gaussian
                                                  : FilterType::gaussian;
  if (filter["cutoff_mm"].is_number()) s.cutoff_mm = filter["cutoff_mm"].get<double>();
  if (filter["cutoff_upr"].is_number()) s.cutoff_upr = filter["cutoff_upr"].get<double>();
  s.max_iterations = filter["max_iterations"].get<int>();
  s.value_to_um = unit_to_um(input["unit"].get<std::string>());
  s.sampling_lengths = parameters["sampling_lengths"].get<int>();
  s.motif_a_mm = parameters["motif_a_mm"].get<double>();
  s.motif_b_mm = parameters["motif_b_mm"].get<double>();
  if (process["wheel_speed_rpm"].is_number())
    s.wheel_speed_rpm = process["wheel_speed_rpm"].get<double>();
  if (process["work_speed_rpm"].is_number())
    s.work_speed_rpm = process["work_speed_rpm"].get<double>();
  auto band = [&](const char* key) -> std::optional<std::pair<double, double>> {
    if (!process[key].is_array()) return std::nullopt;
    return std::pair{process[key][0].get<double>(), process[key][1].get<double>()};
  };
  s.low_band_upr = band("low_band_upr");
  s.high_band_upr = band("high_band_upr");
  // value()/contains(): operator[] on a const JSON object is undefined for a missing key, and the
  // analysis plugin's document carries no `closed`/`spacing_mm`.
  if (input.value("closed", false) && s.cutoff_mm && input.contains("spacing_mm") &&
      input["spacing_mm"].is_number() && rows > 0) {
    s.cutoff_upr = static_cast<double>(rows) * input["spacing_mm"].get<double>() / *s.cutoff_mm;
    s.cutoff_mm.reset();
  }
  return s;
}

// Uniform spacing of an x column: every step within 0.1 % of the mean step (and increasing).
void check_uniform(const DataTable& table, const std::string& x_column, const SourceMap& sources) {
  const auto& x = table.column(x_column);
  if (x.size() < 2) return;
  const double mean = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double step = x[i + 1] - x[i];
    if (!(mean > 0) || std::abs(step - mean) > 1e-3 * mean) {
      const std::size_t line = table.source_line(i + 1) != 0 ? table.source_line(i + 1) : i + 2;
      throw InputError(fmt::format(
          "{}: input.x_column = \"{}\": non-uniform spacing in {} at line {}: step {} mm differs "
          "from the mean spacing {} mm by more than 0.1 % (resample the profile uniformly)",
          sources.locate("input.x_column").str(), x_column, table.file.string(), line, step,
          mean));
    }
  }
}

// ---------------------------------------------------------------- outputs

void plot_profiles(const SurfaceEvaluation& e, bool closed, const std::string& title,
                   const fs::path& dir) {
  // Min/max per bucket (kit::decimated), so a short wave or a spike in a long profile stays
  // visible; at most ~20,000 points per curve.
  const std::size_t n = e.samples(), buckets = 10000;
  const auto x_at = [&](std::size_t i) { return e.position(i); };
  const std::string x_label = closed ? "angle [deg]" : "x [mm]";
  plot::Curves profile;
  profile.title = title + ": profile and waviness (filter mean line)";
  profile.x_label = x_label;
  profile.y_label = "height [um]";
  profile.series.push_back(kit::decimated("profile", n, x_at, [&](std::size_t i) { return e.profile_um[i]; }, buckets));
  const Json& filter = e.summary.at("filter");
  const std::string cutoff = filter.contains("cutoff_upr")
                                 ? fmt::format("{} UPR", filter["cutoff_upr"].get<double>())
                                 : fmt::format("lc = {} mm", filter["cutoff_mm"].get<double>());
  profile.series.push_back(kit::decimated(fmt::format("waviness ({} filter, {})", filter["type"].get<std::string>(), cutoff),
                                          n, x_at, [&](std::size_t i) { return e.waviness_um[i]; }, buckets));
  plot::render(profile, dir, "profile");
  plot::Curves roughness;
  roughness.title = title + ": roughness (profile - waviness)";
  roughness.x_label = x_label;
  roughness.y_label = "roughness [um]";
  roughness.series.push_back(kit::decimated("roughness", n, x_at, [&](std::size_t i) { return e.roughness_um(i); }, buckets));
  roughness.reference_y = 0.0;
  roughness.reference_label = "mean line";
  plot::render(roughness, dir, "roughness");
}

// Polar plot of the waviness about the least-squares centre (eccentricity removed, as roundness
// instruments draw it), magnified onto a base circle of twice the LS peak-to-valley, with the
// four reference circles (limacons relative to the LS circle) in the same scale.
void plot_polar(const SurfaceEvaluation& e, const std::string& title, const fs::path& dir,
                const std::string& stem) {
  const Json& rd = e.summary.at("roundness");
  const Json& ls = rd.at("least_squares");
  const double base = std::max(2.0 * ls.at("RONt_um").get<double>(), 1e-9);
  auto limacon = [](const Json& c, double th) {
    return c.at("radius_offset_um").get<double>() + c.at("centre_x_um").get<double>() * std::cos(th) +
           c.at("centre_y_um").get<double>() * std::sin(th);
  };
  const std::size_t n = e.waviness_um.size(), stride = std::max<std::size_t>(1, n / 4000);
  plot::Curves polar;
  polar.title = fmt::format("{}: roundness about the LS centre (base circle {:.3g} um)", title, base);
  polar.x_label = "x [um]";
  polar.y_label = "y [um]";
  polar.equal_aspect = true;  // a round part must look round
  plot::Series profile{"waviness", {}, {}, "lines"};
  for (std::size_t i = 0; i <= n; i += stride) {
    const std::size_t k = i % n;
    const double th = e.position(k) * std::numbers::pi / 180.0;
    const double rho = base + e.waviness_um[k] - limacon(ls, th);
    profile.x.push_back(rho * std::cos(th));
    profile.y.push_back(rho * std::sin(th));
  }
  polar.series.push_back(std::move(profile));
  auto circle_points = [&](plot::Series& series, const Json& c, double offset_um) {
    for (int k = 0; k <= 360; ++k) {
      const double th = k * std::numbers::pi / 180.0;
      const double rho = base + limacon(c, th) + offset_um - limacon(ls, th);
      series.x.push_back(rho * std::cos(th));
      series.y.push_back(rho * std::sin(th));
    }
  };
  for (const char* name : {"minimum_circumscribed", "maximum_inscribed", "least_squares"}) {
    const Json& c = rd.at(name);
    const bool dashed = std::string_view(name) == "least_squares";
    plot::Series circle{fmt::format("{} (RONt {:.3g} um)", name, c.at("RONt_um").get<double>()),
                        {}, {}, dashed ? "dashes" : "lines"};
    circle_points(circle, c, 0.0);
    polar.series.push_back(std::move(circle));
  }
  // The minimum zone is two concentric circles (its centre, radii R -+ RONt/2) holding the whole
  // profile between them: one series (a NaN breaks the line between the two), drawn last and
  // dashed because the circumscribed and inscribed circles often lie almost on them.
  const Json& mz = rd.at("minimum_zone");
  const double half = 0.5 * mz.at("RONt_um").get<double>();
  plot::Series zone{fmt::format("minimum zone: two circles {:.3g} um apart (RONt)", 2 * half), {}, {},
                    "dashes"};
  circle_points(zone, mz, half);
  zone.x.push_back(std::nan(""));
  zone.y.push_back(std::nan(""));
  circle_points(zone, mz, -half);
  polar.series.push_back(std::move(zone));
  plot::render(polar, dir, stem);
}

// Amplitude per UPR of the profile with the Wz|f bands marked.
void plot_bands(const SurfaceEvaluation& e, const std::string& title, const fs::path& dir,
                const std::string& stem) {
  const Json& wzf = e.summary.at("Wz_f");
  const std::size_t n = e.profile_um.size();
  InPlaceRealFft fft(e.profile_um);  // one buffer: 8 bytes per sample of a long profile
  fft.forward();
  const std::span<const std::complex<double>> spectrum = fft.spectrum();
  plot::Curves bands;
  bands.title = fmt::format("{}: Wz|f low {:.3g} um, high {:.3g} um", title,
                            wzf["low"]["Wz_um"].get<double>(), wzf["high"]["Wz_um"].get<double>());
  bands.x_label = "undulations per revolution [UPR]";
  bands.y_label = "amplitude [um]";
  bands.log_x = true;
  plot::Series low{"low band (forced lobes)", {}, {}, "impulses"},
      high{"high band (chatter)", {}, {}, "impulses"}, other{"outside the bands", {}, {}, "impulses"};
  // A long closed profile has millions of spectral lines: on the log UPR axis each of ~4000
  // log-spaced bins is drawn as its largest line (what an impulse plot shows there anyway), so
  // the plot's size is bounded whatever the profile's; below ~270 UPR every line is its own bin.
  const std::size_t k_end = spectrum.size();
  const double bins_per_e = 4000.0 / std::log(std::max(3.0, static_cast<double>(k_end) / 2.0));
  auto bin_of = [&](std::size_t k) {
    return static_cast<long long>(std::floor(std::log(static_cast<double>(k) / 2.0) * bins_per_e));
  };
  struct Peak {
    plot::Series* series = nullptr;
    long long bin = -1;
    double upr = 0.0, amplitude = -1.0;
  } peak;
  auto flush = [&] {
    if (peak.series == nullptr) return;
    peak.series->x.push_back(peak.upr);
    peak.series->y.push_back(peak.amplitude);
    peak = Peak{};
  };
  for (std::size_t k = 2; k < k_end; ++k) {
    const double upr = static_cast<double>(k);
    const double amplitude = (2 * k == n ? 1.0 : 2.0) * std::abs(spectrum[k]) / static_cast<double>(n);
    plot::Series& target =
        upr >= wzf["low"]["from_upr"].get<double>() && upr <= wzf["low"]["to_upr"].get<double>()
            ? low
            : (upr >= wzf["high"]["from_upr"].get<double>() &&
                       upr <= wzf["high"]["to_upr"].get<double>()
                   ? high
                   : other);
    const long long bin = bin_of(k);
    if (peak.series != &target || peak.bin != bin) flush();
    if (amplitude > peak.amplitude) {
      peak.series = &target;
      peak.bin = bin;
      peak.upr = upr;
      peak.amplitude = amplitude;
    }
  }
  flush();
  for (auto* s : {&low, &high, &other})
    if (!s->x.empty()) bands.series.push_back(std::move(*s));
  plot::render(bands, dir, stem);
}

}  // namespace chatterlab::surface
