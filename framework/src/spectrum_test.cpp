// Known answers for RealFft and amplitude_spectrum: round trip, a DFT computed by the definition,
// Parseval, and sines of known amplitude and frequency (on and between bins).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "chatterlab/fft.hpp"
#include "chatterlab/spectrum.hpp"

namespace chatterlab {
namespace {

constexpr double pi = std::numbers::pi;

TEST(RealFft, MatchesTheDefinitionAndRoundTrips) {
  for (std::size_t n : {1u, 2u, 7u, 16u, 33u}) {
    std::mt19937 rng(static_cast<unsigned>(n));
    std::normal_distribution<double> noise;
    std::vector<double> x(n);
    for (auto& v : x) v = noise(rng);
    RealFft fft(n);
    auto spectrum = fft.forward(x);
    ASSERT_EQ(spectrum.size(), n / 2 + 1);
    for (std::size_t k = 0; k < spectrum.size(); ++k) {
      std::complex<double> direct = 0.0;
      for (std::size_t j = 0; j < n; ++j)
        direct += x[j] * std::polar(1.0, -2.0 * pi * static_cast<double>(k * j) / static_cast<double>(n));
      EXPECT_NEAR(std::abs(spectrum[k] - direct), 0.0, 1e-12 * static_cast<double>(n)) << n << " " << k;
    }
    auto back = fft.inverse(spectrum);
    for (std::size_t j = 0; j < n; ++j) EXPECT_NEAR(back[j], x[j], 1e-13) << n;
  }
}

TEST(RealFft, RejectsWrongLengths) {
  RealFft fft(8);
  std::vector<double> x(7);
  EXPECT_THROW(fft.forward(x), std::invalid_argument);
  EXPECT_THROW(RealFft(0), std::invalid_argument);
}

TEST(RealFft, MovedObjectStillTransforms) {
  RealFft a(4);
  RealFft b = std::move(a);
  std::vector<double> x{1, 0, 0, 0};
  auto s = b.forward(x);
  for (auto v : s) EXPECT_NEAR(std::abs(v - 1.0), 0.0, 1e-15);
}

TEST(InPlaceRealFft, AgreesWithRealFftAndRoundTrips) {
  for (std::size_t n : {1u, 2u, 7u, 16u, 33u, 1000u}) {
    SCOPED_TRACE(n);
    std::mt19937 rng(static_cast<unsigned>(n) + 5);
    std::normal_distribution<double> noise;
    std::vector<double> x(n);
    for (auto& v : x) v = noise(rng);
    RealFft reference(n);
    const auto expected = reference.forward(x);
    InPlaceRealFft fft(x);
    ASSERT_EQ(fft.size(), n);
    fft.forward();
    ASSERT_EQ(fft.spectrum().size(), n / 2 + 1);
    for (std::size_t k = 0; k < expected.size(); ++k)
      EXPECT_NEAR(std::abs(fft.spectrum()[k] - expected[k]), 0.0, 1e-13 * static_cast<double>(n));
    fft.inverse();
    const std::vector<double> back = fft.take_samples();
    ASSERT_EQ(back.size(), n);
    for (std::size_t j = 0; j < n; ++j) EXPECT_NEAR(back[j], x[j], 1e-13);
    EXPECT_EQ(fft.size(), 0u);
  }
  EXPECT_THROW(InPlaceRealFft(std::vector<double>{}), std::invalid_argument);
}

TEST(AmplitudeSpectrum, SineOnABinReadsItsAmplitude) {
  const double rate = 1000.0;
  const std::size_t n = 1000;
  std::vector<double> x(n);
  for (std::size_t j = 0; j < n; ++j)
    x[j] = 3.0 + 0.7 * std::sin(2 * pi * 50.0 * static_cast<double>(j) / rate);  // offset removed
  for (auto window : {SpectralWindow::hann, SpectralWindow::rectangular}) {
    Spectrum s = amplitude_spectrum(x, rate, window);
    EXPECT_DOUBLE_EQ(s.resolution_hz, 1.0);
    EXPECT_NEAR(s.amplitude[50], 0.7, 1e-12) << to_string(window);
    EXPECT_NEAR(s.amplitude[0], 0.0, 1e-12);
  }
}

TEST(FindPeaks, LocatesOffBinSinesLargestFirst) {
  const double rate = 8000.0;
  const std::size_t n = 8000;  // 1 Hz bins
  std::vector<double> x(n);
  for (std::size_t j = 0; j < n; ++j) {
    const double t = static_cast<double>(j) / rate;
    x[j] = 1.0 * std::sin(2 * pi * 1031.3 * t) + 0.4 * std::sin(2 * pi * 2163.7 * t);
  }
  auto peaks = find_peaks(amplitude_spectrum(x, rate), 5, 10.0, 0.05);
  ASSERT_EQ(peaks.size(), 2u);
  EXPECT_NEAR(peaks[0].frequency_hz, 1031.3, 0.02);
  EXPECT_NEAR(peaks[1].frequency_hz, 2163.7, 0.02);
  // Scalloping loss of Hann between bins is up to 15 %; the refinement recovers most of it.
  EXPECT_NEAR(peaks[0].amplitude, 1.0, 0.02);
  EXPECT_NEAR(peaks[1].amplitude, 0.4, 0.01);
}

TEST(AmplitudeSpectrum, RejectsTooShortOrBadRate) {
  std::vector<double> x(3, 1.0);
  EXPECT_THROW(amplitude_spectrum(x, 10.0), std::invalid_argument);
  std::vector<double> y(10, 1.0);
  EXPECT_THROW(amplitude_spectrum(y, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace chatterlab
