#include "study_kinds/simulate/simulate_point.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>

#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/time_series_file.hpp"

namespace chatterlab::simulate_point {

namespace {

namespace fs = std::filesystem;

constexpr std::size_t max_peaks = 10;
constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel), work = static_cast<std::size_t>(Rotor::work);

// The samples of `x` whose times lie in [start, end], minus their least-squares line (the static
// deflection growing with the infeed is not a vibration); empty below min_samples.
std::vector<double> detrended_window(const SimulationResult& r, double start, double end,
                                     std::ptrdiff_t min_samples = 64) {
  auto first = std::lower_bound(r.t_s.begin(), r.t_s.end(), start) - r.t_s.begin();
  auto last = std::upper_bound(r.t_s.begin(), r.t_s.end(), end) - r.t_s.begin();
  if (last - first < min_samples) return {};
  std::vector<double> window(r.displacement_m.begin() + first, r.displacement_m.begin() + last);
  const double n = static_cast<double>(window.size());
  double st = 0, sx = 0, stt = 0, stx = 0;
  for (std::size_t i = 0; i < window.size(); ++i) {
    const double ti = static_cast<double>(i);
    st += ti; sx += window[i]; stt += ti * ti; stx += ti * window[i];
  }
  const double slope = (n * stx - st * sx) / (n * stt - st * st), offset = (sx - slope * st) / n;
  for (std::size_t i = 0; i < window.size(); ++i) window[i] -= offset + slope * static_cast<double>(i);
  return window;
}

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

// The speeds of the work revolution that cut the surface of a snapshot at t: their means over the
// last work revolution before t.
ProfileSpeeds cutting_speeds(const SimulationResult& r, double t) {
  const double nw_end = mean_speed(r, work, t, t);
  const double from = nw_end > 0 ? t - 60.0 / nw_end : 0.0;
  return {mean_speed(r, wheel, from, t), mean_speed(r, work, from, t)};
}

// The work surface of a snapshot as a closed profile in metres: one work revolution of radius
// deviation, the infeed ramp removed. During a plunge the removal rises by a revolution's infeed
// along the revolution (a spiral with a step at the seam), which would dominate Wt and RONt of
// waves a few um deep. The plots show the same residual.
SampledSeries work_profile(const SurfaceSnapshot& snap) {
  SampledSeries series;
  std::vector<double> radius_m = without_infeed_ramp(snap.surface_m[work]).values;
  for (double& v : radius_m) v = -v;  // removal -> radius deviation
  series.set_samples(std::move(radius_m));
  series.sample_interval = 360.0 / static_cast<double>(series.values.size());
  series.sample_unit = "deg";
  series.closed = true;
  series.name = fmt::format("work surface at t = {:.4g} s", snap.t_s);
  return series;
}

Json number_or_null(const std::optional<double>& v) { return v ? Json(*v) : Json(); }

// timeseries.csv or .npy (every k-th sample); its entry of the summary.
Json write_timeseries(const SimulationResult& r, const SimulateSettings& settings, const PointContext& context) {
  std::vector<std::string> header{"t_s", "displacement_m", "force_n", "depth_of_cut_m", "infeed_m",
                                  "wheel_speed_rpm", "work_speed_rpm", "wheel_surface_at_contact_m",
                                  "work_surface_at_contact_m", "in_contact"};
  std::vector<std::span<const double>> columns{r.t_s, r.displacement_m, r.force_n, r.depth_of_cut_m, r.infeed_m,
                                               r.speed_rpm[wheel], r.speed_rpm[work],
                                               r.surface_at_contact_m[wheel], r.surface_at_contact_m[work],
                                               r.in_contact};
  std::vector<double> measured;
  if (const double noise = settings.measurement_noise_m; noise > 0) {
    // A displacement sensor's reading: x plus white Gaussian noise (never fed back to the
    // dynamics). Monitors built for measured signals (C1-C3) need it: a noise-free simulated
    // signal has no stable "texture", and amplitude-normalised criteria flag any pure sine.
    std::mt19937_64 random(settings.simulation.disturbance.seed + 0x5eed);
    std::normal_distribution<double> gauss(0.0, noise);
    measured = r.displacement_m;
    for (double& x : measured) x += gauss(random);
    header.emplace_back("measured_displacement_m");
    columns.push_back(measured);
  }
  const std::string file = write_time_series(context.artifact_dir, "timeseries", header, columns,
                                             settings.timeseries_format, settings.timeseries_decimation);
  return {{"file", file},
          {"columns", header},
          {"sample_rate_hz",
           settings.simulation.sample_rate_hz / static_cast<double>(settings.timeseries_decimation)}};
}

// surfaces_NN.csv per snapshot; their list for the summary.
Json write_snapshots(const SimulationResult& r, const PointContext& context) {
  Json snapshots = Json::array();
  for (std::size_t i = 0; i < r.snapshots.size(); ++i) {
    const SurfaceSnapshot& s = r.snapshots[i];
    const std::string name = fmt::format("surfaces_{:02d}.csv", i);
    kit::write_table(context, name, {"angle_deg", "work_surface_m", "wheel_surface_m"},
                     {s.angle_deg, s.surface_m[work], s.surface_m[wheel]});
    snapshots.push_back({{"t_s", s.t_s}, {"file", name}});
  }
  return snapshots;
}

// Why there is no fit, and what ended the default window when that explains it.
std::string no_fit_problem(const kit::SimulationTable& sim, const SimulationResult& r, const kit::FitWindow& window,
                           const std::string& what) {
  std::string problem = fmt::format("no fit in the window {:.4g}..{:.4g} s: {}", window.start_s, window.end_s, what);
  if (!sim.fit.fit_end_s && window.end_s < r.end_time_s)
    problem += fmt::format(" (the contact first opened at t = {:.4g} s, ending the linear regime{})", window.end_s,
                           sim.contact.infeed_rate_m_per_s > 0.0
                               ? ""
                               : "; with no infeed the depth of cut is zero and any vibration lifts the wheel: set "
                                 "infeed_rate_m_per_s, or one_sided_contact = false for the linear growth");
  return problem;
}

// Half peak-to-peak of x over the last tenth of the run about its least-squares line (the
// infeed's drift); null when that tenth has fewer than 8 samples.
struct FinalAmplitude {
  double amplitude_m = 0.0;
  Json window_s;
};
FinalAmplitude final_amplitude(const SimulationResult& r) {
  const std::size_t n = r.displacement_m.size(), from = n - n / 10;
  if (n / 10 < 8) return {};
  const std::vector<double> tail = detrended_window(r, r.t_s[from], r.t_s[n - 1], 8);
  const auto [lo, hi] = std::minmax_element(tail.begin(), tail.end());
  return {0.5 * (*hi - *lo), Json::array({r.t_s[from], r.t_s[n - 1]})};
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
  const FinalAmplitude final = final_amplitude(r);
  return {{"first_contact_loss_s", first},
          {"open_fraction_after_first_loss", open / span},
          {"lift_off_count", r.contact_loss_intervals.size()},
          {"mean_lift_off_s", open / static_cast<double>(r.contact_loss_intervals.size())},
          {"longest_lift_off_s", longest},
          {"final_amplitude_m", final.amplitude_m},
          {"final_amplitude_window_s", final.window_s}};
}

Json fit_summary(const PointAnalysis& a) {
  if (!a.fit) return {{"problem", a.fit_problem}};
  const FitValidity& v = *a.validity;
  return {{"window_s", {a.fit->start_s, a.fit->end_s}},
          {"method", "ln of the per-period envelope (half peak-to-peak per period of the dominant "
                     "frequency), least squares"},
          {"residual_rms", a.fit->residual_rms},
          {"valid", v.valid},
          {"regime", to_string(v.regime)},
          {"reason", v.reason},
          {"contact_loss_fraction_in_window", v.contact_loss_fraction},
          {"longest_delays_in_window", v.delays_in_window},
          {"growth_rate_first_half_per_s", v.first_half_growth_per_s},
          {"growth_rate_second_half_per_s", v.second_half_growth_per_s},
          {"final_envelope_m", v.final_amplitude_m}};
}

Json point_summary(const SimulationResult& r, const PointAnalysis& a, const WorkSurfaceQuality& quality,
                   const Json& document, const SimulateSettings& settings, Json timeseries, Json snapshots) {
  Json summary;
  summary["model"] = document.at("model").at("type");
  summary["status"] = r.status;
  summary["one_sided_contact"] = kit::one_sided(settings.simulation.contact);
  summary["end_time_s"] = r.end_time_s;
  summary["timeseries"] = std::move(timeseries);
  summary["fitted_growth_rate_per_s"] = a.fit ? Json(a.fit->growth_rate_per_s) : Json();
  summary["fit"] = fit_summary(a);
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
  if (!r.contact_loss_intervals.empty()) summary["after_contact_loss"] = after_contact_loss(r);
  summary["contact_loss_interval_count"] = r.contact_loss_intervals.size();
  summary["surface_snapshots"] = std::move(snapshots);
  summary["work_surface_quality"] = quality.summary;
  summary["diagnostics"] = {{"messages", r.diagnostics},
                            {"integrator_steps", r.steps},
                            {"rhs_evaluations", r.rhs_evaluations},
                            {"contact_events", r.contact_events},
                            {"wheel_surface_samples_per_rev", r.surface_samples_per_rev[wheel]},
                            {"work_surface_samples_per_rev", r.surface_samples_per_rev[work]},
                            {"method", r.method},
                            {"relative_tolerance", settings.simulation.integration.relative_tolerance}};
  return summary;
}

plot::Curves time_figure(const std::string& title, const std::string& y_label, plot::Series series) {
  plot::Curves c;
  c.title = title;
  c.x_label = "time t [s]";
  c.y_label = y_label;
  c.series.push_back(std::move(series));
  return c;
}

// The rotor speeds' relative changes, when a model lets them vary (torsion, G5; speed
// modulation, S2/S3): relative, because the force follows n_w / n_g (G5), so 1 rpm of the work
// (55 rpm) weighs 26 times 1 rpm of the wheel (1450 rpm). Empty when both speeds stay constant.
plot::Curves speed_figure(const SimulationResult& r, const std::string& title) {
  plot::Curves c = time_figure(fmt::format("{}: rotor speeds", title), "speed change [% of the speed at t = 0]", {});
  c.series.clear();
  for (std::size_t rotor : {work, wheel}) {
    const std::vector<double>& rpm = r.speed_rpm[rotor];
    if (rpm.empty()) continue;
    const auto [lo, hi] = std::minmax_element(rpm.begin(), rpm.end());
    if (rpm.front() == 0.0 || *hi - *lo <= 1e-9 * std::abs(rpm.front())) continue;
    std::vector<double> change(rpm.size());
    for (std::size_t i = 0; i < rpm.size(); ++i) change[i] = 100.0 * (rpm[i] / rpm.front() - 1.0);
    c.series.push_back(kit::decimated(fmt::format("{} ({:.4g} rpm at t = 0)", to_string(static_cast<Rotor>(rotor)),
                                                  rpm.front()),
                                      r.t_s, change));
  }
  return c;
}

plot::Curves envelope_figure(const std::string& title, const EnvelopeFit& fit, const FitValidity& validity) {
  const std::string verdict = validity.valid ? fmt::format("growth {:.4g} /s, {}", fit.growth_rate_per_s,
                                                           to_string(validity.regime))
                                             : fmt::format("growth {:.4g} /s NOT VALID: {}", fit.growth_rate_per_s,
                                                           to_string(validity.regime));
  plot::Curves env = time_figure(fmt::format("{}: envelope and fit ({})", title, verdict),
                                 "envelope of x [m]",
                                 kit::decimated("envelope (half peak-to-peak per period)", fit.t_s, fit.envelope));
  env.log_y = true;
  plot::Series line{fmt::format("fit exp({:.4g} t)", fit.growth_rate_per_s), {}, {}, "lines"};
  for (double t : {fit.start_s, fit.end_s}) {
    line.x.push_back(t);
    line.y.push_back(std::exp(fit.intercept + fit.growth_rate_per_s * t));
  }
  env.series.push_back(std::move(line));
  return env;
}

plot::Curves spectrum_figure(const std::string& title, const Spectrum& spectrum, const std::vector<SpectralPeak>& peaks) {
  plot::Curves spec;
  spec.title = fmt::format("{}: spectrum (Hann) of x over the fit window", title);
  spec.x_label = "frequency [Hz]";
  spec.y_label = "amplitude [m]";
  spec.log_y = true;
  plot::Series line{"amplitude", {}, {}, "lines"};
  for (std::size_t k = 1; k < spectrum.frequency_hz.size(); ++k) {
    line.x.push_back(spectrum.frequency_hz[k]);
    line.y.push_back(std::max(spectrum.amplitude[k], 1e-30));
  }
  spec.series.push_back(std::move(line));
  plot::Series marks{"peaks", {}, {}, "points"};
  for (const SpectralPeak& p : peaks) {
    marks.x.push_back(p.frequency_hz);
    marks.y.push_back(p.amplitude);
  }
  spec.series.push_back(std::move(marks));
  return spec;
}

void plot_surfaces(const SimulationResult& r, const std::string& title, const fs::path& dir, kit::Figures& figures) {
  for (std::size_t rotor : {work, wheel}) {
    if (r.snapshots.empty() || r.surface_samples_per_rev[rotor] == 0) continue;
    const std::string name = to_string(static_cast<Rotor>(rotor));
    plot::Curves surf;
    surf.title = fmt::format("{}: {} surface, unrolled", title, name);
    surf.x_label = "body angle [deg]";
    surf.y_label = "radius removed minus the infeed ramp [um]";
    for (const SurfaceSnapshot& s : r.snapshots) {
      // The ramp (a revolution's infeed, tens of um) would hide waves of a few um.
      Deramped d = without_infeed_ramp(s.surface_m[rotor]);
      for (double& v : d.values) v *= 1e6;
      const std::string ramp = d.rise_per_revolution == 0.0
                                   ? std::string("no ramp above the waves; mean removed")
                                   : fmt::format("ramp {:.3g} um/rev removed", 1e6 * d.rise_per_revolution);
      surf.series.push_back(kit::decimated(fmt::format("t = {:.4g} s ({})", s.t_s, ramp), s.angle_deg, d.values));
    }
    figures.render(surf, dir, name + "_surface");
  }
}

void plot_point(const SimulationResult& r, const PointAnalysis& a, const WorkSurfaceQuality& quality,
                const std::string& title, const fs::path& dir) {
  kit::Figures figures;
  figures.render(time_figure(fmt::format("{}: displacement", title), "structural displacement x [m]",
                             kit::decimated("displacement x", r.t_s, r.displacement_m)),
                 dir, "timeseries");
  figures.render(time_figure(fmt::format("{}: normal grinding force", title), "normal force Fn [N]",
                             kit::decimated("force Fn", r.t_s, r.force_n)),
                 dir, "force");
  if (plot::Curves speeds = speed_figure(r, title); !speeds.series.empty()) figures.render(speeds, dir, "speeds");
  if (a.fit) figures.render(envelope_figure(title, *a.fit, *a.validity), dir, "envelope_fit");
  if (a.spectrum) figures.render(spectrum_figure(title, *a.spectrum, a.peaks), dir, "spectrum");
  plot_surfaces(r, title, dir, figures);
  if (quality.analysis && quality.profile_m) {
    try {
      quality.analysis->profile_quality()->plot_profile(*quality.profile_m, quality.speeds, dir);
    } catch (const std::exception& e) {
      figures.add_error("surface_profile_polar", e.what());
    }
  }
  figures.finish();
}

}  // namespace

// See simulate_point.hpp.
Deramped without_infeed_ramp(std::span<const double> y) {
  const std::size_t n = y.size();
  Deramped out{std::vector<double>(y.begin(), y.end()), 0.0};
  if (n < 3) return out;
  const double nd = static_cast<double>(n);
  const double su = nd * (nd - 1.0) / 2.0, suu = (nd - 1.0) * nd * (2.0 * nd - 1.0) / 6.0;
  const double var_u = suu - su * su / nd;
  double sy = 0.0, siy = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sy += y[i];
    siy += static_cast<double>(i) * y[i];
  }
  double before = 0.0, best_cov = 0.0;  // before: sum of y[i] for i < b
  std::size_t best = 0;
  for (std::size_t b = 0; b < n; ++b) {
    const double suy = siy - static_cast<double>(b) * sy + nd * before;
    const double cov = suy - su * sy / nd;
    if (b == 0 || std::abs(cov) > std::abs(best_cov)) {
      best_cov = cov;
      best = b;
    }
    before += y[b];
  }
  const double slope = best_cov / var_u, offset = (sy - slope * su) / nd;
  double squares = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double u = static_cast<double>((i + n - best) % n);
    out.values[i] = y[i] - (offset + slope * u);
    squares += out.values[i] * out.values[i];
  }
  out.rise_per_revolution = slope * nd;
  // The best of n breakpoints always finds some sawtooth in random waviness: a ramp that does not
  // rise above twice the residual rms is not one, and only the mean is removed.
  if (std::abs(out.rise_per_revolution) < 2.0 * std::sqrt(squares / nd)) {
    for (std::size_t i = 0; i < n; ++i) out.values[i] = y[i] - sy / nd;
    out.rise_per_revolution = 0.0;
  }
  return out;
}


PointAnalysis analyse(const SimulationResult& r, const kit::SimulationTable& sim, double longest_delay_s) {
  PointAnalysis a;
  for (double x : r.displacement_m) a.max_displacement = std::max(a.max_displacement, std::abs(x));
  const kit::FitWindow window = kit::fit_window(sim.fit, r, longest_delay_s);
  const double start = window.start_s, end = window.end_s;
  try {
    a.fit = fit_envelope(r.t_s, r.displacement_m, start, end, sim.fit.min_frequency_hz);
    a.validity = assess_fit(*a.fit, r.t_s, r.in_contact, longest_delay_s);
  } catch (const std::invalid_argument& e) {
    a.fit_problem = no_fit_problem(sim, r, window, e.what());
  }
  // Spectrum of the fit window (where chatter has developed), Hann-windowed.
  const std::vector<double> samples = detrended_window(r, start, end);
  if (samples.empty()) return a;
  a.spectrum = amplitude_spectrum(samples, sim.sample_rate_hz);
  for (const SpectralPeak& p : find_peaks(*a.spectrum, 4 * max_peaks, 4.0 * a.spectrum->resolution_hz, 1e-3))
    if (p.frequency_hz >= sim.fit.min_frequency_hz && a.peaks.size() < max_peaks) a.peaks.push_back(p);
  return a;
}

const Registry<Analysis>::Entry* profile_quality_analysis() {
  const auto found = kit::plugins_with(analysis_registry(), &Analysis::profile_quality);
  return found.empty() ? nullptr : found.front();
}

WorkSurfaceQuality measure_work_surface(const SimulationResult& r, const Json& surface_table,
                                        double infeed_rate_m_per_s) {
  WorkSurfaceQuality q;
  const auto* entry = profile_quality_analysis();
  if (r.snapshots.empty() || r.surface_samples_per_rev[work] == 0 || !entry) {
    q.summary = {{"problem", "no work surface to evaluate (the model does not store one, or no "
                             "snapshot was taken)"}};
    return q;
  }
  const SurfaceSnapshot& snap = r.snapshots.back();
  const SampledSeries profile = work_profile(snap);
  q.speeds = cutting_speeds(r, snap.t_s);
  ProfileQuality measured;
  try {
    q.analysis = entry->create(ParamValues(kit::plugin_parameters(entry->info, surface_table)));
    measured = q.analysis->profile_quality()->measure_profile(profile, q.speeds);
  } catch (const InputError& e) {
    q.summary = {{"problem", e.what()}};
    q.analysis.reset();
    return q;
  }
  q.summary = std::move(measured.report);
  q.summary["t_s"] = snap.t_s;
  q.summary["profile"] = "radius deviation = -(removal so far), one work revolution, infeed ramp removed";
  if (measured.speeds_from_caller)
    q.summary["speeds"] = {{"wheel_speed_rpm", q.speeds.wheel_speed_rpm}, {"work_speed_rpm", q.speeds.work_speed_rpm},
                           {"from", "mean over the last work revolution before the snapshot"}};
  if (infeed_rate_m_per_s > 0 && measured.speeds)
    q.summary["infeed_per_work_revolution_um"] = 1e6 * infeed_rate_m_per_s * 60.0 / measured.speeds->work_speed_rpm;
  q.wt_um = number_or_null(measured.waviness_wt_um);
  q.wz_um = number_or_null(measured.waviness_wz_um);
  q.ront_um = number_or_null(measured.roundness_ront_um);
  q.profile_m = profile;
  return q;
}

void write_point_files(const SimulationResult& r, const PointAnalysis& a, const WorkSurfaceQuality& quality,
                       const Json& document, const SimulateSettings& settings, const PointContext& context) {
  Json timeseries = write_timeseries(r, settings, context);
  Json snapshots = write_snapshots(r, context);
  if (a.spectrum)
    kit::write_table(context, "spectrum.csv", {"frequency_hz", "amplitude_m"},
                     {a.spectrum->frequency_hz, a.spectrum->amplitude});
  kit::write_summary(context, point_summary(r, a, quality, document, settings, std::move(timeseries), std::move(snapshots)));
  // Titled by [study] name, else "simulation".
  if (context.plots) plot_point(r, a, quality, kit::study_title(document, "simulation"), context.artifact_dir);
}

}  // namespace chatterlab::simulate_point
