#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "shared/nonlinear/test_signals.hpp"

namespace chatterlab {
namespace {

using test_signals::make_analysis;
using test_signals::series;

double exponent(const Json& r, std::size_t i) {
  return r["exponents_per_sample"][i]["value"].get<double>();
}

// Henon: lambda1 = 0.419, lambda2 = ln(0.3) - lambda1 = -1.623 per iteration (the sum is
// ln |det J| = ln b exactly).
TEST(LyapunovSpectrum, HenonSpectrumAndSum) {
  const Json r = make_analysis("lyapunov_spectrum")->analyse(
      series(test_signals::henon(10000), 1.0, "henon x"), Json::object());
  EXPECT_NEAR(exponent(r, 0), 0.419, 0.02);
  EXPECT_NEAR(exponent(r, 1), -1.623, 0.1);
  EXPECT_NEAR(r["sum_per_sample"].get<double>(), std::log(0.3), 0.1);
  EXPECT_FALSE(r["exponents_per_sample"][0]["spurious"].get<bool>());
}

// Henon embedded in 4 dimensions (2 would do): the two extra exponents are combinations of the
// true ones (2 lambda_1 = 0.84, lambda_1 + lambda_2 = -1.21) and are flagged; the genuine ones
// sum to ln 0.3 and give the Kaplan-Yorke dimension 1 + 0.419 / 1.623 = 1.258.
TEST(LyapunovSpectrum, SpuriousExponentsOfAnOverEmbeddedMapAreFlagged) {
  const Json r = make_analysis("lyapunov_spectrum",
                               Json{{"embedding_dimension", 4}, {"delay_samples", 1}})
                     ->analyse(series(test_signals::henon(10000), 1.0, "henon x"), Json::object());
  const Json& e = r["exponents_per_sample"];
  ASSERT_EQ(e.size(), 4u);
  EXPECT_TRUE(e[0]["spurious"].get<bool>()) << e[0].dump();
  EXPECT_FALSE(e[1]["spurious"].get<bool>()) << e[1].dump();
  EXPECT_TRUE(e[2]["spurious"].get<bool>()) << e[2].dump();
  EXPECT_FALSE(e[3]["spurious"].get<bool>()) << e[3].dump();
  EXPECT_EQ(r["genuine_exponents"], 2);
  EXPECT_NEAR(r["sum_per_sample"].get<double>(), std::log(0.3), 0.05);
  EXPECT_NEAR(r["kaplan_yorke_dimension"].get<double>(), 1.258, 0.03);
  EXPECT_TRUE(r["dissipative"].get<bool>());
  // The spectrum's largest exponent is the largest genuine one, flagged for what lies above it.
  EXPECT_NEAR(r["lyapunov_max_per_sample"]["value"].get<double>(), 0.419, 0.03);
  EXPECT_EQ(r["lyapunov_max_per_sample"]["quality"], "uncertain");
}

// A quasi-periodic torus has no positive exponent: the spectrum's positive one changes in one
// more dimension and is flagged, and no Kaplan-Yorke dimension is claimed.
TEST(LyapunovSpectrum, TorusHasNoGenuinePositiveExponent) {
  const Json r = make_analysis("lyapunov_spectrum")->analyse(
      series(test_signals::torus(20000), 1.0, "torus"), Json::object());
  for (const Json& e : r["exponents_per_sample"])
    if (!e["spurious"].get<bool>()) {
      EXPECT_LT(e["value"].get<double>(), 0.003) << e.dump();
    }
  EXPECT_TRUE(r["kaplan_yorke_dimension"].is_null());
}

// The spectrum's largest exponent is "good" only when it agrees with a divergence estimate that
// is itself "good": agreeing with an uncertain one (noise, a short series) confirms nothing.
TEST(LyapunovSpectrum, AgreementWithAnUncertainDivergenceEstimateIsNotGood) {
  const auto x = series(test_signals::henon(5000), 1.0, "henon x");
  auto context = [](const char* quality) {
    return Json{{"lyapunov",
                 {{"divergence", "exponential"},
                  {"lyapunov_max_per_sample",
                   {{"value", 0.419}, {"ci_low", 0.41}, {"ci_high", 0.43}, {"quality", quality}}}}}};
  };
  const Json good = make_analysis("lyapunov_spectrum")->analyse(x, context("good"));
  EXPECT_EQ(good["lyapunov_max_per_sample"]["quality"], "good") << good["lyapunov_max_per_sample"];
  const Json doubtful = make_analysis("lyapunov_spectrum")->analyse(x, context("uncertain"));
  const Json& e = doubtful["lyapunov_max_per_sample"];
  EXPECT_EQ(e["quality"], "uncertain") << e;
  EXPECT_NE(e["reason"].get<std::string>().find("checked against is not good"), std::string::npos)
      << e;
}

TEST(LyapunovSpectrumAccuracy, Lorenz) {
  const Json r = make_analysis("lyapunov_spectrum")->analyse(
      series(test_signals::lorenz(100000), 0.01, "lorenz x"), Json::object());
  const double l1 = r["exponents_per_sample"][0]["value_per_s"].get<double>();
  const double l2 = r["exponents_per_sample"][1]["value_per_s"].get<double>();
  EXPECT_NEAR(l1, 0.906, 0.05 * 0.906);
  EXPECT_LT(std::abs(l2), 0.05);
  // Dissipative: the third exponent and the sum are negative (the true third exponent, -14.57,
  // is underestimated in magnitude by local fits over one delay; docs/analysis/chaos.md).
  EXPECT_LT(r["exponents_per_sample"][2]["value_per_s"].get<double>(), -1.0);
  EXPECT_LT(r["sum_per_sample"].get<double>(), 0.0);
}

}  // namespace
}  // namespace chatterlab
