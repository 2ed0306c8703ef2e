#include "study_kinds/error_separation/error_separation.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "chatterlab/fft.hpp"

namespace chatterlab::error_separation {

namespace {

using Complex = std::complex<double>;
constexpr double two_pi = 2.0 * std::numbers::pi;

double sum_abs(std::span<const double> v) {
  double s = 0.0;
  for (double x : v) s += std::abs(x);
  return s;
}

double norm2(std::span<const double> v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

std::size_t common_length(std::span<const std::vector<double>> probes) {
  if (probes.empty()) throw std::invalid_argument("error separation: no probe signals");
  const std::size_t n = probes.front().size();
  for (const auto& p : probes)
    if (p.size() != n)
      throw std::invalid_argument(fmt::format(
          "error separation: probe signals differ in length ({} and {} samples)", n, p.size()));
  if (n < 4) throw std::invalid_argument("error separation: fewer than 4 samples per revolution");
  return n;
}

int harmonic_limit(int requested, std::size_t n) {
  const int nyquist = static_cast<int>(n / 2);
  return requested < 0 ? nyquist : std::min(requested, nyquist);
}

double range_of(std::span<const double> v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

// Amplitude of the once-per-revolution component of x (direct sums, O(N)).
Complex first_coefficient(std::span<const double> x) {
  const double n = static_cast<double>(x.size());
  Complex c{0.0, 0.0};
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double theta = two_pi * static_cast<double>(i) / n;
    c += x[i] * Complex(std::cos(theta), -std::sin(theta));
  }
  return c;
}

FirstHarmonicCheck check_first_harmonic(std::span<const double> s, double fraction) {
  FirstHarmonicCheck check;
  check.amplitude = 2.0 * std::abs(first_coefficient(s)) / static_cast<double>(s.size());
  check.limit = fraction * range_of(s);
  check.valid = check.amplitude <= check.limit;
  return check;
}

// Spindle motion by least squares over the probes (any number >= 2):
// e_q(i) = Y_q(i) - r(theta_i + phi_q) = dx cos phi_q + dy sin phi_q.
void spindle_motion(std::span<const std::vector<double>> probes, std::span<const double> angles_rad,
                    std::span<const std::vector<double>> shifted_profiles, Separation& out) {
  double scc = 0, scs = 0, sss = 0;
  for (double phi : angles_rad) {
    scc += std::cos(phi) * std::cos(phi);
    scs += std::cos(phi) * std::sin(phi);
    sss += std::sin(phi) * std::sin(phi);
  }
  const double det = scc * sss - scs * scs;
  if (!(std::abs(det) > 1e-300))
    throw std::invalid_argument("error separation: probe directions do not span the plane");
  const std::size_t n = probes.front().size();
  out.dx.assign(n, 0.0);
  out.dy.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double bx = 0, by = 0;
    for (std::size_t q = 0; q < probes.size(); ++q) {
      const double e = probes[q][i] - shifted_profiles[q][i];
      bx += e * std::cos(angles_rad[q]);
      by += e * std::sin(angles_rad[q]);
    }
    out.dx[i] = (sss * bx - scs * by) / det;
    out.dy[i] = (scc * by - scs * bx) / det;
  }
}

// r(theta_i + phi) for each probe angle from the spectrum of r (l = 0..N/2): R(l) e^{j l phi}.
std::vector<std::vector<double>> shifted_from_spectrum(RealFft& fft,
                                                       std::span<const Complex> spectrum,
                                                       std::span<const double> angles_rad) {
  std::vector<std::vector<double>> out;
  std::vector<Complex> shifted(spectrum.size());
  for (double phi : angles_rad) {
    for (std::size_t l = 0; l < spectrum.size(); ++l)
      shifted[l] = spectrum[l] * std::polar(1.0, static_cast<double>(l) * phi);
    out.push_back(fft.inverse(shifted));
  }
  return out;
}

// Band limit (max_harmonic) and FIR smoothing of a finished profile, in the spectrum.
void post_filter(RealFft& fft, std::vector<double>& profile, const SeparationOptions& options) {
  const std::size_t n = profile.size();
  const int limit = harmonic_limit(options.max_harmonic, n);
  if (limit >= static_cast<int>(n / 2) && !options.fir) return;
  std::vector<Complex> spectrum = fft.forward(profile);
  const std::vector<double> h = options.fir ? fir_response(*options.fir, n) : std::vector<double>{};
  for (std::size_t l = 0; l < spectrum.size(); ++l) {
    if (static_cast<int>(l) > limit) spectrum[l] = 0.0;
    if (options.fir) spectrum[l] *= h[l];
  }
  profile = fft.inverse(spectrum);
}

// The frequency-domain core shared by the three-point, n-point and two-point methods: R = S/G.
// Returns the separation without spindle motion and the full spectrum of r (mean included,
// unsmoothed) for the spindle step.
std::vector<Complex> divide_by_weight_function(RealFft& fft, std::span<const double> s,
                                               const ProbeLayout& layout,
                                               const SeparationOptions& options, Separation& out) {
  const std::size_t n = s.size();
  const int limit = harmonic_limit(options.max_harmonic, n);
  const std::vector<Complex> s_spectrum = fft.forward(s);
  const std::vector<Complex> g = weight_function(layout, static_cast<int>(n / 2));
  const double zero = options.suppression_tolerance * sum_abs(layout.weights);

  std::vector<Complex> r(s_spectrum.size(), 0.0);
  out.mean_radius_known = std::abs(g[0]) > zero;
  if (out.mean_radius_known) r[0] = s_spectrum[0] / g[0];
  out.mean_radius = r[0].real() / static_cast<double>(n);
  for (std::size_t l = 2; l < r.size(); ++l) {
    if (static_cast<int>(l) > limit) continue;
    if (std::abs(g[l]) <= zero) {
      out.suppressed.push_back(static_cast<int>(l));
      continue;
    }
    r[l] = s_spectrum[l] / g[l];
  }
  out.first_harmonic = check_first_harmonic(s, options.validity_fraction);

  std::vector<Complex> profile_spectrum = r;
  profile_spectrum[0] = 0.0;
  if (options.fir) {
    const std::vector<double> h = fir_response(*options.fir, n);
    for (std::size_t l = 0; l < profile_spectrum.size(); ++l) profile_spectrum[l] *= h[l];
  }
  out.profile = fft.inverse(profile_spectrum);
  return r;
}

}  // namespace

std::vector<double> three_point_weights(std::span<const double> angles_rad) {
  if (angles_rad.size() != 3)
    throw std::invalid_argument("three-point weights need exactly three probe angles");
  const double phi0 = angles_rad[0], phi1 = angles_rad[1], phi2 = angles_rad[2];
  const double d = std::sin(phi2 - phi1);
  auto same_angle = [](double a, double b) { return std::abs(std::sin(0.5 * (a - b))) < 1e-12; };
  if (std::abs(d) < 1e-9 || same_angle(phi1, phi0) || same_angle(phi2, phi0))
    throw std::invalid_argument(
        "three-point weights: two probes are at the same angle or opposite each other "
        "(sin of an angle between probes is 0)");
  return {1.0, -std::sin(phi2 - phi0) / d, std::sin(phi1 - phi0) / d};
}

std::vector<double> balanced_weights(std::span<const double> angles_rad, int max_harmonic) {
  const std::size_t n = angles_rad.size();
  if (n < 3) throw std::invalid_argument("n-point weights need at least three probes");
  const int top = std::max(max_harmonic, 2);
  Eigen::MatrixXd constraints(2, static_cast<Eigen::Index>(n));
  for (std::size_t q = 0; q < n; ++q) {
    constraints(0, static_cast<Eigen::Index>(q)) = std::cos(angles_rad[q]);
    constraints(1, static_cast<Eigen::Index>(q)) = std::sin(angles_rad[q]);
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(constraints);
  const Eigen::MatrixXd basis = lu.kernel();  // n x (n - rank)
  if (basis.cols() == 0 || lu.rank() < 2)
    throw std::invalid_argument("n-point weights: the probe directions do not span the plane");
  const Eigen::Index rows = 2 * (top - 1);
  Eigen::MatrixXd a(rows, static_cast<Eigen::Index>(n));
  Eigen::VectorXd target = Eigen::VectorXd::Zero(rows);
  for (int l = 2; l <= top; ++l) {
    const Eigen::Index row = 2 * (l - 2);
    for (std::size_t q = 0; q < n; ++q) {
      a(row, static_cast<Eigen::Index>(q)) = std::cos(l * angles_rad[q]);
      a(row + 1, static_cast<Eigen::Index>(q)) = std::sin(l * angles_rad[q]);
    }
    target(row) = 1.0;  // G(l) close to 1 + 0j
  }
  const Eigen::VectorXd y = (a * basis).completeOrthogonalDecomposition().solve(target);
  const Eigen::VectorXd c = basis * y;
  std::vector<double> weights(c.data(), c.data() + c.size());
  double scale = weights[0];
  if (std::abs(scale) <= 1e-9 * c.cwiseAbs().maxCoeff()) scale = c.cwiseAbs().maxCoeff();
  if (!(std::abs(scale) > 0))
    throw std::invalid_argument("n-point weights: least squares gave zero weights");
  for (double& w : weights) w /= scale;
  return weights;
}

double spindle_residual(const ProbeLayout& layout) {
  double x = 0, y = 0;
  for (std::size_t q = 0; q < layout.weights.size(); ++q) {
    x += layout.weights[q] * std::cos(layout.angles_rad[q]);
    y += layout.weights[q] * std::sin(layout.angles_rad[q]);
  }
  return std::max(std::abs(x), std::abs(y)) / sum_abs(layout.weights);
}

std::vector<Complex> weight_function(const ProbeLayout& layout, int max_harmonic) {
  std::vector<Complex> g(static_cast<std::size_t>(std::max(max_harmonic, 0)) + 1, 0.0);
  for (std::size_t l = 0; l < g.size(); ++l)
    for (std::size_t q = 0; q < layout.weights.size(); ++q)
      g[l] += layout.weights[q] * std::polar(1.0, static_cast<double>(l) * layout.angles_rad[q]);
  return g;
}

Transfer transfer(const ProbeLayout& layout, int max_harmonic) {
  Transfer t;
  const double weight_norm = norm2(layout.weights);
  const auto g = weight_function(layout, max_harmonic);
  const double zero = 1e-13 * sum_abs(layout.weights);
  for (std::size_t l = 0; l < g.size(); ++l) {
    const double a = std::abs(g[l]) <= zero ? 0.0 : std::abs(g[l]);
    t.harmonic.push_back(static_cast<int>(l));
    t.g_abs.push_back(a);
    t.w.push_back(a > 0 ? 1.0 / a : std::numeric_limits<double>::infinity());
    t.q.push_back(a > 0 ? weight_norm / a : std::numeric_limits<double>::infinity());
  }
  return t;
}

std::vector<int> suppressed_harmonics(const ProbeLayout& layout, int max_harmonic,
                                      double tolerance) {
  std::vector<int> out;
  const auto g = weight_function(layout, max_harmonic);
  const double zero = tolerance * sum_abs(layout.weights);
  for (std::size_t l = 2; l < g.size(); ++l)
    if (std::abs(g[l]) <= zero) out.push_back(static_cast<int>(l));
  return out;
}

WorstTransfer worst_q(const ProbeLayout& layout, int max_harmonic, double suppression_tolerance,
                      int min_harmonic) {
  WorstTransfer worst;
  const Transfer t = transfer(layout, max_harmonic);
  const double zero = suppression_tolerance * sum_abs(layout.weights);
  for (std::size_t l = static_cast<std::size_t>(std::max(min_harmonic, 2)); l < t.q.size(); ++l) {
    if (t.g_abs[l] <= zero) {
      if (worst.lost++ == 0) worst.harmonic = static_cast<int>(l);
      continue;
    }
    if (t.q[l] > worst.seen_q) {
      worst.seen_q = t.q[l];
      worst.seen_harmonic = static_cast<int>(l);
    }
  }
  if (worst.lost > 0) {
    worst.q = std::numeric_limits<double>::infinity();
  } else {
    worst.q = worst.seen_q;
    worst.harmonic = worst.seen_harmonic;
  }
  return worst;
}

LostSpectrum lost_spectrum(std::span<const std::vector<double>> probes, const std::vector<int>& lost,
                           int min_harmonic, int max_harmonic) {
  const std::size_t n = common_length(probes);
  const int top = harmonic_limit(max_harmonic, n);
  LostSpectrum out;
  out.amplitude.assign(static_cast<std::size_t>(top) + 1, 0.0);
  RealFft fft(n);
  for (const auto& p : probes) {
    const auto spectrum = fft.forward(p);
    for (int l = 0; l <= top; ++l) {
      // One-sided amplitude: 2|X(l)|/N (|X(0)|/N and at N/2).
      const bool edge = l == 0 || 2 * static_cast<std::size_t>(l) == n;
      out.amplitude[static_cast<std::size_t>(l)] +=
          (edge ? 1.0 : 2.0) * std::abs(spectrum[static_cast<std::size_t>(l)]) / static_cast<double>(n) /
          static_cast<double>(probes.size());
    }
  }
  double band = 0.0, missing = 0.0;
  for (int l = std::max(min_harmonic, 2); l <= top; ++l) band += std::pow(out.amplitude[static_cast<std::size_t>(l)], 2);
  for (int l : lost)
    if (l >= min_harmonic && l <= top) {
      out.harmonics.push_back(l);
      missing += std::pow(out.amplitude[static_cast<std::size_t>(l)], 2);
    }
  out.lost_share = band > 0 ? missing / band : 0.0;
  return out;
}

FirDesign design_zero_phase_lowpass(double passband_upr, double stopband_upr,
                                    std::size_t samples_per_rev) {
  if (!(passband_upr > 0 && stopband_upr > passband_upr))
    throw std::invalid_argument(fmt::format("FIR: need 0 < passband ({}) < stopband ({}) [UPR]",
                                            passband_upr, stopband_upr));
  const double n = static_cast<double>(samples_per_rev);
  if (stopband_upr > n / 2)
    throw std::invalid_argument(fmt::format(
        "FIR: stopband {} UPR is above the Nyquist limit N/2 = {} UPR", stopband_upr, n / 2));
  auto length = static_cast<std::size_t>(std::ceil(3.3 * n / (stopband_upr - passband_upr)));
  if (length % 2 == 0) ++length;
  length = std::max<std::size_t>(length, 3);
  if (length > samples_per_rev)
    throw std::invalid_argument(fmt::format(
        "FIR: a transition band of {} UPR needs {} taps, more than the {} samples per revolution; "
        "widen it (stopband - passband >= {:.3g} UPR)",
        stopband_upr - passband_upr, length, samples_per_rev, 3.3));
  FirDesign fir;
  fir.passband_upr = passband_upr;
  fir.stopband_upr = stopband_upr;
  const double fc = 0.5 * (passband_upr + stopband_upr) / n;  // cycles per sample
  const auto half = static_cast<long>(length / 2);
  for (long k = -half; k <= half; ++k) {
    const double x = two_pi * fc * static_cast<double>(k);
    const double sinc =
        k == 0 ? 2.0 * fc : std::sin(x) / (std::numbers::pi * static_cast<double>(k));
    const double window = 0.54 + 0.46 * std::cos(std::numbers::pi * static_cast<double>(k) /
                                                 static_cast<double>(half));
    fir.taps.push_back(sinc * window);
  }
  // Not renormalised to a DC gain of exactly 1: that would shift the whole passband by the
  // ripple at l = 0 and double the worst passband error.
  return fir;
}

std::vector<double> fir_response(const FirDesign& fir, std::size_t samples_per_rev) {
  const std::size_t n = samples_per_rev;
  const std::size_t half = fir.taps.size() / 2;
  if (fir.taps.size() > n) throw std::invalid_argument("FIR longer than one revolution");
  std::vector<double> wrapped(n, 0.0);
  for (std::size_t k = 0; k <= half; ++k) {
    wrapped[k] += fir.taps[half + k];
    if (k > 0) wrapped[n - k] += fir.taps[half - k];
  }
  RealFft fft(n);
  const auto spectrum = fft.forward(wrapped);
  std::vector<double> h(spectrum.size());
  for (std::size_t l = 0; l < h.size(); ++l) h[l] = spectrum[l].real();  // symmetric: real
  return h;
}

std::vector<double> average_revolutions(std::span<const double> values, std::size_t n) {
  if (n == 0 || values.empty() || values.size() % n != 0)
    throw std::invalid_argument(fmt::format(
        "{} samples are not a whole number of revolutions of {} samples", values.size(), n));
  const std::size_t m = values.size() / n;
  std::vector<double> mean(n, 0.0);
  for (std::size_t rev = 0; rev < m; ++rev)
    for (std::size_t i = 0; i < n; ++i) mean[i] += values[rev * n + i];
  for (double& v : mean) v /= static_cast<double>(m);
  return mean;
}

double Separation::roundness() const { return profile.empty() ? 0.0 : range_of(profile); }

std::vector<double> combine(std::span<const std::vector<double>> probes,
                            std::span<const double> weights) {
  const std::size_t n = common_length(probes);
  if (weights.size() != probes.size())
    throw std::invalid_argument("error separation: one weight per probe needed");
  std::vector<double> s(n, 0.0);
  for (std::size_t q = 0; q < probes.size(); ++q)
    for (std::size_t i = 0; i < n; ++i) s[i] += weights[q] * probes[q][i];
  return s;
}

Separation separate_frequency(std::span<const std::vector<double>> probes,
                              const ProbeLayout& layout, const SeparationOptions& options) {
  const std::size_t n = common_length(probes);
  if (layout.angles_rad.size() != probes.size())
    throw std::invalid_argument("error separation: one angle per probe needed");
  RealFft fft(n);
  Separation out;
  const std::vector<double> s = combine(probes, layout.weights);
  const std::vector<Complex> r = divide_by_weight_function(fft, s, layout, options, out);
  spindle_motion(probes, layout.angles_rad, shifted_from_spectrum(fft, r, layout.angles_rad), out);
  return out;
}

namespace {

// The sample offsets of a time-recursion layout (0, p, 2p after the first probe's p0), checked:
// whole samples, equally spaced, and gcd(p, N) = 1 so that the chain k -> k p visits every sample.
struct RecursionOffsets {
  long first = 0;    // p0
  long spacing = 0;  // p
  long chain = 0;    // p mod N, the step of the recursion's chain
};

RecursionOffsets recursion_offsets(const ProbeLayout& layout, std::size_t n) {
  const double samples_per_rad = static_cast<double>(n) / two_pi;
  auto whole_samples = [&](double angle) {
    const double p = angle * samples_per_rad;
    if (std::abs(p - std::round(p)) > 1e-6)
      throw std::invalid_argument(fmt::format(
          "time recursion: probe offset {:.6g} samples is not a whole number of samples", p));
    return static_cast<long>(std::llround(p));
  };
  RecursionOffsets o;
  o.first = whole_samples(layout.angles_rad[0]);
  o.spacing = whole_samples(layout.angles_rad[1] - layout.angles_rad[0]);
  const long p2 = whole_samples(layout.angles_rad[2] - layout.angles_rad[0]);
  const long nl = static_cast<long>(n);
  if (p2 != 2 * o.spacing)
    throw std::invalid_argument(fmt::format(
        "time recursion: probes must be equally spaced (offsets 0, p, 2p); got 0, {}, {}", o.spacing, p2));
  o.chain = ((o.spacing % nl) + nl) % nl;
  if (std::gcd(o.chain, nl) != 1)
    throw std::invalid_argument(fmt::format(
        "time recursion: probe offset p = {} and N = {} share the factor {} (need gcd(p, N) = 1)",
        o.spacing, n, std::gcd(o.chain, nl)));
  return o;
}

// r'(k + 2) = S(k) + 2 cos(phi) r'(k + 1) - r'(k) along the chain k -> k p (E4), restarted from
// its own end values until it closes on itself (the recursion is periodic with period N).
// Returns r'(i) = r(i + p0).
std::vector<double> close_recursion(const std::vector<double>& s, double two_cos, long chain,
                                    const SeparationOptions& options, Separation& out) {
  const std::size_t n = s.size();
  const long nl = static_cast<long>(n);
  const double tolerance = 1e-13 * static_cast<double>(n) * std::max(range_of(s), 1e-300);
  std::vector<double> rp(n, 0.0);
  auto at = [&](long k) { return static_cast<std::size_t>((k * chain) % nl); };  // chain sample k
  double start0 = 0.0, start1 = 0.0;
  bool closed = false;
  for (int pass = 1; pass <= options.max_recursion_passes && !closed; ++pass) {
    rp[at(0)] = start0;
    rp[at(1)] = start1;
    for (long k = 0; k + 2 < nl; ++k)
      rp[at(k + 2)] = s[at(k)] + two_cos * rp[at(k + 1)] - rp[at(k)];
    const double next0 = s[at(nl - 2)] + two_cos * rp[at(nl - 1)] - rp[at(nl - 2)];
    const double next1 = s[at(nl - 1)] + two_cos * next0 - rp[at(nl - 1)];
    closed = std::max(std::abs(next0 - start0), std::abs(next1 - start1)) <= tolerance;
    start0 = next0;
    start1 = next1;
    out.recursion_passes = pass;
  }
  if (!closed)
    throw std::runtime_error(
        fmt::format("time recursion did not close after {} passes", options.max_recursion_passes));
  return rp;
}

}  // namespace

Separation separate_time_recursion(std::span<const std::vector<double>> probes,
                                   const ProbeLayout& layout, const SeparationOptions& options) {
  const std::size_t n = common_length(probes);
  if (probes.size() != 3 || layout.angles_rad.size() != 3)
    throw std::invalid_argument("time recursion needs exactly three probes");
  const RecursionOffsets offsets = recursion_offsets(layout, n);
  const long nl = static_cast<long>(n), p0 = offsets.first;

  // Weights (1, -2 cos phi, 1) of the layout (0, phi, 2 phi), phi = 2 pi p / N (E4).
  const double phi = two_pi * static_cast<double>(offsets.chain) / static_cast<double>(n);
  const double two_cos = 2.0 * std::cos(phi);
  Separation out;
  std::vector<double> s = combine(probes, std::vector<double>{1.0, -two_cos, 1.0});
  out.first_harmonic = check_first_harmonic(s, options.validity_fraction);
  // S has no first harmonic in theory; a measured one would drive the marginally stable
  // recursion at resonance (a drift growing with every step), so it is removed first.
  s = remove_first_harmonic(s);
  const std::vector<double> rp = close_recursion(s, two_cos, offsets.chain, options, out);

  std::vector<double> r(n);
  for (long i = 0; i < nl; ++i)
    r[static_cast<std::size_t>(i)] = rp[static_cast<std::size_t>((((i - p0) % nl) + nl) % nl)];
  out.mean_radius = std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(n);
  // The starting values added a first harmonic (homogeneous solution): remove it with the
  // least-squares centre before the spindle step, as the frequency method has R(1) = 0.
  for (double& v : r) v -= out.mean_radius;
  r = remove_first_harmonic(r);
  out.profile = r;
  for (double& v : r) v += out.mean_radius;
  std::vector<double> shifted_profiles[3];
  for (std::size_t q = 0; q < 3; ++q) {
    const long offset = p0 + static_cast<long>(q) * offsets.spacing;
    shifted_profiles[q].resize(n);
    for (long i = 0; i < nl; ++i)
      shifted_profiles[q][static_cast<std::size_t>(i)] =
          r[static_cast<std::size_t>((((i + offset) % nl) + nl) % nl)];
  }
  spindle_motion(probes, layout.angles_rad, shifted_profiles, out);

  RealFft fft(n);
  post_filter(fft, out.profile, options);
  ProbeLayout recursion_layout{layout.angles_rad, {1.0, -two_cos, 1.0}};
  out.suppressed = suppressed_harmonics(recursion_layout, harmonic_limit(options.max_harmonic, n),
                                        options.suppression_tolerance);
  return out;
}

ProbeLayout two_point_layout(double phi0_rad, std::size_t samples_per_rev) {
  const double step = two_pi / static_cast<double>(samples_per_rev);
  ProbeLayout layout;
  layout.angles_rad = {phi0_rad, phi0_rad + std::numbers::pi / 2,
                       phi0_rad + std::numbers::pi - step};
  layout.weights = three_point_weights(layout.angles_rad);
  return layout;
}

Separation separate_two_point(std::span<const std::vector<double>> probes, double phi0_rad,
                              const SeparationOptions& options) {
  const std::size_t n = common_length(probes);
  if (probes.size() != 2) throw std::invalid_argument("two-point separation needs two probes");
  const ProbeLayout layout = two_point_layout(phi0_rad, n);
  RealFft fft(n);
  Separation out;
  // S^ = A + c C: the middle probe's weight b = -tan(2 pi/N) is dropped (book 6-52).
  const std::vector<double> s = combine(probes, std::vector<double>{1.0, layout.weights[2]});
  const std::vector<Complex> r = divide_by_weight_function(fft, s, layout, options, out);
  const std::vector<double> angles{layout.angles_rad[0], layout.angles_rad[2]};
  spindle_motion(probes, angles, shifted_from_spectrum(fft, r, angles), out);
  return out;
}

std::vector<double> remove_first_harmonic(std::span<const double> profile) {
  const Complex c = first_coefficient(profile);
  const double n = static_cast<double>(profile.size());
  const double a = 2.0 * c.real() / n, b = -2.0 * c.imag() / n;
  std::vector<double> out(profile.begin(), profile.end());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double theta = two_pi * static_cast<double>(i) / n;
    out[i] -= a * std::cos(theta) + b * std::sin(theta);
  }
  return out;
}

AngleOptimum optimise_three_point_angles(std::size_t samples_per_rev, int max_harmonic,
                                         double max_span_rad, double suppression_tolerance,
                                         int min_harmonic) {
  AngleOptimum best;
  const std::size_t n = samples_per_rev;
  const std::size_t step = std::max<std::size_t>(1, n / 360);
  const auto span = static_cast<std::size_t>(
      std::floor(std::min(max_span_rad, two_pi) / two_pi * static_cast<double>(n)));
  const int top = harmonic_limit(max_harmonic, n);
  std::vector<Complex> g;
  for (std::size_t p1 = step; p1 < span; p1 += step) {
    for (std::size_t p2 = p1 + step; p2 <= span && p2 < n; p2 += step) {
      const std::vector<double> angles{0.0,
                                       two_pi * static_cast<double>(p1) / static_cast<double>(n),
                                       two_pi * static_cast<double>(p2) / static_cast<double>(n)};
      std::vector<double> c;
      try {
        c = three_point_weights(angles);
      } catch (const std::invalid_argument&) {
        continue;  // collinear layout
      }
      ++best.layouts_checked;
      const double zero = suppression_tolerance * sum_abs(c);
      const double weight_norm = norm2(c);
      // G(l) by rotation: e^{j (l+1) phi} = e^{j l phi} e^{j phi}.
      const int first = std::max(min_harmonic, 2);
      const Complex step1 = std::polar(1.0, angles[1]), step2 = std::polar(1.0, angles[2]);
      Complex e1 = std::polar(1.0, first * angles[1]), e2 = std::polar(1.0, first * angles[2]);
      WorstTransfer worst;
      bool ok = true;
      for (int l = first; l <= top; ++l) {
        const double a = std::abs(c[0] + c[1] * e1 + c[2] * e2);
        if (a <= zero) {
          ok = false;
          break;
        }
        if (weight_norm / a > worst.q) {
          worst.q = worst.seen_q = weight_norm / a;
          worst.harmonic = worst.seen_harmonic = l;
        }
        if (best.found && worst.q >= best.worst.q) {
          ok = false;  // already worse than the best layout
          break;
        }
        e1 *= step1;
        e2 *= step2;
      }
      if (!ok) continue;
      best.found = true;
      best.worst = worst;
      best.angles_rad = angles;
    }
  }
  return best;
}

std::vector<double> suppression_map(double phi1_rad, std::span<const double> phi2_rad,
                                    int max_harmonic) {
  std::vector<double> z;
  for (double phi2 : phi2_rad) {
    ProbeLayout layout;
    layout.angles_rad = {0.0, phi1_rad, phi2};
    bool degenerate = false;
    try {
      layout.weights = three_point_weights(layout.angles_rad);
    } catch (const std::invalid_argument&) {
      degenerate = true;
    }
    const auto g = degenerate ? std::vector<Complex>{} : weight_function(layout, max_harmonic);
    const double scale = degenerate ? 1.0 : sum_abs(layout.weights);
    for (int l = 2; l <= max_harmonic; ++l)
      z.push_back(degenerate ? std::numeric_limits<double>::quiet_NaN()
                             : std::abs(g[static_cast<std::size_t>(l)]) / scale);
  }
  return z;
}

}  // namespace chatterlab::error_separation
