// assess_fit (chatterlab/fit_validity.hpp) on synthetic responses whose regime is known by
// construction: a pure exponential (valid, both signs), a logistic envelope (saturated), an open
// contact, a window shorter than the delays, a pulse per revolution (not exponential) and a
// constant forced vibration (steady: no root to estimate).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "chatterlab/fit_validity.hpp"

namespace chatterlab {
namespace {

struct Response {
  std::vector<double> t, x, in_contact;
};

// x = A(t) sin(2 pi 500 t), sampled at 20 kHz over [0, duration].
Response response(const std::function<double(double)>& amplitude, double duration_s = 2.0) {
  Response r;
  for (double i = 0; i / 20000.0 <= duration_s; ++i) {
    const double t = i / 20000.0;
    r.t.push_back(t);
    r.x.push_back(amplitude(t) * std::sin(2 * std::numbers::pi * 500.0 * t + 0.3));
    r.in_contact.push_back(1.0);
  }
  return r;
}

FitValidity assess(const Response& r, double delay_s, double from_s = 1.0, double to_s = 2.0) {
  const EnvelopeFit fit = fit_envelope(r.t, r.x, from_s, to_s);
  return assess_fit(fit, r.t, r.in_contact, delay_s);
}

TEST(FitValidity, ExponentialGrowthAndDecayAreValid) {
  const FitValidity up = assess(response([](double t) { return 1e-6 * std::exp(3.0 * t); }), 0.2);
  EXPECT_TRUE(up.valid) << up.reason;
  EXPECT_EQ(up.regime, ResponseRegime::linear_growth);
  EXPECT_NEAR(up.first_half_growth_per_s, 3.0, 0.05);
  EXPECT_NEAR(up.second_half_growth_per_s, 3.0, 0.05);
  EXPECT_NEAR(up.delays_in_window, 5.0, 0.01);
  const FitValidity down = assess(response([](double t) { return 1e-6 * std::exp(-2.0 * t); }), 0.2);
  EXPECT_TRUE(down.valid) << down.reason;
  EXPECT_EQ(down.regime, ResponseRegime::linear_decay);
  EXPECT_TRUE(down.reason.empty());
}

TEST(FitValidity, LogisticEnvelopeIsSaturated) {
  // Growth 12 /s until t = 1.5 s, then flat at 1e-4 m.
  const FitValidity v = assess(response([](double t) { return 1e-4 / (1 + std::exp(-12.0 * (t - 1.5))); }), 0.2);
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::saturated);
  EXPECT_GT(v.first_half_growth_per_s, 8.0);
  EXPECT_LT(v.second_half_growth_per_s, 4.0);
  EXPECT_NEAR(v.final_amplitude_m, 1e-4, 1e-5);
  EXPECT_NE(v.reason.find("the envelope saturates"), std::string::npos) << v.reason;
}

TEST(FitValidity, OpenContactInvalidatesTheFitAndSaysHowLong) {
  Response r = response([](double t) { return 1e-6 * std::exp(3.0 * t); });
  for (std::size_t i = 0; i < r.t.size(); ++i)
    if (r.t[i] >= 1.5) r.in_contact[i] = 0.0;  // the second half of the window is open
  const FitValidity v = assess(r, 0.2);
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::contact_lost);
  EXPECT_NEAR(v.contact_loss_fraction, 0.5, 0.01);
  EXPECT_NE(v.reason.find("contact open for 50.0 % of the fit window 1..2 s (limit 2.0 %)"), std::string::npos)
      << v.reason;
  // A brief opening below the limit does not.
  for (std::size_t i = 0; i < r.t.size(); ++i) r.in_contact[i] = r.t[i] >= 1.5 && r.t[i] < 1.51 ? 0.0 : 1.0;
  EXPECT_TRUE(assess(r, 0.2).valid);
}

TEST(FitValidity, WindowBeforeOrShorterThanADelayIsTransient) {
  const auto growing = response([](double t) { return 1e-6 * std::exp(3.0 * t); });
  const FitValidity v = assess(growing, 1.5);  // window 1..2 s: starts at 0.67, spans 0.67 delays
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::transient);
  EXPECT_NE(v.reason.find("the fit window 1..2 s starts at 0.67 and spans 0.67 of the longest regenerative delay "
                          "(1.5 s; at least 1 each needed)"),
            std::string::npos)
      << v.reason;
  EXPECT_TRUE(assess(growing, 0.8).valid);             // starts after 1.25 delays, spans 1.25
  EXPECT_FALSE(assess(growing, 0.8, 1.0, 1.7).valid);  // starts after 1.25, spans 0.875
  EXPECT_FALSE(assess(growing, 0.5, 0.3, 2.0).valid);  // spans 3.4 delays but starts within the first
}

TEST(FitValidity, OnePulsePerRevolutionIsNotExponential) {
  // The regenerative pattern of a long work period: the amplitude peaks once per revolution.
  const auto pulses = [](double t) {
    return 1e-6 * std::exp(0.5 * t + 2.0 * std::cos(2 * std::numbers::pi * t / 0.2));
  };
  const FitValidity v = assess(response(pulses), 0.2);
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::not_exponential);
  EXPECT_GT(v.residual_rms, 1.0);
  EXPECT_NE(v.reason.find("the envelope is not exponential"), std::string::npos) << v.reason;
}

TEST(FitValidity, AStepBetweenTwoExponentialHalvesIsNotExponential) {
  // Each half grows at 0.5 /s, the amplitude steps by 1.8 in the middle: the line through the
  // whole window fits well (ln residual ~0.09) but its slope, ~1.4 /s, describes neither half.
  const auto stepped = [](double t) { return 1e-6 * std::exp(0.5 * t) * (t < 1.5 ? 1.0 : 1.8); };
  const FitValidity v = assess(response(stepped), 0.2);
  EXPECT_LT(v.residual_rms, 0.35);
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::not_exponential);
  EXPECT_NEAR(v.first_half_growth_per_s, 0.5, 0.05);
  EXPECT_NE(v.reason.find("the envelope steps inside the window"), std::string::npos) << v.reason;
}

TEST(FitValidity, AConstantForcedVibrationIsSteadyNotGrowth) {
  // A forced vibration of constant amplitude (G6's unbalance response): the fitted slope is ~0,
  // which is no root of the system; a slow growth of 0.05 /s (5 % over the window) still counts.
  const FitValidity v = assess(response([](double) { return 3e-8; }), 0.2);
  EXPECT_FALSE(v.valid);
  EXPECT_EQ(v.regime, ResponseRegime::steady);
  EXPECT_NEAR(v.final_amplitude_m, 3e-8, 1e-9);
  EXPECT_NE(v.reason.find("the envelope holds its level"), std::string::npos) << v.reason;
  EXPECT_NE(v.reason.find("forced steady vibration"), std::string::npos) << v.reason;
  const FitValidity slow = assess(response([](double t) { return 1e-6 * std::exp(0.05 * t); }), 0.2);
  EXPECT_TRUE(slow.valid) << slow.reason;
  EXPECT_EQ(slow.regime, ResponseRegime::linear_growth);
}

}  // namespace
}  // namespace chatterlab
