#pragma once
// Profile filters of surface metrology (docs/analysis/surface.md, MODELS.md W1): the ISO 16610-21
// Gaussian filter and the ISO 16610-31 robust Gaussian regression filter. The filter output is the
// mean line = the waviness profile (long waves); roughness = profile - waviness.
//
//   Gaussian, open profile: weighting s(x) = exp(-pi (x / (alpha lc))^2) / (alpha lc),
//     alpha = sqrt(ln 2 / pi); end effects per ISO 16610-28 by moment retention: at every position
//     the filter is a local *linear* regression with these weights over the samples that exist.
//     Inside the profile (>= 1.5 lc from the ends) the first moment of the symmetric kernel is
//     zero, so the result is exactly the Gaussian filter with transmission
//     H(lambda) = exp(-pi (alpha lc / lambda)^2); near the ends the truncated kernel keeps the
//     zeroth and first moments, so a straight line passes unchanged right up to the ends (no
//     end run-out, no discarded lc/2).
//   Gaussian, closed profile (one revolution): periodic, exact transmission
//     H(k) = exp(-pi (alpha k / k_c)^2) applied to DFT bin k (k undulations per revolution).
//   Robust Gaussian regression (ISO 16610-31): local *quadratic* regression with Gaussian weights
//     of constant gamma = 0.7309 (so that H(lc) = 50 %: interior transmission
//     H = (1 + t) exp(-t), t = pi gamma^2 (lc/lambda)^2), times Tukey biweights of the residuals
//     delta_k = (1 - (r_k / c)^2)^2 for |r_k| < c, else 0, c = 4.4478 median|r|
//     (= 3 sigma for Gaussian residuals; c is floored at 1e-3 of the profile's rms, because
//     smaller residuals are the regression's bias on smooth profiles). Iterated from delta = 1 until the largest change of the
//     mean line is below 1e-6 of the profile's range (or max_iterations: reported, not hidden).
//     Closed profiles use the periodically continued profile.
// All sums are convolutions with fixed kernels done by FFT: O(N log N).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace chatterlab::surface {

enum class FilterType { gaussian, robust_gaussian };

std::string to_string(FilterType type);

inline constexpr double gaussian_alpha = 0.46971863934982566;   // sqrt(ln 2 / pi)
inline constexpr double regression_gamma = 0.7309;              // ISO 16610-31, 2nd order
inline constexpr double tukey_c_over_median = 4.4478;           // ISO 16610-31

struct FilterSettings {
  FilterType type = FilterType::gaussian;
  // Cut-off wavelength in samples (lc / sample spacing); for closed profiles equal to
  // samples_per_revolution / cutoff_upr.
  double cutoff_samples = 0.0;
  bool closed = false;
  int max_iterations = 50;              // robust filter
  double relative_tolerance = 1e-6;     // robust filter: max |change| / profile range
};

struct FilterResult {
  std::vector<double> waviness;   // filter output (mean line), same length as the input
  int iterations = 1;             // robust filter: reweighting passes
  bool converged = true;
  std::size_t zero_weight_samples = 0;  // robust filter: samples given weight 0 (outliers)
};

// Throws std::invalid_argument for fewer than 4 samples or a non-positive cut-off.
FilterResult filter_profile(std::span<const double> profile, const FilterSettings& settings);

// Interior amplitude transmission of the waviness (mean line) at wavelength/cut-off ratio
// `lambda_over_cutoff` (the analytic value the filters reproduce, for docs and tests).
double waviness_transmission(FilterType type, double lambda_over_cutoff);

}  // namespace chatterlab::surface
