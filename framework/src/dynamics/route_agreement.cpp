#include "dynamics/route_agreement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "chatterlab/spectrum.hpp"

namespace chatterlab::dynamics_detail {

namespace {

std::vector<SpectralPeak> window_peaks(const SimulationResult& r, double from_s, double to_s, double floor_hz) {
  auto first = std::lower_bound(r.t_s.begin(), r.t_s.end(), from_s) - r.t_s.begin();
  auto last = std::upper_bound(r.t_s.begin(), r.t_s.end(), to_s) - r.t_s.begin();
  std::vector<SpectralPeak> out;
  if (last - first < 64) return out;
  std::span<const double> x(r.displacement_m.data() + first, static_cast<std::size_t>(last - first));
  const Spectrum spectrum = amplitude_spectrum(x, 1.0 / (r.t_s[1] - r.t_s[0]));
  for (const SpectralPeak& p : find_peaks(spectrum, 16, 4.0 * spectrum.resolution_hz, 1e-3))
    if (p.frequency_hz >= floor_hz && out.size() < 4) out.push_back(p);
  return out;
}

double surface_difference(const SurfaceSnapshot& a, const SurfaceSnapshot& b, std::size_t rotor) {
  const std::vector<double>& x = a.surface_m[rotor];
  const std::vector<double>& y = b.surface_m[rotor];
  if (x.size() != y.size() || x.empty()) return std::numeric_limits<double>::infinity();
  double mean = 0.0;
  for (double v : x) mean += v / static_cast<double>(x.size());
  double diff = 0.0, size = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    diff += (y[i] - x[i]) * (y[i] - x[i]);
    size += (x[i] - mean) * (x[i] - mean);
  }
  return size > 0.0 ? std::sqrt(diff / size) : (diff > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
}

}  // namespace

RouteAgreement route_agreement(const SimulationResult& reference, const SimulationResult& other, double from_s,
                               double to_s, double floor_hz, std::size_t snapshot) {
  RouteAgreement out;
  out.reference_growth_per_s = fit_envelope(reference.t_s, reference.displacement_m, from_s, to_s, floor_hz).growth_rate_per_s;
  out.growth_per_s = fit_envelope(other.t_s, other.displacement_m, from_s, to_s, floor_hz).growth_rate_per_s;
  out.growth_error = std::abs(out.growth_per_s / out.reference_growth_per_s - 1.0);
  const std::vector<SpectralPeak> a = window_peaks(reference, from_s, to_s, floor_hz);
  const std::vector<SpectralPeak> b = window_peaks(other, from_s, to_s, floor_hz);
  if (!a.empty() && !b.empty()) {
    out.reference_frequency_hz = a.front().frequency_hz;
    out.frequency_hz = std::min_element(b.begin(), b.end(), [&](const SpectralPeak& p, const SpectralPeak& q) {
                         return std::abs(p.frequency_hz - out.reference_frequency_hz) <
                                std::abs(q.frequency_hz - out.reference_frequency_hz);
                       })->frequency_hz;
    out.frequency_error = std::abs(out.frequency_hz / out.reference_frequency_hz - 1.0);
  } else {
    out.frequency_error = std::numeric_limits<double>::infinity();
  }
  for (std::size_t rotor = 0; rotor < rotor_count; ++rotor)
    if (reference.surface_samples_per_rev[rotor] > 0 && snapshot < reference.snapshots.size() &&
        snapshot < other.snapshots.size())
      out.surface_error = std::max(out.surface_error,
                                   surface_difference(reference.snapshots[snapshot], other.snapshots[snapshot], rotor));
  return out;
}

}  // namespace chatterlab::dynamics_detail
