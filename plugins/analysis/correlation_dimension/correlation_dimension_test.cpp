#include "analysis/correlation_dimension/correlation_dimension.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "shared/nonlinear/test_signals.hpp"

namespace chatterlab {
namespace {

using test_signals::make_analysis;
using test_signals::series;

double value(const Json& r) { return r["correlation_dimension"]["value"].get<double>(); }

// Pair counting against a direct double loop: the histogram must hold exactly the pairs outside
// the Theiler window, each dimension's distance being the maximum-norm distance.
TEST(CorrelationDimension, SumsCountEveryPairOutsideTheTheilerWindow) {
  const auto x = test_signals::henon(400);
  const int dims = 3, delay = 2;
  const std::size_t theiler = 5;
  const auto sums = correlation_sums(x, dims, delay, theiler, 1000);
  const std::size_t n = x.size() - std::size_t((dims - 1) * delay);
  // Bin edges are exact: count distances below the first edge at or above 10 % of the range.
  std::size_t bin = 0;
  while (CorrelationSums::edge(bin) < 0.1) ++bin;
  const double edge = CorrelationSums::edge(bin) * sums.range;
  for (int d = 1; d <= dims; ++d) {
    std::uint64_t direct = 0, pairs = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        if ((i > j ? i - j : j - i) <= theiler) continue;
        ++pairs;
        double dist = 0;
        for (int k = 0; k < d; ++k)
          dist = std::max(dist, std::abs(x[i + std::size_t(k * delay)] - x[j + std::size_t(k * delay)]));
        if (dist < edge) ++direct;
      }
    std::uint64_t counted = 0;
    double counted_pairs = 0;
    for (std::size_t b = 0; b < CorrelationSums::blocks; ++b) {
      counted_pairs += sums.pairs[b];
      for (std::size_t k = 0; k <= bin; ++k)
        counted += sums.counts[(b * std::size_t(dims) + std::size_t(d - 1)) * CorrelationSums::bins + k];
    }
    EXPECT_EQ(counted, direct) << "dimension " << d;
    EXPECT_EQ(counted_pairs, double(pairs));
  }
}

// The interval of a "good" D2 covers the accepted value (Grassberger and Procaccia 1983: Henon
// 1.21 +- 0.01, Lorenz 2.05 +- 0.01); tests/validation/ covers more systems and noise.
void expect_covers(const Json& estimate, double low, double high) {
  EXPECT_EQ(estimate["quality"], "good") << estimate.dump();
  EXPECT_LE(estimate["ci_low"].get<double>(), high) << estimate.dump();
  EXPECT_GE(estimate["ci_high"].get<double>(), low) << estimate.dump();
}

TEST(CorrelationDimensionAccuracy, Henon) {
  const Json r = make_analysis("correlation_dimension")
                     ->analyse(series(test_signals::henon(10000), 1.0, "henon x"), Json::object());
  expect_covers(r["correlation_dimension"], 1.20, 1.22);
  EXPECT_NEAR(value(r), 1.21, 0.03);
}

TEST(CorrelationDimensionAccuracy, Lorenz) {
  const Json r = make_analysis("correlation_dimension")
                     ->analyse(series(test_signals::lorenz(100000), 0.01, "lorenz x"), Json::object());
  expect_covers(r["correlation_dimension"], 2.04, 2.06);
  EXPECT_NEAR(value(r), 2.05, 0.06);
}

TEST(CorrelationDimension, SineIsOneDimensional) {
  const Json r = make_analysis("correlation_dimension")
                     ->analyse(series(test_signals::sine(5000, 20 * std::sqrt(3.0)), 1.0, "sine"), Json::object());
  EXPECT_NEAR(value(r), 1.0, 0.05);
}

// 5 % measurement noise: the noise scale is found, and above it the slopes of three dimensions
// agree over less than a factor 4 in r: reported, not fitted.
TEST(CorrelationDimension, NoisyHenonReportsTheNoiseScaleAndIsNotFitted) {
  const Json r = make_analysis("correlation_dimension")
                     ->analyse(series(test_signals::with_noise(test_signals::henon(10000), 0.05, 9),
                                      1.0, "henon + noise"),
                               Json{{"embedding",
                                     Json{{"delay_samples", 1}, {"embedding_dimension", 2},
                                          {"theiler_window_samples", 1}}}});
  const Json& e = r["correlation_dimension"];
  EXPECT_TRUE(e["value"].is_null()) << e.dump();
  const std::string reason = e["reason"].get<std::string>();
  EXPECT_NE(reason.find("not fitted"), std::string::npos) << reason;
  EXPECT_NE(reason.find("noise scale"), std::string::npos) << reason;
  EXPECT_TRUE(r["noise_level"].is_number());
}

TEST(CorrelationDimensionAccuracy, QuasiPeriodicTorusIsTwoDimensional) {
  // The strands of the finite trajectory look one-dimensional below r ~ 0.08; the scaling
  // range of the torus (slope 2) lies above: the value is about 2 and the interval spans both.
  const Json r = make_analysis("correlation_dimension")
                     ->analyse(series(test_signals::torus(50000), 1.0, "torus"), Json::object());
  const Json& e = r["correlation_dimension"];
  EXPECT_NEAR(e["value"].get<double>(), 2.0, 0.15) << e.dump();
  EXPECT_LE(e["ci_low"].get<double>(), 2.0);
  EXPECT_GE(e["ci_high"].get<double>(), 2.0);
}

TEST(CorrelationDimension, WhiteNoiseDoesNotSaturate) {
  const Json r = make_analysis("correlation_dimension", {{"max_dimension", 6}})
                     ->analyse(series(test_signals::white_noise(5000, 3), 1.0, "noise"), Json::object());
  EXPECT_EQ(r["saturation_dimension"], 0);
  EXPECT_EQ(r["correlation_dimension"]["quality"], "failed");
}


// All pairs below the cut (sorted strips, pairs of blocks) == every vector a reference of the
// sampled scheme, bin by bin below the cut and block by block (the two count each pair from both
// of its vectors). Returns the number of nonzero compared counts.
std::size_t expect_all_pairs_match(const std::vector<double>& x, int dims, int delay,
                                   std::size_t theiler, double cut) {
  const auto all = correlation_sums_within(x, dims, delay, theiler, cut);
  const auto every = correlation_sums(x, dims, delay, theiler, 1000000);
  EXPECT_EQ(all.counts.size(), every.counts.size());
  EXPECT_EQ(all.pairs, every.pairs);
  std::size_t nonzero = 0;
  const auto d_count = std::size_t(dims);
  for (std::size_t b = 0; b < CorrelationSums::blocks; ++b)
    for (std::size_t d = 0; d < d_count; ++d)
      for (std::size_t k = 0; CorrelationSums::edge(k) <= cut; ++k) {
        const std::size_t q = (b * d_count + d) * CorrelationSums::bins + k;
        EXPECT_EQ(all.counts[q], every.counts[q])
            << "dims " << dims << " cut " << cut << ": block " << b << " d " << d + 1
            << " bin " << k;
        nonzero += all.counts[q] > 0;
      }
  return nonzero;
}

TEST(CorrelationDimension, AllPairsWithinMatchesEveryReference) {
  const auto x = test_signals::henon(3000);
  EXPECT_GT(expect_all_pairs_match(x, 4, 2, 5, 0.05), 200u);
  // Dimension counts that leave padding lanes (3, 7) or none beyond the first two (2); a cut near
  // the largest allowed (few strips); no Theiler window (neighbouring blocks unchecked).
  EXPECT_GT(expect_all_pairs_match(x, 7, 1, 0, 0.3), 1000u);
  EXPECT_GT(expect_all_pairs_match(x, 3, 1, 12, 0.01), 100u);
  EXPECT_GT(expect_all_pairs_match(x, 2, 3, 0, 0.5), 100u);
  // More than two groups of four further coordinates (the general kernel).
  EXPECT_GT(expect_all_pairs_match(x, 13, 1, 3, 0.2), 2000u);
  // Fewer vectors than bootstrap blocks (empty blocks) and a Theiler window longer than a block.
  const auto tiny = test_signals::henon(30);
  EXPECT_GT(expect_all_pairs_match(tiny, 5, 1, 0, 0.5), 10u);
  EXPECT_GT(expect_all_pairs_match(tiny, 3, 1, 4, 0.2), 5u);
}

TEST(CorrelationDimensionAccuracy, HenonAllPairsWithin) {
  // Exact C(r) below 20 % of the range from all pairs (TISEAN d2 -N 0 style) against the default
  // sampled references (2000): two counting routes, one scaling-region rule. Both intervals
  // cover 1.21 +- 0.01 (with all pairs the region reaches smaller r, where the lacunarity of the
  // Henon set lowers the slope: 1.19 against 1.21).
  const auto henon = series(test_signals::henon(10000), 1.0, "henon x");
  const Json all = make_analysis("correlation_dimension", Json{{"all_pairs_within", 0.2}})
                       ->analyse(henon, Json::object());
  const Json sampled = make_analysis("correlation_dimension")->analyse(henon, Json::object());
  EXPECT_NEAR(value(all), value(sampled), 0.03);
  expect_covers(all["correlation_dimension"], 1.20, 1.22);
  EXPECT_EQ(all["all_pairs_within"], 0.2);
}

}  // namespace
}  // namespace chatterlab
