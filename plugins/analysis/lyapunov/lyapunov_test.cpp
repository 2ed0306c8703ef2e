#include "analysis/lyapunov/lyapunov.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/nonlinear_common/test_signals.hpp"

namespace chatterlab {
namespace {

using test_signals::make_analysis;
using test_signals::series;

double per_sample(const Json& r) { return r["lyapunov_max_per_sample"]["value"].get<double>(); }


TEST(Lyapunov, LinearRegionOfAnIdealCurve) {
  // Transient, straight rise of slope 0.3 and saturation: the fit recovers the slope.
  std::vector<double> y;
  for (int k = 0; k < 60; ++k)
    y.push_back(k < 2 ? -5.0 + 0.05 * k : std::min(-4.9 + 0.3 * (k - 2), 1.0));
  const auto fit = linear_region(y);
  ASSERT_TRUE(fit.found);
  EXPECT_NEAR(fit.slope, 0.3, 1e-9);
  EXPECT_TRUE(fit.diverging);
}

TEST(LyapunovAccuracy, Henon) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::henon(10000), 1.0, "henon x"), Json::object());
  EXPECT_NEAR(per_sample(r), 0.419, 0.01);
  EXPECT_EQ(r["lyapunov_max_per_sample"]["quality"], "good");
}

TEST(LyapunovAccuracy, Lorenz) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::lorenz(100000), 0.01, "lorenz x"), Json::object());
  const double per_s = r["lyapunov_max_per_s"]["value"].get<double>();
  EXPECT_NEAR(per_s, 0.906, 0.05 * 0.906);
  EXPECT_NEAR(per_s, per_sample(r) / 0.01, 1e-9);
}

TEST(Lyapunov, SineDoesNotDiverge) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::sine(5000, 20 * std::sqrt(3.0)), 1.0, "sine"), Json::object());
  EXPECT_NEAR(per_sample(r), 0.0, 0.005);
}

}  // namespace
}  // namespace chatterlab
