#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/nonlinear_common/test_signals.hpp"

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
