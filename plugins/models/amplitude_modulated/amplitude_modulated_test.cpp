// Known answers for amplitude_modulated (MODELS.md G7): with modulation the Floquet solution has sidebands spaced exactly by the wheel rotation frequency (24.17 Hz at
// 1450 rpm) and the envelope beats with the wheel period.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/spectrum.hpp"
#include "models/amplitude_modulated/amplitude_modulated.hpp"

namespace chatterlab {
namespace {

AmplitudeModulatedParameters g8_like(double q) {
  AmplitudeModulatedParameters p;
  p.frequency_hz = 800.0;
  p.damping_ratio = 0.05;
  p.stiffness_n_per_m = 5e7;
  p.grinding_stiffness_n_per_m = 5e6;  // decays at ~3 /s without modulation
  p.contact_stiffness_n_per_m = 1e8;
  p.overlap_factor = 1.0;
  p.modulation_depth = q;
  p.wheel_speed_rpm = 1450.0;
  p.work_speed_rpm = 55.0;
  return p;
}

SimulationResult run(const AmplitudeModulatedParameters& p, double duration_s) {
  AmplitudeModulatedTimeDomain model(p);
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = 8000.0;
  s.one_sided_contact = false;
  s.divergence_limit_m = 1e6;
  return simulate(model, s);
}

// Spectrum of the second half of the run (transient gone).
std::vector<SpectralPeak> late_peaks(const SimulationResult& r, std::size_t count) {
  const std::size_t half = r.t_s.size() / 2;
  std::span<const double> x(r.displacement_m.data() + half, r.displacement_m.size() - half);
  Spectrum s = amplitude_spectrum(x, 8000.0);
  return find_peaks(s, count, 8.0, 1e-4);
}

TEST(AmplitudeModulated, SidebandsSpacedByTheWheelRotationFrequency) {
  const SimulationResult r = run(g8_like(0.3), 4.0);
  ASSERT_EQ(r.status, "completed");
  auto peaks = late_peaks(r, 3);
  ASSERT_EQ(peaks.size(), 3u);
  std::vector<double> f;
  for (const auto& p : peaks) f.push_back(p.frequency_hz);
  std::sort(f.begin(), f.end());
  const double rotation_hz = 1450.0 / 60.0;  // 24.1667 Hz
  EXPECT_NEAR(f[1] - f[0], rotation_hz, 0.1);
  EXPECT_NEAR(f[2] - f[1], rotation_hz, 0.1);
}

TEST(AmplitudeModulated, SidebandSpacingFollowsTheWheelSpeed) {
  auto p = g8_like(0.3);
  p.wheel_speed_rpm = 1200.0;  // 20 Hz
  auto peaks = late_peaks(run(p, 4.0), 3);
  ASSERT_EQ(peaks.size(), 3u);
  std::vector<double> f;
  for (const auto& peak : peaks) f.push_back(peak.frequency_hz);
  std::sort(f.begin(), f.end());
  EXPECT_NEAR(f[1] - f[0], 20.0, 0.1);
  EXPECT_NEAR(f[2] - f[1], 20.0, 0.1);
}

TEST(AmplitudeModulated, EnvelopeBeatsWithTheWheelPeriod) {
  const SimulationResult r = run(g8_like(0.3), 2.0);
  EnvelopeFit fit = fit_envelope(r.t_s, r.displacement_m, 1.0, 2.0);
  // ln envelope minus its trend, analysed as a signal: its strongest line is at the wheel
  // rotation frequency.
  std::vector<double> residual;
  for (std::size_t i = 0; i < fit.t_s.size(); ++i)
    residual.push_back(std::log(fit.envelope[i]) - fit.intercept - fit.growth_rate_per_s * fit.t_s[i]);
  // One envelope sample per period of the carrier: nearly uniform in time.
  const double rate = static_cast<double>(fit.t_s.size() - 1) / (fit.t_s.back() - fit.t_s.front());
  Spectrum s = amplitude_spectrum(residual, rate);
  auto peak = find_peaks(s, 1);
  ASSERT_EQ(peak.size(), 1u);
  EXPECT_NEAR(peak[0].frequency_hz, 1450.0 / 60.0, 0.5);
}

}  // namespace
}  // namespace chatterlab
