#include "shared/metrology/surface.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <span>

#include "shared/metrology/motif.hpp"
#include "shared/metrology/roundness.hpp"
#include "shared/metrology/waviness.hpp"
#include "chatterlab/errors.hpp"

namespace chatterlab::surface {
namespace {

// The least-squares straight line intercept + slope * i through y (form of an open profile).
struct Line {
  double intercept, slope;
};

Line least_squares_line(std::span<const double> y) {
  const double n = static_cast<double>(y.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double x = static_cast<double>(i);
    sx += x;
    sy += y[i];
    sxx += x * x;
    sxy += x * y[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double intercept = (sy - slope * sx) / n;
  return {intercept, slope};
}

// The profile minus its least-squares straight line (form removal of an open profile).
std::vector<double> without_line(std::span<const double> y) {
  const auto [intercept, slope] = least_squares_line(y);
  std::vector<double> out(y.size());
  for (std::size_t i = 0; i < y.size(); ++i)
    out[i] = y[i] - intercept - slope * static_cast<double>(i);
  return out;
}

Json circle_json(const ReferenceCircle& c) {
  return Json{{"RONt_um", c.RONt},         {"RONp_um", c.RONp},
              {"RONv_um", c.RONv},         {"RONq_um", c.RONq},
              {"centre_x_um", c.centre_x}, {"centre_y_um", c.centre_y},
              {"radius_offset_um", c.radius}, {"certified", c.certified}};
}

Json band_json(const BandWaviness& b) {
  return Json{{"Wz_um", b.Wz},
              {"from_upr", b.band.from_upr},
              {"to_upr", b.band.to_upr},
              {"dominant_upr", b.dominant_upr},
              {"dominant_amplitude_um", b.dominant_amplitude},
              {"dominant_frequency_hz", b.dominant_frequency_hz},
              {"wave_count", b.wave_count}};
}

// Samples left out at each end of an open profile when evaluating parameters: lc / 2.
std::size_t ends_skipped(double cutoff_samples) {
  return static_cast<std::size_t>(std::floor(cutoff_samples / 2));
}

double samples_per_revolution(const SampledSeries& series) {
  const double turn = series.sample_unit == "rad" ? 2 * std::numbers::pi : 360.0;
  return turn / series.sample_interval;
}

}  // namespace

FilterSettings resolve_filter(const SampledSeries& series, const SurfaceSettings& settings,
                              Json& filter_json) {
  const std::size_t n = series.values.size();
  const std::string what = series.name.empty() ? std::string("profile") : series.name;
  if (n < 4)
    throw InputError(fmt::format("{}: {} samples; a surface profile needs at least 4", what, n));
  if (series.closed && series.sample_unit != "deg" && series.sample_unit != "rad")
    throw InputError(fmt::format("{}: a closed profile is sampled by angle (deg or rad), not '{}'",
                                 what, series.sample_unit));
  if (!series.closed && series.sample_unit != "mm")
    throw InputError(fmt::format("{}: an open profile is sampled along x in mm, not '{}'", what,
                                 series.sample_unit));
  FilterSettings filter;
  filter.type = settings.filter;
  filter.max_iterations = settings.max_iterations;
  filter.closed = series.closed;
  filter_json = Json{{"type", to_string(settings.filter)}};
  if (series.closed) {
    const double per_rev = samples_per_revolution(series);
    if (std::abs(per_rev - static_cast<double>(n)) > 1e-6 * per_rev)
      throw InputError(fmt::format(
          "{}: {} samples at {} {} spacing is not one revolution ({} samples per revolution)",
          what, n, series.sample_interval, series.sample_unit, per_rev));
    if (settings.cutoff_mm)
      throw InputError(fmt::format("{}: a closed profile takes its cut-off in undulations per "
                                   "revolution (cutoff_upr), not cutoff_mm",
                                   what));
    const double upr = settings.cutoff_upr.value_or(50.0);
    if (!(upr >= 1.0))
      throw InputError(fmt::format("{}: cutoff_upr = {}: the cut-off wavelength is longer than "
                                   "the circumference (cutoff_upr must be >= 1)",
                                   what, upr));
    filter.cutoff_samples = static_cast<double>(n) / upr;
    filter_json["cutoff_upr"] = upr;
  } else {
    if (!settings.cutoff_mm)
      throw InputError(fmt::format("{}: an open profile needs cutoff_mm", what));
    const double length_mm = static_cast<double>(n - 1) * series.sample_interval;
    if (*settings.cutoff_mm > length_mm ||
        n < 2 * ends_skipped(*settings.cutoff_mm / series.sample_interval) + 4)
      throw InputError(fmt::format("{}: cutoff_mm = {} is longer than the profile ({} mm, {} "
                                   "samples at {} mm)",
                                   what, *settings.cutoff_mm, length_mm, n, series.sample_interval));
    filter.cutoff_samples = *settings.cutoff_mm / series.sample_interval;
    filter_json["cutoff_mm"] = *settings.cutoff_mm;
    filter_json["end_effects"] =
        "moment retaining (ISO 16610-28): local linear (gaussian) or quadratic (robust) "
        "regression over the samples that exist (filtered.csv: full length); parameters over "
        "the evaluation length = the profile without cutoff/2 at each end";
  }
  if (filter.cutoff_samples < min_samples_per_cutoff) {
    const std::string setting =
        series.closed ? fmt::format("cutoff_upr = {} on {} samples per revolution",
                                    settings.cutoff_upr.value_or(50.0), n)
                      : fmt::format("cutoff_mm = {} at {} mm spacing", *settings.cutoff_mm,
                                    series.sample_interval);
    throw InputError(fmt::format(
        "{}: too few samples per cut-off: {:.4g} ({}; at least {} needed: sample more densely "
        "or use a longer cut-off)",
        what, filter.cutoff_samples, setting, min_samples_per_cutoff));
  }

  return filter;
}

SurfaceEvaluation evaluate_surface_profile(const SampledSeries& series,
                                           const SurfaceSettings& settings) {
  const std::size_t n = series.values.size();
  Json filter_json;
  const FilterSettings filter = resolve_filter(series, settings, filter_json);

  SurfaceEvaluation out;
  if (settings.value_to_um == 1.0) {
    out.profile_um = series.values;
  } else {
    out.scaled_profile_um.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      out.scaled_profile_um[i] = series.values[i] * settings.value_to_um;
    out.profile_um = out.scaled_profile_um;
  }
  FilterResult filtered = filter_profile(out.profile_um, filter);
  out.waviness_um = std::move(filtered.waviness);
  const double position_step = series.closed && series.sample_unit == "rad"
                                   ? series.sample_interval * 180.0 / std::numbers::pi
                                   : series.sample_interval;
  out.position_step = position_step;
  filter_json["cutoff_samples"] = filter.cutoff_samples;
  if (settings.filter == FilterType::robust_gaussian) {
    filter_json["iterations"] = filtered.iterations;
    filter_json["converged"] = filtered.converged;
    filter_json["zero_weight_samples"] = filtered.zero_weight_samples;
  }

  Json& s = out.summary;
  s["closed"] = series.closed;
  s["samples"] = n;
  s["filter"] = filter_json;

  // Form removal before the W parameters: a straight line (open) or the least-squares circle
  // (closed: mean radius and eccentricity). `w` is freed after the parameters (peak memory).
  std::vector<double> w;
  std::optional<Roundness> round;
  if (series.closed) {
    round = roundness(out.waviness_um, References::all, Deviations::least_squares);
    w = std::move(round->least_squares_deviations);
    s["form_removed"] = "least-squares circle (limacon: mean radius and centre offset)";
  } else {
    // Evaluation length: the filtered profile without lc/2 at each end. The mean line is
    // defined up to the ends (moment retention), but there it passes more of the short waves
    // than the Gaussian does; lc/2 in (2.7 sigma of the Gaussian weights) it is the Gaussian.
    const std::size_t skip = ends_skipped(filter.cutoff_samples);
    w = without_line(std::span<const double>(out.waviness_um).subspan(skip, n - 2 * skip));
    s["form_removed"] = "least-squares straight line";
    s["evaluation_from_mm"] = out.position(skip);
    s["evaluation_to_mm"] = out.position(n - 1 - skip);
  }
  // Width discrimination: 1 % of the cut-off (ISO 4287's 1 % of the sampling length lr = lc).
  const WavinessParameters p = waviness_parameters(w, position_step, series.closed,
                                                   settings.sampling_lengths,
                                                   0.01 * filter.cutoff_samples);
  std::vector<double>().swap(w);
  s["Wa_um"] = p.Wa;
  s["Wq_um"] = p.Wq;
  s["Wp_um"] = p.Wp;
  s["Wv_um"] = p.Wv;
  s["Wz_um"] = p.Wz;
  s["Wt_um"] = p.Wt;
  const std::string wsm_key = series.closed ? "WSm_deg" : "WSm_mm";
  s[wsm_key] = p.WSm ? Json(*p.WSm) : Json();
  s["Wsk"] = p.Wsk;
  s["Wku"] = p.Wku;
  s["Wz_five_um"] = p.Wz_five;
  s["wave_count"] = p.wave_count;
  s["sampling_lengths"] = std::clamp<int>(settings.sampling_lengths, 1, static_cast<int>(n / 4));

  if (!series.closed) {
    const Line form = least_squares_line(out.profile_um);
    const MotifParameters m = motif_parameters(out.profile_um, form.intercept, form.slope,
                                               series.sample_interval, settings.motif_a_mm,
                                               settings.motif_b_mm);
    s["motif"] = Json{{"A_mm", settings.motif_a_mm}, {"B_mm", settings.motif_b_mm},
                      {"R_um", m.R},   {"AR_mm", m.AR}, {"Rx_um", m.Rx},
                      {"W_um", m.W},   {"AW_mm", m.AW}, {"Wx_um", m.Wx},
                      {"Wte_um", m.Wte}, {"roughness_motifs", m.roughness_motifs},
                      {"waviness_motifs", m.waviness_motifs}};
  }

  if (series.closed) {
    s["RONt_um"] = round->least_squares.RONt;  // flat key: least-squares reference
    s["roundness"] = Json{{"least_squares", circle_json(round->least_squares)},
                          {"minimum_zone", circle_json(round->minimum_zone)},
                          {"minimum_circumscribed", circle_json(round->minimum_circumscribed)},
                          {"maximum_inscribed", circle_json(round->maximum_inscribed)}};
    // Roundness with the standard UPR filters (ISO 12181-2: 15, 50, 150, 500), Gaussian.
    Json by_upr = Json::object();
    for (double upr : {15.0, 50.0, 150.0, 500.0}) {
      const std::string key = fmt::format("{}", upr);
      FilterSettings f;
      f.closed = true;
      f.cutoff_samples = static_cast<double>(n) / upr;
      if (f.cutoff_samples < min_samples_per_cutoff) {
        by_upr[key] = Json{{"skipped", fmt::format("{} samples per revolution < {} x {} UPR", n,
                                                   min_samples_per_cutoff, upr)}};
        continue;
      }
      const Roundness r =
          roundness(filter_profile(out.profile_um, f).waviness, References::least_squares_and_zone);
      by_upr[key] = Json{{"least_squares_RONt_um", r.least_squares.RONt},
                         {"minimum_zone_RONt_um", r.minimum_zone.RONt}};
    }
    s["roundness_by_upr"] = by_upr;
  }

  if (settings.wheel_speed_rpm && settings.work_speed_rpm) {
    if (!series.closed)
      throw InputError(fmt::format("{}: Wz|f (wheel and work speeds) needs a closed "
                                   "(circumferential) profile",
                                   series.name.empty() ? "profile" : series.name));
    auto [low, high] = default_bands(*settings.wheel_speed_rpm, *settings.work_speed_rpm, n);
    if (settings.low_band_upr) low = {settings.low_band_upr->first, settings.low_band_upr->second};
    if (settings.high_band_upr)
      high = {settings.high_band_upr->first, settings.high_band_upr->second};
    s["Wz_f"] = Json{
        {"forced_lobes_per_rev", *settings.wheel_speed_rpm / *settings.work_speed_rpm},
        {"low", band_json(band_waviness(out.profile_um, low, *settings.work_speed_rpm))},
        {"high", band_json(band_waviness(out.profile_um, high, *settings.work_speed_rpm))}};
  }
  return out;
}

Json evaluate_surface(const SampledSeries& series, const SurfaceSettings& settings) {
  return evaluate_surface_profile(series, settings).summary;
}

}  // namespace chatterlab::surface
