#include "kinds/simulate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "chatterlab/analysis.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/fit_validity.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/spectrum.hpp"
#include "chatterlab/time_series_file.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;

constexpr const char* col_growth = "fitted_growth_rate_per_s";
constexpr const char* col_frequency = "dominant_frequency_hz";
constexpr const char* col_max_displacement = "max_displacement_m";
constexpr const char* col_contact_loss = "contact_loss_fraction";
constexpr const char* col_outcome = "simulation_outcome";
constexpr const char* col_fit_valid = "fit_valid";
constexpr const char* col_fit_regime = "fit_regime";
constexpr const char* col_fit_reason = "fit_reason";
constexpr const char* col_work_wt = "work_waviness_wt_um";
constexpr const char* col_work_wz = "work_waviness_wz_um";
constexpr const char* col_work_ront = "work_roundness_ront_um";
// Part quality (issue 7 part 6): the final work surface is evaluated by the surface metrology's
// analysis plugin, reached through the registry (the framework does not link plugin code).
constexpr const char* surface_plugin = "surface_profile";
constexpr std::size_t max_peaks = 10;

using kit::build_model;

ParamSpec real_spec(std::string key, std::string unit, std::string description, double default_value,
                    double min, bool min_exclusive) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.default_value = default_value;
  spec.min = min;
  spec.min_exclusive = min_exclusive;
  return spec;
}

ParamSpec optional_real(std::string key, std::string unit, std::string description) {
  ParamSpec spec = param_spec(std::move(key), ValueKind::real, std::move(unit), std::move(description));
  spec.optional = true;
  spec.min = 0.0;
  return spec;
}

// The speed-law keys of one rotor: <rotor>_speed_modulation, _amplitude_ratio, _frequency_hz,
// _schedule.
std::vector<ParamSpec> speed_specs(const std::string& rotor) {
  ParamSpec shape = param_spec(rotor + "_speed_modulation", ValueKind::string, "",
                               "speed law of the " + rotor +
                                   " around the model's speed: constant, sinusoidal, triangular, "
                                   "square, or schedule (" + rotor + "_speed_schedule)");
  shape.default_value = "constant";
  shape.choices = {"constant", "sinusoidal", "triangular", "square", "schedule"};
  ParamSpec amplitude = real_spec(rotor + "_speed_amplitude_ratio", "1",
                                  "modulation amplitude over the mean speed (< 1: the spindle never "
                                  "stops or reverses)", 0.0, 0.0, false);
  amplitude.max = 1.0;
  amplitude.max_exclusive = true;
  ParamSpec frequency = real_spec(rotor + "_speed_frequency_hz", "Hz", "modulation frequency", 0.0, 0.0, false);
  ParamSpec schedule = param_spec(rotor + "_speed_schedule", ValueKind::real_matrix, "s, rpm",
                                  "rows [t_s, rpm]: piecewise-linear speed from t = 0, held after "
                                  "the last row (with modulation = \"schedule\")");
  schedule.optional = true;
  return {shape, amplitude, frequency, schedule};
}

std::shared_ptr<const SpeedLaw> speed_law(const Json& sim, const std::string& rotor, double mean_rpm) {
  const std::string shape = sim.at(rotor + "_speed_modulation").get<std::string>();
  if (shape == "schedule") {
    std::vector<double> times, rpm;
    for (const Json& row : sim.at(rotor + "_speed_schedule")) {
      times.push_back(row.at(0).get<double>());
      rpm.push_back(row.at(1).get<double>());
    }
    return make_scheduled_speed(std::move(times), std::move(rpm));
  }
  return make_modulated_speed(mean_rpm, parse_speed_modulation(shape),
                              sim.at(rotor + "_speed_amplitude_ratio").get<double>(),
                              sim.at(rotor + "_speed_frequency_hz").get<double>());
}

bool one_sided_contact(const Json& sim) {
  const Json& v = sim.at("one_sided_contact");
  return v.is_null() ? sim.at("infeed_rate_m_per_s").get<double>() > 0.0 : v.get<bool>();
}

// The default fit window is the later half of the linear regime: it ends where the one-sided
// contact first opens after the first revolution of the slowest rotor (after that the amplitude is
// limited by lift-off, not by the roots; lift-offs while the infeed builds the first cut do not
// count) or at the end of the run, and starts half-way there but not before one such revolution
// (only then are the regenerated surfaces under the contact). Explicit fit_start_s / fit_end_s
// are taken as given; assess_fit judges either.
double fit_end(const Json& sim, const SimulationResult& r, double delay_s) {
  const Json& v = sim.at("fit_end_s");
  if (!v.is_null()) return std::min(v.get<double>(), r.end_time_s);
  for (const auto& [from, to] : r.contact_loss_intervals)
    if (from >= delay_s) return std::min(from, r.end_time_s);
  return r.end_time_s;
}
double fit_start(const Json& sim, double end_s, double delay_s) {
  const Json& v = sim.at("fit_start_s");
  if (!v.is_null()) return v.get<double>();
  const double half = 0.5 * end_s;
  return half < delay_s && delay_s < end_s ? delay_s : half;
}

// The longest regenerative delay of the model: one revolution of its slowest rotor.
double longest_delay_s(const TimeDomainModel& model) {
  double delay = 0.0;
  for (Rotor r : {Rotor::wheel, Rotor::work}) {
    const double rpm = model.nominal_speed_rpm(r);
    if (rpm > 0) delay = std::max(delay, 60.0 / rpm);
  }
  return delay;
}

// Keeps at most ~2 x buckets points of a long series for a plot: the minimum and maximum of each
// bucket, in time order, so the envelope of a fast oscillation stays visible.
plot::Series decimated(std::string label, const std::vector<double>& x, const std::vector<double>& y,
                       std::size_t buckets = 2000) {
  plot::Series s{std::move(label), {}, {}, "lines"};
  const std::size_t n = x.size();
  const std::size_t per = std::max<std::size_t>(1, n / buckets);
  for (std::size_t i = 0; i < n; i += per) {
    std::size_t end = std::min(n, i + per), lo = i, hi = i;
    for (std::size_t j = i; j < end; ++j) {
      if (y[j] < y[lo]) lo = j;
      if (y[j] > y[hi]) hi = j;
    }
    for (std::size_t j : {std::min(lo, hi), std::max(lo, hi)}) {
      s.x.push_back(x[j]);
      s.y.push_back(y[j]);
      if (lo == hi) break;
    }
  }
  return s;
}

std::string study_name(const Json& document) {
  auto it = document.find("study");
  if (it != document.end() && it->is_object() && it->contains("name") && (*it)["name"].is_string())
    return (*it)["name"].get<std::string>();
  return "simulation";
}

// The optional [surface] table: the surface_profile plugin's keys except `unit` (a simulated
// surface is in metres). Empty when the plugin is not registered.
std::vector<ParamSpec> surface_specs() {
  std::vector<ParamSpec> specs;
  if (const auto* entry = analysis_registry().find(surface_plugin))
    for (const ParamSpec& spec : entry->info.params)
      if (spec.key != "unit") specs.push_back(spec);
  return specs;
}

struct WorkSurfaceQuality {
  Json summary;  // the surface summary of the final snapshot (+ t_s), or {problem}
  Json wt_um, wz_um, ront_um;
  std::optional<SampledSeries> series;  // the evaluated profile (for the plot)
  std::unique_ptr<Analysis> analysis;
};

// Mean of a recorded speed over [from, to] (samples inside; the value at `to` if none).
double mean_speed(const SimulationResult& r, std::size_t rotor, double from, double to) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < r.t_s.size(); ++i)
    if (r.t_s[i] >= from && r.t_s[i] <= to) {
      sum += r.speed_rpm[rotor][i];
      ++n;
    }
  if (n > 0) return sum / static_cast<double>(n);
  return r.speed_rpm[rotor].empty() ? 0.0 : r.speed_rpm[rotor].back();
}

// Waviness and roundness of the last work-surface snapshot: radius deviation = -(removal so far)
// over one revolution, a closed profile. Wz|f bands from the speeds of the revolution that cut
// it (mean over the last work revolution before the snapshot) unless [surface] gives them.
WorkSurfaceQuality evaluate_work_surface(const SimulationResult& r, const Json& document) {
  WorkSurfaceQuality q;
  constexpr auto work = static_cast<std::size_t>(Rotor::work), wheel = static_cast<std::size_t>(Rotor::wheel);
  if (r.snapshots.empty() || r.surface_samples_per_rev[work] == 0 ||
      !analysis_registry().find(surface_plugin)) {
    q.summary = {{"problem", "no work surface to evaluate (the model does not store one, or no "
                             "snapshot was taken)"}};
    return q;
  }
  const SurfaceSnapshot& snap = r.snapshots.back();
  Json params = document.contains("surface") ? document.at("surface") : Json::object();
  params["unit"] = "m";
  Json speeds;
  if (!params["work_speed_rpm"].is_number()) {
    const double nw_end = mean_speed(r, work, snap.t_s, snap.t_s);
    const double from = nw_end > 0 ? snap.t_s - 60.0 / nw_end : 0.0;
    const double nw = mean_speed(r, work, from, snap.t_s), ng = mean_speed(r, wheel, from, snap.t_s);
    if (nw > 0 && ng > 0) {
      params["work_speed_rpm"] = nw;
      params["wheel_speed_rpm"] = ng;
      speeds = {{"wheel_speed_rpm", ng}, {"work_speed_rpm", nw},
                {"from", "mean over the last work revolution before the snapshot"}};
    }
  }
  SampledSeries series;
  series.values.reserve(snap.surface_m[work].size());
  for (double removed : snap.surface_m[work]) series.values.push_back(-removed);
  series.sample_interval = 360.0 / static_cast<double>(series.values.size());
  series.sample_unit = "deg";
  series.closed = true;
  series.name = fmt::format("work surface at t = {:.4g} s", snap.t_s);
  try {
    q.analysis = analysis_registry().at(surface_plugin).create(ParamValues(params));
    q.summary = q.analysis->analyse(series, Json::object());
  } catch (const InputError& e) {
    q.summary = {{"problem", e.what()}};
    q.analysis.reset();
    return q;
  }
  q.summary["t_s"] = snap.t_s;
  q.summary["profile"] = "radius deviation = -(removal so far), one work revolution";
  if (!speeds.is_null()) q.summary["speeds"] = speeds;
  const double infeed = document.at("simulation").at("infeed_rate_m_per_s").get<double>();
  if (infeed > 0 && params["work_speed_rpm"].is_number())
    q.summary["infeed_per_work_revolution_um"] = 1e6 * infeed * 60.0 / params["work_speed_rpm"].get<double>();
  q.wt_um = q.summary["Wt_um"];
  q.wz_um = q.summary["Wz_um"];
  q.ront_um = q.summary["RONt_um"];
  q.series = std::move(series);
  return q;
}

struct PointAnalysis {
  std::optional<EnvelopeFit> fit;
  std::optional<FitValidity> validity;  // with fit
  std::string fit_problem;
  std::optional<Spectrum> spectrum;
  std::vector<SpectralPeak> peaks;
  double max_displacement = 0.0;
};

PointAnalysis analyse(const SimulationResult& r, const Json& sim, double delay_s) {
  PointAnalysis a;
  for (double x : r.displacement_m) a.max_displacement = std::max(a.max_displacement, std::abs(x));
  const double end = fit_end(sim, r, delay_s), start = fit_start(sim, end, delay_s);
  try {
    a.fit = fit_envelope(r.t_s, r.displacement_m, start, end, sim.at("min_frequency_hz").get<double>());
    a.validity = assess_fit(*a.fit, r.t_s, r.in_contact, delay_s);
  } catch (const std::invalid_argument& e) {
    a.fit_problem = fmt::format("no fit in the window {:.4g}..{:.4g} s: {}", start, end, e.what());
    if (sim.at("fit_end_s").is_null() && end < r.end_time_s)
      a.fit_problem += fmt::format(
          " (the contact first opened at t = {:.4g} s, ending the linear regime{})", end,
          sim.at("infeed_rate_m_per_s").get<double>() > 0.0
              ? ""
              : "; with no infeed the depth of cut is zero and any vibration lifts the wheel: set "
                "infeed_rate_m_per_s, or one_sided_contact = false for the linear growth");
  }
  // Spectrum of the fit window (where chatter has developed), Hann-windowed.
  auto first = std::lower_bound(r.t_s.begin(), r.t_s.end(), start) - r.t_s.begin();
  auto last = std::upper_bound(r.t_s.begin(), r.t_s.end(), end) - r.t_s.begin();
  if (last - first >= 64) {
    // Linear trend removed: the static deflection growing with the infeed is not a vibration.
    std::vector<double> window(r.displacement_m.begin() + first, r.displacement_m.begin() + last);
    const double n = static_cast<double>(window.size());
    double st = 0, sx = 0, stt = 0, stx = 0;
    for (std::size_t i = 0; i < window.size(); ++i) {
      const double ti = static_cast<double>(i);
      st += ti; sx += window[i]; stt += ti * ti; stx += ti * window[i];
    }
    const double slope = (n * stx - st * sx) / (n * stt - st * st), offset = (sx - slope * st) / n;
    for (std::size_t i = 0; i < window.size(); ++i) window[i] -= offset + slope * static_cast<double>(i);
    a.spectrum = amplitude_spectrum(window, sim.at("sample_rate_hz").get<double>());
    const double floor_hz = sim.at("min_frequency_hz").get<double>();
    for (const SpectralPeak& p : find_peaks(*a.spectrum, 4 * max_peaks, 4.0 * a.spectrum->resolution_hz, 1e-3))
      if (p.frequency_hz >= floor_hz && a.peaks.size() < max_peaks) a.peaks.push_back(p);
  }
  return a;
}

// Lift-off statistics and the amplitude the response settles at once the contact has opened: the
// nonlinear outcome that the (then invalid) linear growth rate does not describe.
Json after_contact_loss(const SimulationResult& r) {
  const double first = r.contact_loss_intervals.front().first;
  double open = 0.0, longest = 0.0;
  for (const auto& [from, to] : r.contact_loss_intervals) {
    open += to - from;
    longest = std::max(longest, to - from);
  }
  const double span = std::max(r.end_time_s - first, 1e-300);
  // Half peak-to-peak of x over the last tenth of the run, about its least-squares line (infeed).
  const std::size_t n = r.displacement_m.size(), from = n - n / 10;
  double amplitude = 0.0;
  if (n / 10 >= 8) {
    double st = 0, sx = 0, stt = 0, stx = 0, m = static_cast<double>(n - from);
    for (std::size_t i = from; i < n; ++i) {
      st += r.t_s[i]; sx += r.displacement_m[i]; stt += r.t_s[i] * r.t_s[i]; stx += r.t_s[i] * r.displacement_m[i];
    }
    const double slope = (m * stx - st * sx) / (m * stt - st * st), offset = (sx - slope * st) / m;
    double lo = INFINITY, hi = -INFINITY;
    for (std::size_t i = from; i < n; ++i) {
      const double d = r.displacement_m[i] - offset - slope * r.t_s[i];
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    amplitude = 0.5 * (hi - lo);
  }
  return {{"first_contact_loss_s", first},
          {"open_fraction_after_first_loss", open / span},
          {"lift_off_count", r.contact_loss_intervals.size()},
          {"mean_lift_off_s", open / static_cast<double>(r.contact_loss_intervals.size())},
          {"longest_lift_off_s", longest},
          {"final_amplitude_m", amplitude},
          {"final_amplitude_window_s", n / 10 >= 8 ? Json::array({r.t_s[from], r.t_s[n - 1]}) : Json()}};
}

void write_point_files(const SimulationResult& r, const PointAnalysis& a, const WorkSurfaceQuality& quality,
                       const Json& document, const PointContext& context) {
  const fs::path& dir = context.artifact_dir;
  const Json& sim = document.at("simulation");
  std::vector<std::string> header{"t_s", "displacement_m", "force_n", "depth_of_cut_m", "infeed_m",
                                  "wheel_speed_rpm", "work_speed_rpm", "wheel_surface_at_contact_m",
                                  "work_surface_at_contact_m", "in_contact"};
  constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel), work = static_cast<std::size_t>(Rotor::work);
  std::vector<std::span<const double>> columns{r.t_s, r.displacement_m, r.force_n, r.depth_of_cut_m, r.infeed_m,
                                               r.speed_rpm[wheel], r.speed_rpm[work],
                                               r.surface_at_contact_m[wheel], r.surface_at_contact_m[work],
                                               r.in_contact};
  std::vector<double> measured;
  if (const double noise = sim.at("measurement_noise_m").get<double>(); noise > 0) {
    // A displacement sensor's reading: x plus white Gaussian noise (never fed back to the
    // dynamics). Monitors built for measured signals (C1-C3) need it: a noise-free simulated
    // signal has no stable "texture", and amplitude-normalised criteria flag any pure sine.
    std::mt19937_64 random(sim.at("seed").get<std::uint64_t>() + 0x5eed);
    std::normal_distribution<double> gauss(0.0, noise);
    measured = r.displacement_m;
    for (double& x : measured) x += gauss(random);
    header.emplace_back("measured_displacement_m");
    columns.push_back(measured);
  }
  const std::string timeseries_file =
      write_time_series(dir, "timeseries", header, columns, parse_time_series_format(sim.at("timeseries_format").get<std::string>()),
                        sim.at("timeseries_decimation").get<std::size_t>());
  Json snapshots = Json::array();
  for (std::size_t i = 0; i < r.snapshots.size(); ++i) {
    const SurfaceSnapshot& s = r.snapshots[i];
    std::string name = fmt::format("surfaces_{:02d}.csv", i);
    write_file_atomically(dir / name, csv_text({"angle_deg", "work_surface_m", "wheel_surface_m"},
                                               {s.angle_deg, s.surface_m[work], s.surface_m[wheel]}));
    snapshots.push_back({{"t_s", s.t_s}, {"file", name}});
  }
  if (a.spectrum)
    write_file_atomically(dir / "spectrum.csv", csv_text({"frequency_hz", "amplitude_m"},
                                                         {a.spectrum->frequency_hz, a.spectrum->amplitude}));

  Json summary;
  summary["model"] = document.at("model").at("type");
  summary["status"] = r.status;
  summary["one_sided_contact"] = one_sided_contact(sim);
  summary["end_time_s"] = r.end_time_s;
  summary["timeseries"] = {{"file", timeseries_file}, {"columns", header},
                           {"sample_rate_hz", sim.at("sample_rate_hz").get<double>() /
                                                  sim.at("timeseries_decimation").get<double>()}};
  summary["fitted_growth_rate_per_s"] = a.fit ? Json(a.fit->growth_rate_per_s) : Json();
  if (a.fit)
    summary["fit"] = {{"window_s", {a.fit->start_s, a.fit->end_s}},
                      {"method", "ln of the per-period envelope (half peak-to-peak per period of the dominant "
                                 "frequency), least squares"},
                      {"residual_rms", a.fit->residual_rms},
                      {"valid", a.validity->valid},
                      {"regime", to_string(a.validity->regime)},
                      {"reason", a.validity->reason},
                      {"contact_loss_fraction_in_window", a.validity->contact_loss_fraction},
                      {"longest_delays_in_window", a.validity->delays_in_window},
                      {"growth_rate_first_half_per_s", a.validity->first_half_growth_per_s},
                      {"growth_rate_second_half_per_s", a.validity->second_half_growth_per_s},
                      {"final_envelope_m", a.validity->final_amplitude_m}};
  else
    summary["fit"] = {{"problem", a.fit_problem}};
  summary["dominant_frequency_hz"] = a.peaks.empty() ? Json() : Json(a.peaks.front().frequency_hz);
  Json peaks = Json::array();
  for (const SpectralPeak& p : a.peaks) peaks.push_back({{"frequency_hz", p.frequency_hz}, {"amplitude_m", p.amplitude}});
  summary["peaks"] = peaks;
  summary["max_displacement_m"] = a.max_displacement;
  summary["contact_loss_fraction"] = r.end_time_s > 0 ? r.contact_loss_time_s / r.end_time_s : 0.0;
  Json intervals = Json::array();
  for (std::size_t i = 0; i < r.contact_loss_intervals.size() && i < 200; ++i)
    intervals.push_back({r.contact_loss_intervals[i].first, r.contact_loss_intervals[i].second});
  summary["contact_loss_intervals_s"] = intervals;
  if (!r.contact_loss_intervals.empty())
    summary["after_contact_loss"] = after_contact_loss(r);
  summary["contact_loss_interval_count"] = r.contact_loss_intervals.size();
  summary["surface_snapshots"] = snapshots;
  summary["work_surface_quality"] = quality.summary;
  summary["diagnostics"] = {{"messages", r.diagnostics},
                            {"integrator_steps", r.steps},
                            {"rhs_evaluations", r.rhs_evaluations},
                            {"contact_events", r.contact_events},
                            {"wheel_surface_samples_per_rev", r.surface_samples_per_rev[wheel]},
                            {"work_surface_samples_per_rev", r.surface_samples_per_rev[work]},
                            {"method", r.method},
                            {"relative_tolerance", sim.at("relative_tolerance")}};
  write_json_file(dir / "summary.json", summary);

  if (!context.plots) return;
  const std::string title = study_name(document);
  std::string errors;
  auto render = [&](const auto& figure, const std::string& stem) {
    try {
      plot::render(figure, dir, stem);
    } catch (const std::exception& e) {
      errors += fmt::format("{}{}: {}", errors.empty() ? "" : "; ", stem, e.what());
    }
  };
  plot::Curves series;
  series.title = fmt::format("{}: displacement", title);
  series.x_label = "time t [s]";
  series.y_label = "structural displacement x [m]";
  series.series.push_back(decimated("displacement x", r.t_s, r.displacement_m));
  render(series, "timeseries");
  plot::Curves force;
  force.title = fmt::format("{}: normal grinding force", title);
  force.x_label = "time t [s]";
  force.y_label = "normal force Fn [N]";
  force.series.push_back(decimated("force Fn", r.t_s, r.force_n));
  render(force, "force");
  if (a.fit) {
    plot::Curves env;
    env.title = a.validity->valid
                    ? fmt::format("{}: envelope and fit (growth {:.4g} /s, {})", title, a.fit->growth_rate_per_s,
                                  to_string(a.validity->regime))
                    : fmt::format("{}: envelope and fit (growth {:.4g} /s NOT VALID: {})", title,
                                  a.fit->growth_rate_per_s, to_string(a.validity->regime));
    env.x_label = "time t [s]";
    env.y_label = "envelope of x [m]";
    env.log_y = true;
    env.series.push_back(decimated("envelope (half peak-to-peak per period)", a.fit->t_s, a.fit->envelope));
    plot::Series line{fmt::format("fit exp({:.4g} t)", a.fit->growth_rate_per_s), {}, {}, "lines"};
    for (double t : {a.fit->start_s, a.fit->end_s}) {
      line.x.push_back(t);
      line.y.push_back(std::exp(a.fit->intercept + a.fit->growth_rate_per_s * t));
    }
    env.series.push_back(std::move(line));
    render(env, "envelope_fit");
  }
  if (a.spectrum) {
    plot::Curves spec;
    spec.title = fmt::format("{}: spectrum (Hann) of x over the fit window", title);
    spec.x_label = "frequency [Hz]";
    spec.y_label = "amplitude [m]";
    spec.log_y = true;
    plot::Series line{"amplitude", {}, {}, "lines"};
    for (std::size_t k = 1; k < a.spectrum->frequency_hz.size(); ++k) {
      line.x.push_back(a.spectrum->frequency_hz[k]);
      line.y.push_back(std::max(a.spectrum->amplitude[k], 1e-30));
    }
    spec.series.push_back(std::move(line));
    plot::Series marks{"peaks", {}, {}, "points"};
    for (const SpectralPeak& p : a.peaks) {
      marks.x.push_back(p.frequency_hz);
      marks.y.push_back(p.amplitude);
    }
    spec.series.push_back(std::move(marks));
    render(spec, "spectrum");
  }
  if (!r.snapshots.empty()) {
    for (std::size_t rotor : {work, wheel}) {
      if (r.surface_samples_per_rev[rotor] == 0) continue;
      plot::Curves surf;
      surf.title = fmt::format("{}: {} surface, unrolled (removal so far)", title, to_string(static_cast<Rotor>(rotor)));
      surf.x_label = "body angle [deg]";
      surf.y_label = "radius removed [m]";
      for (const SurfaceSnapshot& s : r.snapshots)
        surf.series.push_back(decimated(fmt::format("t = {:.4g} s", s.t_s), s.angle_deg, s.surface_m[rotor]));
      render(surf, fmt::format("{}_surface", to_string(static_cast<Rotor>(rotor))));
    }
  }
  if (quality.analysis && quality.series) {
    try {
      quality.analysis->plot(quality.summary, *quality.series, dir);
    } catch (const std::exception& e) {
      errors += fmt::format("{}surface_profile_polar: {}", errors.empty() ? "" : "; ", e.what());
    }
  }
  if (!errors.empty()) throw plot::PlotError(errors);
}

}  // namespace

PluginInfo Simulate::info() {
  PluginInfo info;
  info.name = "simulate";
  info.description = "time-domain simulation of the model (angle-indexed regenerative surfaces, "
                     "one-sided contact): growth rate, chatter frequency, surfaces";
  info.models_md_ids = "G1, G5, G6, G7";
  ParamSpec duration = real_spec("duration_s", "s", "simulated time", 0.0, 0.0, true);
  duration.default_value = Json();
  ParamSpec seed = param_spec("seed", ValueKind::integer, "1", "seed of the random initial waviness");
  seed.default_value = 1;
  seed.min = 0;
  // Default: one-sided exactly when there is a cut to lose. Without an infeed the mean depth of cut
  // is zero, so a one-sided contact opens at the first vibration and never carries the linear
  // growth (issue 19: 97 % of the time open, a fitted -0.1 /s where the root grows at 4.79 /s);
  // the bilateral contact is then the linearisation the roots describe.
  ParamSpec one_sided = param_spec("one_sided_contact", ValueKind::boolean, "1",
                                   "the force cannot pull: the wheel leaves the work and re-enters "
                                   "(false: bilateral, linear contact; default: true with an infeed, "
                                   "false without one)");
  one_sided.optional = true;
  ParamSpec snapshots = param_spec("snapshot_times_s", ValueKind::real_list, "s",
                                   "times at which wheel and work surfaces are written (default: the end)");
  snapshots.optional = true;
  snapshots.min = 0.0;
  ParamSpec tolerance = real_spec("relative_tolerance", "1",
                                  "relative tolerance of the adaptive integrators (explicit_runge_kutta, adams)",
                                  1e-6, 0.0, true);
  tolerance.max = 1e-3;
  ParamSpec integrator = param_spec("integrator", ValueKind::string, "",
                                    "time integrator (docs/dynamics.md): fixed_step (fixed steps; exact "
                                    "exponential propagation of linear models, Runge-Kutta otherwise), "
                                    "explicit_runge_kutta (adaptive ARKODE Dormand-Prince 5(4), the reference) "
                                    "or adams (CVODE Adams)");
  integrator.choices = {"fixed_step", "explicit_runge_kutta", "adams"};
  integrator.default_value = "fixed_step";
  ParamSpec steps_per_wave = real_spec("fixed_steps_per_wave", "1",
                                       "fixed_step: steps per wave at the model's highest frequency (0: the "
                                       "default, 10 exponential (40 with one-sided contact) / 60 Runge-Kutta; with initial_waviness_m > 0 never more than 3/4 of the time "
                                       "between surface samples)", 0.0, 0.0, false);
  ParamSpec format = param_spec("timeseries_format", ValueKind::string, "",
                                "time-series file: csv (timeseries.csv) or npy (timeseries.npy, a NumPy "
                                "structured array with one float64 field per column: long runs)");
  format.choices = {"csv", "npy"};
  format.default_value = "csv";
  ParamSpec decimation = param_spec("timeseries_decimation", ValueKind::integer, "1",
                                    "write every k-th output sample to the time-series file (exact samples, "
                                    "no filter; the fit and spectrum use every sample)");
  decimation.default_value = 1;
  decimation.min = 1;
  ParamSpec files = param_spec("write_point_files", ValueKind::boolean, "1",
                               "in a grid, also write each point's files into points/<i>/");
  files.default_value = false;
  info.params = {
      duration,
      real_spec("sample_rate_hz", "Hz", "output sample rate", 20000.0, 0.0, true),
      real_spec("initial_displacement_m", "m", "initial structural displacement (disturbance)", 1e-6,
                -std::numeric_limits<double>::infinity(), false),
      real_spec("initial_velocity_m_per_s", "m/s", "initial structural velocity (an impulse)", 0.0,
                -std::numeric_limits<double>::infinity(), false),
      real_spec("initial_waviness_m", "m", "random initial waviness of wheel and work (+/-, uniform)", 0.0, 0.0, false),
      seed,
      real_spec("infeed_rate_m_per_s", "m/s", "plunge infeed rate (G1 U0 = rate * t)", 0.0, 0.0, false),
      one_sided,
      real_spec("wheel_contact_arc_deg", "deg",
                "geometric filtering (G4): wheel surface averaged over this arc (0: point contact)", 0.0, 0.0, false),
      real_spec("work_contact_arc_deg", "deg",
                "geometric filtering (G4): work surface averaged over this arc (0: point contact)", 0.0, 0.0, false),
      snapshots,
      optional_real("fit_start_s", "s", "start of the envelope-fit window (default: half-way to its end)"),
      optional_real("fit_end_s", "s", "end of the envelope-fit window (default: where the contact first opens, else the end of the run)"),
      tolerance,
      integrator,
      steps_per_wave,
      format,
      decimation,
      real_spec("min_frequency_hz", "Hz",
                "spectral peaks below this are not the dominant (chatter) frequency: the infeed "
                "transient and work-revolution waviness live there", 10.0, 0.0, false),
      real_spec("divergence_limit_m", "m", "|displacement| beyond this stops the run as diverged", 0.01, 0.0, true),
      real_spec("measurement_noise_m", "m",
                "rms of white Gaussian sensor noise added to x in timeseries.csv column "
                "measured_displacement_m (seeded by seed; 0: no column)", 0.0, 0.0, false),
      files,
  };
  for (const std::string rotor : {"wheel", "work"})
    for (ParamSpec& s : speed_specs(rotor)) info.params.push_back(std::move(s));
  for (ParamSpec& s : info.params)
    if (s.key == "wheel_contact_arc_deg" || s.key == "work_contact_arc_deg") {
      s.max = 90.0;
      s.max_exclusive = true;
    }
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"duration_s", 0.2}, {"sample_rate_hz", 10000.0}};
  return info;
}

void Simulate::validate(Json& document, const SourceMap& sources) const {
  Json model = validate_component(document, "model", model_registry(), sources);
  Json sim = document.contains("simulation") ? document["simulation"] : Json();
  if (!sim.is_object())
    throw InputError(fmt::format("{}: missing table [simulation] (at least duration_s)",
                                 sources.locate("simulation").str()));
  sim = validate_params(sim, info().params, "simulation", sources);
  auto where = [&](const std::string& key) { return sources.locate("simulation." + key).str(); };

  const std::string type = model["type"].get<std::string>();
  auto time_domain = build_model(model)->time_domain();
  if (!time_domain)
    throw InputError(fmt::format("{}: model.type = \"{}\": this model has no time-domain form, which "
                                 "the simulate study needs",
                                 sources.locate("model.type").str(), type));
  const double duration = sim["duration_s"].get<double>();
  const double samples = duration * sim["sample_rate_hz"].get<double>();
  if (samples > max_output_samples)
    throw InputError(fmt::format(
        "{}: simulation.duration_s = {}: duration_s * sample_rate_hz = {:.4g} output samples exceeds "
        "the limit of {:.4g} (shorten duration_s or lower sample_rate_hz = {})",
        where("duration_s"), duration, samples, max_output_samples, sim["sample_rate_hz"].get<double>()));
  if (samples < 64)
    throw InputError(fmt::format("{}: simulation.duration_s = {}: only {:.0f} output samples; at "
                                 "least 64 are needed for the spectrum and the growth fit",
                                 where("duration_s"), duration, samples));
  if (sim["snapshot_times_s"].is_null()) sim["snapshot_times_s"] = Json::array({duration});
  for (const Json& t : sim["snapshot_times_s"])
    if (t.get<double>() > duration)
      throw InputError(fmt::format("{}: simulation.snapshot_times_s = {}: a time is beyond duration_s = {}",
                                   where("snapshot_times_s"), t.dump(), duration));
  // The window as given (the defaults follow the run: fit_end below).
  const double end = sim["fit_end_s"].is_null() ? duration : sim["fit_end_s"].get<double>();
  const double start = fit_start(sim, end, 0.0);
  if (!(start < end) || end > duration)
    throw InputError(fmt::format("{}: simulation.fit_start_s/fit_end_s = {}/{}: the envelope-fit window "
                                 "must satisfy fit_start_s < fit_end_s <= duration_s = {}",
                                 where(sim.contains("fit_start_s") ? "fit_start_s" : "fit_end_s"), start, end, duration));
  for (const std::string rotor : {"wheel", "work"}) {
    const std::string shape = sim[rotor + "_speed_modulation"].get<std::string>();
    const std::string key = rotor + "_speed_schedule";
    if (shape == "schedule") {
      if (sim[key].is_null())
        throw InputError(fmt::format("{}: simulation.{}_speed_modulation = \"schedule\" needs {} "
                                     "(rows [t_s, rpm])", where(rotor + "_speed_modulation"), rotor, key));
      for (const Json& row : sim[key])
        if (row.size() != 2)
          throw InputError(fmt::format("{}: simulation.{} = {}: each row must be [t_s, rpm]",
                                       where(key), key, row.dump()));
    } else if (shape != "constant" && sim[rotor + "_speed_amplitude_ratio"].get<double>() > 0.0 &&
               !(sim[rotor + "_speed_frequency_hz"].get<double>() > 0.0)) {
      throw InputError(fmt::format("{}: simulation.{}_speed_frequency_hz = 0: a {} modulation with "
                                   "amplitude_ratio > 0 needs a frequency > 0",
                                   where(rotor + "_speed_frequency_hz"), rotor, shape));
    }
    if (shape == "schedule" || (shape != "constant")) {
      try {
        speed_law(sim, rotor, time_domain->nominal_speed_rpm(rotor == "wheel" ? Rotor::wheel : Rotor::work));
      } catch (const std::invalid_argument& e) {
        throw InputError(fmt::format("{}: simulation.{}: {}", where(shape == "schedule" ? key : rotor + "_speed_modulation"),
                                     shape == "schedule" ? key : rotor + "_speed_modulation", e.what()));
      }
    }
  }
  document["model"] = std::move(model);
  document["simulation"] = std::move(sim);
  validate_surface(document, sources);
}

void Simulate::validate_surface(Json& document, const SourceMap& sources) {
  // [surface] (optional): the surface study's [filter]/[process]/[parameters] keys, flat, with
  // their limits and joint checks (the surface_profile plugin's own); a closed profile takes its
  // cut-off in UPR only.
  const std::vector<ParamSpec> specs = surface_specs();
  if (specs.empty()) {
    if (document.contains("surface"))
      throw InputError(fmt::format("{}: [surface] needs the surface metrology plugin '{}', which "
                                   "is not registered in this build",
                                   sources.locate("surface").str(), surface_plugin));
    return;
  }
  Json table = document.contains("surface") ? document["surface"] : Json::object();
  if (!table.is_object())
    throw InputError(fmt::format("{}: surface = {}: expected a table [surface]",
                                 sources.locate("surface").str(), table.dump()));
  table = validate_params(table, specs, "surface", sources);
  if (table["cutoff_mm"].is_number())
    throw InputError(fmt::format("{}: surface.cutoff_mm = {}: a simulated work surface is a closed "
                                 "profile (one revolution); give its cut-off as surface.cutoff_upr",
                                 sources.locate("surface.cutoff_mm").str(), table["cutoff_mm"].dump()));
  Json params = table;
  params["unit"] = "m";
  try {
    analysis_registry().at(surface_plugin).create(ParamValues(params));
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: [surface]: {}", sources.locate("surface").str(), e.what()));
  }
  document["surface"] = std::move(table);
}

SimulationSettings Simulate::settings(const Json& document, const TimeDomainModel& model) {
  const Json& sim = document.at("simulation");
  SimulationSettings s;
  s.duration_s = sim.at("duration_s").get<double>();
  s.sample_rate_hz = sim.at("sample_rate_hz").get<double>();
  s.disturbance.displacement_m = sim.at("initial_displacement_m").get<double>();
  s.disturbance.velocity_m_per_s = sim.at("initial_velocity_m_per_s").get<double>();
  s.initial_waviness_m = sim.at("initial_waviness_m").get<double>();
  s.seed = sim.at("seed").get<std::uint64_t>();
  s.infeed_rate_m_per_s = sim.at("infeed_rate_m_per_s").get<double>();
  s.one_sided_contact = one_sided_contact(sim);
  s.contact_arc_deg[static_cast<std::size_t>(Rotor::wheel)] = sim.at("wheel_contact_arc_deg").get<double>();
  s.contact_arc_deg[static_cast<std::size_t>(Rotor::work)] = sim.at("work_contact_arc_deg").get<double>();
  for (const Json& t : sim.at("snapshot_times_s")) s.snapshot_times_s.push_back(t.get<double>());
  s.relative_tolerance = sim.at("relative_tolerance").get<double>();
  s.integrator = parse_time_integrator(sim.at("integrator").get<std::string>());
  s.fixed_steps_per_wave = sim.at("fixed_steps_per_wave").get<double>();
  s.divergence_limit_m = sim.at("divergence_limit_m").get<double>();
  for (Rotor r : {Rotor::wheel, Rotor::work})
    if (!model.angle_state(r))
      s.speed[static_cast<std::size_t>(r)] = speed_law(sim, to_string(r), model.nominal_speed_rpm(r));
  return s;
}

std::vector<std::string> Simulate::output_columns(const Json&) const {
  return {col_growth, col_fit_valid, col_fit_regime, col_fit_reason, col_frequency, col_max_displacement,
          col_contact_loss, col_outcome, col_work_wt, col_work_wz, col_work_ront};
}

std::vector<Json> Simulate::run_point(const Json& document, const PointContext& context) const {
  auto model = build_model(document.at("model"))->time_domain();
  if (!model) throw PointFailure("the model has no time-domain form here");
  SimulationResult result;
  try {
    result = simulate(*model, settings(document, *model));
  } catch (const std::invalid_argument& e) {
    throw PointFailure(e.what());
  }
  const Json& sim = document.at("simulation");
  PointAnalysis a = analyse(result, sim, longest_delay_s(*model));
  const WorkSurfaceQuality quality = evaluate_work_surface(result, document);
  if (!context.artifact_dir.empty() && (context.single_point() || sim.at("write_point_files").get<bool>()))
    write_point_files(result, a, quality, document, context);
  return {a.fit ? Json(a.fit->growth_rate_per_s) : Json(), a.validity ? Json(a.validity->valid) : Json(false),
          a.validity ? to_string(a.validity->regime) : "no fit", a.validity ? a.validity->reason : a.fit_problem,
          a.peaks.empty() ? Json() : Json(a.peaks.front().frequency_hz), a.max_displacement,
          result.end_time_s > 0 ? result.contact_loss_time_s / result.end_time_s : 0.0,
          result.diverged ? std::string("diverged") : std::string("completed"),
          quality.wt_um, quality.wz_um, quality.ront_um};
}

void Simulate::write_artifacts(const Study& study, const ResultTable& results, const fs::path& out_dir) const {
  // A 1-D grid: fitted growth rate and dominant frequency against the grid key.
  std::vector<std::size_t> varying;
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    if (study.grid[a].values.size() > 1) varying.push_back(a);
  if (varying.size() != 1) return;  // single point: its plots are per point; 2+ axes: results.csv
  const std::size_t axis = varying[0];
  for (const Json& v : study.grid[axis].values)
    if (!v.is_number()) return;
  auto column = [&](const char* name) {
    for (std::size_t c = 0; c < results.output_columns.size(); ++c)
      if (results.output_columns[c] == name) return results.grid_columns.size() + c;
    throw std::logic_error("simulate: no column");
  };
  const std::string title = study_name(study.document);
  std::string errors;
  for (auto [name, label] : {std::pair{col_growth, "fitted growth rate [1/s]"},
                             std::pair{col_frequency, "dominant frequency [Hz]"}}) {
    plot::Curves c;
    c.title = fmt::format("{}: {}", title, name);
    c.x_label = study.grid[axis].key;
    c.y_label = label;
    plot::Series s{name, {}, {}, "linespoints"};
    const std::size_t col = column(name);
    for (std::size_t r = 0; r < results.rows.size(); ++r)
      if (results.rows[r][col].is_number()) {
        s.x.push_back(results.rows[r][axis].get<double>());
        s.y.push_back(results.rows[r][col].get<double>());
      }
    c.series.push_back(std::move(s));
    if (std::string(name) == col_growth) {
      c.reference_y = 0.0;
      c.reference_label = "growth = 0";
    }
    try {
      plot::render(c, out_dir, name == std::string(col_growth) ? "fitted_growth_rate" : "dominant_frequency");
    } catch (const std::exception& e) {
      errors += fmt::format("{}{}", errors.empty() ? "" : "; ", e.what());
    }
  }
  if (!errors.empty()) throw plot::PlotError(errors);
}

bool Simulate::requires_serial(const Json& document) const {
  return model_is_serial(document.at("model"));
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::Simulate);
