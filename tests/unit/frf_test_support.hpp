#pragma once
// Synthetic measured FRFs for the tests of the FRF readers, the modal fit, the measured-machine
// model and the stability_lobes kind: real modes (MODELS.md G1's H) on a line grid, with optional
// multiplicative complex Gaussian noise (a fraction of |H| per line, seeded).
#include <cmath>
#include <random>
#include <vector>

#include "chatterlab/frf.hpp"
#include "chatterlab/modal_fit.hpp"

namespace chatterlab::testing {

// The seven measured machine modes of MODELS.md G8 with the default study's stiffnesses and 3 %
// damping (studies/default.toml explains them).
inline std::vector<FittedMode> g8_modes() {
  const double f[] = {67.56, 102.44, 184.08, 221.11, 255.01, 275.05, 305.60};
  const double k[] = {5.53e7, 1.27e8, 4.11e8, 5.93e8, 7.88e8, 9.17e8, 1.132e9};
  std::vector<FittedMode> modes;
  for (int i = 0; i < 7; ++i) {
    FittedMode m;
    m.frequency_hz = f[i];
    m.damping_ratio = 0.03;
    m.stiffness_n_per_m = k[i];
    modes.push_back(m);
  }
  return modes;
}

// Lines from f_lo to f_hi step df (exact multiples), H of `modes` times (1 + noise (n_re + j n_im)),
// n standard normal.
inline MeasuredFrf synthetic_frf(const std::vector<FittedMode>& modes, double f_lo, double f_hi, double df,
                                 double noise = 0.0, unsigned seed = 1) {
  MeasuredFrf frf;
  frf.source = "synthetic";
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const auto n = static_cast<long>(std::llround((f_hi - f_lo) / df));
  for (long i = 0; i <= n; ++i) {
    const double f = f_lo + static_cast<double>(i) * df;
    Complex h = modes_receptance(modes, f);
    if (noise > 0.0) h *= Complex(1.0 + noise * normal(rng), noise * normal(rng));
    frf.frequency_hz.push_back(f);
    frf.receptance_m_per_n.push_back(h);
  }
  return frf;
}

}  // namespace chatterlab::testing
