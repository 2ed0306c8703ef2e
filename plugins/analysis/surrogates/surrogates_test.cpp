#include "analysis/surrogates/surrogates.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "analysis/nonlinear_common/test_signals.hpp"
#include "chatterlab/fft.hpp"

namespace chatterlab {
namespace {

using test_signals::make_analysis;
using test_signals::series;

// IAAFT keeps the amplitude distribution exactly (a permutation of the data) and the power
// spectrum closely.
TEST(Surrogates, IaaftKeepsDistributionAndSpectrum) {
  const auto x = test_signals::henon(2048);
  const auto s = iaaft_surrogate(x, 5);
  auto a = x, b = s;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  EXPECT_NE(x, s);
  RealFft fft(x.size());
  const auto fx = fft.forward(x), fs = fft.forward(s);
  double num = 0, den = 0;
  for (std::size_t k = 1; k < fx.size(); ++k) {
    num += std::pow(std::abs(fx[k]) - std::abs(fs[k]), 2);
    den += std::norm(fx[k]);
  }
  EXPECT_LT(std::sqrt(num / den), 0.1);
}

TEST(Surrogates, HenonIsDeterministic) {
  const Json r = make_analysis("surrogates")->analyse(
      series(test_signals::henon(2000), 1.0, "henon x"), Json::object());
  EXPECT_TRUE(r["null_rejected"].get<bool>()) << r.dump();
  EXPECT_EQ(r["rank"], 1);
}

TEST(Surrogates, WhiteNoiseIsNotRejected) {
  const Json r = make_analysis("surrogates")->analyse(
      series(test_signals::white_noise(2000, 11), 1.0, "noise"), Json::object());
  EXPECT_FALSE(r["null_rejected"].get<bool>()) << r["prediction_error"].dump();
  EXPECT_GT(r["rank"].get<int>(), 1);
}

}  // namespace
}  // namespace chatterlab
