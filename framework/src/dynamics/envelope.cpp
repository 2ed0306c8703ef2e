// Growth-rate fit of a simulated response (chatterlab/dynamics.hpp, fit_envelope): the envelope
// is taken period by period (half the peak-to-peak swing of each period of the dominant
// frequency, extremes refined by a parabola), which is local in time. A Fourier-based (Hilbert)
// envelope is not: for a response growing by orders of magnitude over the window, the leakage
// of the large end swamps the small beginning and flattens the fitted slope.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/spectrum.hpp"

namespace chatterlab {

namespace {

// Vertex of the parabola through (i-1, i, i+1) of y: refined extreme value and its offset.
std::pair<double, double> parabolic_extreme(const std::vector<double>& y, std::size_t i) {
  if (i == 0 || i + 1 >= y.size()) return {y[i], 0.0};
  const double a = y[i - 1], b = y[i], c = y[i + 1];
  const double curvature = a - 2.0 * b + c;
  if (curvature == 0.0) return {b, 0.0};
  const double offset = std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5);
  return {b - 0.25 * (a - c) * offset, offset};
}

}  // namespace

EnvelopeFit fit_envelope(std::span<const double> t_s, std::span<const double> x, double start_s,
                         double end_s, double min_frequency_hz) {
  if (t_s.size() != x.size()) throw std::invalid_argument("fit_envelope: t and x differ in length");
  const auto first = static_cast<std::size_t>(std::lower_bound(t_s.begin(), t_s.end(), start_s) - t_s.begin());
  const auto last = static_cast<std::size_t>(std::upper_bound(t_s.begin(), t_s.end(), end_s) - t_s.begin());
  if (last < first + 64) throw std::invalid_argument("fit_envelope: fewer than 64 samples in the fit window");
  const std::size_t m = last - first;
  const double dt = (t_s[last - 1] - t_s[first]) / static_cast<double>(m - 1);
  std::vector<double> y(x.begin() + static_cast<std::ptrdiff_t>(first), x.begin() + static_cast<std::ptrdiff_t>(last));
  {  // remove the least-squares line (static deflection, slow drift)
    double st = 0, sx = 0, stt = 0, stx = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const double ti = static_cast<double>(i);
      st += ti; sx += y[i]; stt += ti * ti; stx += ti * y[i];
    }
    const double dm = static_cast<double>(m);
    const double slope = (dm * stx - st * sx) / (dm * stt - st * st);
    const double offset = (sx - slope * st) / dm;
    for (std::size_t i = 0; i < m; ++i) y[i] -= offset + slope * static_cast<double>(i);
  }
  // Dominant frequency of the window (Hann spectrum: its peak survives leakage).
  const Spectrum spectrum = amplitude_spectrum(y, 1.0 / dt);
  std::vector<SpectralPeak> peaks;
  for (const SpectralPeak& peak : find_peaks(spectrum, 64))
    if (peak.frequency_hz >= min_frequency_hz) {
      peaks.push_back(peak);
      break;
    }
  if (peaks.empty() || !(peaks.front().frequency_hz > 0.0))
    throw std::invalid_argument("fit_envelope: the window holds no oscillation");
  const double period_samples = 1.0 / (peaks.front().frequency_hz * dt);
  if (period_samples < 4.0)
    throw std::invalid_argument("fit_envelope: fewer than 4 samples per period of the dominant frequency");

  EnvelopeFit fit;
  double st = 0, sy = 0, stt = 0, sty = 0;
  const auto block = static_cast<std::size_t>(std::lround(period_samples));
  for (std::size_t b = 0; b + block <= m; b += block) {
    std::size_t hi = b, lo = b;
    for (std::size_t i = b; i < b + block; ++i) {
      if (y[i] > y[hi]) hi = i;
      if (y[i] < y[lo]) lo = i;
    }
    const auto [top, top_offset] = parabolic_extreme(y, hi);
    const auto [bottom, bottom_offset] = parabolic_extreme(y, lo);
    const double amplitude = 0.5 * (top - bottom);
    if (!(amplitude > 0.0) || !std::isfinite(amplitude)) continue;
    const double t = t_s[first] + dt * 0.5 * (static_cast<double>(hi + lo) + top_offset + bottom_offset);
    const double ly = std::log(amplitude);
    fit.t_s.push_back(t);
    fit.envelope.push_back(amplitude);
    st += t; sy += ly; stt += t * t; sty += t * ly;
  }
  const std::size_t count = fit.t_s.size();
  if (count < 8) throw std::invalid_argument("fit_envelope: fewer than 8 periods in the fit window");
  const double n = static_cast<double>(count);
  fit.growth_rate_per_s = (n * sty - st * sy) / (n * stt - st * st);
  fit.intercept = (sy - fit.growth_rate_per_s * st) / n;
  double ss = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double r = std::log(fit.envelope[i]) - fit.intercept - fit.growth_rate_per_s * fit.t_s[i];
    ss += r * r;
  }
  fit.residual_rms = std::sqrt(ss / n);
  fit.start_s = t_s[first];
  fit.end_s = t_s[last - 1];
  return fit;
}

}  // namespace chatterlab
