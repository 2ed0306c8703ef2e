#include "shared/metrology/waviness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace chatterlab::surface {
namespace {

constexpr double pi = std::numbers::pi;

std::vector<double> sine(std::size_t n, double amplitude, double samples_per_wave, double phase = 0.3) {
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i)
    y[i] = amplitude * std::sin(2 * pi * static_cast<double>(i) / samples_per_wave + phase);
  return y;
}

TEST(WavinessParameters, SineHasAnalyticValues) {
  const double a = 2.5, wave = 400.0, spacing = 0.001;  // 0.4 mm waves at 1 um spacing
  const auto y = sine(40000, a, wave);                  // 100 whole waves
  const WavinessParameters p = waviness_parameters(y, spacing, false);
  EXPECT_NEAR(p.Wa, 2 * a / pi, 1e-4);  // Riemann sum of |sin|: O(h^2)
  EXPECT_NEAR(p.Wq, a / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(p.Wsk, 0.0, 1e-6);
  EXPECT_NEAR(p.Wku, 1.5, 1e-6);
  EXPECT_NEAR(p.Wp, a, 1e-4);
  EXPECT_NEAR(p.Wv, a, 1e-4);
  EXPECT_NEAR(p.Wz, 2 * a, 2e-4);
  EXPECT_NEAR(p.Wt, 2 * a, 2e-4);
  ASSERT_TRUE(p.WSm.has_value());
  EXPECT_NEAR(*p.WSm, wave * spacing, 1e-9);
  EXPECT_NEAR(p.Wz_five, 2 * a, 2e-4);
  EXPECT_GE(p.wave_count, 98u);
}

TEST(WavinessParameters, ClosedSineAndSamplingLengths) {
  const auto y = sine(3600, 1.0, 3600.0 / 12, 0.0);  // 12 lobes per revolution
  const WavinessParameters p = waviness_parameters(y, 0.1, true, 4);
  EXPECT_NEAR(p.Wa, 2 / pi, 1e-4);  // 3 whole lobes per sampling length
  EXPECT_NEAR(p.Wz, 2.0, 1e-9);
  ASSERT_TRUE(p.WSm.has_value());
  EXPECT_NEAR(*p.WSm, 30.0, 1e-9);  // 360 deg / 12
  EXPECT_EQ(p.wave_count, 12u);
  EXPECT_NEAR(p.Wz_five, 2.0, 1e-9);
}

TEST(WavinessParameters, BookWzIsTheMeanOfTheFiveLargestWaveHeights) {
  // Hand-worked profile: square-ish waves with peaks/valleys (+1,-1), (+2,-2), (+3,-1),
  // (+1,-4), (+2,-1), (+1,-1), (+5,-5): wave heights 2, 4, 4, 5, 3, 2, 10; five largest
  // 10, 5, 4, 4, 3 -> mean 5.2. A small ripple of 0.1 (< 10 % of Wz) must not count as a wave.
  const double peaks[] = {1, 2, 3, 1, 2, 1, 5}, valleys[] = {-1, -2, -1, -4, -1, -1, -5};
  std::vector<double> y{-0.5};
  for (int k = 0; k < 7; ++k) {
    for (double v : {0.5, peaks[k], 0.05, peaks[k] * 0.9, 0.5, -0.5, valleys[k], -0.05,
                     valleys[k] * 0.9, -0.5})
      y.push_back(v);
  }
  const ProfileElements e = profile_elements(y, 0.2, false);
  ASSERT_EQ(e.wave_heights.size(), 7u);
  const double expected[] = {2, 4, 4, 5, 3, 2, 10};
  for (int k = 0; k < 7; ++k) EXPECT_DOUBLE_EQ(e.wave_heights[static_cast<std::size_t>(k)], expected[k]);
  EXPECT_DOUBLE_EQ(mean_of_five_largest(e.wave_heights), 5.2);
  EXPECT_DOUBLE_EQ(mean_of_five_largest({3.0, 1.0}), 2.0);
  EXPECT_EQ(e.up_crossings.size(), 7u);
}

TEST(WavinessParameters, WidthDiscriminationJoinsNarrowFeatures) {
  // 10 waves of 1000 samples; inside every crest a 5-sample notch down to -0.5 (below the
  // height discrimination of 0.2 but 0.5 % of the sampling length wide): without width
  // discrimination each notch splits a peak, with 1 % it does not.
  std::vector<double> y(10000);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = std::sin(2 * pi * static_cast<double>(i) / 1000.0);
    if (i % 1000 >= 248 && i % 1000 < 253) y[i] = -0.5;
  }
  EXPECT_EQ(profile_elements(y, 0.2, false).wave_heights.size(), 19u);
  const ProfileElements e = profile_elements(y, 0.2, false, 100.0);
  // The first crest starts at x = 0 (no up-crossing, not a complete wave): 9 of each.
  EXPECT_EQ(e.wave_heights.size(), 9u);
  EXPECT_EQ(e.up_crossings.size(), 9u);
  const WavinessParameters p = waviness_parameters(y, 0.001, false, 1, 100.0);
  ASSERT_TRUE(p.WSm.has_value());
  EXPECT_NEAR(*p.WSm, 1.0, 1e-6);
}

TEST(WavinessParameters, WidthDiscriminationOverHundredsOfElements) {
  // 300 waves of 200 samples (crests +1, troughs -1 on samples), a 3-sample notch to -0.5 in
  // every crest: over a thousand phases, so the joins happen while earlier elements are already
  // final. Every notch joins its crest: 300 waves of height 2 (closed), wherever the revolution
  // starts; without width discrimination each notch splits its crest into two waves.
  const std::size_t per_wave = 200, waves = 300;
  std::vector<double> y(per_wave * waves);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = std::sin(2 * pi * static_cast<double>(i) / static_cast<double>(per_wave));
    if (i % per_wave >= 20 && i % per_wave < 23) y[i] = -0.5;  // the crest is at 50
  }
  EXPECT_EQ(profile_elements(y, 0.2, true).wave_heights.size(), 2 * waves);
  for (std::size_t shift : {0u, 1u, 21u, 12345u}) {
    SCOPED_TRACE(shift);
    std::vector<double> rotated(y.size());
    for (std::size_t i = 0; i < y.size(); ++i) rotated[i] = y[(i + shift) % y.size()];
    const ProfileElements e = profile_elements(rotated, 0.2, true, 10.0);
    ASSERT_EQ(e.wave_heights.size(), waves);
    for (double h : e.wave_heights) EXPECT_NEAR(h, 2.0, 1e-12);
    EXPECT_EQ(e.up_crossings.size(), waves);
  }
  // Open: the first crest has no up-crossing before it (no complete wave).
  const ProfileElements open = profile_elements(y, 0.2, false, 10.0);
  EXPECT_EQ(open.wave_heights.size(), waves - 1);
  EXPECT_EQ(open.up_crossings.size(), waves - 1);
}

TEST(WavinessParameters, FrequencyResolvedWzSeparatesForcedLobesFromChatter) {
  // G8-like part: n_g = 1450 rpm, n_w = 55 rpm (Z = 26.4), 26 forced lobes of Wz 4.26 um and
  // 895 chatter lobes (820 Hz at 55 rpm) of Wz 3.12 um.
  const std::size_t n = 23400;  // peaks and valleys of both lobe counts fall on samples
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double th = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
    y[i] = 2.13 * std::cos(26 * th) + 1.56 * std::cos(900 * th) + 5.0 * std::cos(th + 1);
  }
  const auto [low, high] = default_bands(1450, 55, n);
  EXPECT_DOUBLE_EQ(low.from_upr, 13);
  EXPECT_DOUBLE_EQ(low.to_upr, 40);
  EXPECT_DOUBLE_EQ(high.from_upr, 41);
  const BandWaviness l = band_waviness(y, low, 55), h = band_waviness(y, high, 55);
  EXPECT_NEAR(l.Wz, 4.26, 1e-6);
  EXPECT_DOUBLE_EQ(l.dominant_upr, 26);
  EXPECT_NEAR(l.dominant_amplitude, 2.13, 1e-9);
  EXPECT_NEAR(l.dominant_frequency_hz, 26 * 55 / 60.0, 1e-12);
  EXPECT_NEAR(h.Wz, 3.12, 1e-6);
  EXPECT_DOUBLE_EQ(h.dominant_upr, 900);
  EXPECT_NEAR(h.dominant_frequency_hz, 825.0, 1e-9);
  // The band-limited profiles themselves: each band keeps exactly its own cosine.
  const auto high_only = band_limited(y, high);
  ASSERT_EQ(high_only.size(), n);
  for (std::size_t i = 0; i < n; i += 97) {
    const double th = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
    EXPECT_NEAR(high_only[i], 1.56 * std::cos(900 * th), 1e-12);
  }
}

}  // namespace
}  // namespace chatterlab::surface
