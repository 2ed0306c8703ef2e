#include "chatterlab/spectrum.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "chatterlab/fft.hpp"

namespace chatterlab {

std::string to_string(SpectralWindow window) {
  return window == SpectralWindow::hann ? "hann" : "rectangular";
}

Spectrum amplitude_spectrum(std::span<const double> samples, double sample_rate_hz,
                            SpectralWindow window) {
  const std::size_t n = samples.size();
  if (n < 4)
    throw std::invalid_argument(fmt::format("amplitude spectrum needs at least 4 samples, got {}", n));
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    throw std::invalid_argument(
        fmt::format("amplitude spectrum needs a positive sample rate, got {}", sample_rate_hz));

  const double mean = std::accumulate(samples.begin(), samples.end(), 0.0) / static_cast<double>(n);
  std::vector<double> weighted(n);
  double gain_sum = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    // Periodic Hann (divisor n): its coherent gain is exactly 1/2 and it tiles without overlap gaps.
    const double w = window == SpectralWindow::hann
                         ? 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(j) /
                                                static_cast<double>(n))
                         : 1.0;
    weighted[j] = (samples[j] - mean) * w;
    gain_sum += w;
  }
  RealFft fft(n);
  const auto bins = fft.forward(weighted);

  Spectrum spectrum;
  spectrum.resolution_hz = sample_rate_hz / static_cast<double>(n);
  spectrum.frequency_hz.resize(bins.size());
  spectrum.amplitude.resize(bins.size());
  for (std::size_t k = 0; k < bins.size(); ++k) {
    spectrum.frequency_hz[k] = static_cast<double>(k) * spectrum.resolution_hz;
    // One-sided: every bin but DC (and Nyquist for even n) carries its mirror image's half too.
    const bool unpaired = k == 0 || (n % 2 == 0 && k == n / 2);
    spectrum.amplitude[k] = std::abs(bins[k]) * (unpaired ? 1.0 : 2.0) / gain_sum;
  }
  return spectrum;
}

std::vector<SpectralPeak> find_peaks(const Spectrum& spectrum, std::size_t max_peaks,
                                     double min_separation_hz, double relative_threshold) {
  const auto& a = spectrum.amplitude;
  std::vector<SpectralPeak> candidates;
  if (a.size() < 3 || max_peaks == 0) return candidates;
  const double largest = *std::max_element(a.begin() + 1, a.end());
  if (!(largest > 0.0)) return candidates;
  for (std::size_t k = 1; k + 1 < a.size(); ++k) {
    if (!(a[k] > a[k - 1] && a[k] > a[k + 1]) || a[k] < relative_threshold * largest) continue;
    SpectralPeak peak{spectrum.frequency_hz[k], a[k], k};
    if (a[k - 1] > 0.0 && a[k + 1] > 0.0) {
      // Gaussian interpolation: a parabola through the log amplitudes of the three bins.
      const double l = std::log(a[k - 1]), c = std::log(a[k]), r = std::log(a[k + 1]);
      const double denom = l - 2.0 * c + r;
      if (denom < 0.0) {
        const double offset = 0.5 * (l - r) / denom;
        peak.frequency_hz += offset * spectrum.resolution_hz;
        peak.amplitude = std::exp(c - 0.25 * (l - r) * offset);
      }
    }
    candidates.push_back(peak);
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const SpectralPeak& x, const SpectralPeak& y) { return x.amplitude > y.amplitude; });
  std::vector<SpectralPeak> kept;
  for (const auto& peak : candidates) {
    if (kept.size() == max_peaks) break;
    const bool clear = std::all_of(kept.begin(), kept.end(), [&](const SpectralPeak& other) {
      return std::abs(other.frequency_hz - peak.frequency_hz) >= min_separation_hz;
    });
    if (clear) kept.push_back(peak);
  }
  return kept;
}

}  // namespace chatterlab
