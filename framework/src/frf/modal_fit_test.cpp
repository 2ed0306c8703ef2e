// Modal fit known answers: synthetic FRFs from known modes (the seven G8 machine modes; two modes
// 2 % apart), exact without noise, within the issue's bounds with 2 % noise, uncertainties that
// cover the truth, the stabilisation diagram's labels, and the message when nothing is stable.
#include "chatterlab/modal_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "chatterlab/errors.hpp"
#include "unit/frf_test_support.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::g8_modes;
using testing::synthetic_frf;

// The fitted mode nearest in frequency to `truth`.
const FittedMode& nearest(const ModalFit& fit, const FittedMode& truth) {
  const FittedMode* best = &fit.modes.front();
  for (const FittedMode& m : fit.modes)
    if (std::abs(m.frequency_hz - truth.frequency_hz) < std::abs(best->frequency_hz - truth.frequency_hz)) best = &m;
  return *best;
}

TEST(ModalFit, NoiseFreeG8ModesAreRecoveredExactly) {
  const MeasuredFrf frf = synthetic_frf(g8_modes(), 20.0, 400.0, 0.25);
  const ModalFit fit = fit_modes(frf, {});
  ASSERT_EQ(fit.modes.size(), 7u);
  for (const FittedMode& truth : g8_modes()) {
    const FittedMode& m = nearest(fit, truth);
    EXPECT_NEAR(m.frequency_hz, truth.frequency_hz, 1e-7 * truth.frequency_hz);
    EXPECT_NEAR(m.damping_ratio, truth.damping_ratio, 1e-6 * truth.damping_ratio);
    EXPECT_NEAR(m.stiffness_n_per_m, truth.stiffness_n_per_m, 1e-6 * truth.stiffness_n_per_m);
  }
  EXPECT_LT(fit.relative_misfit, 1e-8);
  EXPECT_EQ(fit.lines, 1521);
}

// The issue's known answer: 2 % noise, frequencies within 0.5 %, damping within 10 %; and the
// stated uncertainties cover the error (4 standard deviations).
TEST(ModalFit, TwoPercentNoiseG8ModesWithinTheIssueBounds) {
  const MeasuredFrf frf = synthetic_frf(g8_modes(), 20.0, 400.0, 0.25, 0.02, 7);
  const ModalFit fit = fit_modes(frf, {});
  ASSERT_EQ(fit.modes.size(), 7u);
  for (const FittedMode& truth : g8_modes()) {
    SCOPED_TRACE(truth.frequency_hz);
    const FittedMode& m = nearest(fit, truth);
    EXPECT_NEAR(m.frequency_hz, truth.frequency_hz, 0.005 * truth.frequency_hz);
    EXPECT_NEAR(m.damping_ratio, truth.damping_ratio, 0.10 * truth.damping_ratio);
    EXPECT_NEAR(m.stiffness_n_per_m, truth.stiffness_n_per_m, 0.10 * truth.stiffness_n_per_m);
    EXPECT_LE(std::abs(m.frequency_hz - truth.frequency_hz), 4 * m.frequency_sd_hz);
    EXPECT_LE(std::abs(m.damping_ratio - truth.damping_ratio), 4 * m.damping_ratio_sd);
    EXPECT_LE(std::abs(m.stiffness_n_per_m - truth.stiffness_n_per_m), 4 * m.stiffness_sd_n_per_m);
    EXPECT_GT(m.frequency_sd_hz, 0.0);
  }
  // The misfit is the noise: 2 % per component, sqrt(2) x 2 % in modulus.
  EXPECT_NEAR(fit.relative_misfit, 0.028, 0.006);
}

// Two modes 2 % apart, with half-power bandwidths (2 zeta f = 2 and 3 Hz) as wide as their
// separation: one peak to the eye, two modes to the fit.
TEST(ModalFit, CloselySpacedModesAreSeparated) {
  FittedMode a, b;
  a.frequency_hz = 100.0, a.damping_ratio = 0.01, a.stiffness_n_per_m = 4e7;
  b.frequency_hz = 102.0, b.damping_ratio = 0.015, b.stiffness_n_per_m = 6e7;
  const MeasuredFrf frf = synthetic_frf({a, b}, 60.0, 150.0, 0.1, 0.02, 3);
  const ModalFit fit = fit_modes(frf, {});
  ASSERT_EQ(fit.modes.size(), 2u);
  EXPECT_NEAR(fit.modes[0].frequency_hz, 100.0, 0.5);
  EXPECT_NEAR(fit.modes[1].frequency_hz, 102.0, 0.51);
  EXPECT_NEAR(fit.modes[0].damping_ratio, 0.01, 0.001);
  EXPECT_NEAR(fit.modes[1].damping_ratio, 0.015, 0.0015);
}

TEST(ModalFit, StabilisationDiagramLabelsPhysicalPolesStable) {
  const MeasuredFrf frf = synthetic_frf(g8_modes(), 20.0, 400.0, 0.25, 0.02, 7);
  ModalFitSettings settings;
  settings.max_order = 40;
  const ModalFit fit = fit_modes(frf, settings);
  EXPECT_EQ(fit.orders.size(), 20u);
  // Every mode is stable in most orders from 14 (seven modes need 14 poles) upwards.
  for (const FittedMode& m : fit.modes) EXPECT_GE(m.stable_orders, 10);
  int stable = 0;
  for (const StabilisationPole& p : fit.stabilisation) {
    EXPECT_GE(p.frequency_hz, 20.0);
    EXPECT_LE(p.frequency_hz, 400.0);
    stable += p.status == StabilisationPole::Status::stable;
  }
  EXPECT_GE(stable, 70);
}

TEST(ModalFit, ModesSettingKeepsTheMostPersistent) {
  const MeasuredFrf frf = synthetic_frf(g8_modes(), 20.0, 400.0, 0.25, 0.02, 7);
  ModalFitSettings settings;
  settings.modes = 3;
  EXPECT_EQ(fit_modes(frf, settings).modes.size(), 3u);
}

TEST(ModalFit, NothingStableIsAnInputErrorSayingWhatToChange) {
  // White noise has no modes.
  MeasuredFrf frf;
  frf.source = "noise.csv";
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n;
  for (int i = 1; i <= 400; ++i) {
    frf.frequency_hz.push_back(i);
    frf.receptance_m_per_n.emplace_back(1e-8 * n(rng), 1e-8 * n(rng));
  }
  const std::string e = testing::input_error_of([&] { fit_modes(frf, {}); });
  EXPECT_NE(e.find("noise.csv: no stable mode in 1-400 Hz"), std::string::npos) << e;
  EXPECT_NE(e.find("raise max_order, widen frequency_tolerance or lower min_stable_fraction"), std::string::npos) << e;
  ModalFitSettings narrow;
  narrow.min_frequency_hz = 100.0;
  narrow.max_frequency_hz = 105.0;
  const std::string few = testing::input_error_of([&] { fit_modes(frf, narrow); });
  EXPECT_NE(few.find("the modal fit band 100-105 Hz holds 6 measured lines; at least 16 are needed"), std::string::npos)
      << few;
}

// Monte Carlo over noise seeds: the stated standard uncertainties are honest (about 95 % of the
// errors within 2 standard deviations for Gaussian estimates).
TEST(ModalFitAccuracy, UncertaintiesCoverTheErrorsOverNoiseSeeds) {
  int inside = 0, total = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const ModalFit fit = fit_modes(synthetic_frf(g8_modes(), 20.0, 400.0, 0.25, 0.02, seed), {});
    ASSERT_EQ(fit.modes.size(), 7u) << "seed " << seed;
    for (const FittedMode& truth : g8_modes()) {
      const FittedMode& m = nearest(fit, truth);
      inside += std::abs(m.frequency_hz - truth.frequency_hz) <= 2 * m.frequency_sd_hz;
      inside += std::abs(m.damping_ratio - truth.damping_ratio) <= 2 * m.damping_ratio_sd;
      inside += std::abs(m.stiffness_n_per_m - truth.stiffness_n_per_m) <= 2 * m.stiffness_sd_n_per_m;
      total += 3;
    }
  }
  const double coverage = static_cast<double>(inside) / total;
  std::printf("modal fit: %d of %d estimates within 2 standard uncertainties\n", inside, total);
  EXPECT_GT(coverage, 0.88) << inside << "/" << total;
  EXPECT_LT(coverage, 0.995) << "uncertainties too large to be informative";
}

// The close pair over noise seeds: separated every time.
TEST(ModalFitAccuracy, CloselySpacedModesAreSeparatedOverNoiseSeeds) {
  FittedMode a, b;
  a.frequency_hz = 100.0, a.damping_ratio = 0.01, a.stiffness_n_per_m = 4e7;
  b.frequency_hz = 102.0, b.damping_ratio = 0.015, b.stiffness_n_per_m = 6e7;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const ModalFit fit = fit_modes(synthetic_frf({a, b}, 60.0, 150.0, 0.1, 0.02, seed), {});
    ASSERT_EQ(fit.modes.size(), 2u) << "seed " << seed;
    EXPECT_NEAR(fit.modes[0].frequency_hz, 100.0, 0.5) << "seed " << seed;
    EXPECT_NEAR(fit.modes[1].frequency_hz, 102.0, 0.51) << "seed " << seed;
    EXPECT_NEAR(fit.modes[1].damping_ratio, 0.015, 0.0015) << "seed " << seed;
  }
}

}  // namespace
}  // namespace chatterlab
