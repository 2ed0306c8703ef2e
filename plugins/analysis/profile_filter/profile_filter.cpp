#include "analysis/profile_filter/profile_filter.hpp"

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

// Correlations S(i) = sum_m x[i + m] g(m), m in [-H, H], of several signals with several fixed
// kernels, by FFT. Open profiles: x is zero outside [0, N) (transform length >= N + H, so no
// wrap-around reaches [0, N)). Closed profiles: x is periodic (length N, kernel wrapped).
class KernelCorrelator {
 public:
  KernelCorrelator(std::size_t n, std::ptrdiff_t half_width, bool periodic)
      : n_(n),
        length_(periodic ? n : fast_fft_size(n + static_cast<std::size_t>(half_width))),
        half_width_(half_width),
        fft_(length_) {}

  // Spectrum of the kernel array k[j] = g(-j) (so that x * k is the correlation with g).
  template <class Kernel>
  std::vector<Complex> kernel_spectrum(Kernel g) {
    std::vector<double> k(length_, 0.0);
    const auto length = static_cast<std::ptrdiff_t>(length_);
    for (std::ptrdiff_t m = -half_width_; m <= half_width_; ++m) {
      std::ptrdiff_t j = ((-m) % length + length) % length;
      k[static_cast<std::size_t>(j)] += g(m);
    }
    return fft_.forward(k);
  }

  // Spectrum of x zero-padded to the transform length, into `spectrum` (reused buffers: these
  // run 10 times per pass on million-sample profiles, where fresh pages cost as much as FFTs).
  void signal_spectrum(const std::vector<double>& x, std::vector<Complex>& spectrum) {
    padded_.assign(length_, 0.0);
    std::copy(x.begin(), x.end(), padded_.begin());
    spectrum.resize(fft_.spectrum_size());
    fft_.forward(padded_, spectrum);
  }

  // The first N samples of x * k from their spectra, into `out`.
  void correlate(const std::vector<Complex>& x_spectrum, const std::vector<Complex>& kernel_spectrum,
                 std::vector<double>& out) {
    product_.resize(x_spectrum.size());
    for (std::size_t k = 0; k < product_.size(); ++k)
      product_[k] = x_spectrum[k] * kernel_spectrum[k];
    padded_.resize(length_);
    fft_.inverse(product_, padded_);
    out.assign(padded_.begin(), padded_.begin() + static_cast<std::ptrdiff_t>(n_));
  }

 private:
  std::size_t n_, length_;
  std::ptrdiff_t half_width_;
  RealFft fft_;
  std::vector<double> padded_;
  std::vector<Complex> product_;
};

// Local polynomial regression (order 1 or 2) of z with Gaussian weights exp(-pi (u/c)^2),
// u = offset / cutoff, times per-sample weights delta: the value of the fitted polynomial at
// u = 0. Moment kernels g_p(m) = w(m) u^p, p = 0..2 order.
class GaussianRegression {
 public:
  GaussianRegression(std::size_t n, double cutoff_samples, double constant, int order,
                     double half_width_cutoffs, bool periodic)
      : order_(order),
        correlator_(n, static_cast<std::ptrdiff_t>(std::ceil(half_width_cutoffs * cutoff_samples)),
                    periodic) {
    for (int p = 0; p <= 2 * order; ++p) {
      kernels_.push_back(correlator_.kernel_spectrum([&](std::ptrdiff_t m) {
        const double u = static_cast<double>(m) / cutoff_samples;
        return std::exp(-std::numbers::pi * (u / constant) * (u / constant)) * std::pow(u, p);
      }));
    }
  }

  std::vector<double> fit(const std::vector<double>& z, const std::vector<double>& delta,
                          const std::vector<double>& fallback) {
    const std::size_t n = z.size();
    std::vector<double> weighted(n);
    for (std::size_t i = 0; i < n; ++i) weighted[i] = delta[i] * z[i];
    correlator_.signal_spectrum(delta, delta_spectrum_);
    correlator_.signal_spectrum(weighted, weighted_spectrum_);
    auto& s = moments_;
    auto& t = weighted_moments_;
    s.resize(static_cast<std::size_t>(2 * order_ + 1));
    t.resize(static_cast<std::size_t>(order_ + 1));
    for (std::size_t p = 0; p < s.size(); ++p) correlator_.correlate(delta_spectrum_, kernels_[p], s[p]);
    for (std::size_t p = 0; p < t.size(); ++p)
      correlator_.correlate(weighted_spectrum_, kernels_[p], t[p]);

    std::vector<double> out(n);
    for (std::size_t i = 0; i < n; ++i) {
      double value;
      if (order_ == 1) {
        const double det = s[0][i] * s[2][i] - s[1][i] * s[1][i];
        value = (t[0][i] * s[2][i] - t[1][i] * s[1][i]) / det;
        if (!(std::abs(det) > 1e-12 * s[0][i] * s[2][i])) value = t[0][i] / s[0][i];
      } else {
        // Cramer's rule for the 3x3 normal equations; a = det(M with column 0 = t) / det(M).
        const double s0 = s[0][i], s1 = s[1][i], s2 = s[2][i], s3 = s[3][i], s4 = s[4][i];
        const double det = s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) +
                           s2 * (s1 * s3 - s2 * s2);
        const double num = t[0][i] * (s2 * s4 - s3 * s3) - s1 * (t[1][i] * s4 - s3 * t[2][i]) +
                           s2 * (t[1][i] * s3 - s2 * t[2][i]);
        value = num / det;
        // Too few weighted samples for a parabola (outliers cleared a window): local mean.
        if (!(std::abs(det) > 1e-12 * s0 * s2 * s4)) value = t[0][i] / s0;
      }
      if (!std::isfinite(value)) value = fallback[i];
      out[i] = value;
    }
    return out;
  }

 private:
  int order_;
  KernelCorrelator correlator_;
  std::vector<std::vector<Complex>> kernels_;
  // Work buffers kept between passes of the robust filter.
  std::vector<Complex> delta_spectrum_, weighted_spectrum_;
  std::vector<std::vector<double>> moments_, weighted_moments_;
};

std::vector<double> closed_gaussian(const std::vector<double>& z, double cutoff_samples) {
  const std::size_t n = z.size();
  RealFft fft(n);
  auto spectrum = fft.forward(z);
  const double cutoff_upr = static_cast<double>(n) / cutoff_samples;
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double ratio = gaussian_alpha * static_cast<double>(k) / cutoff_upr;
    spectrum[k] *= std::exp(-std::numbers::pi * ratio * ratio);
  }
  return fft.inverse(spectrum);
}

double median_abs(std::vector<double> r) {
  for (double& v : r) v = std::abs(v);
  auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  return *mid;
}

FilterResult robust_regression(const std::vector<double>& z, const FilterSettings& settings) {
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
  std::vector<double> delta(n, 1.0);
  FilterResult result;
  result.waviness = regression.fit(z, delta, z);
  result.converged = false;
  for (result.iterations = 1; result.iterations < settings.max_iterations;) {
    std::vector<double> residual(n);
    for (std::size_t i = 0; i < n; ++i) residual[i] = z[i] - result.waviness[i];
    // Residuals below 0.1 % of the profile's rms are the regression's own bias on a smooth
    // profile, not outliers: reweighting them makes the mean line wander without converging,
    // so the biweight scale is floored there.
    const double c = std::max(tukey_c_over_median * median_abs(residual), c_floor);
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
    std::vector<double> next = regression.fit(z, delta, result.waviness);
    double change = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      change = std::max(change, std::abs(next[i] - result.waviness[i]));
    result.waviness = std::move(next);
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

FilterResult filter_profile(const std::vector<double>& profile, const FilterSettings& settings) {
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
    result.waviness = regression.fit(profile, std::vector<double>(profile.size(), 1.0), profile);
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
