#include "analysis/surrogates/surrogates.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "shared/nonlinear/test_signals.hpp"
#include "chatterlab/fft.hpp"
#include "unit/study_test_support.hpp"

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

TEST(Surrogates, PhaseRandomisedKeepsTheSpectrumExactly) {
  const auto x = test_signals::henon(1000);
  const auto s = phase_randomised_surrogate(x, 9);
  RealFft fft(x.size());
  const auto fx = fft.forward(x), fs = fft.forward(s);
  for (std::size_t k = 0; k < fx.size(); ++k)
    EXPECT_NEAR(std::abs(fs[k]), std::abs(fx[k]), 1e-9 * (1 + std::abs(fx[k]))) << k;
  EXPECT_NE(x, s);
}

// Henon: all three statistics (prediction, divergence for the exponent, correlation-sum slope
// for the dimension) reject the linear stochastic null against both surrogate kinds (9 of each
// here, significance 0.1; the validation suite runs the default 19).
TEST(Surrogates, HenonIsDeterministic) {
  const Json r = make_analysis("surrogates", Json{{"surrogates", 9}})
                     ->analyse(series(test_signals::henon(2000), 1.0, "henon x"), Json::object());
  EXPECT_TRUE(r["null_rejected"].get<bool>()) << r.dump();
  EXPECT_EQ(r["rank"], 1);
  EXPECT_TRUE(r["rejected_for_prediction"].get<bool>());
  EXPECT_TRUE(r["rejected_for_exponent"].get<bool>()) << r["statistics"]["divergence"].dump();
  EXPECT_TRUE(r["rejected_for_dimension"].get<bool>()) << r["statistics"]["dimension"].dump();
  EXPECT_EQ(r["kinds"], Json::array({"iaaft", "phase_randomised"}));
}

// A linear stochastic process: no statistic rejects.
TEST(Surrogates, LinearStochasticProcessIsNotRejected) {
  for (const auto& [name, x] :
       {std::pair{"white noise", test_signals::white_noise(2000, 11)},
        std::pair{"AR(2)", test_signals::ar2(2000, 4)}}) {
    const Json r = make_analysis("surrogates", Json{{"embedding_dimension", 3},
                                                    {"delay_samples", 2},
                                                    {"surrogates", 9}})
                       ->analyse(series(x, 1.0, name), Json::object());
    EXPECT_FALSE(r["rejected_for_prediction"].get<bool>()) << name << r["prediction_error"].dump();
    EXPECT_FALSE(r["rejected_for_exponent"].get<bool>()) << name;
    EXPECT_FALSE(r["rejected_for_dimension"].get<bool>()) << name;
  }
}

// The prediction error sums over 10,000 references: the same bits with one thread, with two,
// and from one run to the next (fixed blocks merged in block order).
TEST(Surrogates, PredictionErrorDoesNotDependOnTheThreadCount) {
  const auto x = test_signals::henon(20000);
  const auto [one, two, again] = testing::with_one_two_two_threads(
      [&] { return prediction_error(x, 2, 1, 10, 5, 10000); });
  EXPECT_GT(one, 0.0);
  EXPECT_EQ(one, two);
  EXPECT_EQ(two, again);
}

}  // namespace
}  // namespace chatterlab
