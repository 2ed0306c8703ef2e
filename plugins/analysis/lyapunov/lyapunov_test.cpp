#include "analysis/lyapunov/lyapunov.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "shared/nonlinear/test_signals.hpp"
#include "unit/study_test_support.hpp"

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
  // The interval (every admissible curve's bootstrap interval: dimensions, sizes, methods)
  // covers 0.906 per time unit; the per-second value is the per-sample one over dt.
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::lorenz(100000), 0.01, "lorenz x"), Json::object());
  const Json& e = r["lyapunov_max_per_s"];
  EXPECT_EQ(e["quality"], "good") << e.dump();
  EXPECT_LE(e["ci_low"].get<double>(), 0.906) << e.dump();
  EXPECT_GE(e["ci_high"].get<double>(), 0.906) << e.dump();
  EXPECT_NEAR(e["value"].get<double>(), 0.906, 0.1);
  EXPECT_NEAR(e["value"].get<double>(), per_sample(r) / 0.01, 1e-9);
}

// Noise separates neighbours at once whatever their distance: the curves of different
// neighbourhood sizes collapse onto one, so no exponent is reported.
TEST(Lyapunov, WhiteNoiseIsNotDetermined) {
  const Json r = make_analysis("lyapunov", Json{{"embedding_dimension", 3}, {"delay_samples", 1}})
                     ->analyse(series(test_signals::white_noise(3000, 5), 1.0, "noise"),
                               Json::object());
  EXPECT_EQ(r["divergence"], "undetermined");
  const Json& e = r["lyapunov_max_per_sample"];
  EXPECT_TRUE(e["value"].is_null()) << e.dump();
  EXPECT_EQ(e["quality"], "failed");
  EXPECT_EQ(e["reason"].get<std::string>().rfind("not determined:", 0), 0u) << e.dump();
}

// Measurement noise (5 % of the standard deviation) biases the exponent low: never "good", and
// the reason names the noise.
TEST(Lyapunov, NoisyHenonIsNotGood) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::with_noise(test_signals::henon(8000), 0.05, 9), 1.0, "henon + noise"),
      Json::object());
  const Json& e = r["lyapunov_max_per_sample"];
  EXPECT_EQ(e["quality"], "uncertain") << e.dump();
  EXPECT_NE(e["reason"].get<std::string>().find("noise"), std::string::npos) << e.dump();
}

// 400 samples of a flow (about five orbits): an exponent may show, never a "good" one.
TEST(Lyapunov, ShortFlowIsNotGood) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::lorenz(400), 0.01, "lorenz x"), Json::object());
  EXPECT_NE(r["lyapunov_max_per_s"]["quality"], "good") << r["lyapunov_max_per_s"].dump();
}

// Without a time unit (a series counted in samples) there is only the per-sample exponent, and
// its reason speaks of samples only.
TEST(Lyapunov, PerSampleSeriesHasOnlyPerSampleRates) {
  SampledSeries s = series(test_signals::henon(3000), 1.0, "henon x");
  s.sample_unit = "sample";
  const Json r = make_analysis("lyapunov")->analyse(s, Json::object());
  EXPECT_TRUE(r.contains("lyapunov_max_per_sample"));
  EXPECT_FALSE(r.contains("lyapunov_max_per_s"));
  const std::string reason = r["lyapunov_max_per_sample"]["reason"].get<std::string>();
  EXPECT_NE(reason.find("per sample"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("per s "), std::string::npos) << reason;
}

// With a sample rate the per-second reason states every rate per second.
TEST(Lyapunov, PerSecondReasonStatesRatesPerSecond) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::henon(3000), 0.001, "henon x"), Json::object());
  const std::string reason = r["lyapunov_max_per_s"]["reason"].get<std::string>();
  EXPECT_EQ(reason.find("per sample"), std::string::npos) << reason;
  EXPECT_NE(reason.find("per s"), std::string::npos) << reason;
  EXPECT_NEAR(r["lyapunov_max_per_s"]["value"].get<double>(),
              r["lyapunov_max_per_sample"]["value"].get<double>() / 0.001, 1e-6);
}

TEST(Lyapunov, SineDoesNotDiverge) {
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::sine(5000, 20 * std::sqrt(3.0)), 1.0, "sine"), Json::object());
  EXPECT_NEAR(per_sample(r), 0.0, 0.005);
}


// kantz_scan (one search at the largest radius, binned by radius, shared coordinate differences,
// products logged per chunk) against the definition evaluated pair by pair in double precision.
// The neighbour sets are the definition's exactly (decided in double precision); the histories
// are summed from single-precision copies of x - mid-range, so each reference's ln rms may move
// by up to sqrt(m) 2^-24 (max - min) / rms (rounding of the samples; triangle inequality over
// the neighbours) plus (n + 3) 2^-24 (the float subtraction, square and sum of its n
// neighbours). Every curve point must lie within the mean of that bound over the references
// (a wrong neighbour set or step is off by >> 1e-3), and the bound itself must stay small.
// `exact`: x is integer-valued and every sum of squared separations stays below 2^24, so the
// single-precision sums are exact and only the order of the sums differs: within 1e-11.
// Pairs of vectors coincident in m0 dimensions (closer than 1e-9 of the range) are skipped, as
// in the scan.
void expect_kantz_scan_matches_direct_evaluation(const std::vector<double>& x, int m0, int m1,
                                                  int delay, std::size_t theiler,
                                                  std::size_t steps,
                                                  const std::vector<double>& radii,
                                                  bool exact = false, std::size_t stride = 1,
                                                  std::size_t references = 0) {
  const auto scan = kantz_scan(x, m0, m1, delay, theiler, steps, references, radii, stride);
  // Curve point k is the separation after k stride samples.
  const std::size_t reach = (steps - 1) * stride + std::size_t(m1 - 1) * std::size_t(delay) + 1;
  const std::size_t limit = x.size() - reach + 1;
  ASSERT_EQ(scan.references, references == 0 ? limit : references);
  // The scan's references: every vector, or `references` evenly spread.
  std::vector<std::size_t> reference_index;
  for (std::size_t r = 0; r < scan.references; ++r)
    reference_index.push_back(references == 0 ? r
                                              : std::size_t(double(r) * double(limit) /
                                                            double(references)));
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double unit = std::ldexp(1.0, -24), range = *hi - *lo;
  const double coincident2 = std::pow(1e-9 * range, 2);  // the scan's coincidence rule
  auto dist2 = [&](std::size_t i, std::size_t j, int m, std::size_t k) {
    double s = 0;
    for (int l = 0; l < m; ++l) s += std::pow(x[i + k + std::size_t(l * delay)] - x[j + k + std::size_t(l * delay)], 2);
    return s;
  };
  for (std::size_t r = 0; r < radii.size(); ++r)
    for (int m = m0; m <= m1; ++m) {
      // refs[k]: references whose neighbours are not all coincident at step k (the scan, like
      // TISEAN, leaves a zero mean out of the average).
      std::vector<double> sum(steps, 0.0), bound(steps, 0.0), refs(steps, 0.0);
      for (const std::size_t i : reference_index) {
        std::vector<double> mean(steps, 0.0);
        double n = 0;
        for (std::size_t j = 0; j < limit; ++j) {
          if ((j > i ? j - i : i - j) <= theiler || dist2(i, j, m, 0) > radii[r] * radii[r] ||
              dist2(i, j, m0, 0) <= coincident2)
            continue;
          for (std::size_t k = 0; k < steps; ++k) mean[k] += dist2(i, j, m, k * stride);
          n += 1;
        }
        if (n == 0) continue;
        for (std::size_t k = 0; exact && k < steps; ++k) ASSERT_LT(mean[k], std::ldexp(1.0, 24));
        for (std::size_t k = 0; k < steps; ++k) {
          if (mean[k] == 0) continue;
          refs[k] += 1;
          const double rms = std::sqrt(mean[k] / n);
          sum[k] += std::log(rms);
          bound[k] += std::sqrt(double(m)) * unit * range / rms + (n + 3) * unit;
        }
      }
      ASSERT_GT(refs[0], references == 0 ? 50.0 : 0.2 * double(references))
          << "radius " << radii[r] << ", m = " << m;
      const auto curve = scan.curve(r, m);
      for (std::size_t k = 0; k < steps; ++k) {
        const double tolerance = exact ? 1e-11 : bound[k] / refs[k] + 1e-11;
        EXPECT_LT(tolerance, 2e-4) << "radius " << radii[r] << ", m = " << m << ", k = " << k;
        EXPECT_NEAR(curve[k], sum[k] / refs[k], tolerance)
            << "radius " << radii[r] << ", m = " << m << ", k = " << k;
      }
    }
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluation) {
  // One-axis grid (m from 1), delay 2, a Theiler window.
  expect_kantz_scan_matches_direct_evaluation(test_signals::henon(2500), 1, 3, 2, 3, 12,
                                              {0.02, 0.05, 0.1});
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationInManyDimensions) {
  // Two-axis grid, six dimensions (two groups of four in the profile code), Theiler window 0.
  expect_kantz_scan_matches_direct_evaluation(test_signals::henon(1200), 2, 7, 1, 0, 9,
                                              {0.1, 0.3});
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationOverTwoHistoryPlanes) {
  // 60 steps: the separation histories (62 samples, padded to 64) span two storage planes of the
  // window (56 + 8 samples).
  expect_kantz_scan_matches_direct_evaluation(test_signals::henon(1000), 2, 3, 1, 0, 60,
                                              {0.05, 0.12});
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationWithNineRadii) {
  // More than eight radii: the radius loop with its count known only at run time.
  expect_kantz_scan_matches_direct_evaluation(test_signals::henon(1000), 2, 3, 1, 0, 6,
                                              {0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.1, 0.11, 0.12});
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationWithAHistoryStride) {
  // Every third sample of the histories (delay 6 = two history samples): the curve of a flow
  // evaluated every few samples.
  expect_kantz_scan_matches_direct_evaluation(test_signals::lorenz(1500, 0.02), 2, 4, 6, 10, 15,
                                              {1.0, 2.5}, false, 3);
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationExactlyOnAnIntegerSignal) {
  // Henon x in units of 1/1000, rounded: the float histories are exact, so the scan must agree
  // with the double-precision definition to the order of the sums (radii between integers).
  std::vector<double> x = test_signals::henon(1500);
  for (double& v : x) v = std::round(1000 * v);
  expect_kantz_scan_matches_direct_evaluation(x, 2, 3, 1, 0, 4, {12.5, 20.5, 40.5}, true);
}

TEST(Lyapunov, KantzScanMatchesDirectEvaluationWithSparseReferences) {
  // A sample of references (a long series): each row's window holds only the candidates of its
  // references. Two-axis grid with a Theiler window, exactly (integer signal) ...
  std::vector<double> x = test_signals::henon(3000);
  for (double& v : x) v = std::round(1000 * v);
  expect_kantz_scan_matches_direct_evaluation(x, 2, 3, 1, 2, 4, {20.5, 40.5}, true, 1, 300);
  // ... one-axis grid (m from 1) with delay 2, and a flow with a history stride.
  expect_kantz_scan_matches_direct_evaluation(test_signals::henon(3000), 1, 3, 2, 3, 12,
                                              {0.05, 0.1}, false, 1, 250);
  expect_kantz_scan_matches_direct_evaluation(test_signals::lorenz(3000, 0.02), 2, 4, 6, 10, 15,
                                              {1.0, 2.5}, false, 3, 200);
}

TEST(LyapunovAccuracy, HenonCurvesAreParallelInEveryDimension) {
  // Every Kantz curve the estimate uses (m = 2..4, the two smallest admissible sizes) has a
  // slope near lambda1 = 0.419, and the curves of neighbouring sizes stay apart (admissible).
  const Json r = make_analysis("lyapunov")->analyse(
      series(test_signals::henon(20000), 1.0, "henon x"), Json::object());
  EXPECT_EQ(r["divergence"], "exponential");
  EXPECT_EQ(r["dimensions"], Json::array({2, 4}));
  std::size_t selected = 0;
  for (const Json& c : r["curves"])
    if (c["selected"].get<bool>() && c["method"] == "Kantz") {
      ++selected;
      EXPECT_NEAR(c["slope_per_sample"].get<double>(), 0.419, 0.03) << c["radius"];
    }
  EXPECT_EQ(selected, 6u);
}

// The divergence curves are sums of logs over thousands of references: the same bits with one
// thread, with two, and from one run to the next. Rosenstein's curve sums fixed blocks of
// references in block order; the Kantz scan merges its grid rows (logs and leftover products)
// in row order. runs: one thread, two, two again.
template <class Curves>
void expect_same_sums(const std::array<Curves, 3>& runs) {
  EXPECT_EQ(runs[0].sum, runs[1].sum) << "one thread against two";
  EXPECT_EQ(runs[0].count, runs[1].count) << "one thread against two";
  EXPECT_EQ(runs[1].sum, runs[2].sum) << "two runs with two threads";
  EXPECT_EQ(runs[1].count, runs[2].count) << "two runs with two threads";
}

TEST(Lyapunov, RosensteinCurveDoesNotDependOnTheThreadCount) {
  const auto x = test_signals::henon(20000);
  const auto runs = testing::with_one_two_two_threads(
      [&] { return rosenstein_curve(x, 2, 1, 10, 20, 1, 5000); });
  EXPECT_GT(runs[0].references_at_start(), 4000);
  expect_same_sums(runs);
}

TEST(Lyapunov, KantzScanDoesNotDependOnTheThreadCount) {
  const auto x = test_signals::henon(20000);
  expect_same_sums(testing::with_one_two_two_threads(
      [&] { return kantz_scan(x, 2, 4, 1, 0, 30, 0, {0.005, 0.02, 0.08}); }));
}

// The whole analysis (embedding, Kantz scan, Rosenstein curves, bootstrap): the same result
// with one thread, with two, and from one run to the next.
TEST(Lyapunov, ResultDoesNotDependOnTheThreadCount) {
  const auto x = test_signals::henon(4000);
  const auto [one, two, again] = testing::with_one_two_two_threads([&] {
    return make_analysis("lyapunov")->analyse(series(x, 1.0, "henon x"), Json::object()).dump();
  });
  EXPECT_EQ(one, two);
  EXPECT_EQ(two, again);
}

}  // namespace
}  // namespace chatterlab
