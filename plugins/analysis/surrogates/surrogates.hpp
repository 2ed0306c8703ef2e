#pragma once
// Analysis `surrogates`: tests for determinism against the null hypothesis "linear stochastic
// process" with surrogate series that share the data's linear properties: IAAFT surrogates
// (Schreiber and Schmitz 1996: same amplitude distribution and, iteratively, the same power
// spectrum; null: a linear Gaussian process seen through a static monotone nonlinearity) and
// phase-randomised Fourier surrogates (Theiler et al. 1992: same power spectrum; null: a linear
// Gaussian process). Three discriminating statistics, each a one-sided rank test (rejected at
// significance 1 / (surrogates + 1) when the data lie below every surrogate):
//  - the one-step error of a locally constant predictor (deterministic data predict better);
//  - the growth of Kantz's divergence curve at a fixed neighbourhood size up to the time the
//    data's curve makes half its rise (deterministic neighbours separate more slowly than
//    those of a linear process with the same spectrum): the test "for the exponent";
//  - the slope of ln C(r) between the radii where the data's correlation sum is 10^-3 and 10^-2
//    (a low-dimensional attractor has a smaller slope than its surrogates): the test "for the
//    dimension".
// Time-reversal asymmetry is reported beside them. docs/analysis/chaos.md, section "Surrogates".
#include <cstdint>
#include <span>
#include <vector>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

// One IAAFT surrogate of x (iterations until the ranks stop changing, at most max_iterations).
std::vector<double> iaaft_surrogate(std::span<const double> x, std::uint64_t seed,
                                    int max_iterations = 200);
// One phase-randomised (Fourier) surrogate: the data's Fourier amplitudes with uniformly random
// phases (the mean and, for even length, the Nyquist term kept real).
std::vector<double> phase_randomised_surrogate(std::span<const double> x, std::uint64_t seed);

// Normalised RMS one-step error of the locally constant predictor (k nearest neighbours).
double prediction_error(std::span<const double> x, int dimension, int delay,
                        std::size_t theiler, std::size_t neighbours, std::size_t references);

// <(x_{n+tau} - x_n)^3> / <(x_{n+tau} - x_n)^2>^{3/2}: zero for time-reversible processes.
double time_reversal_asymmetry(std::span<const double> x, int delay);

// The plugin: info(), analyse() and plot() are defined in surrogates.cpp.
struct SurrogatesMethod;
using Surrogates = nonlinear::MethodAnalysis<SurrogatesMethod>;

}  // namespace chatterlab
