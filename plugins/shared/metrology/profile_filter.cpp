#include "shared/metrology/profile_filter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "chatterlab/fft.hpp"

namespace chatterlab::surface {
namespace {

using Complex = std::complex<double>;

// Smallest n >= target whose prime factors are 2, 3, 5, 7 (FFTW's fast sizes).
std::size_t fast_fft_size(std::size_t target) {
  for (std::size_t n = std::max<std::size_t>(target, 1);; ++n) {
    std::size_t m = n;
    for (std::size_t p : {2u, 3u, 5u, 7u})
      while (m % p == 0) m /= p;
    if (m == 1) return n;
  }
}

// Local polynomial regression (order 1 or 2) of z with Gaussian weights exp(-pi (u/c)^2),
// u = offset / cutoff, times per-sample weights delta: the value of the fitted polynomial at
// u = 0. The normal equations need the moment sums
//   S_p(i) = sum_m delta[i+m] g_p(m), p = 0..2 order,   T_p(i) = sum_m (delta z)[i+m] g_p(m),
//   p = 0..order, with g_p(m) = w(m) u^p, m in [-H, H],
// i.e. correlations of two signals with fixed kernels, done by FFT (overlap-save). Open profiles
// are zero outside [0, N); closed profiles are periodic.
//
// Long profiles are cut into blocks of B outputs, each transformed at a fixed length M = B + 2H
// (tens of thousands of samples): per block 2 forward and 2 order + 1 + order + 1 inverse real
// transforms share one plan and one set of kernel spectra, and the 3x3 (2x2) solve runs while the
// block's moment sums are still in cache. The arithmetic is that of one transform of the whole
// profile (B / M ~ 80-90 % useful outputs against log M / log N fewer operations per sample), but
// the working set stays in the processor's cache instead of streaming eight million-sample
// arrays through memory per pass (docs/performance.md, "Surface metrology").
class GaussianRegression {
 public:
  GaussianRegression(std::size_t n, double cutoff_samples, double constant, int order,
                     double half_width_cutoffs, bool periodic)
      : n_(n),
        order_(order),
        periodic_(periodic),
        half_width_(static_cast<std::ptrdiff_t>(std::ceil(half_width_cutoffs * cutoff_samples))),
        fft_(transform_length()) {
    const auto length = static_cast<std::ptrdiff_t>(fft_.size());
    std::vector<double> k(fft_.size());
    for (int p = 0; p <= 2 * order; ++p) {
      // Kernel array k[j] = g_p(-j) (wrapped), so that the circular convolution y * k is the
      // correlation with g_p.
      std::fill(k.begin(), k.end(), 0.0);
      std::vector<double> cumulative;
      cumulative.reserve(static_cast<std::size_t>(2 * half_width_ + 1));
      double running = 0.0;
      for (std::ptrdiff_t m = -half_width_; m <= half_width_; ++m) {
        const double u = static_cast<double>(m) / cutoff_samples;
        const double g = std::exp(-std::numbers::pi * (u / constant) * (u / constant)) * std::pow(u, p);
        const std::ptrdiff_t j = ((-m) % length + length) % length;
        k[static_cast<std::size_t>(j)] += g;
        cumulative.push_back(running += g);
      }
      cumulative_.push_back(std::move(cumulative));
      // g_p is even for even p (real spectrum) and odd for odd p (imaginary spectrum): one real
      // number per bin, the other part is rounding noise of the transform.
      const auto spectrum = fft_.forward(k);
      std::vector<double> part(spectrum.size());
      for (std::size_t b = 0; b < part.size(); ++b)
        part[b] = p % 2 == 0 ? spectrum[b].real() : spectrum[b].imag();
      kernels_.push_back(std::move(part));
    }
    const std::size_t m = fft_.size();
    delta_block_.resize(m);
    weighted_block_.resize(m);
    delta_spectrum_.resize(fft_.spectrum_size());
    weighted_spectrum_.resize(fft_.spectrum_size());
    product_.resize(fft_.spectrum_size());
    s_.assign(static_cast<std::size_t>(2 * order + 1), std::vector<double>(m));
    t_.assign(static_cast<std::size_t>(order + 1), std::vector<double>(m));
  }

  // The fitted values into `out` (resized to N; must not be `fallback`, the value where the
  // normal equations fail).
  void fit(std::span<const double> z, const std::vector<double>& delta,
           std::span<const double> fallback, std::vector<double>& out) {
    out.resize(n_);
    for (std::size_t first = 0; first < n_; first += outputs_per_block_)
      fit_block(z, &delta, fallback, first, std::min(outputs_per_block_, n_ - first), out);
  }
  // The same with every delta = 1 (the Gaussian filter, the robust filter's first pass): the
  // sums S_p are then sums of g_p over the part of the window inside the profile, taken from
  // cumulative sums of the kernel instead of 2 order + 2 transforms per block.
  void fit_unit_weights(std::span<const double> z, std::vector<double>& out) {
    out.resize(n_);
    for (std::size_t first = 0; first < n_; first += outputs_per_block_)
      fit_block(z, nullptr, z, first, std::min(outputs_per_block_, n_ - first), out);
  }

 private:
  // Transform length M, and outputs_per_block_ B and lead_ (input sample y[0] = x[first - lead]).
  // A whole profile in one transform when it is short: open, M >= N + H (the zero padding keeps
  // the wrap-around out of [0, N)); closed, M = N (the kernel wraps with the profile). Otherwise
  // blocks: M >= B + 2H, M a power of two >= 8 (2H + 1), at least 2^15.
  std::size_t transform_length() {
    const auto h = static_cast<std::size_t>(half_width_);
    std::size_t block = std::size_t{1} << 15;
    while (block < 8 * (2 * h + 1)) block *= 2;
    if (periodic_ ? n_ <= block : n_ + h <= block) {
      lead_ = 0;
      outputs_per_block_ = n_;
      return periodic_ ? n_ : fast_fft_size(n_ + h);
    }
    lead_ = half_width_;
    outputs_per_block_ = block - 2 * h;
    return block;
  }

  // S_p of unit weights for the block's outputs (at y index q + lead).
  void unit_weight_moments(std::size_t first, std::size_t count) {
    const auto h = half_width_;
    const auto n = static_cast<std::ptrdiff_t>(n_);
    for (std::size_t p = 0; p < s_.size(); ++p) {
      const std::vector<double>& c = cumulative_[p];
      for (std::size_t q = 0; q < count; ++q) {
        const auto i = static_cast<std::ptrdiff_t>(first + q);
        // Window offsets m in [lo, hi] with 0 <= i + m < N (all of them on a closed profile).
        const std::ptrdiff_t lo = periodic_ ? -h : std::max(-h, -i);
        const std::ptrdiff_t hi = periodic_ ? h : std::min(h, n - 1 - i);
        s_[p][q + static_cast<std::size_t>(lead_)] =
            c[static_cast<std::size_t>(hi + h)] - (lo > -h ? c[static_cast<std::size_t>(lo - 1 + h)] : 0.0);
      }
    }
  }

  // delta == nullptr: unit weights.
  void fit_block(std::span<const double> z, const std::vector<double>* delta,
                 std::span<const double> fallback, std::size_t first, std::size_t count,
                 std::vector<double>& out) {
    const std::size_t m = fft_.size();
    // Inputs y[j] = x[first - lead + j] for the samples the block's outputs reach, zero beyond
    // (open profile) or wrapped (closed).
    const std::size_t reach = std::min(m, count + 2 * static_cast<std::size_t>(lead_));
    const auto n = static_cast<std::ptrdiff_t>(n_);
    std::ptrdiff_t source = static_cast<std::ptrdiff_t>(first) - lead_;
    if (periodic_) source = (source % n + n) % n;
    for (std::size_t j = 0; j < m; ++j, ++source) {
      if (periodic_ && source == n) source = 0;
      const bool inside = j < reach && source >= 0 && source < n;
      const auto at = static_cast<std::size_t>(inside ? source : 0);
      const double weight = delta ? (*delta)[at] : 1.0;
      delta_block_[j] = inside ? weight : 0.0;
      weighted_block_[j] = inside ? weight * z[at] : 0.0;
    }
    fft_.forward(weighted_block_, weighted_spectrum_);
    auto correlate = [&](const std::vector<Complex>& spectrum, std::size_t p,
                         std::vector<double>& sums) {
      const std::vector<double>& kernel = kernels_[p];
      if (p % 2 == 0) {
        for (std::size_t k = 0; k < product_.size(); ++k) product_[k] = spectrum[k] * kernel[k];
      } else {  // times j kernel[k]
        for (std::size_t k = 0; k < product_.size(); ++k)
          product_[k] = {-spectrum[k].imag() * kernel[k], spectrum[k].real() * kernel[k]};
      }
      fft_.inverse(product_, sums);
    };
    if (delta) {
      fft_.forward(delta_block_, delta_spectrum_);
      for (std::size_t p = 0; p < s_.size(); ++p) correlate(delta_spectrum_, p, s_[p]);
    } else {
      unit_weight_moments(first, count);
    }
    for (std::size_t p = 0; p < t_.size(); ++p) correlate(weighted_spectrum_, p, t_[p]);

    const auto& s = s_;
    const auto& t = t_;
    const auto offset = static_cast<std::size_t>(lead_);  // output i sits at y index i - first + lead
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t i = first + q, b = q + offset;
      double value;
      if (order_ == 1) {
        const double det = s[0][b] * s[2][b] - s[1][b] * s[1][b];
        value = (t[0][b] * s[2][b] - t[1][b] * s[1][b]) / det;
        if (!(std::abs(det) > 1e-12 * s[0][b] * s[2][b])) value = t[0][b] / s[0][b];
      } else {
        // Cramer's rule for the 3x3 normal equations; a = det(M with column 0 = t) / det(M).
        const double s0 = s[0][b], s1 = s[1][b], s2 = s[2][b], s3 = s[3][b], s4 = s[4][b];
        const double det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) +
                           s2 * (s1 * s3 - s2 * s2);
        const double num = t[0][b] * (s2 * s4 - s3 * s3) - s1 * (t[1][b] * s4 - s3 * t[2][b]) +
                           s2 * (t[1][b] * s3 - s2 * t[2][b]);
        value = num / det;
        // Too few weighted samples for a parabola (outliers cleared a window): local mean.
        if (!(std::abs(det) > 1e-12 * s0 * s2 * s4)) value = t[0][b] / s0;
      }
      if (!std::isfinite(value)) value = fallback[i];
      out[i] = value;
    }
  }

  std::size_t n_;
  int order_;
  bool periodic_;
  std::ptrdiff_t half_width_;
  std::ptrdiff_t lead_ = 0;
  std::size_t outputs_per_block_ = 0;
  RealFft fft_;
  std::vector<std::vector<double>> kernels_;  // Re (even p) or Im (odd p) of the spectrum of g_p
  std::vector<std::vector<double>> cumulative_;  // [p][m + H] = sum of g_p over [-H, m]
  // Work buffers of one block, kept between blocks and passes.
  std::vector<double> delta_block_, weighted_block_;
  std::vector<Complex> delta_spectrum_, weighted_spectrum_, product_;
  std::vector<std::vector<double>> s_, t_;
};

// In place in one padded buffer (8 bytes per sample beside the profile: a 10^7-sample revolution
// is filtered within issue 23's 48 bytes per sample), which becomes the mean line.
std::vector<double> closed_gaussian(std::span<const double> z, double cutoff_samples) {
  const std::size_t n = z.size();
  InPlaceRealFft fft(z);
  fft.forward();
  const double cutoff_upr = static_cast<double>(n) / cutoff_samples;
  const std::span<Complex> spectrum = fft.spectrum();
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double ratio = gaussian_alpha * static_cast<double>(k) / cutoff_upr;
    spectrum[k] *= std::exp(-std::numbers::pi * ratio * ratio);
  }
  fft.inverse();
  return fft.take_samples();
}

// Median of |r| (the element of rank N/2, as std::nth_element would pick it), using `scratch` as
// work space. Exact and O(N) with a small constant: a histogram of |r| over [0, max |r|] finds the
// bin holding that rank (the bin index floor(|r| * bins / max) never decreases with |r|), and
// only that bin's values are selected; on million-sample profiles this is several times faster
// than nth_element over all of them, and it runs once per reweighting pass.
double median_abs(const std::vector<double>& r, std::vector<double>& scratch) {
  const std::size_t rank = r.size() / 2;
  double top = 0.0;
  for (double v : r) top = std::max(top, std::abs(v));
  constexpr std::size_t bins = 4096;
  const double scale = static_cast<double>(bins) / top;
  auto bin_of = [&](double v) {
    return std::min(bins - 1, static_cast<std::size_t>(std::abs(v) * scale));
  };
  scratch.clear();
  if (top > 0.0 && std::isfinite(scale)) {
    std::array<std::size_t, bins> count{};
    for (double v : r) ++count[bin_of(v)];
    std::size_t below = 0, bin = 0;
    while (below + count[bin] <= rank) below += count[bin++];
    for (double v : r)
      if (bin_of(v) == bin) scratch.push_back(std::abs(v));
    auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(rank - below);
    std::nth_element(scratch.begin(), mid, scratch.end());
    return *mid;
  }
  for (double v : r) scratch.push_back(std::abs(v));  // all zero, or not finite
  auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(rank);
  std::nth_element(scratch.begin(), mid, scratch.end());
  return *mid;
}

FilterResult robust_regression(std::span<const double> z, const FilterSettings& settings) {
  const std::size_t n = z.size();
  GaussianRegression regression(n, settings.cutoff_samples, regression_gamma, 2, 2.0,
                                settings.closed);
  const auto [lo, hi] = std::minmax_element(z.begin(), z.end());
  const double range = *hi - *lo;
  double mean = 0, square = 0;
  for (double v : z) mean += v;
  mean /= static_cast<double>(n);
  for (double v : z) square += (v - mean) * (v - mean);
  const double c_floor = 1e-3 * std::sqrt(square / static_cast<double>(n));
  // Buffers reused by every pass (fresh million-sample vectors cost page faults). `work` holds
  // the residuals until the weights are made from them, then the next mean line: one array less
  // on profiles of 10^7 samples.
  std::vector<double> delta(n, 1.0), work(n), scratch;
  FilterResult result;
  regression.fit_unit_weights(z, result.waviness);
  result.converged = false;
  for (result.iterations = 1; result.iterations < settings.max_iterations;) {
    std::vector<double>& residual = work;
    for (std::size_t i = 0; i < n; ++i) residual[i] = z[i] - result.waviness[i];
    // Residuals below 0.1 % of the profile's rms are the regression's own bias on a smooth
    // profile, not outliers: reweighting them makes the mean line wander without converging,
    // so the biweight scale is floored there.
    const double c = std::max(tukey_c_over_median * median_abs(residual, scratch), c_floor);
    if (!(c > 0.0)) {  // a constant profile: nothing to reweight
      result.converged = true;
      break;
    }
    result.zero_weight_samples = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double q = residual[i] / c;
      delta[i] = std::abs(q) < 1.0 ? (1 - q * q) * (1 - q * q) : 0.0;
      result.zero_weight_samples += delta[i] == 0.0 ? 1 : 0;
    }
    std::vector<double>& next = work;  // the residuals are no longer needed
    regression.fit(z, delta, result.waviness, next);
    double change = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      change = std::max(change, std::abs(next[i] - result.waviness[i]));
    std::swap(result.waviness, next);
    ++result.iterations;
    if (change <= settings.relative_tolerance * range) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace

std::string to_string(FilterType type) {
  return type == FilterType::gaussian ? "gaussian" : "robust_gaussian";
}

FilterResult filter_profile(std::span<const double> profile, const FilterSettings& settings) {
  if (profile.size() < 4) throw std::invalid_argument("filter_profile: fewer than 4 samples");
  if (!(settings.cutoff_samples > 0.0 && std::isfinite(settings.cutoff_samples)))
    throw std::invalid_argument("filter_profile: cut-off must be positive");
  if (settings.type == FilterType::robust_gaussian) return robust_regression(profile, settings);
  FilterResult result;
  if (settings.closed) {
    result.waviness = closed_gaussian(profile, settings.cutoff_samples);
  } else {
    // Order-1 regression = Gaussian inside, moment-retaining at the ends (ISO 16610-28).
    GaussianRegression regression(profile.size(), settings.cutoff_samples, gaussian_alpha, 1, 1.5,
                                  false);
    regression.fit_unit_weights(profile, result.waviness);
  }
  return result;
}

double waviness_transmission(FilterType type, double lambda_over_cutoff) {
  const double x = 1.0 / lambda_over_cutoff;
  if (type == FilterType::gaussian)
    return std::exp(-std::numbers::pi * gaussian_alpha * gaussian_alpha * x * x);
  const double t = std::numbers::pi * regression_gamma * regression_gamma * x * x;
  return (1 + t) * std::exp(-t);
}

}  // namespace chatterlab::surface
