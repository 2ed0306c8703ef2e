#pragma once
// Analysis `lyapunov_spectrum` (MODELS.md N3, book eqs 4-20..4-26): the Lyapunov spectrum of a
// scalar series from local Jacobians. At reference points X_j along the trajectory, the
// displacements Y_i = X_i - X_j of the k nearest neighbours (Theiler window) and their images
// Z_i after m steps give the local map A^j by least squares (A Y = Z); tangent vectors are
// propagated through the A^j and re-orthonormalised by QR, and lambda_i = sum ln |R_ii| / (n m).
// Exponents that do not reappear with opposite sign in the spectrum of the time-reversed series
// are flagged spurious (Parlitz 1992). docs/analysis/chaos.md, section "Lyapunov spectrum".
#include <vector>
#include <span>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/analysis.hpp"

namespace chatterlab {

struct SpectrumEstimate {
  std::vector<double> exponents;           // per sample, largest first
  std::vector<std::vector<double>> block_sums;  // [block][i]: sum of ln |R_ii| per block
  std::vector<double> block_steps;             // samples covered per block
};
// `dimension` x `delay` embedding, Jacobians over `evolution_steps` samples fitted to
// `neighbours` nearest neighbours at up to `references` points spaced evolution_steps apart.
SpectrumEstimate lyapunov_spectrum(std::span<const double> x, int dimension, int delay,
                                   std::size_t theiler, std::size_t evolution_steps,
                                   std::size_t neighbours, std::size_t references);

// The plugin: info(), analyse() and plot() are defined in lyapunov_spectrum.cpp.
struct LyapunovSpectrumMethod;
using LyapunovSpectrum = nonlinear::MethodAnalysis<LyapunovSpectrumMethod>;

}  // namespace chatterlab
