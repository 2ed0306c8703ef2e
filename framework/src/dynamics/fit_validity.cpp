// assess_fit (chatterlab/fit_validity.hpp): the regime of a fitted envelope and whether its growth
// rate stands for the rightmost root. The checks run from the physical to the statistical, so the
// reason names the cause rather than its symptom (a saturated envelope also fits badly).
#include "chatterlab/fit_validity.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace chatterlab {

const char* to_string(ResponseRegime regime) {
  switch (regime) {
    case ResponseRegime::linear_growth: return "linear growth";
    case ResponseRegime::linear_decay: return "linear decay";
    case ResponseRegime::saturated: return "saturated";
    case ResponseRegime::contact_lost: return "contact lost";
    case ResponseRegime::transient: return "transient";
    case ResponseRegime::not_exponential: return "not exponential";
    case ResponseRegime::steady: return "steady";
  }
  return "?";
}

namespace {

// Least-squares slope of ln(envelope) over the samples with t in [from, to).
double ln_slope(const EnvelopeFit& fit, double from, double to) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t i = 0; i < fit.t_s.size(); ++i) {
    const double t = fit.t_s[i];
    if (t < from || t >= to) continue;
    const double y = std::log(fit.envelope[i]);
    n += 1; st += t; sy += y; stt += t * t; sty += t * y;
  }
  const double d = n * stt - st * st;
  return n >= 3 && d > 0 ? (n * sty - st * sy) / d : 0.0;
}

double contact_loss_fraction(std::span<const double> t_s, std::span<const double> in_contact, double from, double to) {
  if (in_contact.size() != t_s.size()) return 0.0;
  std::size_t inside = 0, open = 0;
  for (std::size_t i = 0; i < t_s.size(); ++i)
    if (t_s[i] >= from && t_s[i] <= to) {
      ++inside;
      if (in_contact[i] < 0.5) ++open;
    }
  return inside ? static_cast<double>(open) / static_cast<double>(inside) : 0.0;
}

double final_amplitude(const EnvelopeFit& fit) {
  const double from = fit.end_s - (fit.end_s - fit.start_s) / 8.0;
  double sum = 0, n = 0;
  for (std::size_t i = 0; i < fit.t_s.size(); ++i)
    if (fit.t_s[i] >= from) { sum += fit.envelope[i]; n += 1; }
  return n > 0 ? sum / n : (fit.envelope.empty() ? 0.0 : fit.envelope.back());
}

}  // namespace

FitValidity assess_fit(const EnvelopeFit& fit, std::span<const double> t_s, std::span<const double> in_contact,
                       double longest_delay_s, const FitValidityLimits& limits) {
  FitValidity v;
  v.window_start_s = fit.start_s;
  v.window_end_s = fit.end_s;
  const double length = fit.end_s - fit.start_s, middle = 0.5 * (fit.start_s + fit.end_s);
  v.contact_loss_fraction = contact_loss_fraction(t_s, in_contact, fit.start_s, fit.end_s);
  v.delays_in_window = longest_delay_s > 0 ? length / longest_delay_s : INFINITY;
  v.residual_rms = fit.residual_rms;
  v.first_half_growth_per_s = ln_slope(fit, fit.start_s, middle);
  v.second_half_growth_per_s = ln_slope(fit, middle, fit.end_s + 1e-12);
  v.final_amplitude_m = final_amplitude(fit);

  const double first_growth_ln = v.first_half_growth_per_s * 0.5 * length;
  if (v.contact_loss_fraction > limits.max_contact_loss_fraction) {
    v.regime = ResponseRegime::contact_lost;
    v.reason = fmt::format(
        "contact open for {:.1f} % of the fit window {:.4g}..{:.4g} s (limit {:.1f} %): the one-sided contact "
        "limits the amplitude, so the slope is not the linear growth rate",
        100 * v.contact_loss_fraction, fit.start_s, fit.end_s, 100 * limits.max_contact_loss_fraction);
  } else if (v.delays_in_window < limits.min_delays_in_window ||
             fit.start_s < limits.min_delays_in_window * longest_delay_s) {
    v.regime = ResponseRegime::transient;
    v.reason = fmt::format(
        "the fit window {:.4g}..{:.4g} s starts at {:.2f} and spans {:.2f} of the longest regenerative delay "
        "({:.4g} s; at least {:.0f} each needed): the regenerated surfaces have not yet taken over the growth",
        fit.start_s, fit.end_s, longest_delay_s > 0 ? fit.start_s / longest_delay_s : 0.0, v.delays_in_window,
        longest_delay_s, limits.min_delays_in_window);
  } else if (first_growth_ln > limits.min_growth_for_saturation_check &&
             v.second_half_growth_per_s < limits.saturation_slope_ratio * v.first_half_growth_per_s) {
    v.regime = ResponseRegime::saturated;
    v.reason = fmt::format(
        "the envelope saturates: growth {:.4g} /s in the window's first half, {:.4g} /s in its second (below "
        "{:.0f} %), final amplitude {:.3g} m",
        v.first_half_growth_per_s, v.second_half_growth_per_s, 100 * limits.saturation_slope_ratio,
        v.final_amplitude_m);
  } else if (v.residual_rms > limits.max_residual_rms) {
    v.regime = ResponseRegime::not_exponential;
    v.reason = fmt::format(
        "the envelope is not exponential over the window (ln residual rms {:.3g}, limit {:.3g}): beating roots "
        "or one pulse per revolution; lengthen the run or move the window",
        v.residual_rms, limits.max_residual_rms);
  } else if (const double halves = 0.5 * (v.first_half_growth_per_s + v.second_half_growth_per_s);
             std::abs(fit.growth_rate_per_s - halves) >
             limits.slope_consistency * std::max(std::abs(fit.growth_rate_per_s), std::abs(halves)) +
                 limits.slope_consistency / length) {
    // Both halves grow alike but the whole window does not: the envelope steps between them
    // (beating of nearly equal roots, a jump at a revolution), so no single rate describes it.
    v.regime = ResponseRegime::not_exponential;
    v.reason = fmt::format(
        "the envelope steps inside the window: growth {:.4g} /s over the whole window but {:.4g} and {:.4g} /s over "
        "its halves (beating roots or one pulse per revolution); lengthen the run or move the window",
        fit.growth_rate_per_s, v.first_half_growth_per_s, v.second_half_growth_per_s);
  } else if (std::abs(fit.growth_rate_per_s) * length < limits.max_steady_change) {
    v.regime = ResponseRegime::steady;
    v.reason = fmt::format(
        "the envelope holds its level: growth {:.3g} /s changes it by {:.2g} % over the window {:.4g}..{:.4g} s "
        "(limit {:.2g} %): a forced steady vibration (or a root on Re s = 0), so the slope does not estimate a "
        "root; the final amplitude {:.3g} m is the result",
        fit.growth_rate_per_s, 100 * std::abs(fit.growth_rate_per_s) * length, fit.start_s, fit.end_s,
        100 * limits.max_steady_change, v.final_amplitude_m);
  } else {
    v.valid = true;
    v.regime = fit.growth_rate_per_s >= 0 ? ResponseRegime::linear_growth : ResponseRegime::linear_decay;
  }
  return v;
}

}  // namespace chatterlab
